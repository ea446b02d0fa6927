"""Reliability matrix: bad input and faults against the four apps, on tiny data.

Every case asserts that the message names the key or file it is about, and that nothing
was lost (files that were there are still there, unchanged; nothing half-made blocks a
rerun). Kinds: A deletion safety, B config schema, C ranges and physical validity,
D data-set integrity, E measured data, F app failures (one line, exit code 2),
G signals and full disk.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from bad_input import calibrate_call, friction_csv, message, process_group, small_cfg, snapshot

from swgcli import compose_app
from swgsim.datasets import generate as gen
from swgsim.datasets import outdir
from swgsim.datasets import schema as dsio
from swgsim.files import atomic

BIN = Path(sys.executable).parent


# ------------------------------------------------------------------ A deletion safety
def test_A1_overwrite_refuses_a_folder_with_other_files(copy_of):
    folder = copy_of()
    (folder / "thesis.tex").write_text("years of work")
    before = snapshot(folder)
    cfg = small_cfg()
    cfg["seed"] = 7
    msg = message(lambda: gen.generate(cfg, folder, progress=False, overwrite=True))
    assert str(folder) in msg and "thesis.tex" in msg
    assert snapshot(folder) == before


def test_A2_main_job_refuses_a_data_root_with_other_files(tmp_path):
    folder = tmp_path / "data" / "paper"
    folder.mkdir(parents=True)
    (folder / "notes.txt").write_text("mine")
    cfg = compose_app("paper", ["grid=tiny", f"data_root={tmp_path}/data",
                                f"report_root={tmp_path}/reports",
                                f"tracking_uri=sqlite:///{tmp_path}/m.db"])
    from swgcli.paper import run_paper

    msg = message(lambda: run_paper(cfg))
    assert str(folder) in msg and "notes.txt" in msg
    assert (folder / "notes.txt").read_text() == "mine"
    assert not (tmp_path / "reports").exists()


# ------------------------------------------------------------------ B config schema
@pytest.mark.parametrize("app, overrides, key", [
    ("generate", ["+dataset.chain.windows_s=0.1"], "dataset.chain.windows_s: unknown key"),
    ("generate", ["dataset.chain.windows_s=0.1"], "dataset.chain.windows_s: unknown key"),
    ("generate", ["dataset.seed=abc"], "dataset.seed"),
    ("generate", ["dataset=papr"], "dataset/papr"),
    ("paper", ["+study.scales=true"], "study.scales: unknown key"),
    ("paper", ["n_jobs=two"], "n_jobs"),
    ("train", ["+model.estimator.max_dept=9"], "model.estimator.max_dept"),
    ("train", ["+features.max_ordr=4"], "features.max_ordr: unknown key"),
    ("calibrate", ["out_dir=/tmp/x"], "measured: missing value"),
    ("calibrate", ["measured=a.csv", "out_dir=/tmp/x", "selection.max_iter=many"],
     "selection.max_iter"),
])
def test_B_unknown_missing_mistyped_keys_are_refused(app, overrides, key):
    msg = message(lambda: compose_app(app, overrides))
    assert key in msg


def test_B_generate_refuses_a_plain_dict_with_an_unknown_key(tmp_path):
    cfg = small_cfg()
    cfg["chain"]["windows_s"] = 0.1
    msg = message(lambda: gen.generate(cfg, tmp_path / "never", progress=False))
    assert msg.startswith("dataset.chain.windows_s: unknown key")
    assert not (tmp_path / "never").exists()


# ------------------------------------------------------------------ C ranges, physics
@pytest.mark.parametrize("edit, key", [
    (lambda c: c["chain"].update(window_s=0.02), "dataset.chain.window_s=0.02"),
    (lambda c: c["chain"].update(contact_half_width_deg=95.0),
     "dataset.chain.contact_half_width_deg"),
    (lambda c: c["chain"].update(ecc_load_share=20.0), "dataset.chain.ecc_load_share"),
    (lambda c: c["tolerances"].update(sd_theta_deg=-0.1), "dataset.tolerances.sd_theta_deg"),
    (lambda c: c.update(seed=-1), "dataset.seed"),
    (lambda c: c["gears"][0].update(tolerance_seed=-5), "dataset.gears[0].tolerance_seed"),
    (lambda c: c["mesh"].update(n_theta=20), "dataset.mesh.n_theta"),
    (lambda c: c["disturbance"].update(offset_mvv=2.0), "dataset.disturbance.offset_mvv"),
])
def test_C_out_of_range_and_unphysical_data_sets_are_refused(tmp_path, edit, key):
    cfg = small_cfg()
    edit(cfg)
    msg = message(lambda: gen.generate(cfg, tmp_path / "never", progress=False))
    assert key in msg and ("must" in msg or "allowed" in msg or "raise" in msg)
    assert not (tmp_path / "never").exists()


@pytest.mark.parametrize("override, key", [
    ("features.max_order=100", "features.max_order=100"),   # above Nyquist at 4000 rpm
    ("features.order_step=0.05", "features.order_step=0.05"),  # finer than the window
])
def test_C_feature_orders_the_data_cannot_carry_are_refused(small, tmp_path, override, key):
    from learn.tasks.train import run_train

    cfg = compose_app("train", [f"stored.path={small}", "~logger", "features=selection3",
                                override, f"paths.report_dir={tmp_path}"])
    msg = message(lambda: run_train(cfg))
    assert key in msg and str(small) in msg


# ------------------------------------------------------------------ D data-set integrity
def _manifest(folder: Path) -> dict:
    return json.loads((folder / dsio.MANIFEST).read_text())


def test_D1_manifest_with_an_entry_removed_is_refused_naming_it(copy_of, tmp_path):
    from learn.tasks.train import run_train

    folder = copy_of()
    m = _manifest(folder)
    m["shards"].pop(sorted(m["shards"])[0])
    (folder / dsio.MANIFEST).write_text(json.dumps(m))
    assert "n_shards" in message(lambda: dsio.load(folder))
    m.pop("n_shards")
    m["n_samples"] = sum(e["n_samples"] for e in m["shards"].values())
    (folder / dsio.MANIFEST).write_text(json.dumps(m))
    msg = message(lambda: dsio.load(folder))
    assert "not in manifest.json" in msg and ".nc" in msg
    cfg = compose_app("train", [f"stored.path={folder}", "~logger",
                                f"paths.report_dir={tmp_path}"])
    assert "not in manifest.json" in message(lambda: run_train(cfg))  # no partial training


def test_D2_extra_and_miscounted_shards_are_named(copy_of):
    folder = copy_of()
    shutil.copy(next(folder.glob("*.nc")), folder / "gear9_n4000rpm.nc")
    assert "gear9_n4000rpm.nc" in message(lambda: dsio.load(folder))
    (folder / "gear9_n4000rpm.nc").unlink()
    m = _manifest(folder)
    name = sorted(m["shards"])[0]
    m["shards"][name]["n_samples"] += 1
    m["n_samples"] += 1
    (folder / dsio.MANIFEST).write_text(json.dumps(m))
    msg = message(lambda: dsio.load(folder))
    assert name in msg and "samples" in msg


def test_D3_an_unfinished_run_never_blocks_a_corrected_rerun(tmp_path, monkeypatch):
    calls = []
    real = gen.run_shard

    def fail_second(*a, **k):
        calls.append(1)
        if len(calls) == 2:
            raise RuntimeError("the machine went down")
        return real(*a, **k)

    monkeypatch.setattr(gen, "run_shard", fail_second)
    out = tmp_path / "ds"
    with pytest.raises(RuntimeError):
        gen.generate(small_cfg(), out, n_jobs=1, progress=False)
    monkeypatch.setattr(gen, "run_shard", real)
    fixed = small_cfg()
    fixed["seed"] = 11  # the corrected run has another config, and no overwrite flag
    s = gen.generate(fixed, out, n_jobs=1, progress=False)
    assert s["complete"] and "unfinished data set" in s["replaced"]


def test_D4_temporary_files_of_a_killed_run_are_cleaned(copy_of):
    folder = copy_of()
    (folder / dsio.MANIFEST).unlink()  # killed before the end: no manifest
    code = ("import os, sys; from pathlib import Path; from swgsim.files import atomic, ownership; "
            "f = Path(sys.argv[1]); ownership.join(f.parent); "
            "(f.parent / (atomic.temp_prefix(f) + 'k.tmp')).write_bytes(b'half'); os._exit(0)")
    subprocess.run([sys.executable, "-c", code, str(folder / "gear1_n4000rpm.nc")], check=True)
    assert len(list(folder.glob("*.tmp"))) == 1  # its stamp names the killed run: ours
    gen.generate(small_cfg(), folder, n_jobs=1, progress=False)
    assert not list(folder.glob("*.tmp")) and (folder / dsio.MANIFEST).is_file()


# ------------------------------------------------------------------ E measured data
T = np.arange(2000) * 0.002


@pytest.mark.parametrize("case, make, words", [
    ("constant angle", lambda p: friction_csv(p, T, np.full_like(T, 0.3), np.sin(T)),
     "q_rad stays at"),
    ("velocity in deg/s", lambda p: friction_csv(p, T, np.sin(T), np.rad2deg(np.cos(T))),
     "not the time derivative"),
    ("time backwards", lambda p: friction_csv(p, T[::-1], np.sin(T), np.cos(T)), "goes backwards"),
    ("all non-finite", lambda p: friction_csv(p, T, np.full_like(T, np.nan), np.cos(T)),
     "no usable rows"),
    ("too few rows", lambda p: friction_csv(p, T[:60], np.sin(T[:60]), np.cos(T[:60])),
     "at least 100 needed"),
    ("binary", lambda p: (p.write_bytes(b"time_s,q_rad,dq_rad_per_s,tau_friction_Nm\n"
                                        + bytes(range(256)) * 8), p)[1], "not a text CSV"),
    ("header only", lambda p: (p.write_text("time_s,q_rad,dq_rad_per_s,tau_friction_Nm\n"),
                               p)[1], "no data rows"),
])
def test_E_inconsistent_friction_recordings_are_refused(tmp_path, case, make, words):
    csv = make(tmp_path / "rec.csv")
    msg = message(calibrate_call(csv, tmp_path / "out"))
    assert words in msg and str(csv) in msg, case
    assert not (tmp_path / "out").exists()


def test_E_too_few_samples_for_the_held_out_split(tmp_path):
    csv = friction_csv(tmp_path / "rec.csv", T[:150], np.sin(T[:150]), np.cos(T[:150]))
    msg = message(calibrate_call(csv, tmp_path / "out"))
    assert "split.n_blocks=10" in msg and "allowed: n_blocks <= 7" in msg


def test_E_strain_data_set_refuses_friction_only_options(small, tmp_path):
    before = snapshot(small)
    msg = message(calibrate_call(small, tmp_path / "out", "split.n_blocks=5"))
    assert "split.n_blocks=5" in msg and str(small) in msg and "kind 1" in msg
    assert snapshot(small) == before and not (tmp_path / "out").exists()


# ------------------------------------------------------------------ F app failures
def _app(name, *args, env=None, cwd=None):
    return subprocess.run([str(BIN / name), *args], capture_output=True, text=True,
                          cwd=cwd, env={**os.environ, **(env or {})}, timeout=300)


@pytest.mark.parametrize("app, args, words", [
    ("swgsim-generate", ["dataset=tiny", "+dataset.chain.windows_s=1"], "windows_s"),
    ("swgsim-generate", ["dataset=tiny", "dataset.life={hours: 1.0}"], "dataset.life: is null"),
    ("swgsim-train", ["stored.path=/nowhere/data", "~logger"], "/nowhere/data"),
    ("swgsim-calibrate", ["measured=/nowhere/x.csv", "out_dir=out"], "/nowhere/x.csv"),
])
def test_F_apps_end_bad_input_in_one_line_with_exit_code_2(tmp_path, app, args, words):
    r = _app(app, *args, cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    lines = [s for s in r.stderr.splitlines() if s.strip()]
    assert lines == [lines[-1]] and lines[-1].startswith(f"{app}: error: ")
    assert words in lines[-1] and "Traceback" not in r.stderr
    full = _app(app, *args, cwd=tmp_path, env={"HYDRA_FULL_ERROR": "1"})
    assert "Traceback" in full.stderr  # asked for


def test_F_tracking_store_is_checked_before_any_work(tmp_path):
    bad = tmp_path / "not_a_db.db"
    bad.write_text("not sqlite")
    r = _app("swgsim-paper", "grid=tiny", f"data_root={tmp_path}/data",
             f"report_root={tmp_path}/reports", f"tracking_uri=sqlite:///{bad}", cwd=tmp_path)
    assert r.returncode == 2 and f"tracking_uri=sqlite:///{bad}" in r.stderr
    assert not (tmp_path / "data").exists() and bad.read_text() == "not sqlite"
    r = _app("swgsim-paper", "grid=tiny", f"data_root={tmp_path}/data",
             "tracking_uri=sqlite:////nowhere/at/all/mlflow.db", cwd=tmp_path)
    assert r.returncode == 2 and "/nowhere/at/all does not exist" in r.stderr


# ------------------------------------------------------------------ G signals, disk
@pytest.mark.parametrize("sig, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_G_stopping_the_generator_stops_its_workers(tmp_path, sig, code):
    out = tmp_path / "ds"
    # 12 speeds (2000-4200 rpm): 36 shards, minutes of work, so that the signal always meets running
    # workers, even on a loaded machine (the paper grid alone can finish before it)
    speeds = ",".join(str(2000.0 + 200.0 * k) for k in range(12))
    p = subprocess.Popen([str(BIN / "swgsim-generate"), "dataset=paper", f"out_dir={out}",
                          f"dataset.operating_points.n_in_rpm=[{speeds}]",
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


def test_G_full_disk_is_refused_before_writing_naming_the_folder(tmp_path, monkeypatch):
    monkeypatch.setattr(outdir.shutil, "disk_usage",
                        lambda p: shutil._ntuple_diskusage(10**9, 10**9 - 1000, 1000))
    out = tmp_path / "ds"
    msg = message(lambda: gen.generate(small_cfg(), out, n_jobs=1, progress=False))
    assert str(out) in msg and "MiB free" in msg and not out.exists()


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
def test_G_disk_full_while_writing_names_the_folder(tmp_path, monkeypatch):
    real = atomic.tempfile.mkstemp

    def full(*a, **k):  # a shard's temporary file on a full disk: the kernel's ENOSPC
        fd, name = real(*a, **k)
        if ".nc." in Path(name).name:  # written by path: the name leads to /dev/full
            os.unlink(name)
            os.symlink("/dev/full", name)
        return fd, name

    monkeypatch.setattr(atomic.tempfile, "mkstemp", full)
    out = tmp_path / "ds"
    msg = message(lambda: gen.generate(small_cfg(), out, n_jobs=1, progress=False))
    assert "disk full" in msg and str(out) in msg
    assert not list(out.glob("*.tmp")) and not list(out.glob("*.nc"))
