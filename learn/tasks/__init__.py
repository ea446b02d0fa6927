"""The tasks behind the apps: each runs a study and writes its report.

:mod:`learn.tasks.train` (``swgsim-train``'s dispatch, :data:`learn.tasks.train.TASKS`,
and one study job), :mod:`learn.tasks.paper` (the paper's study with its report) and
:mod:`learn.tasks.transfer` (the transfer comparison over data sets with its report).
The top layer of :mod:`learn`.
"""
