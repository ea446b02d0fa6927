"""A full disk: too little free space is refused before writing, and a disk that fills
while a data set is written ends in one line naming the folder, with the workers stopped,
no half-written shard or temporary file left and no HDF5 file left open."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest
from bad_input import message, one_error_line, process_group, small_cfg

from swgsim.datasets import generate as gen
from swgsim.datasets import outdir
from swgsim.files import atomic


def test_full_disk_is_refused_before_writing_naming_the_folder(tmp_path, monkeypatch):
    monkeypatch.setattr(outdir.shutil, "disk_usage",
                        lambda p: shutil._ntuple_diskusage(10**9, 10**9 - 1000, 1000))
    out = tmp_path / "ds"
    msg = message(lambda: gen.generate(small_cfg(), out, n_jobs=1, progress=False))
    assert str(out) in msg and "MiB free" in msg and not out.exists()


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
def test_disk_full_while_writing_names_the_folder(tmp_path, monkeypatch):
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
def test_a_full_disk_ends_in_one_line_with_the_workers_stopped(tmp_path):
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
