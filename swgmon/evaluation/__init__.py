"""The monitor's and the prognosis's evaluations (ISO 13374 leaves them to the user; here
they are the studies the monitor is judged by): the families of benign changes
(:mod:`.families`), the per-window detectors and the reviewer's baselines
(:mod:`.detectors`, :mod:`.baselines`), the study's design and the training on simulated
gears (:mod:`.study`, :mod:`.training`); the monitor's leave-one-gear-out evaluation
(:mod:`.evaluate`, the task ``monitor``: :mod:`.task`, :mod:`.report`), the prognosis's on
lives to failure (:mod:`.prognosis_evaluation`, the task ``prognosis``:
:mod:`.prognosis_task`, :mod:`.prognosis_report`) and the pre-registered benchmark
(:mod:`.benchmark`, :mod:`.benchmark_task`, :mod:`.statistics`). The resumable parts the
tasks run are :mod:`learn.tasks.parts`. Docs: ``docs/monitor.md``."""
