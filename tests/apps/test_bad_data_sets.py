"""Stored data sets spoiled on disk: a manifest naming a shard outside its folder, manifests
and shards that are not regular files, flipped bytes, extra, missing, miscounted or unhashed
shards, a sample rate that is none or differs, metadata contradicting the shards. Each is
refused on load in one line naming the file, by every reader (the monitor, training,
calibration), the data set left as it was."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest
from bad_input import app_line, calibrate_call, load_message, message, snapshot

from swgcli import compose_app
from swgsim.datasets import schema as dsio
from swgsim.datasets.plan import config_hash


def _manifest(folder: Path) -> dict:
    return json.loads((folder / dsio.MANIFEST).read_text())


# ------------------------------------------------------------------ a spoiled life
def _edit_manifest(folder: Path, change) -> None:
    mf = folder / dsio.MANIFEST
    m = json.loads(mf.read_text())
    change(m)
    mf.write_text(json.dumps(m))


def _rename_shard(new: str):
    def change(m):
        (old, entry), = m["shards"].items()
        m["shards"] = {new: entry}
    return lambda f: _edit_manifest(f, change)


def _fifo(name: str):
    def make(f: Path):
        (f / name).unlink()
        os.mkfifo(f / name)
    return make


def _to_dev_zero(name: str):
    def make(f: Path):
        (f / name).unlink()
        (f / name).symlink_to("/dev/zero")
    return make


def _flip_byte(f: Path):
    p = f / "gear3_life.nc"
    b = bytearray(p.read_bytes())
    b[len(b) // 2] ^= 0xFF
    p.write_bytes(bytes(b))


DATA_CASES = {  # case -> (how the copy of the life is spoiled, what the line names)
    "shard named ../x.nc": (_rename_shard("../x.nc"), "'../x.nc' is not a file name"),
    "shard named by an absolute path": (_rename_shard("/etc/passwd.nc"),
                                        "'/etc/passwd.nc' is not a file name"),
    "shard in a subfolder": (_rename_shard("sub/gear3_life.nc"), "is not a file name"),
    "shard not *.nc": (_rename_shard("gear3_life.json"), "not *.nc"),
    "manifest.json a FIFO": (_fifo(dsio.MANIFEST), "is not a regular file"),
    "manifest.json a link to /dev/zero": (_to_dev_zero(dsio.MANIFEST),
                                          "is not a regular file"),
    "shard a FIFO": (_fifo("gear3_life.nc"), "is not a regular file"),
    "shard a link to /dev/zero": (_to_dev_zero("gear3_life.nc"), "is not a regular file"),
    "one byte of the shard flipped": (_flip_byte, "gear3_life.nc"),
    "an extra shard": (lambda f: shutil.copy(f / "gear3_life.nc", f / "gear9_life.nc"),
                       "gear9_life.nc"),
    "manifest not JSON": (lambda f: (f / dsio.MANIFEST).write_text("{"), "not valid JSON"),
    "manifest incomplete": (lambda f: _edit_manifest(f, lambda m: m.update(complete=False)),
                            "incomplete"),
    "manifest of another schema": (lambda f: _edit_manifest(
        f, lambda m: m.update(schema_version=2)), "schema_version 2"),
    "a shard's SHA-256 missing": (lambda f: _edit_manifest(
        f, lambda m: next(iter(m["shards"].values())).pop("sha256")), "sha256 is missing"),
}


@pytest.mark.parametrize("case", DATA_CASES)
def test_a_spoiled_data_set_is_refused_in_one_line(tmp_path, life, case):
    spoil, named = DATA_CASES[case]
    folder = tmp_path / "life"
    shutil.copytree(life, folder, symlinks=True)
    spoil(folder)
    msg = message(lambda: dsio.load(folder))
    assert named in msg, msg


def test_the_monitor_app_refuses_a_manifest_pointing_out(tmp_path, life):
    folder = tmp_path / "life"
    shutil.copytree(life, folder)
    _rename_shard("../outside.nc")(folder)
    model = tmp_path / "m.joblib"
    import joblib

    from swgmon.assessment.model import DiagnosisModel
    joblib.dump(DiagnosisModel.__new__(DiagnosisModel), model)
    line = app_line("monitor", [f"stream={folder}", f"diagnosis_model={model}",
                                "trust_pickle=true", f"out_dir={tmp_path}/out", "~logger"],
                    tmp_path)
    assert "'../outside.nc' is not a file name in its folder" in line
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------ shards and counts
def test_manifest_with_an_entry_removed_is_refused_naming_it(copy_of, tmp_path):
    from swgcli.tasks import run_train

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


def test_extra_and_miscounted_shards_are_named(copy_of):
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


@pytest.mark.parametrize("edit, words", [
    (lambda m: m["shards"][sorted(m["shards"])[0]].pop("sha256"), ".sha256 is missing"),
    (lambda m: m.pop("shards"), "shards is missing"),
    (lambda m: m.update(shards=sorted(m["shards"])), "shards is not a mapping"),
])
def test_a_manifest_without_hashes_is_named_to_every_reader(copy_of, tmp_path, edit,
                                                            words):
    from swgcli.tasks import run_train

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


# ------------------------------------------------------------------ sample rate
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


def test_an_impossible_sample_rate_attribute_names_the_file(copy_of):
    folder = copy_of()

    def text(ds):
        ds.attrs["sample_rate_hz"] = "10 kHz"
        return ds

    f = _rewrite_first_shard(folder, text)
    msg = message(lambda: dsio.load(folder))
    assert msg == (f"shard {f}: attribute sample_rate_hz='10 kHz' is not a sample rate (a "
                   "positive number of Hz)")


def test_shards_of_another_rate_are_named_not_the_features(copy_of, tmp_path):
    from swgcli.tasks import run_train

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


# ------------------------------------------------------------------ manifest metadata
def _rehash(m: dict) -> None:
    m["config_hash"] = config_hash(m["config"])


@pytest.mark.parametrize("edit, where, words", [
    (lambda m, s: (m["shards"][s].update(n_samples=m["shards"][s]["n_samples"] + 1),
                   m.update(n_samples=m["n_samples"] + 1)), "shard", ["holds 10 samples", "11"]),
    (lambda m, s: m.update(n_shards=m["n_shards"] + 1), "manifest", ["n_shards=3"]),
    (lambda m, s: (m["config"]["chain"].update(sample_rate_hz=20e3), _rehash(m)), "shard",
     ["sample_rate_hz=10000 Hz", "config.chain.sample_rate_hz=20000"]),
    (lambda m, s: (m["config"]["chain"].update(window_s=0.1), _rehash(m)), "shard",
     ["variable time holds 600 samples", "says 1000"]),
    (lambda m, s: m["config"]["chain"].update(window_s=0.1), "manifest",
     ["config_hash", "contradicts its config"]),
    (lambda m, s: (m["config"].update(name="other"), _rehash(m)), "shard",
     ["attribute config contradicts"]),
    (lambda m, s: m.update(seed=m["seed"] + 1), "shard", ["attribute seed=", "contradicts"]),
    (lambda m, s: m["shards"][s].update(content_sha256="0" * 64), "shard",
     ["attribute content_sha256="]),
], ids=["entry_n_samples", "n_shards", "sample_rate", "window_length", "config_hash",
        "config", "seed", "content_sha256"])
def test_load_refuses_manifest_metadata_that_contradicts_the_shards(copy_of, edit, where,
                                                                     words):
    folder = copy_of()
    m = _manifest(folder)
    name = sorted(m["shards"])[0]
    edit(m, name)
    (folder / dsio.MANIFEST).write_text(json.dumps(m))
    msg = load_message(folder)
    assert (f"shard {folder / name}" if where == "shard" else str(folder / dsio.MANIFEST)) in msg
    for w in words:
        assert w in msg
