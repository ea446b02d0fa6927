"""Command-line apps (Hydra): swgsim-generate, swgsim-train, swgsim-calibrate, swgsim-paper.

Thin wrappers: each app's work lives in a task function that tests call directly.
"""

from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parent.parent


def _conf_dir() -> str:
    """The config folder: ``conf/`` of a source checkout (editable install), else the copy
    shipped inside this package by a plain ``pip install .`` (``swgcli/conf``,
    pyproject's ``package-dir``)."""
    for cand in (REPO_ROOT / "conf", Path(__file__).resolve().parent / "conf"):
        if (cand / "paper.yaml").is_file():
            return str(cand)
    raise FileNotFoundError(f"no config folder: neither {REPO_ROOT / 'conf'} nor "
                            f"{Path(__file__).resolve().parent / 'conf'} holds paper.yaml; "
                            "reinstall the package")


CONF_DIR = _conf_dir()


def compose_app(config_name: str, overrides: list[str] | tuple[str, ...] = ()):
    """Compose an app's config as its command line would, without running it.

    Registers the schemas (:mod:`swgcli.schema`), composes ``conf/<config_name>.yaml``
    with Hydra's compose API and checks it against the app's schema, so tests and
    notebooks get exactly what the app would see.

    Parameters
    ----------
    config_name : {"generate", "paper", "train", "calibrate", "observability", "monitor", "export"}
    overrides : sequence of str
        Hydra overrides, e.g. ``["dataset=tiny", "n_jobs=1"]``.

    Returns
    -------
    omegaconf.DictConfig

    Raises
    ------
    ValueError
        A key the schema does not have (see :func:`swgcli.schema.validate`); Hydra's own
        composition errors are raised as they are.
    """
    import importlib

    from hydra import compose, initialize_config_dir

    from swgcli import schema

    # the app's module registers its schema (the calibration app's loads its stack)
    module = importlib.import_module(f"swgcli.{config_name}") if config_name in (
        "generate", "paper", "train", "calibrate", "observability", "monitor",
        "export") else None
    with initialize_config_dir(config_dir=CONF_DIR, version_base="1.3"):
        cfg = compose(config_name=config_name, overrides=list(overrides))
    if module is not None:
        schema.validate(cfg, module.main.schema)
    return cfg


def dataset_preset(name: str, overrides: list[str] | tuple[str, ...] = ()) -> dict:
    """The data-set config of a preset in ``conf/dataset/``, composed as the apps do.

    Parameters
    ----------
    name : str
        Preset name (``paper``, ``bench``, ``tiny``, ``tiny_bench``, ...).
    overrides : sequence of str
        Hydra overrides relative to the data set, e.g. ``["chain.window_s=0.12"]``.

    Returns
    -------
    dict
        Plain, resolved config for :func:`swgsim.datasets.generate.generate`.
    """
    from omegaconf import OmegaConf

    cfg = compose_app("generate", [f"dataset={name}", *(f"dataset.{o}" for o in overrides)])
    return OmegaConf.to_container(cfg.dataset, resolve=True)
