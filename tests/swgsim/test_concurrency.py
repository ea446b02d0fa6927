"""Concurrency: a lock per output folder and per tracking store, so that no finished work is
lost to a second run started meanwhile.

* Two processes opening a fresh SQLite MLflow store at the same moment both log their run:
  MLflow creates the schema under the store's lock (``learn.tracking.store.tracking_client``).
* A folder claimed by a run (:func:`swgsim.files.ownership.claim`) is refused to a second run of
  another process in one line naming the folder and the run, before anything is touched;
  a worker joining the run is not; once the run is over, its lock files are proved ours
  (listed in the stamp), so a rerun into the folder works.

The processes are forked (nothing to import again), and started behind a barrier.
"""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import sys
import traceback
from pathlib import Path

import pytest

from swgcli.app import one_line
from swgsim.datasets import schema as dsio
from swgsim.files import atomic, ownership

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="forked processes")
FORK = mp.get_context("fork")
TIMEOUT_S = 120


def _log_one_run(uri: str, name: str, barrier, results) -> None:
    """Child: wait for the other, then log one run to ``uri``; report ``ok`` or the error."""
    from learn.tracking import log_run

    barrier.wait()
    try:
        with log_run("race", name, tracking_uri=uri) as run:
            run.log_metrics({"x": 1.0})
        results.put((name, "ok"))
    except BaseException:  # noqa: BLE001 - reported to the parent
        results.put((name, traceback.format_exc().strip().splitlines()[-1]))


def test_two_processes_start_on_a_fresh_store_and_both_runs_are_kept(tmp_path):
    import mlflow  # imported once, before the fork

    uri = f"sqlite:///{tmp_path / 'mlflow.db'}"
    barrier, results = FORK.Barrier(2), FORK.Queue()
    procs = [FORK.Process(target=_log_one_run, args=(uri, f"run{i}", barrier, results))
             for i in range(2)]
    for p in procs:
        p.start()
    got = dict(results.get(timeout=TIMEOUT_S) for _ in procs)
    for p in procs:
        p.join(TIMEOUT_S)
    assert got == {"run0": "ok", "run1": "ok"}
    client = mlflow.MlflowClient(uri)
    exp = client.get_experiment_by_name("race")
    runs = client.search_runs([exp.experiment_id])
    assert sorted(r.info.run_name for r in runs) == ["run0", "run1"]
    assert all(r.info.status == "FINISHED" and r.data.metrics == {"x": 1.0} for r in runs)


def _hold_claim(folder: str, ready, done, results) -> None:
    """Child: claim ``folder``, write a file into it, hold the claim until ``done``."""
    try:
        with ownership.claim(folder, "swgsim-generate"):
            dsio.atomic_write_bytes(Path(folder) / "result.txt", b"finished work\n")
            ready.set()
            done.wait(TIMEOUT_S)
        results.put("ok")
    except BaseException:  # noqa: BLE001 - reported to the parent
        ready.set()
        results.put(traceback.format_exc())


def _files(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def _refusal(call) -> str:
    with pytest.raises(ValueError) as info:
        call()
    msg = one_line(info.value)
    assert msg is not None and "\n" not in msg
    return msg


def test_second_run_is_refused_worker_joins_rerun_works(tmp_path):
    folder = tmp_path / "out"
    ready, done, results = FORK.Event(), FORK.Event(), FORK.Queue()
    first = FORK.Process(target=_hold_claim, args=(str(folder), ready, done, results))
    first.start()
    try:
        assert ready.wait(TIMEOUT_S)
        before = _files(folder)
        assert before["result.txt"] == b"finished work\n"
        holder = f"{atomic.temp_host()}-{first.pid}, swgsim-generate"
        # (b) another run: refused in one line naming the folder and the run, by check()
        # before any work and by claim(); nothing of the first run's is touched
        for call in (lambda: ownership.check(folder, "out_dir"),
                     lambda: ownership.claim(folder, "swgsim-calibrate", "out_dir")):
            msg = _refusal(call)
            assert msg.startswith(f"out_dir={folder}: another run ({holder}) is writing")
            assert "wait for it to finish or choose another out_dir" in msg
        assert _files(folder) == before
        # (d) a worker of the run joins it while the run lock is held: no deadlock
        with ownership.join(folder, "worker"):
            dsio.atomic_write_bytes(folder / "part.txt", b"worker's part\n")
        assert "part.txt" in ownership.survey(folder).owned
    finally:
        done.set()
        first.join(TIMEOUT_S)
    assert results.get(timeout=TIMEOUT_S) == "ok" and first.exitcode == 0
    # (c) the run is over: its lock files are ours (listed in the stamp), so a rerun works
    assert (folder / ownership.LOCK).is_file() and (folder / ownership.STAMP_LOCK).is_file()
    found = ownership.check(folder, "out_dir")
    assert found.foreign == [] and sorted(found.owned) == ["part.txt", "result.txt"]
    with ownership.claim(folder, "swgsim-calibrate") as claim:
        assert claim.remove(found.owned) == 2  # the lock files are never removed
    assert sorted(os.listdir(folder)) == sorted(
        [ownership.STAMP, ownership.LOCK, ownership.STAMP_LOCK])
    assert ownership.check(folder, "out_dir").foreign == []


def test_lock_file_of_another_tool_is_foreign_and_never_opened(tmp_path):
    folder = tmp_path / "out"
    with ownership.claim(folder, "swgsim-generate"):
        pass
    (folder / ownership.LOCK).write_bytes(b"not ours\n")  # same name, other content
    msg = _refusal(lambda: ownership.claim(folder, "swgsim-generate"))
    assert ownership.LOCK in msg and str(folder) in msg
    assert (folder / ownership.LOCK).read_bytes() == b"not ours\n"
    shared = tmp_path / "shared"  # a shared folder looks at its lock files too
    shared.mkdir()
    (shared / ownership.LOCK).write_bytes(b"")
    msg = _refusal(lambda: ownership.check(shared, "report_root", only=["summary.md"]))
    assert ownership.LOCK in msg


def test_a_claim_held_by_this_process_can_be_claimed_again(tmp_path):
    folder = tmp_path / "out"
    slot = f".swg-owner.{atomic.temp_host()}-{os.getpid()}.lock"
    with ownership.claim(folder, "a"):
        with ownership.claim(folder, "b"):
            ownership.check(folder)
        ownership.check(folder)  # still held by this process: no refusal
        assert (folder / slot).is_file()
    assert not (folder / slot).exists()  # let go at the last close
    assert json.loads((folder / ownership.STAMP).read_text())["holders"] == {}


def _claim_and_wait(folder: str, share, go, results) -> None:
    """Child: claim ``folder`` with ``share``, report, hold it until ``go``."""
    try:
        with ownership.claim(folder, "swgsim-generate", share=share):
            results.put("ok")
            go.wait(TIMEOUT_S)
    except ValueError as e:
        results.put(str(e))


def test_runs_sharing_a_folder_write_together_others_are_refused(tmp_path):
    folder = tmp_path / "out"
    go, results = FORK.Event(), FORK.Queue()
    procs = [FORK.Process(target=_claim_and_wait, args=(str(folder), "cfg1", go, results))
             for _ in range(2)]
    for p in procs:
        p.start()
    try:
        assert [results.get(timeout=TIMEOUT_S) for _ in procs] == ["ok", "ok"]
        ownership.check(folder, "out_dir", share="cfg1")
        for share in (None, "cfg2"):
            msg = _refusal(lambda s=share: ownership.claim(folder, "swgsim-generate", share=s))
            assert msg.startswith(f"out_dir={folder}: another run (")
    finally:
        go.set()
        for p in procs:
            p.join(TIMEOUT_S)
    with ownership.claim(folder, "swgsim-generate", share="cfg2"):
        assert sorted(json.loads((folder / ownership.STAMP).read_text())["holders"]) == [
            f"{atomic.temp_host()}-{os.getpid()}"]


def test_a_killed_run_leaves_a_free_lock_that_the_next_run_removes(tmp_path):
    folder = tmp_path / "out"
    ready, done, results = FORK.Event(), FORK.Event(), FORK.Queue()
    first = FORK.Process(target=_hold_claim, args=(str(folder), ready, done, results))
    first.start()
    assert ready.wait(TIMEOUT_S)
    first.kill()
    first.join(TIMEOUT_S)
    slot = folder / f".swg-owner.{atomic.temp_host()}-{first.pid}.lock"
    assert slot.is_file() and ownership.check(folder).foreign == []
    with ownership.claim(folder, "swgsim-calibrate"):
        assert not slot.exists()
    assert ownership.check(folder).foreign == []
