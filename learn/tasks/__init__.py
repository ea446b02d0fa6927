"""The tasks behind the apps: each runs a study and writes its report.

:mod:`learn.tasks.train` (``swgsim-train``'s dispatch, :data:`learn.tasks.train.TASKS`,
and one study job) and the monitor's and the prognosis's evaluations; the paper study's
task is :mod:`learn.paper.task` and the transfer comparison's :mod:`learn.transfer.task`,
floors up (they use :func:`learn.tasks.config.typed_app`; the transfer task reuses
:func:`learn.tasks.monitor_evaluation.part_key`). The top layer of :mod:`learn`'s kinds.
"""
