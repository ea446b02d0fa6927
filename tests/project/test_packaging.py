"""Packaging and public API: every package listed for a plain `pip install .`, configs
shipped with it, the curated exports resolve."""

import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def test_every_package_and_config_folder_is_listed():
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(cfg["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts)
             for top in ("swgsim", "swgcal", "learn", "swgmon", "swgcli")
             for p in (ROOT / top).rglob("__init__.py")}
    conf = {"swgcli.conf", *("swgcli.conf." + ".".join(d.relative_to(ROOT / "conf").parts)
                             for d in (ROOT / "conf").rglob("*") if d.is_dir()
                             and any(d.glob("*.yaml")))}
    assert listed == found | conf, (sorted(listed - found - conf), sorted((found | conf) - listed))
    assert cfg["package-dir"]["swgcli.conf"] == "conf"


@pytest.mark.parametrize("package", ["swgsim", "learn", "swgmon"])
def test_public_api_resolves(package):
    import importlib

    mod = importlib.import_module(package)
    assert isinstance(mod.__version__, str) and mod.__version__
    for name in mod.__all__:
        assert hasattr(mod, name), name
    with pytest.raises(AttributeError, match="no attribute"):
        mod.not_a_name  # noqa: B018


def test_calibration_api_resolves_and_the_simulator_does_not_export_it():
    import swgcal
    import swgsim

    for name in swgcal.__all__:
        assert hasattr(swgcal, name), name
    assert not set(swgcal.__all__) & set(swgsim.__all__) - {"Param", "Term"}


def test_config_folder_found():
    import swgcli

    assert (Path(swgcli.CONF_DIR) / "paper.yaml").is_file()
