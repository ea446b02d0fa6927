"""Reports of the studies' results: Tables VII-X and figures (:mod:`learn.reports.report`),
the paper's published numbers (:mod:`learn.reports.paper_results`), its findings
(:mod:`learn.reports.findings`), the summary of both protocols
(:mod:`learn.reports.summary`, :mod:`learn.reports.open_choices`), the monitor's and the
prognosis's reports (the transfer report is in :mod:`learn.transfer`). Reports read
result tables; of the studies they import only names and result columns."""
