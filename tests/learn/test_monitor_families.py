"""scripts/monitor_families.py --out: each family saved as it ends and a rerun of the same
command resumes from it; a family made otherwise is run again; a folder holding files of
anything else is refused before any work. The lives are stubbed (the evaluation's rows,
made up): what is tested is the bookkeeping, not the monitor."""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd
import pytest

import swgmon.evaluation.evaluate as evaluate

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))
import monitor_families  # noqa: E402


@pytest.fixture
def lives(monkeypatch):
    """The families each run lived, in order; a family named in ``stop`` raises
    KeyboardInterrupt (a Ctrl-C while it runs), one in ``fail`` its exception."""
    state = {"lived": [], "trained": 0, "stop": set(), "fail": {}}

    def evaluate_gear(p, banks, g, model, cfg, dataset, nuisance, seeds):
        fam = nuisance.removeprefix("family:")
        if fam in state["stop"]:
            raise KeyboardInterrupt
        if fam in state["fail"]:
            raise state["fail"][fam]
        state["lived"].append(fam)
        key = {"dataset": dataset, "held_out_gear": g, "nuisance": nuisance,
               "detector": "monitor"}
        rows = [{**key, "seed": s, "fault": "eccentric_wg", "severity": 0.02,
                 "onset": "step", "detected": True, "time_to_detect_h": 0.1 * (s + 1),
                 "fault_after_1h": "eccentric_wg"} for s in seeds]
        fa = [{**key, "seed": s, "healthy_hours": 200.0, "gear_fault_alarms": 1,
               "unexplained_changes": 0, "advisories": 0,
               "temperature_sensor_h": float("nan")} for s in seeds]
        return rows, fa, []

    def trained(*args):
        state["trained"] += 1
        return {}, None
    monkeypatch.setattr(evaluate, "evaluate_gear", evaluate_gear)
    monkeypatch.setattr(monitor_families, "trained", trained)
    return state


ARGS = ["--families", "warm_up", "drift", "--n-seeds", "2"]


def test_a_stopped_run_resumes_from_its_finished_families(tmp_path, lives, capsys):
    out = tmp_path / "out"
    lives["stop"] = {"drift"}
    assert monitor_families.main([*ARGS, "--out", str(out)]) == 130
    assert "rerun the same command to resume" in capsys.readouterr().err
    assert lives["lived"] == ["warm_up"]
    assert list(pd.read_csv(out / "table.csv").family) == ["warm_up"]
    first = (out / "warm_up_results.csv").read_bytes()

    lives["stop"] = set()
    assert monitor_families.main([*ARGS, "--out", str(out)]) == 0
    assert lives["lived"] == ["warm_up", "drift"]  # warm_up read back, not lived again
    assert "warm_up: " in (text := capsys.readouterr().out) and "(resumed from" in text
    table = pd.read_csv(out / "table.csv")
    assert list(table.family) == ["warm_up", "drift"]
    assert list(table.gear_fault_alarms_per_1000h) == [5.0, 5.0]  # 2 alarms in 400 h
    assert table.wall_s.notna().all()  # the resumed family keeps its own wall time
    assert (out / "warm_up_results.csv").read_bytes() == first

    assert monitor_families.main([*ARGS, "--out", str(out)]) == 0
    assert lives["lived"] == ["warm_up", "drift"] and lives["trained"] == 2  # nothing to run

    walls = list(table.wall_s)
    assert monitor_families.main([*ARGS, "--read", str(out)]) == 0  # the parts' wall times
    assert list(pd.read_csv(out / "table.csv").wall_s) == walls


def test_a_family_made_otherwise_is_run_again(tmp_path, lives):
    out = str(tmp_path / "out")
    for change in ([], ["--study", "nuisance_hours=100"], ["--n-seeds", "1"]):
        assert monitor_families.main([*ARGS, "--out", out, *change]) == 0  # each run anew
    assert lives["lived"] == ["warm_up", "drift"] * 3


def test_a_folder_with_files_of_anything_else_is_refused_before_work(tmp_path, lives,
                                                                    capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "warm_up_results.csv").write_text("mine\n")
    assert monitor_families.main([*ARGS, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "warm_up_results.csv" in err and "--out" in err
    assert (out / "warm_up_results.csv").read_text() == "mine\n"
    assert lives["lived"] == [] and lives["trained"] == 0


@pytest.mark.parametrize("argv, words", [
    (["--dataset", "nope"], "--dataset nope: Could not find 'dataset/nope'; available: "),
    (["--train-from", "nope"], "--train-from nope: Could not find 'dataset/nope'"),
    (["--families"], "--families: give one or more of "),
    (["--study", "faults=3"], "monitor.study.faults: must be a list, got 3"),
    (["--study", "families=3"], "monitor.study.families: must be a mapping, got 3"),
    # cause 2: the top of nuisance_hours' range allocated 1.56 GiB and failed after training
    (["--study", "nuisance_hours=1e6"], "monitor.study.nuisance_hours=1e+06 h at "
                                        "interval_min=1 min is 6e+07 windows a life; allowed: "
                                        "at most 5e+06"),
    # every hours option that makes a life, by the same window bound (fault_life_h=1e5: a
    # MemoryError at 7.4 GB after 36 s of training; the others by the same path)
    (["--study", "fault_life_h=100000"], "monitor.study.fault_life_h=100000 h at interval_min=1 "
                                      "min is 6.01e+06 windows a life; allowed: at most "
                                      "5e+06 (up to 8.32e+04 h)"),
    (["--study", "family_growth_h=1e5"], "monitor.study.family_growth_h=100000 h at "
                                         "interval_min=1 min is 6.01e+06 windows a life"),
    (["--study", "train_healthy_h=1e5"], "monitor.study.train_healthy_h=100000 h at "
                                         "interval_min=1 min is 6e+06 windows a life; "
                                         "allowed: at most 5e+06 (up to 8.33e+04 h)"),
    (["--study", "train_fault_h=1e5"], "monitor.study.train_fault_h=100000 h at "
                                       "interval_min=1 min is 6e+06 windows a life"),
])
def test_bad_input_is_one_line_before_any_work(argv, words, lives, capsys):
    """Issue 82, cause 8: every bad input reaches the apps' one-line path (before, a
    bad preset, an empty --families and a wrongly typed --study value were tracebacks),
    before any training or life."""
    assert monitor_families.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("monitor_families: error: ") and words in err, err
    assert "\n" not in err and "Traceback" not in err
    assert lives["trained"] == 0 and lives["lived"] == []


def test_a_refusal_while_running_is_one_line_and_a_bug_its_traceback(lives, capsys):
    """Issue 82: the run caught only KeyboardInterrupt, so a refusal raised while a family
    ran was a traceback; it ends in one line (exit 2), a bug still raises."""
    lives["fail"] = {"drift": ValueError("monitor.x must lie in [0, 1], got 2\nmore")}
    assert monitor_families.main(ARGS) == 2
    err = capsys.readouterr().err.strip()
    assert err == "monitor_families: error: monitor.x must lie in [0, 1], got 2", err
    assert lives["lived"] == ["warm_up"]
    lives["fail"] = {"drift": RuntimeError("a bug")}
    with pytest.raises(RuntimeError, match="a bug"):
        monitor_families.main(ARGS)
