"""Command-line apps (Hydra): swgsim-generate, swgsim-train, swgsim-calibrate, swgsim-paper.

Thin wrappers: each app's work lives in a task function that tests call directly.
"""

from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parent.parent
CONF_DIR = str(REPO_ROOT / "conf")


def dataset_preset(name: str, overrides: list[str] | tuple[str, ...] = ()) -> dict:
    """The data-set config of a preset in ``conf/dataset/``, composed as the apps do.

    Parameters
    ----------
    name : str
        Preset name (``paper``, ``bench``, ``tiny``, ``tiny_bench``, ...).
    overrides : sequence of str
        Hydra overrides relative to the data set, e.g. ``["chain.window_s=0.02"]``.

    Returns
    -------
    dict
        Plain, resolved config for :func:`swgsim.generate.generate`.
    """
    from hydra import compose, initialize_config_dir
    from omegaconf import OmegaConf

    with initialize_config_dir(config_dir=CONF_DIR, version_base="1.3"):
        cfg = compose(config_name="generate",
                      overrides=[f"dataset={name}", *(f"dataset.{o}" for o in overrides)])
    return OmegaConf.to_container(cfg.dataset, resolve=True)
