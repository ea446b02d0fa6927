"""What the workflows' tasks share: :mod:`learn.tasks.config` (:func:`typed_app
<learn.tasks.config.typed_app>`, an app's config as its typed object) and
:mod:`learn.tasks.parts` (the resumable parts of an evaluation, grouped for job arrays).
The tasks themselves are in their workflows' folders, floors up (:mod:`learn`); ``swgsim-train``'s
dispatch, :data:`swgcli.tasks.TASKS`, is on the top floor above them all.
"""
