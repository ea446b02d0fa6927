"""What the workflows' tasks share: :mod:`learn.tasks.config`
(:func:`learn.tasks.config.typed_app`, an app's config as its typed object) and
:mod:`learn.tasks.parts` (the resumable parts of an evaluation, grouped for job arrays).
The tasks themselves are in their workflows' folders, floors up: the paper study's
:mod:`learn.paper.task` and one job of it, :mod:`learn.paper.job`; the monitor's and the
prognosis's evaluations :mod:`learn.monitor_evaluation` and the transfer comparison's
:mod:`learn.transfer.task` (they use :func:`learn.tasks.config.typed_app`; the
evaluations and the transfer task reuse :mod:`learn.tasks.parts`); ``swgsim-train``'s
dispatch, :data:`learn.train.TASKS`, on :mod:`learn`'s top floor above them all.
"""
