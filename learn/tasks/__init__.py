"""The tasks behind the apps: each runs a study and writes its report.

:mod:`learn.tasks.train` (``swgsim-train``'s dispatch, :data:`learn.tasks.train.TASKS`,
and one study job), :mod:`learn.tasks.paper` (the paper's study with its report) and the
monitor's and the prognosis's evaluations; the transfer comparison's task is
:mod:`learn.transfer.task`, one floor up (it reuses
:func:`learn.tasks.monitor_evaluation.part_key`). The top layer of :mod:`learn`'s kinds.
"""
