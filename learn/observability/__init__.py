"""The observability map, one workflow: which faults the flexspline gauges can see over
the output inertia, speed and load (:mod:`learn.observability.study`), and what a joint
in motion adds (:mod:`learn.observability.motion`); :mod:`learn.observability.task` is
what ``swgsim-observability`` (:mod:`swgcli.observability`) runs. Docs:
``docs/observability.md``."""
