"""A start in a second: an app's ``--help`` and a refused override import no heavy library,
and the help lists exactly the config groups the app accepts (issue 43).

The times themselves are measured by ``scripts/bench_startup.py``, not here.
"""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
from pathlib import Path

import pytest
from hydra.core.config_store import ConfigStore

from swgcli import CONF_DIR, compose_app
from swgsim.base.lazy import lazy_module

#: config name -> app module
APPS = {"generate": "generate", "train": "train", "calibrate": "calibrate",
        "paper": "paper", "observability": "observability", "monitor": "monitor",
        "export": "export", "import": "importer"}
#: values of the mandatory keys, so that a config composes
MANDATORY = {"monitor": ["stream=s", "diagnosis_model=m.skops"],
             "calibrate": ["measured=m.csv", "out_dir=o"]}
#: what no app's start may load (issue 43: torch, skops, scikit-learn, MLflow, aeon; and
#: the libraries that cost most of a second besides)
HEAVY = ("torch", "sklearn", "skops.io", "mlflow", "aeon", "pandas", "matplotlib",
         "scipy.signal", "scipy.sparse", "scipy.stats", "scipy.special",
         "scipy.interpolate", "scipy.optimize", "xarray", "pyarrow")


def test_importing_every_app_loads_no_heavy_library():
    probe = ("import importlib, sys\n"
             f"for m in {sorted(set(APPS.values()))!r}: importlib.import_module('swgcli.' + m)\n"
             f"print(' '.join(m for m in {HEAVY!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", probe], check=True, capture_output=True,
                         text=True).stdout.split()
    assert out == []


def test_a_lazy_module_loads_on_first_use_and_a_missing_one_is_refused_at_once():
    code = ("import sys\nfrom swgsim.base.lazy import lazy_module\n"
            "m = lazy_module('fractions')\n"
            "assert 'fractions' not in sys.modules\n"
            "assert m.Fraction(1, 2) * 2 == 1 and 'fractions' in sys.modules\n")
    subprocess.run([sys.executable, "-c", code], check=True)
    with pytest.raises(ModuleNotFoundError, match="no_such_library_43"):
        lazy_module("no_such_library_43")


def _help(app: str, monkeypatch, capsys, *args: str) -> str:
    main = importlib.import_module(f"swgcli.{APPS[app]}").main
    monkeypatch.setattr(sys, "argv", [f"swgsim-{app}", *args])
    main()
    return capsys.readouterr().out


def _listed(text: str) -> dict[str, list[str]]:
    block = text.split("== Configuration groups ==")[1].split("== Config ==")[0]
    rows = [r for r in block.splitlines()[2:] if ": " in r]
    return {k: v.split(", ") for k, v in (r.split(": ", 1) for r in rows)}


def _all_groups() -> set[str]:
    repo = ConfigStore.instance().repo
    return ({g for g, n in repo.items() if isinstance(n, dict) and g != "hydra"}
            | {d.name for d in os.scandir(CONF_DIR) if d.is_dir()})


@pytest.mark.parametrize("app", [a for a in APPS if a != "import"])
def test_the_help_lists_only_groups_the_app_accepts(app, monkeypatch, capsys):
    text = _help(app, monkeypatch, capsys, "--help")
    listed = _listed(text)
    assert "== Config ==" in text and "hydra" not in listed
    for key, options in listed.items():  # each listed group: its first and last option
        for option in {options[0], options[-1]}:
            compose_app(app, [*MANDATORY.get(app, []), f"{key}={option}"])
    for group in sorted(_all_groups() - {k.split("@")[0] for k in listed}):
        # the last option: thermal's first (industrial) changes nothing, so merges anywhere
        option = sorted(ConfigStore.instance().repo.get(group, {}) or
                        [p.name for p in (Path(CONF_DIR) / group).glob("*.yaml")]
                        )[-1].removesuffix(".yaml")
        with pytest.raises(Exception):  # noqa: B017 - Hydra's or the schema's refusal
            compose_app(app, [*MANDATORY.get(app, []), f"+{group}={option}"])


def test_the_import_app_lists_no_group_and_shows_its_mandatory_keys(monkeypatch, capsys):
    text = _help("import", monkeypatch, capsys, "-h")
    assert _listed(text) == {} and "recording: ???" in text


def test_help_shows_the_overrides_and_refuses_a_bad_one_in_one_line(monkeypatch, capsys):
    assert "name: cnn" in _help("train", monkeypatch, capsys, "model=cnn", "--help")
    with pytest.raises(SystemExit) as e:
        _help("train", monkeypatch, capsys, "model=no_such_model", "--help")
    err = capsys.readouterr().err.strip().splitlines()
    assert e.value.code == 2 and len(err) == 1 and "no_such_model" in err[0]


def test_a_lazy_module_whose_import_fails_raises_and_is_tried_again(tmp_path, monkeypatch):
    flag = tmp_path / "broken"
    flag.touch()
    (tmp_path / "flaky_lib_43.py").write_text(
        f"import pathlib\nif pathlib.Path({str(flag)!r}).exists():\n"
        "    raise RuntimeError('half-built')\nVALUE = 43\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    m = lazy_module("flaky_lib_43")
    with pytest.raises(RuntimeError, match="half-built"):
        m.VALUE  # noqa: B018
    flag.unlink()
    assert m.VALUE == 43
    sys.modules.pop("flaky_lib_43", None)
