"""Wrong blame (issue 22): every bad input ends in one line naming its true cause.

One case per root cause that used to be reported wrong: Hydra overrides it cannot parse,
a dynamic simulation that diverges, a manifest without hashes, a file given as an output
folder, an unknown strain candidate, a full disk, a grid length of zero, a false sample
rate and ``n_jobs`` out of range. Each asserts exit code 2 (apps) or the exception, that
the message is one line naming the key or file, and that nothing the user had was lost.
Apps run in-process (``main()`` with ``sys.argv`` set), except where a process must die.
"""

from __future__ import annotations

import importlib
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from bad_input import calibrate_call, message, process_group, small_cfg, snapshot

from swgcli import compose_app
from swgcli.app import check_out_dirs, override_message
from swgsim.datasets import generate as gen
from swgsim.datasets import schema as dsio
from swgsim.datasets.plan import plan

APPS = {"swgsim-generate": "generate", "swgsim-calibrate": "calibrate",
        "swgsim-monitor": "monitor", "swgsim-observability": "observability",
        "swgsim-paper": "paper", "swgsim-train": "train"}


def run_app(prog: str, args: list[str], cwd: Path, monkeypatch, capsys) -> tuple[int, str]:
    """Run an app in-process as its command line would: exit code and stderr."""
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


# ------------------------------------------------------------------ 1 override syntax
@pytest.mark.parametrize("args, words", [
    (["out_dir=/tmp/my", "data"], ["override 'data': not key=value",
                                   "'out_dir=/tmp/my data'"]),
    (["out_dir=~/x"], ["override 'out_dir=~/x'", "delete prefix",
                       f"out_dir={os.path.expanduser('~/x')}", "'out_dir=\"~/x\"'"]),
    (["~no_such_key"], ["no_such_key"]),
])
def test_1_unparsable_overrides_name_the_override_and_how_to_quote(tmp_path, monkeypatch,
                                                                   capsys, args, words):
    code, err = run_app("swgsim-generate", ["dataset=tiny", *args], tmp_path, monkeypatch,
                        capsys)
    line = one_error_line("swgsim-generate", err)
    assert code == 2 and all(w in line for w in words), line
    assert sorted(p.name for p in tmp_path.iterdir()) in ([], ["outputs"])  # no work done


def test_1_a_key_under_a_null_section_names_the_override(tmp_path, monkeypatch, capsys):
    """``monitor.*`` without ``experiment=monitor``: the section is null (OmegaConf asserts
    without a key); one line naming the override and the experiment that defines it."""
    code, err = run_app("swgsim-train", ["monitor.report_dir=x"], tmp_path, monkeypatch,
                        capsys)
    line = one_error_line("swgsim-train", err)
    assert code == 2 and "monitor.report_dir" in line and "experiment=monitor" in line, line


def test_1_a_value_with_a_space_in_one_argument_is_taken_whole():
    cfg = compose_app("generate", ["dataset=tiny", "out_dir=/tmp/my data"])
    assert cfg.out_dir == "/tmp/my data"
    assert "'out_dir=a b'" in override_message("b", ["out_dir=a", "b"])


# ------------------------------------------------------------------ 2 failed simulation
def test_2_an_integrator_step_too_long_is_refused_before_work(tmp_path):
    cfg = small_cfg(sample_rate_hz=500.0, substeps=1, window_s=0.5, settle_s=0.1)
    cfg["disturbance"]["harmonic_mvv"] = 0.0
    msg = message(lambda: gen.generate(cfg, tmp_path / "never", progress=False))
    assert msg.startswith("dataset.chain.substeps=1 at dataset.chain.sample_rate_hz=500 Hz")
    assert "dataset.gears[0]" in msg and "allowed: dataset.chain.substeps >= 2" in msg
    assert not (tmp_path / "never").exists()
    cfg = small_cfg()
    cfg["load"]["j_out_kgm2"] = 1e-4  # in range, but overdamped: no torsional mode
    assert message(lambda: plan(cfg)).startswith("dataset.load.j_out_kgm2=0.0001")


def test_2_a_diverged_simulation_names_shard_window_and_keys(tmp_path, monkeypatch):
    from swgsim.datasets import grid_shard as shard

    real = shard.dynamics.simulate

    def diverging(*a, **k):
        res = real(*a, **k)
        res.states[:, -1] = np.nan  # the last motion of the shard blows up
        res.success, res.message = False, "non-finite states"
        return res

    monkeypatch.setattr(shard.dynamics, "simulate", diverging)
    out = tmp_path / "ds"
    msg = message(lambda: gen.generate(small_cfg(), out, n_jobs=1, progress=False))
    assert msg.startswith("dataset.chain.substeps=1, dataset.chain.sample_rate_hz=10000 Hz")
    assert "shard gear1_n4000rpm.nc (gear 1, 4000 rpm, 39 N m, fault" in msg
    assert "non-finite states" in msg and "dataset.load.j_out_kgm2" in msg
    assert not list(out.glob("*.tmp")) and not list(out.glob("*.nc"))


# ------------------------------------------------------------------ 3 manifest hashes
@pytest.mark.parametrize("edit, words", [
    (lambda m: m["shards"][sorted(m["shards"])[0]].pop("sha256"), ".sha256 is missing"),
    (lambda m: m.pop("shards"), "shards is missing"),
    (lambda m: m.update(shards=sorted(m["shards"])), "shards is not a mapping"),
])
def test_3_a_manifest_without_hashes_is_named_to_every_reader(copy_of, tmp_path, edit,
                                                              words):
    from learn.tasks.train import run_train

    folder = copy_of()
    m = json.loads((folder / dsio.MANIFEST).read_text())
    edit(m)
    (folder / dsio.MANIFEST).write_text(json.dumps(m))
    before = snapshot(folder)
    msg = message(lambda: dsio.load(folder))
    assert msg.startswith(f"{folder / dsio.MANIFEST}: ") and words in msg
    cfg = compose_app("train", [f"stored.path={folder}", "~logger",
                                f"paths.report_dir={tmp_path}/rep"])
    assert message(lambda: run_train(cfg)) == msg
    msg = message(calibrate_call(folder, tmp_path / "out"))
    assert str(folder / dsio.MANIFEST) in msg and words in msg
    assert snapshot(folder) == before and not (tmp_path / "out").exists()


# ------------------------------------------------------------------ 4 file as out_dir
@pytest.mark.parametrize("prog, args, key", [
    ("swgsim-generate", ["dataset=tiny"], "out_dir"),
    ("swgsim-calibrate", ["measured=rec.csv"], "out_dir"),
    ("swgsim-monitor", ["stream=s", "diagnosis_model=m.joblib"], "out_dir"),
    ("swgsim-observability", [], "report_dir"),
    ("swgsim-observability", [], "data_root"),
    ("swgsim-paper", ["grid=tiny"], "data_root"),
    ("swgsim-paper", ["grid=tiny"], "report_root"),
    ("swgsim-train", ["stored.path=nowhere", "~logger"], "paths.report_dir"),
])
def test_4_a_file_given_as_an_output_folder_is_refused_before_work(
        tmp_path, monkeypatch, capsys, prog, args, key):
    (tmp_path / "thesis.tex").write_text("years of work")
    code, err = run_app(prog, [*args, f"{key}=thesis.tex"], tmp_path, monkeypatch, capsys)
    line = one_error_line(prog, err)
    assert code == 2 and line.endswith(f"{key}=thesis.tex: is a file, not a folder"), line
    assert (tmp_path / "thesis.tex").read_text() == "years of work"
    code, err = run_app(prog, [*args, f"{key}=thesis.tex/sub"], tmp_path, monkeypatch, capsys)
    line = one_error_line(prog, err)
    assert code == 2 and f"{tmp_path / 'thesis.tex'} is a file, not a folder" in line


def test_4_every_app_declares_its_output_folders(tmp_path):
    for name in APPS.values():
        schema = importlib.import_module(f"swgcli.{name}").main.schema
        assert schema.OUT_DIRS, name
    (tmp_path / "f").write_text("x")
    cfg = compose_app("train", ["experiment=monitor", f"monitor.report_dir={tmp_path}/f"])
    schema = importlib.import_module("swgcli.train").main.schema
    with pytest.raises(ValueError, match=r"^monitor\.report_dir=.*: is a file, not a folder$"):
        check_out_dirs(cfg, schema)


# ------------------------------------------------------------------ 5 strain candidate
def test_5_an_unknown_strain_candidate_is_refused_before_loading(small, tmp_path,
                                                                 monkeypatch):
    import swgcal.strain.problem as sp

    def never(*a, **k):
        raise AssertionError("the data set was loaded")

    monkeypatch.setattr(sp, "strain_windows", never)
    before = snapshot(small)
    msg = message(calibrate_call(small, tmp_path / "out", "selection.candidates=[offset,ofset]"))
    assert msg.startswith("selection.candidates: unknown strain effects ['ofset']")
    assert "offset" in msg.split("library:")[1]
    assert snapshot(small) == before and not (tmp_path / "out").exists()


# ------------------------------------------------------------------ 6 full disk
_DEV_FULL = ("import os, tempfile\n"
             "_real = tempfile.mkstemp\n"
             "def _full(*a, **k):\n"
             "    fd, name = _real(*a, **k)\n"
             "    if '.nc.' in os.path.basename(name):  # shards only: a real ENOSPC\n"
             "        os.unlink(name)  # written by path: the name leads to /dev/full\n"
             "        os.symlink('/dev/full', name)\n"
             "    return fd, name\n"
             "tempfile.mkstemp = _full\n")


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
def test_6_a_full_disk_ends_in_one_line_with_the_workers_stopped(tmp_path):
    site = tmp_path / "site"
    site.mkdir()
    (site / "sitecustomize.py").write_text(_DEV_FULL)  # in the app and in its workers
    out = tmp_path / "ds"
    (tmp_path / "keep.txt").write_text("mine")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(site), *filter(None, [os.environ.get("PYTHONPATH")])])}
    p = subprocess.Popen([str(Path(sys.executable).parent / "swgsim-generate"),
                          "dataset=tiny", f"out_dir={out}", "n_jobs=2", "progress=false",
                          "hydra.job_logging.root.level=WARNING"],
                         cwd=tmp_path, env=env, start_new_session=True,
                         stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    _, err = p.communicate(timeout=300)
    assert p.returncode == 2, err  # not -11: no segmentation fault after the message
    line = one_error_line("swgsim-generate", err)
    assert "disk full while writing" in line and str(out) in line
    deadline = time.time() + 10  # the workers were killed: give them time to be gone
    while process_group(p.pid) and time.time() < deadline:
        time.sleep(0.2)
    assert process_group(p.pid) == []  # no worker goes on writing
    assert not list(out.glob("*.tmp")) and not list(out.glob("*.nc"))
    assert (tmp_path / "keep.txt").read_text() == "mine"
    # and in-process: no HDF5 file is left open to be touched after the error
    code = (_DEV_FULL + "import sys, h5py\nsys.path.insert(0, sys.argv[2])\n"
            "from data_sets import make_synthetic\nfrom swgsim.datasets import schema\n"
            "from swgsim.files.atomic import DiskFullError\n"
            "try:\n    schema.write_shard(make_synthetic(n_variants=1), "
            "__import__('pathlib').Path(sys.argv[1]) / 's.nc')\n"
            "except DiskFullError as e:\n    print(e)\n"
            "print([i.name for i in h5py.h5f.get_obj_ids(types=h5py.h5f.OBJ_FILE)])\n")
    r = subprocess.run([sys.executable, "-c", code, str(tmp_path / "w"),
                        str(Path(__file__).parents[1])], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[-2].startswith("disk full while writing")
    assert r.stdout.splitlines()[-1] == "[]" and not list((tmp_path / "w").iterdir())


# ------------------------------------------------------------------ 7 empty grids
@pytest.mark.parametrize("edit, words", [
    (lambda c: c["sensors"].update(grid_length_mm=0.001),
     "dataset.sensors.grid_length_mm must lie in [0.2, 13.6] mm"),
    (lambda c: c["sensors"].update(grid_length_mm=37.9),
     "dataset.sensors.grid_length_mm must lie in [0.2, 13.6] mm"),
    (lambda c: c["operating_points"].update(n_in_rpm=[]),
     "dataset.operating_points.n_in_rpm must list one or more distinct values, got []"),
    (lambda c: c["operating_points"].update(t_out_nm=[]),
     "dataset.operating_points.t_out_nm must list one or more"),
])
def test_7_an_empty_or_zero_grid_is_named_not_the_mesh(tmp_path, edit, words):
    cfg = small_cfg()
    edit(cfg)
    msg = message(lambda: gen.generate(cfg, tmp_path / "never", progress=False))
    assert msg.startswith(words) and "n_theta" not in msg
    assert not (tmp_path / "never").exists()


# ------------------------------------------------------------------ 8 sample rate
def _rewrite_first_shard(folder: Path, edit, drop_config: bool = False) -> Path:
    import xarray as xr

    m = json.loads((folder / dsio.MANIFEST).read_text())
    f = folder / sorted(m["shards"])[0]
    with xr.open_dataset(f, engine="h5netcdf") as ds:
        ds = edit(ds.load())
    f.unlink()
    m["shards"][f.name]["sha256"] = dsio.write_shard(ds, f)
    if drop_config:  # a data set written by another tool: no config to compare with
        m.pop("config")
        m.pop("config_hash")
    (folder / dsio.MANIFEST).write_text(json.dumps(m))
    return f


def test_8_an_impossible_sample_rate_attribute_names_the_file(copy_of):
    folder = copy_of()

    def text(ds):
        ds.attrs["sample_rate_hz"] = "10 kHz"
        return ds

    f = _rewrite_first_shard(folder, text)
    msg = message(lambda: dsio.load(folder))
    assert msg == (f"shard {f}: attribute sample_rate_hz='10 kHz' is not a sample rate (a "
                   "positive number of Hz)")


def test_8_shards_of_another_rate_are_named_not_the_features(copy_of, tmp_path):
    from learn.tasks.train import run_train

    folder = copy_of()

    def slower(ds):  # consistent in itself: 1 kHz, time axis and attribute
        ds.attrs["sample_rate_hz"] = 1000.0
        return ds.assign_coords(time=ds["time"].values * 10)

    f = _rewrite_first_shard(folder, slower, drop_config=True)
    before = snapshot(folder)
    cfg = compose_app("train", [f"stored.path={folder}", "~logger",
                                f"paths.report_dir={tmp_path}/rep"])
    msg = message(lambda: run_train(cfg))
    assert "attribute sample_rate_hz=10000.0 Hz and its time axis" in msg
    assert f"shard {f})" not in msg and str(f) in msg and "feature" not in msg
    assert snapshot(folder) == before


# ------------------------------------------------------------------ 9 n_jobs
@pytest.mark.parametrize("app, extra, key", [
    ("generate", [], "n_jobs"),
    ("paper", [], "n_jobs"),
    ("observability", [], "n_jobs"),
    ("train", [], "n_jobs"),
    ("train", ["experiment=monitor"], "monitor.n_jobs"),
])
@pytest.mark.parametrize("value", [0, -1])
def test_9_n_jobs_out_of_range_is_refused_at_composition(app, extra, key, value):
    msg = message(lambda: compose_app(app, [*extra, f"{key}={value}"]))
    assert msg == f"{key}={value}: out of range; allowed: >= 1 (worker processes)"


def test_9_n_jobs_is_refused_before_the_data_set_is_read(tmp_path, monkeypatch, capsys):
    code, err = run_app("swgsim-train", ["stored.path=/nowhere/data", "~logger", "n_jobs=0"],
                        tmp_path, monkeypatch, capsys)
    assert code == 2 and one_error_line("swgsim-train", err).endswith(
        "n_jobs=0: out of range; allowed: >= 1 (worker processes)")
    assert sorted(p.name for p in tmp_path.iterdir()) in ([], ["outputs"])
