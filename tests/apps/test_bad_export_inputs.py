"""The export: its options refused in one line (exit 2) before any work, and a cross
compiler or emulator that fails reported as the target 'not measured (why)', in size.json
and the summary, with every file written still listed in the folder's stamp."""

from __future__ import annotations

import json
import os
import types

import numpy as np
import pytest
from bad_input import app_line

from swgsim.files import ownership

OPTION_CASES = {  # case -> (overrides, the key the line must name)
    "export held_out_gear=9": (["export.held_out_gear=9"], "export.held_out_gear"),
    "export n_trees=0": (["export.n_trees=0"], "export.n_trees"),
    "export forest_bytes=1": (["export.forest_bytes=1"], "export.forest_bytes"),
    "export an unknown fault": (["export.faults=[bogus]"], "export.faults"),
    "export train_variants=0": (["export.train_variants=0"], "export.train_variants"),
    "export commissioning_h=-1": (["export.commissioning_h=-1"], "export.commissioning_h"),
    "export an unknown key": (["export.bogus=1"], "export.bogus: unknown key"),
}


@pytest.mark.parametrize("case", OPTION_CASES)
def test_a_bad_export_option_is_one_line(tmp_path, case):
    over, key = OPTION_CASES[case]
    base = ["dataset=tiny_bench", "cross=false"]
    line = app_line("export", [*base, f"out_dir={tmp_path}/out", *over], tmp_path)
    assert line.startswith("swgsim-export: error: ") and key in line, line
    assert not (tmp_path / "out").exists()


def test_a_failing_cross_tool_is_reported_not_measured(tmp_path, monkeypatch):
    """The Cortex-M4F figures when the cross compiler fails: 'not measured (why)' in the
    target and in size.json; swgsim-export ends with exit 2 and one line."""
    from swgmon.export import pipeline, target

    fake = tmp_path / "bin"
    fake.mkdir()
    for tool in (target.CROSS, target.QEMU):
        (fake / tool).write_text(f"#!/bin/sh\necho '{tool}: fatal error: no crt0.o' >&2\n"
                                 "exit 1\n")
        (fake / tool).chmod(0o755)
    monkeypatch.setenv("PATH", f"{fake}:{os.environ['PATH']}")
    held = types.SimpleNamespace(signals=np.zeros((1, 5, 8), np.float32), op=np.zeros(1, int),
                                 efficiency=np.ones(1), feats=np.zeros((1, 3), np.float32))
    tables = types.SimpleNamespace(points=np.array([[2000.0, 7.0]]), fs_hz=1e4, n_t=8)
    t = pipeline.target_figures(tmp_path, tables, held, None, cross=True)
    assert t == {"measured": False, "failed": t["why"],
                 "why": f"{target.CROSS} failed (exit 1): {target.CROSS}: fatal error: no "
                        "crt0.o"}
    rec = pipeline.size_record({"target": t, "host_c": {"accuracy_c": 0.9},
                                "accuracy_python": 0.9, "windows": {"held_out": 1},
                                "dataset": "d", "held_out_gear": 3})
    assert rec["flash_bytes"] is None and rec["target"] == f"not measured ({t['why']})"
    from swgcli import export as app

    summary = {"size": rec, "host_c": {"accuracy_c": 0.9, "host_c": "checked"},
               "held_out_gear": 3, "accuracy_python": 0.9, "target": t,
               "files": [str(tmp_path / "swg_monitor.c")], "failed": [t["why"]]}
    monkeypatch.setattr(app, "run_export_app", lambda cfg: summary)
    line = app_line("export", ["dataset=tiny_bench", f"out_dir={tmp_path}/x"], tmp_path)
    assert line.startswith(f"swgsim-export: error: {t['why']}; the C files, size.json")


@pytest.mark.slow  # a real export of the tiny bench grid: about 25 s
def test_a_failing_cross_tool_leaves_every_file_listed(tmp_path, monkeypatch):
    from swgcli import compose_app
    from swgcli.export import run_export_app
    from swgmon.export import target

    fake = tmp_path / "bin"
    fake.mkdir()
    for tool in (target.CROSS, target.QEMU):
        (fake / tool).write_text(f"#!/bin/sh\necho '{tool}: fatal error' >&2\nexit 1\n")
        (fake / tool).chmod(0o755)
    monkeypatch.setenv("PATH", f"{fake}:{os.environ['PATH']}")
    out = tmp_path / "export"
    s = run_export_app(compose_app("export", [
        "dataset=tiny_bench", f"out_dir={out}", "export.commissioning_h=1.0",
        "export.train_healthy_h=0.5", "export.train_fault_h=0.1", "export.train_variants=1",
        "export.faults=[eccentric_wg]", "export.n_trees=2", "export.forest_bytes=500",
        "export.full_model=false"]))
    why = f"{target.CROSS} failed (exit 1): {target.CROSS}: fatal error"
    assert s["failed"] == [why] and s["target"]["why"] == why
    size = json.loads((out / "size.json").read_text())
    assert size["target"] == f"not measured ({why})" and size["flash_bytes"] is None
    assert json.loads((out / "summary.json").read_text())["failed"] == [why]
    found = ownership.survey(out)  # every file written is listed in the stamp
    assert found.foreign == [] and found.stale == [] and {"size.json", "summary.json",
                                                          "swg_monitor.c"} <= set(found.owned)
    assert {w.app for w in found.writers.values()} == {"swgsim-export"}
