"""Studies: protocols and splits (:mod:`learn.studies.protocols`; the paper's tables and
study built on them are :mod:`learn.paper`), the runs of the transfer comparison
(:mod:`learn.studies.runs`, :mod:`learn.studies.kshot`, :mod:`learn.studies.latency`; the
comparison itself is :mod:`learn.transfer`) and the separability of faults
(:mod:`learn.studies.separability`; the observability map built on it is
:mod:`learn.observability`). They compute results; they write no report (that is each
workflow's folder, with its task)."""
