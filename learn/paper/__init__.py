"""The paper's study, one workflow: Tables VII-X on one data set. Which tables and models
a run covers (:mod:`learn.paper.tables`, with its ``StudyOptions``), the study itself
(:mod:`learn.paper.study`), its report's tables and figures (:mod:`learn.paper.report`),
the paper's published numbers and the scorecard against them
(:mod:`learn.paper.results`), its qualitative findings (:mod:`learn.paper.findings`), the
summary of both protocols (:mod:`learn.paper.summary`) with the choices the paper leaves
open (:mod:`learn.paper.open_choices`); :mod:`learn.paper.task` is the task
``paper_study`` (``swgsim-train experiment=paper``) and the public entry point behind
``swgsim-paper``. The protocols and splits (:mod:`learn.studies.protocols`) stay in
:mod:`learn.studies`: other tasks use them too. Docs: ``docs/paper_study.md``."""
