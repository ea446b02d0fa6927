"""``swgsim-train``: Hydra app around :func:`learn.study.run_train`.

Examples
--------
::

    swgsim-train model=rf features=selection3 protocol=ood_disturbed data=tiny
    swgsim-train -m model=rf,knn features=selection1,selection3 protocol=ood_disturbed
    swgsim-train -m experiment=table_vii hydra/launcher=joblib
    swgsim-train experiment=paper n_jobs=2
"""

from __future__ import annotations

from pathlib import Path

import hydra
from omegaconf import DictConfig

CONFIG_PATH = str(Path(__file__).resolve().parents[1] / "conf")


@hydra.main(version_base="1.3", config_path=CONFIG_PATH, config_name="train")
def main(cfg: DictConfig) -> dict:
    """Compose ``conf/train.yaml`` and run the task it names."""
    from learn.study import run_train

    return run_train(cfg)


if __name__ == "__main__":
    main()
