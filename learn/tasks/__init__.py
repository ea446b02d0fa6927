"""The tasks behind the apps: each runs a study and writes its report.

:mod:`learn.tasks.train` (``swgsim-train``'s dispatch, :data:`learn.tasks.train.TASKS`,
and one study job), :mod:`learn.tasks.config` (:func:`learn.tasks.config.typed_app`) and
:mod:`learn.tasks.parts` (the resumable parts of an evaluation, grouped for job arrays);
the workflows' tasks are in their folders, floors up: the paper study's
:mod:`learn.paper.task`, the monitor's and the prognosis's evaluations
:mod:`learn.monitor_evaluation` and the transfer comparison's :mod:`learn.transfer.task`
(they use :func:`learn.tasks.config.typed_app`; the evaluations and the transfer task
reuse :mod:`learn.tasks.parts`). The top layer of :mod:`learn`'s kinds.
"""
