"""Helpers of the bad-input tests (tests/apps, tests/swgsim): a small data set, snapshots
of folders, the one-line message of a refused call, an app run in-process as its console
would run it (its exit code and one line), a friction CSV, the calibration app as a call,
the live members of a process group, and a small diagnosis model whose parts are right."""

from __future__ import annotations

import contextlib
import importlib
import io
import os
import sys
from pathlib import Path

import numpy as np
import pytest

from swgcli import compose_app, dataset_preset
from swgcli.app import one_line
from swgsim.datasets import schema as dsio


def small_cfg(**chain) -> dict:
    """Two gears, three classes, one load: a data set in about a second."""
    cfg = dataset_preset("tiny")
    cfg["variants"] = {"healthy": {"severities": [0.0], "repeat": 2},
                       "eccentric_wg": {"severities": [0.1], "n_positions": 1},
                       "root_tooth_crack": {"severities": [0.9], "n_positions": 1}}
    cfg["gears"] = cfg["gears"][:2]
    cfg["operating_points"]["t_out_nm"] = [39.0]
    cfg["chain"].update({"window_s": 0.06, "settle_s": 0.02, **chain})
    return cfg


def fail_second_shard(monkeypatch, gen) -> None:
    """Make the generator's second shard raise, as a machine going down mid-run would;
    ``monkeypatch.undo()`` or a new ``setattr`` brings the real shard back."""
    calls, real = [], gen.run_shard

    def fail_second(*a, **k):
        calls.append(1)
        if len(calls) == 2:
            raise RuntimeError("the machine went down")
        return real(*a, **k)

    monkeypatch.setattr(gen, "run_shard", fail_second)


def snapshot(folder: Path) -> dict[str, tuple[int, float]]:
    """Every file below ``folder``: size and modification time."""
    return {str(p.relative_to(folder)): (p.stat().st_size, p.stat().st_mtime)
            for p in sorted(folder.rglob("*")) if p.is_file()}


def load_message(folder: Path) -> str:
    """The one-line error of loading a spoiled data set (:func:`swgsim.datasets.schema.load`)."""
    with pytest.raises(dsio.DataSetError) as info:
        dsio.load(folder)
    msg = str(info.value)
    assert "\n" not in msg
    return msg


def message(call) -> str:
    """The one-line message a bad-input exception of ``call`` ends in."""
    with pytest.raises(Exception) as info:  # noqa: PT011 - sorted by one_line below
        call()
    msg = one_line(info.value)
    assert msg is not None, f"not reported as bad input: {info.value!r}"
    assert "\n" not in msg
    return msg


#: The console apps run in-process by :func:`run_app`: command name -> ``swgcli`` module.
APPS = {"swgsim-generate": "generate", "swgsim-calibrate": "calibrate",
        "swgsim-monitor": "monitor", "swgsim-observability": "observability",
        "swgsim-paper": "paper", "swgsim-train": "train"}


def run_app(prog: str, args: list[str], cwd: Path, monkeypatch, capsys) -> tuple[int, str]:
    """Run an app in-process as its command line would: exit code and stderr (a case runs
    the app in a process of its own only where that process must die)."""
    main = importlib.import_module(f"swgcli.{APPS[prog]}").main
    monkeypatch.chdir(cwd)
    monkeypatch.setattr(sys, "argv", [prog, *args])
    capsys.readouterr()
    with pytest.raises(SystemExit) as info:
        main()
    return info.value.code, capsys.readouterr().err


def one_error_line(prog: str, err: str) -> str:
    """The single line of stderr, ``<prog>: error: ...``, without a traceback."""
    lines = [s for s in err.splitlines() if s.strip()]
    assert len(lines) == 1 and lines[0].startswith(f"{prog}: error: "), err
    assert "Traceback" not in err
    return lines[0]


def app_line(module: str, args: list[str], tmp_path: Path) -> str:
    """Run ``swgcli.<module>.main`` in-process as the console would; its one line (exit 2).
    For the cases where the console (Hydra, the one-line wrapper) is what is tested; the
    others call the apps' task functions."""
    main = importlib.import_module(f"swgcli.{module}").main
    argv, sys.argv = sys.argv, [module, *args, f"hydra.run.dir={tmp_path}/hydra"]
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err), pytest.raises(SystemExit) as info:
            main()
    finally:
        sys.argv = argv
    lines = [s for s in err.getvalue().splitlines() if s.strip()]
    assert info.value.code == 2 and len(lines) == 1, err.getvalue()
    assert "Traceback" not in err.getvalue()
    return lines[0]


def friction_csv(path: Path, t, q, dq, tau=None, extra: str = "") -> Path:
    tau = np.zeros_like(t) if tau is None else tau
    rows = "\n".join(f"{a},{b},{c},{d}" for a, b, c, d in zip(t, q, dq, tau, strict=True))
    path.write_text("time_s,q_rad,dq_rad_per_s,tau_friction_Nm\n" + rows + extra + "\n")
    return path


def calibrate_call(measured: Path, out: Path, *extra):
    from swgcli.calibrate import run_calibrate

    cfg = compose_app("calibrate", [f"measured={measured}", f"out_dir={out}",
                                    "~logger", "figures=false", *extra])
    return lambda: run_calibrate(cfg)


def process_group(pgid: int) -> list[int]:
    out = []
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                stat = Path(f"/proc/{d}/stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(stat[2]) == pgid and stat[0] != "Z":
                out.append(int(d))
    return out


def small_model(**change):
    """A small diagnosis model whose parts are those ``fit_diagnosis`` makes (two health
    features and the operating point: four inputs; classes healthy and ``x``), with
    ``change`` (fields of :class:`swgmon.assessment.model.DiagnosisModel`) applied."""
    import dataclasses

    from sklearn.ensemble import HistGradientBoostingClassifier, HistGradientBoostingRegressor

    from swgmon.assessment.model import DiagnosisModel

    x, y = np.eye(4), [0, 1, 0, 1]
    m = DiagnosisModel(
        ["healthy", "x"], HistGradientBoostingClassifier(max_iter=2).fit(x, y),
        {"x": (HistGradientBoostingRegressor(max_iter=2).fit(x, [0.0, 0.1, 0.0, 0.1]),
               (-0.02, 0.03))},
        np.array([[2000.0, 7.0], [4000.0, 70.0]]), 2, 10_000.0, 0.12)
    return dataclasses.replace(m, **change)
