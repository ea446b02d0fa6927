"""The transfer comparison, one workflow: deep learners and transfer to the gear not seen
in training (:mod:`learn.transfer.study`, with its ``TransferConfig``), its report's
tables and targets (:mod:`learn.transfer.report`), which run a line states
(:mod:`learn.transfer.picks`), its figure (:mod:`learn.transfer.figure`) and MLflow runs
(:mod:`learn.transfer.runs`); :mod:`learn.transfer.task` is the task ``transfer`` that
``swgsim-train -m experiment=transfer`` runs. The k-shot split
(:mod:`learn.studies.kshot`), the runs' fit and adaptation (:mod:`learn.studies.runs`)
and latency (:mod:`learn.studies.latency`) stay in :mod:`learn.studies`: other tasks use
them too. Docs: ``docs/learners_transfer.md``."""
