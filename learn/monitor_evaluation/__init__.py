"""The monitor's and the prognosis's evaluations, one workflow: the condition monitor's
leave-one-gear-out evaluation over simulated gear lives, the task ``monitor``
(``swgsim-train experiment=monitor``, :mod:`learn.monitor_evaluation.task`) and its table
and figures (:mod:`learn.monitor_evaluation.report`); the prognosis's on lives that run to
failure, the task ``prognosis`` (``swgsim-train experiment=prognosis``,
:mod:`learn.monitor_evaluation.prognosis_task`) and its tables, targets and figure
(:mod:`learn.monitor_evaluation.prognosis_report`). The monitor itself and the evaluations'
library are :mod:`learn.monitor` (:mod:`learn.monitor.evaluate`,
:mod:`learn.monitor.prognosis_evaluation`); the resumable parts both tasks run are
:mod:`learn.tasks.parts`. Docs: ``docs/monitor.md``."""
