"""Reports of the studies' results: the monitor's (:mod:`learn.reports.monitor_report`) and
the prognosis's (:mod:`learn.reports.prognosis_report`). The paper study's report, its
published numbers, findings and summary are in :mod:`learn.paper`; the transfer report is
in :mod:`learn.transfer`. Reports read result tables; of the studies they import only
names and result columns."""
