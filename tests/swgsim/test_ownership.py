"""Ownership, not names: a run deletes or overwrites only what it can prove it wrote.

A file is this project's only if an ownership stamp (``.swg-owner.json``, signed
``"writer": "swg-monitor"``) lists it with the SHA-256 it has now, or, for a temporary
file, names the run that left it (:mod:`swgsim.files.ownership`). Everything else, whatever its
name, is left byte-identical and the run refuses in one line naming it: the data-set
writer (with and without ``overwrite``) and every app that writes reports, whose Hydra
files never land in the user's folder.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from bad_input import fail_second_shard, run_app

from swgcli import compose_app, dataset_preset
from swgcli.app import one_line
from swgsim.datasets import generate as gen
from swgsim.datasets import schema as dsio
from swgsim.files import atomic, ownership

BIN = Path(sys.executable).parent
SHARD = "gear1_n4000rpm.nc"


def small_cfg(seed: int = 0) -> dict:
    """Two gears, two classes, one load: a data set in about a second."""
    cfg = dataset_preset("tiny")
    cfg["variants"] = {"healthy": {"severities": [0.0], "repeat": 2},
                       "eccentric_wg": {"severities": [0.1], "n_positions": 1}}
    cfg["gears"] = cfg["gears"][:2]
    cfg["operating_points"]["t_out_nm"] = [39.0]
    cfg["chain"].update({"window_s": 0.06, "settle_s": 0.02})
    cfg["seed"] = seed
    return cfg


def files(folder: Path) -> dict[str, bytes]:
    """Every file below ``folder`` (hidden ones included) and its bytes."""
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def refusal(call) -> str:
    """The one-line message ``call`` is refused with."""
    with pytest.raises(ValueError) as info:
        call()
    msg = one_line(info.value)
    assert msg is not None and "\n" not in msg
    return msg


def dead_pid() -> int:
    return int(subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                              capture_output=True, text=True, check=True).stdout)


def killed_run_temp(folder: Path, target: str) -> Path:
    """A temporary file left by a run of ours that was killed: the run joined the
    folder's stamp, started writing ``target`` and died."""
    code = ("import os, sys; from pathlib import Path; from swgsim.files import atomic, ownership; "
            "f = Path(sys.argv[1]); ownership.join(f.parent); "
            "(f.parent / (atomic.temp_prefix(f) + 'k.tmp')).write_bytes(b'half'); os._exit(0)")
    before = set(folder.glob("*.tmp"))
    subprocess.run([sys.executable, "-c", code, str(folder / target)], check=True)
    (tmp,) = set(folder.glob("*.tmp")) - before
    return tmp


@pytest.fixture(scope="module")
def ours(tmp_path_factory) -> Path:
    """A finished data set of ours (stamped)."""
    out = tmp_path_factory.mktemp("own") / "ds"
    gen.generate(small_cfg(), out, n_jobs=1, progress=False)
    return out


# ------------------------------------------------------------------ swgsim-generate
def _foreign_temp(folder: Path) -> None:
    name = atomic.temp_prefix(folder / SHARD).replace(f"-{os.getpid()}.", f"-{dead_pid()}.")
    (folder / f"{name}x.tmp").write_bytes(b"a user's file, named like our temp files")


def _our_config_hash() -> str:
    from swgsim.datasets.plan import plan

    return plan(small_cfg()).config_hash


def _forged_shard(folder: Path) -> None:
    (folder / SHARD).write_bytes(b"\x89HDF\r\n\x1a\n a user's NetCDF")
    (folder / SHARD).with_suffix(".json").write_text(json.dumps(
        {"sha256": dsio.sha256_file(folder / SHARD), "n_samples": 1, "content_sha256": "0",
         "config_hash": _our_config_hash()}))


FOREIGN = {
    "another tool's manifest.json": (
        "manifest.json", lambda f: (f / "manifest.json").write_text(
            '{"tool": "labview-export", "files": ["run1.tdms"]}')),
    "a .config.json with our very config hash": (
        ".config.json", lambda f: (f / ".config.json").write_text(json.dumps(
            {"config_hash": _our_config_hash()}))),
    "a NetCDF named like our shard": (
        SHARD, lambda f: (f / SHARD).write_bytes(b"\x89HDF\r\n\x1a\n a user's NetCDF")),
    "a NetCDF and sidecar forged to look finished": ("gear1_n4000rpm.json", _forged_shard),
    "a temp-named file of a dead process": (".gear1_n4000rpm.nc.", _foreign_temp),
    "another tool's .swg-owner.json": (
        ownership.STAMP, lambda f: (f / ownership.STAMP).write_text('{"owner": "me"}')),
}


@pytest.mark.parametrize("overwrite", [False, True])
@pytest.mark.parametrize("case", sorted(FOREIGN))
def test_generate_refuses_a_folder_of_a_users_file_named_like_ours(tmp_path, case, overwrite):
    name, make = FOREIGN[case]
    folder = tmp_path / "mine"
    folder.mkdir()
    make(folder)
    before = files(folder)
    msg = refusal(lambda: gen.generate(small_cfg(), folder, progress=False,
                                       overwrite=overwrite))
    assert f"out_dir {folder} holds {name}" in msg and "nothing was touched" in msg
    assert files(folder) == before  # byte-identical, and nothing added (no stamp either)


def test_stale_temp_cleanup_leaves_a_foreign_temp_looking_file(ours, tmp_path):
    folder = tmp_path / "unfinished"
    shutil.copytree(ours, folder)
    (folder / dsio.MANIFEST).unlink()  # an unfinished data set of ours
    mine = killed_run_temp(folder, SHARD)  # ours: its run is named in the stamp
    _foreign_temp(folder)  # a dead pid too, but no stamp names it
    (foreign,) = set(folder.glob("*.tmp")) - {mine}
    before = files(folder)
    msg = refusal(lambda: gen.generate(small_cfg(), folder, progress=False, overwrite=True))
    assert foreign.name in msg
    assert files(folder) == before  # the check comes first: not even our temp went
    foreign.unlink()
    s = gen.generate(small_cfg(), folder, progress=False)
    assert s["complete"] and not mine.exists() and not list(folder.glob("*.tmp"))


def test_a_worker_killed_while_it_joined_leaves_a_stamp_copy_that_is_removed(ours, tmp_path):
    """A worker killed between writing the stamp that lists it and renaming it into place
    (clean stops, issue 85's CI run) leaves a temporary copy of the stamp whose run the
    stamp on disk does not list: the copy's own content names it, so it is ours and goes
    once that process is gone; a copy that does not list its writer stays foreign."""
    folder = tmp_path / "joined"
    shutil.copytree(ours, folder)
    stamp = json.loads((folder / ownership.STAMP).read_text())
    dead = dead_pid()
    run = f"{atomic.temp_host()}-{dead}"
    name = atomic.temp_prefix(folder / ownership.STAMP).replace(f"-{os.getpid()}.",
                                                                f"-{dead}.")
    copy = folder / f"{name}j.tmp"
    copy.write_text(json.dumps({**stamp, "runs": [*stamp["runs"], run]}))
    other = folder / f"{name}o.tmp"
    other.write_text(json.dumps(stamp))  # named like a stamp copy, not listing its writer
    s = ownership.survey(folder)
    assert copy in s.stale and other.name in s.foreign


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="no /proc to read")
def test_a_process_that_exited_and_waits_to_be_collected_does_not_run():
    """A zombie (exited, its parent has not waited for it) is not alive: a worker killed
    while its pool shuts down is one, and its temporary files are stale, not live."""
    import time

    child = subprocess.Popen([sys.executable, "-c", "pass"])
    try:
        deadline = time.monotonic() + 30.0
        stat = Path(f"/proc/{child.pid}/stat")
        while stat.read_text().rsplit(")", 1)[1].split()[0] != "Z":
            assert time.monotonic() < deadline, "the child did not exit within 30 s"
            time.sleep(0.01)
        assert not atomic.pid_alive(child.pid)  # exited, not yet collected
    finally:
        child.wait()
    assert atomic.pid_alive(os.getpid())


def test_an_edited_file_of_ours_is_no_longer_ours(ours, tmp_path):
    folder = tmp_path / "edited"
    shutil.copytree(ours, folder)
    with (folder / "gear2_n4000rpm.json").open("a") as f:
        f.write("\n")  # the user annotated our sidecar
    before = files(folder)
    msg = refusal(lambda: gen.generate(small_cfg(seed=5), folder, progress=False,
                                       overwrite=True))
    assert "gear2_n4000rpm.json" in msg and files(folder) == before


def test_rerun_into_our_own_folders(ours, tmp_path, monkeypatch):
    """overwrite=true replaces our own finished data set; an interrupted run resumes,
    bit-identical; a finished one of this config is used as it is."""
    folder = tmp_path / "ds"
    shutil.copytree(ours, folder)
    s = gen.generate(small_cfg(seed=5), folder, progress=False, overwrite=True)
    assert s["complete"] and s["replaced"].startswith("replaced the data set")
    stamp = json.loads((folder / ownership.STAMP).read_text())
    assert stamp["writer"] == ownership.SIGNATURE
    assert set(stamp["files"]) == {p.name for p in folder.iterdir()} - {ownership.STAMP}
    real = gen.run_shard
    fail_second_shard(monkeypatch, gen)
    with pytest.raises(RuntimeError):
        gen.generate(small_cfg(), folder, progress=False, overwrite=True)
    monkeypatch.setattr(gen, "run_shard", real)
    s = gen.generate(small_cfg(), folder, progress=False)
    assert len(s["skipped"]) == 1 and s["content_sha256"] == json.loads(
        (ours / dsio.MANIFEST).read_text())["content_sha256"]
    for f in ours.glob("*.nc"):
        assert (folder / f.name).read_bytes() == f.read_bytes()
    before = files(folder)
    assert not gen.generate(small_cfg(), folder, progress=False)["computed"]
    assert files(folder) == before


# ------------------------------------------------------------------ report writers
USER_FILES = {"report.md": b"# my notes\n", "summary.json": b'{"mine": true}\n'}


def user_folder(path: Path, names=USER_FILES) -> Path:
    path.mkdir(parents=True)
    for name, data in names.items():
        (path / name).write_bytes(data)
    return path


def _friction_csv(path: Path) -> Path:
    t = np.arange(2000) * 0.002
    rows = "\n".join(f"{a},{np.sin(a)},{np.cos(a)},{0.1 * np.tanh(20 * np.cos(a))}"
                     for a in t)
    path.write_text("time_s,q_rad,dq_rad_per_s,tau_friction_Nm\n" + rows + "\n")
    return path


@pytest.mark.parametrize("app, args, key", [
    ("swgsim-calibrate", ["measured={csv}", "out_dir={out}", "~logger"],
     "out_dir"),
    ("swgsim-monitor", ["stream={out}/../life", "diagnosis_model={out}/../m.joblib",
                        "out_dir={out}", "~logger"], "out_dir"),
    ("swgsim-paper", ["grid=tiny", "data_root={out}/../data", "report_root={out}",
                      "tracking_uri=sqlite:///{out}/../m.db"], "report_root"),
])
def test_report_apps_refuse_a_users_folder_and_leave_no_hydra_files(tmp_path, app, args, key,
                                                                     monkeypatch, capsys):
    # the console's entry point in this process, as its command line runs it (run_app)
    names = ({"summary.md": b"# my summary\n", "summary.csv": b"mine\n"}
             if app == "swgsim-paper" else USER_FILES)
    out = user_folder(tmp_path / "mine", names)
    csv = _friction_csv(tmp_path / "rec.csv")
    monkeypatch.setenv("HYDRA_FULL_ERROR", "0")
    code, err = run_app(app, [a.format(out=out, csv=csv) for a in args], tmp_path,
                        monkeypatch, capsys)
    assert code == 2, err
    lines = [s for s in err.splitlines() if s.strip()]
    assert lines == [f"{app}: error: {key} {out} holds {sorted(names)[0]} and 1 more such "
                     "file(s), which this project cannot show it wrote (no ownership stamp "
                     f".swg-owner.json lists it with its SHA-256); nothing was touched: move "
                     f"it away or choose another {key}"]
    assert files(out) == names  # byte-identical; no .hydra/, no *.log, no stamp
    assert not (tmp_path / "data").exists()


def test_main_job_refuses_a_users_file_in_a_study_folder(tmp_path):
    from swgcli.paper import run_paper

    out = user_folder(tmp_path / "reports" / "bench", {"results.csv": b"mine\n"})
    cfg = compose_app("paper", ["grid=tiny", f"data_root={tmp_path}/data",
                                f"report_root={tmp_path}/reports",
                                f"tracking_uri=sqlite:///{tmp_path}/m.db"])
    msg = refusal(lambda: run_paper(cfg))
    assert f"{out} holds results.csv" in msg and files(out) == {"results.csv": b"mine\n"}
    assert not (tmp_path / "data").exists()  # before any work


def test_calibrate_rerun_replaces_its_own_files_only(tmp_path):
    from swgcli.calibrate import run_calibrate

    csv = _friction_csv(tmp_path / "rec.csv")
    out = tmp_path / "out"
    cfg = compose_app("calibrate", [f"measured={csv}", f"out_dir={out}",
                                    "~logger"])
    run_calibrate(cfg)
    stamp = json.loads((out / ownership.STAMP).read_text())
    assert {"report.md", "summary.json", "figures/time.png"} <= set(stamp["files"])
    run_calibrate(cfg)  # its own earlier output: replaced
    (out / "report.md").write_text("# my edits\n")  # ours no longer: the user's now
    before = files(out)
    msg = refusal(lambda: run_calibrate(cfg))
    assert f"out_dir {out} holds report.md" in msg and files(out) == before


@pytest.mark.parametrize("app, key", [("observability", "report_dir"),
                                      ("transfer", "transfer.report_dir"),
                                      ("monitor", "monitor.report_dir")])
def test_observability_and_transfer_refuse_before_any_work(tmp_path, app, key):
    out = user_folder(tmp_path / "mine", {"table.md": b"mine\n"})
    if app == "observability":
        from learn.observability.task import run_observability

        cfg = compose_app("observability", [f"report_dir={out}",
                                            f"data_root={tmp_path}/data"])
        call = lambda: run_observability(cfg)  # noqa: E731
    else:
        from swgcli.tasks import run_train

        cfg = compose_app("train", [f"experiment={app}", "~logger",
                                    f"{key}={out}", f"paths.data_dir={tmp_path}/data"])
        call = lambda: run_train(cfg)  # noqa: E731
    msg = refusal(call)
    assert msg.startswith(f"{key} {out} holds table.md") and files(out) == {"table.md": b"mine\n"}
    assert not (tmp_path / "data").exists()


def test_record_takes_paths_as_the_folder_was_given(tmp_path, monkeypatch):
    """A run that claims a folder by a relative path records the files it writes there by
    paths relative to the current directory (the monitor task's report_dir): a rerun may
    then replace them. Found when a finished ``experiment=monitor`` could not be rerun:
    its tables were missing from the stamp."""
    monkeypatch.chdir(tmp_path)
    out = Path("reports") / "monitor"
    with ownership.claim(out, "monitor", "monitor.report_dir") as c:
        (out / "results.csv").write_text("a,b\n")
        c.record([out / "results.csv"])
        Path("elsewhere.csv").write_text("x\n")
        with pytest.raises(ValueError):
            c.record([Path("elsewhere.csv")])
    assert "results.csv" in json.loads((out / ownership.STAMP).read_text())["files"]
    ownership.check(out, "monitor.report_dir")  # a rerun is allowed


def _half_then_fail(tmp):
    tmp.write_bytes(b"\x89PNG half a figure")  # a kill or a full disk in savefig
    raise OSError(28, "No space left on device")


@pytest.mark.parametrize("where", ["in the write", "between the stamp and the rename"])
def test_a_report_file_is_whole_and_stamped_or_not_there(tmp_path, monkeypatch, where):
    """Issue 43, cause 3: every report file goes through ownership.write_owned (temporary
    file, stamp, rename). A failure while it is written, or after it is stamped and
    before it is renamed, leaves the old file, still proved ours, and no temporary file;
    the same run again (a new claim) replaces it."""
    out = tmp_path / "report"
    with ownership.claim(out, "swgsim-monitor", strict=True):
        ownership.write_owned(out / "health.png", lambda tmp: tmp.write_bytes(b"old"))
    with ownership.claim(out, "swgsim-monitor", strict=True):
        if where == "in the write":
            with pytest.raises(atomic.DiskFullError, match=r"disk full while writing "):
                ownership.write_owned(out / "health.png", _half_then_fail)
        else:
            def killed(*a):
                raise KeyboardInterrupt
            monkeypatch.setattr(atomic.os, "replace", killed)
            with pytest.raises(KeyboardInterrupt):
                ownership.write_owned(out / "health.png", lambda tmp: tmp.write_bytes(b"new"))
            monkeypatch.undo()
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".swg-owner")) \
        == ["health.png"] and (out / "health.png").read_bytes() == b"old"
    found = ownership.check(out, app="swgsim-monitor")
    assert list(found.owned) == ["health.png"] and not found.foreign
    with ownership.claim(out, "swgsim-monitor", strict=True):  # the same command again
        ownership.write_owned(out / "health.png", lambda tmp: tmp.write_bytes(b"new"))
    assert (out / "health.png").read_bytes() == b"new"
    assert list(ownership.check(out, app="swgsim-monitor").owned) == ["health.png"]


def test_a_full_disk_when_the_stamp_is_first_written_leaves_no_stamp(tmp_path, monkeypatch):
    """Issue 82, cause 6: the stamp is created like every other file (a temporary file,
    then linked): a full disk at its first write is one line (DiskFullError, a
    ValueError) and leaves no stamp, not an empty one that made every rerun refuse the
    folder; the same command then claims it."""
    out = tmp_path / "report"
    out.mkdir()
    write_bytes = Path.write_bytes

    def full(self, data):
        if self.name.startswith("..swg-owner.json."):  # the stamp's temporary file
            write_bytes(self, data[:7])
            raise OSError(28, "No space left on device")
        return write_bytes(self, data)
    monkeypatch.setattr(Path, "write_bytes", full)
    with pytest.raises(atomic.DiskFullError, match=r"disk full while writing .*\.swg-owner"):
        ownership.claim(out, "swgsim-monitor", strict=True)
    monkeypatch.undo()
    assert sorted(p.name for p in out.iterdir()) == []
    with ownership.claim(out, "swgsim-monitor", strict=True):
        ownership.write_owned(out / "report.md", lambda tmp: tmp.write_bytes(b"whole"))
    assert list(ownership.check(out, app="swgsim-monitor").owned) == ["report.md"]


def test_a_fresh_claim_removes_what_the_apps_earlier_runs_wrote(tmp_path):
    """Issue 82, cause 5: a monitor run without the prognosis after one with it left the
    earlier prognosis.png beside the new report. A fresh claim removes the files the
    stamp proves the app's before this run writes; a file of the folder it cannot prove
    is refused as before, and a stopped run's folder holds no earlier file either."""
    out = tmp_path / "report"
    with ownership.claim(out, "swgsim-monitor", strict=True, fresh=True):
        for name in ("report.md", "health.png", "prognosis.png", "summary.json"):
            ownership.write_owned(out / name, lambda tmp: tmp.write_bytes(b"run 1"))
    with ownership.claim(out, "swgsim-monitor", strict=True, fresh=True):
        assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".swg")) == []
        for name in ("report.md", "health.png", "summary.json"):  # no prognosis this time
            ownership.write_owned(out / name, lambda tmp: tmp.write_bytes(b"run 2"))
    files = sorted(p.name for p in out.iterdir() if not p.name.startswith(".swg"))
    assert files == ["health.png", "report.md", "summary.json"]
    assert all((out / f).read_bytes() == b"run 2" for f in files)
    assert sorted(ownership.check(out, app="swgsim-monitor").owned) == files
    (out / "mine.txt").write_text("a user's")
    with pytest.raises(ValueError, match=r"mine.txt"):
        ownership.claim(out, "swgsim-monitor", strict=True, fresh=True)
    assert (out / "mine.txt").is_file() and (out / "report.md").is_file()


def test_an_app_with_two_outputs_in_one_folder_renews_one_and_keeps_the_other(tmp_path):
    """Issue 82, cause 5 (audit): swgsim-observability's steady and motion maps share a
    report_dir; a run of one map renews its own files (fresh patterns, as
    learn/observability/task.py passes them) and keeps the other's whole, never a mix of
    two runs of one map."""
    from learn.observability.task import MOTION_FILES, STEADY_FILES

    out, app = tmp_path / "observability", "swgsim-observability"
    for files, run in ((STEADY_FILES, b"steady 1"),
                       (MOTION_FILES, b"motion 1")):
        fresh = STEADY_FILES if files[0] in STEADY_FILES else MOTION_FILES
        with ownership.claim(out, app, strict=True, fresh=fresh):
            for name in files:
                ownership.write_owned(out / name, lambda tmp, run=run: tmp.write_bytes(run))
    with ownership.claim(out, app, strict=True, fresh=MOTION_FILES):  # motion again
        assert not (out / "observability_motion.csv").exists()
        assert (out / "observability.csv").read_bytes() == b"steady 1"
        for name in MOTION_FILES:
            ownership.write_owned(out / name, lambda tmp: tmp.write_bytes(b"motion 2"))
    with ownership.claim(out, app, strict=True, fresh=True):  # the whole app's output
        assert [p.name for p in out.iterdir() if not p.name.startswith(".swg")] == []


def test_the_monitors_figure_is_written_through_write_owned(tmp_path, monkeypatch):
    """A savefig that fails half-way through health.png leaves no health.png at all."""
    import matplotlib.figure

    def half(self, fname, *a, **k):
        Path(fname).write_bytes(b"\x89PNG half")
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", half)
    from swgmon.advisories import report

    with pytest.raises(atomic.DiskFullError):
        report.write_outputs(_TinyResult(), tmp_path, "s")
    assert not (tmp_path / "health.png").exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")] == []


def test_save_figure_writes_in_the_suffixs_format_and_closes_a_pyplot_figure(tmp_path):
    """save_figure: the format the path's suffix names, the file recorded as ours; a
    figure pyplot made is closed, a Figure made without it is left as it is."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.figure import Figure

    out = tmp_path / "rep"
    fig, ax = plt.subplots()
    ax.plot([0, 1], [1, 0])
    bare = Figure()
    bare.subplots().plot([0, 1], [0, 1])
    with ownership.claim(out, "swgsim-monitor", strict=True):
        assert ownership.save_figure(fig, str(out / "a.png"), 50) == out / "a.png"
        ownership.save_figure(bare, out / "b.svg", 50, bbox_inches="tight")
    assert (out / "a.png").read_bytes()[:4] == b"\x89PNG"
    assert b"<svg" in (out / "b.svg").read_bytes()
    assert not plt.fignum_exists(fig.number) and bare.axes  # the Figure still drawn
    assert sorted(ownership.check(out, app="swgsim-monitor").owned) == ["a.png", "b.svg"]


class _TinyResult:
    """What write_outputs reads of a StreamResult: ten monitored windows, no alarm."""

    class trace:  # noqa: N801 - an attribute of the result
        hour = np.arange(10.0)
        p = np.full(10, 0.5)
        s = np.zeros(10)

    alarms, advisories, recommissioned = [], [], []
    n_commissioning, onset_h, true_fault, threshold = 5, None, None, 5.0
    prognosis = None  # the option off

    def events(self):
        return []


def test_a_stop_removes_what_its_killed_workers_left_half_written(tmp_path):
    """A worker of the run, killed while it wrote (here: gone, its temporary file left),
    leaves nothing once the stop's line is made: the next run would remove it anyway,
    but a stopped run's folder holds only whole files."""
    out = tmp_path / "rep"
    child = ("import os, sys\nfrom pathlib import Path\nfrom swgsim.files import ownership\n"
             "from swgsim.files.atomic import temp_prefix\nout = Path(sys.argv[1])\n"
             "ownership.join(out)\n(out / (temp_prefix(out / 'part.json') + 'x.tmp'))"
             ".write_text('half')\nos._exit(0)\n")
    with pytest.raises(KeyboardInterrupt), ownership.claim(out, "monitor", strict=True):
        subprocess.run([sys.executable, "-c", child, str(out)], check=True, timeout=120)
        assert len(list(out.glob("*.tmp"))) == 1
        raise KeyboardInterrupt
    assert "rerun" in ownership.stop_note()
    assert list(out.glob("*.tmp")) == []
