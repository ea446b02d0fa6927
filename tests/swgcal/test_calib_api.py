"""The calibration API: one shape for both data kinds, the simulator free of its consumer."""

from __future__ import annotations

import inspect
import subprocess
import sys

import pytest

from swgcal import KINDS, kind_module
from swgcal.api import STEPS
from swgcal.report import ReportParts


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_every_kind_has_the_same_steps_with_the_same_signatures(kind):
    mod = kind_module(kind)
    ref = kind_module("friction")
    for step in STEPS:
        fn = getattr(mod, step)
        assert callable(fn) and fn.__doc__, (kind, step)
        # the same positional parameters; a kind may add keyword-only options
        pos = [p.name for p in inspect.signature(fn).parameters.values()
               if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
        pos_ref = [p.name for p in inspect.signature(getattr(ref, step)).parameters.values()
                   if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
        assert pos[:2] == pos_ref[:2], (kind, step, pos, pos_ref)
    # what its report adds to the one renderer (swgcal.report.render_report)
    assert isinstance(mod.REPORT, ReportParts), kind


def test_unknown_kind_and_unknown_options_are_named():
    with pytest.raises(ValueError, match="unknown calibration kind 'torque'.*friction"):
        kind_module("torque")
    from swgcal import friction, strain

    with pytest.raises(TypeError, match=r"unknown friction problem options \['n_block'\]"):
        friction.build_problem("x.csv", n_block=3)
    with pytest.raises(TypeError, match=r"unknown strain problem options \['held_out'\]"):
        strain.build_problem("x", held_out="windows")


def test_making_a_data_set_does_not_load_the_calibration():
    code = ("import sys, swgsim.datasets.generate, swgsim.gear.friction; "
            "print(sorted(m for m in sys.modules if m.startswith('swgcal')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"


def test_no_simulator_module_imports_the_calibration():
    """swgsim is the simulator only: importing every one of its modules loads no swgcal
    module, and no swgsim source names swgcal in an import (also inside functions)."""
    import ast
    from pathlib import Path

    import swgsim

    root = Path(swgsim.__file__).parent
    offenders = []
    for f in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(f.read_text(encoding="utf-8"))):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            offenders += [f"{f.relative_to(root)}: {n}" for n in names
                          if n.split(".")[0] == "swgcal"]
    assert offenders == []
    code = ("import pkgutil, importlib, sys, swgsim; "
            "[importlib.import_module(m.name) for m in "
            "pkgutil.walk_packages(swgsim.__path__, 'swgsim.')]; "
            "print(sorted(m for m in sys.modules if m.startswith('swgcal')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"
