"""swgsim-observability: the observability map over the output inertia (Hydra app).

The typed config (:class:`swgcli.schema.ObservabilityApp`, ``conf/observability.yaml``)
and one call: :func:`learn.observability.task.run_observability_app` generates a data set
per output inertia, measures which faults the gauges can see and writes
``<report_dir>/observability.csv``, ``torsional_modes.csv`` and ``observability.png``
(``map=motion``: the joint in motion, :mod:`learn.observability.motion`).
"""

from __future__ import annotations

from omegaconf import DictConfig

from learn.observability.task import run_observability_app
from swgcli.app import hydra_app
from swgcli.schema import ObservabilityApp

#: The libraries its runs import, resolved before any work
#: (:func:`learn.tracking.preflight.check_imports`).
NEEDS = ("numpy", "scipy", "pandas", "xarray", "joblib", "matplotlib")


@hydra_app("observability", ObservabilityApp, "swgsim-observability", NEEDS)
def main(cfg: DictConfig) -> dict:
    """Compose ``conf/observability.yaml`` and run the map."""
    return run_observability_app(cfg)


if __name__ == "__main__":
    main()
