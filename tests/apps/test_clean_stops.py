"""SIGTERM and Ctrl-C end every app cleanly (swgcli.app.run, the one place for all apps):
exit 143 / 130, one line naming what was finished and kept and how a rerun resumes, no
traceback from worker pools, no worker left behind (the generator's when only it is
signalled, the evaluation's when its whole group is); a second signal during the cleanup
is ignored; the resumed monitor evaluation reuses only the parts its stamp and key prove,
and runs as a job array whose last run builds the report.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from bad_input import process_group

from swgcli import app as swgapp
from swgsim.files import ownership

ROOT = Path(__file__).resolve().parents[2]
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "HYDRA_FULL_ERROR": "0"}

#: A tiny monitor evaluation: tiny_bench, one fault, short lives (a part takes 10-30 s).
TINY_MONITOR = [
    "experiment=monitor", "~logger", "monitor.run_on=[tiny_bench]",
    "+dataset@monitor.datasets.tiny_bench=tiny_bench", "monitor.n_jobs=2",
    "monitor.progress=false", "monitor.study.seeds=[0]", "monitor.study.healthy_hours=3.0",
    "monitor.study.commissioning_h=2.0", "monitor.study.fault_life_h=1.0",
    "monitor.study.onset_window_h=[0.5,1.0]", "monitor.study.growth_h=0.5",
    "monitor.study.train_fault_h=0.25", "monitor.study.train_healthy_h=1.0",
    "monitor.study.train_variants=1", "monitor.study.faults=[eccentric_wg]",
    "monitor.study.detector_hours=1.0", "monitor.study.detectors=[]"]


def _evaluation(out: Path, gears: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "swgcli.train", *TINY_MONITOR, f"monitor.study.gears={gears}",
         f"monitor.report_dir={out}", f"hydra.run.dir={out.parent / 'hydra'}"],
        cwd=out.parent, env=ENV, start_new_session=True, stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL, text=True,
        # as from a terminal: SIGINT not ignored (a background runner passes it ignored)
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _group_gone(pgid: int, wait_s: float = 5.0) -> bool:
    """Whether the process group ``pgid`` is empty within ``wait_s`` (loky's resource
    tracker leaves once its pipe closes)."""
    deadline = time.time() + wait_s
    while process_group(pgid) and time.time() < deadline:
        time.sleep(0.1)
    return process_group(pgid) == []


def _lines(text: str) -> list[str]:
    return [s for s in text.splitlines() if s.strip()]


@pytest.mark.parametrize("sig, code, word", [(signal.SIGTERM, 143, "terminated (SIGTERM)"),
                                             (signal.SIGINT, 130, "interrupted (SIGINT)")])
def test_a_running_evaluation_stops_in_one_line_with_its_workers(tmp_path, sig, code, word):
    """The signal to the whole process group, as `timeout` and a terminal's Ctrl-C send
    it: the workers get it too."""
    out = tmp_path / "meval"
    p = _evaluation(out, "[2,3]")
    deadline = time.time() + 120
    while len(process_group(p.pid)) < 3 and time.time() < deadline:  # parent + 2 workers
        time.sleep(0.2)
    assert len(process_group(p.pid)) >= 3, "the evaluation's workers never started"
    time.sleep(1.0)
    os.killpg(p.pid, sig)
    err = p.communicate(timeout=60)[1]
    assert p.returncode == code, err
    lines = _lines(err)
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"swgsim-train: {word}; {out}: ")
    assert "rerun the same command to resume" in lines[0]
    assert _group_gone(p.pid)  # no worker left behind
    assert not list(out.rglob("*.tmp"))


@pytest.mark.parametrize("sig, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_stopping_the_generator_stops_its_workers(tmp_path, sig, code):
    out = tmp_path / "ds"
    # 12 speeds (2000-4200 rpm): 36 shards, minutes of work, so that the signal always meets running
    # workers, even on a loaded machine (the paper grid alone can finish before it)
    speeds = ",".join(str(2000.0 + 200.0 * k) for k in range(12))
    p = subprocess.Popen([str(Path(sys.executable).parent / "swgsim-generate"), "dataset=paper",
                          f"out_dir={out}", f"dataset.operating_points.n_in_rpm=[{speeds}]",
                          "n_jobs=2", "progress=false"], start_new_session=True,
                         stderr=subprocess.PIPE, text=True,
                         # as from a terminal: a runner started in the background (no job
                         # control) passes SIGINT on as ignored, and Python keeps it so
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.time() + 180
    while len(process_group(p.pid)) < 3 and time.time() < deadline:  # parent + 2 workers
        time.sleep(0.2)
    assert len(process_group(p.pid)) >= 3, "the generator's workers never started"
    time.sleep(1.0)
    os.kill(p.pid, sig)
    assert p.wait(timeout=30) == code, p.stderr.read()
    time.sleep(0.5)
    assert process_group(p.pid) == []  # no worker goes on writing
    assert not list(out.glob("*.tmp"))


def _stopped(call, capsys) -> tuple[int, str]:
    with pytest.raises(SystemExit) as info:
        swgapp.run(call, "swgsim-x")
    return info.value.code, capsys.readouterr().err


def test_stop_names_what_was_kept_and_ignores_a_second_signal(tmp_path, capsys):
    folder = tmp_path / "ds"

    def entry():
        with ownership.claim(folder, "swgsim-generate"):
            ownership.atomic_write_bytes(folder / "gear1_n2000rpm.nc", b"a shard")
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(1)  # the handler raises here

    code, err = _stopped(entry, capsys)
    assert code == 143 and _lines(err) == [
        f"swgsim-x: terminated (SIGTERM); {folder}: 1 finished shard(s) of the data set "
        "kept (gear1_n2000rpm.nc); rerun the same command to resume: it reuses each shard "
        "whose SHA-256 its sidecar and the ownership stamp prove complete, and simulates "
        "the rest"]

    def pool_error():  # a worker pool that notices its workers died before the main does
        swgapp._STOPPING.append(signal.SIGINT)
        os.kill(os.getpid(), signal.SIGINT)  # a second signal: ignored, the cleanup goes on
        raise RuntimeError("A worker process managed by the executor was unexpectedly "
                           "terminated")

    code, err = _stopped(pool_error, capsys)
    assert code == 130 and _lines(err) == [
        "swgsim-x: interrupted (SIGINT); nothing was written into an output folder yet; "
        "rerun the same command to start again"]


def test_a_stop_between_two_folders_names_the_one_finished(tmp_path, capsys):
    """Issue 87: a study stopped after its data set was written said nothing had been
    written into an output folder."""
    first, second = tmp_path / "data", tmp_path / "report"

    def entry():
        with ownership.claim(first, "swgsim-generate"):
            ownership.atomic_write_bytes(first / "gear1_n2000rpm.nc", b"a shard")
        os.kill(os.getpid(), signal.SIGTERM)  # SIGINT is a pytest-xdist worker's own
        time.sleep(1)  # the handler raises here, before the report's folder is claimed
        ownership.claim(second, "swgsim-paper")

    code, err = _stopped(entry, capsys)
    assert code == 143 and _lines(err) == [
        f"swgsim-x: terminated (SIGTERM); finished before the stop and kept: {first}; "
        "rerun the same command to go on"]


@pytest.mark.slow  # three parts of a tiny evaluation, stopped and resumed: about 90 s
def test_resumed_evaluation_reuses_only_the_parts_proved_complete(tmp_path):
    out = tmp_path / "meval"
    p = _evaluation(out, "[1,2,3]")
    deadline = time.time() + 300
    while not list((out / "parts").glob("*.json")) and time.time() < deadline:
        time.sleep(0.2)
    os.kill(p.pid, signal.SIGTERM)  # the main process only, as `kill <pid>` sends it
    err = p.communicate(timeout=60)[1]
    assert p.returncode == 143 and len(_lines(err)) == 1 and "Traceback" not in err, err
    kept = {f.name: (f.read_bytes(), f.stat().st_mtime_ns) for f in (out / "parts").glob("*")}
    assert kept and f"{len(kept)} finished part(s) of the monitor evaluation" in err
    assert _group_gone(p.pid)
    r = _evaluation(out, "[1,2,3]")
    err = r.communicate(timeout=400)[1]
    assert r.returncode == 0, err
    for name, (data, mtime) in kept.items():  # reused, not recomputed
        f = out / "parts" / name
        assert f.read_bytes() == data and f.stat().st_mtime_ns == mtime
    assert len(list((out / "parts").glob("*.json"))) == 3 and (out / "table.md").is_file()
    # a part edited since is not proved complete by the stamp: the rerun refuses, naming it
    part = sorted((out / "parts").glob("*.json"))[0]
    part.write_text(part.read_text().replace("{", "{ ", 1))
    r = _evaluation(out, "[1,2,3]")
    err = r.communicate(timeout=120)[1]
    assert r.returncode == 2 and f"parts/{part.name}" in err and len(_lines(err)) == 1


@pytest.mark.slow  # two tiny parts as submitit_local jobs, then the report: about 2 min
def test_an_evaluation_runs_as_a_job_array_and_a_last_run_builds_the_report(tmp_path):
    """A cluster's way (docs/scale_out.md): one submitit job per (data set, held-out gear)
    (``monitor.group``) into one report folder, then the same command without
    ``monitor.group`` finds every part done and builds the report, recomputing none."""
    out = tmp_path / "meval"
    cmd = [sys.executable, "-m", "swgcli.train", "-m", *TINY_MONITOR,
           "monitor.study.gears=[2,3]", "monitor.group=0,1", f"monitor.report_dir={out}",
           "hydra/launcher=submitit_local", "hydra.launcher.timeout_min=10",
           f"hydra.sweep.dir={tmp_path / 'sweep'}"]
    r = subprocess.run(cmd, cwd=tmp_path, env=ENV, capture_output=True, text=True,
                       timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    parts = {f.name: f.stat().st_mtime_ns for f in (out / "parts").glob("*.json")}
    assert sorted(parts) == ["tiny_bench_gear2.json", "tiny_bench_gear3.json"]
    assert not (out / "table.md").exists()
    r = _evaluation(out, "[2,3]")
    err = r.communicate(timeout=400)[1]
    assert r.returncode == 0, err
    assert {f.name: f.stat().st_mtime_ns for f in (out / "parts").glob("*.json")} == parts
    assert (out / "table.md").is_file()
    res = (out / "results.csv").read_text()
    assert ",2," in res and ",3," in res


def test_a_group_beyond_the_evaluations_pairs_is_refused_before_any_work(tmp_path):
    from swgcli import compose_app
    from swgcli.tasks import run_train

    out = tmp_path / "meval"
    cfg = compose_app("train", [*TINY_MONITOR, "monitor.study.gears=[2,3]",
                                "monitor.group=2", f"monitor.report_dir={out}"])
    with pytest.raises(ValueError, match=r"monitor.group must lie in \[0, 1\] \(0: "
                                         r"tiny_bench gear 2, 1: tiny_bench gear 3\), got 2"):
        run_train(cfg)
    assert not out.exists()
