"""``swgsim-train``: Hydra app around :func:`swgcli.tasks.run_train`.

Examples
--------
::

    swgsim-train model=rf features=selection3 protocol=ood_disturbed stored=tiny
    swgsim-train -m model=rf,knn features=selection1,selection3 protocol=ood_disturbed
    swgsim-train -m experiment=table_vii hydra/launcher=joblib
    swgsim-train experiment=paper n_jobs=2
"""

from __future__ import annotations

from omegaconf import DictConfig

from swgcli.app import hydra_app
from swgcli.schema import TrainApp
from swgcli.tasks import check_inputs, run_train

#: The libraries its runs import, resolved before any work
#: (:func:`learn.tracking.preflight.check_imports`).
NEEDS = ("numpy", "scipy", "pandas", "xarray", "h5netcdf", "joblib", "sklearn", "torch", "aeon",
         "skops.io", "mlflow", "matplotlib")


@hydra_app("train", TrainApp, "swgsim-train", NEEDS, inputs=check_inputs)
def main(cfg: DictConfig) -> dict:
    """Compose ``conf/train.yaml`` and run the task it names."""
    return run_train(cfg)


if __name__ == "__main__":
    main()
