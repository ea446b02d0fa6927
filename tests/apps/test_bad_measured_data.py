"""The calibration's measured input: files that are not text tables (devices, FIFOs,
sparse, binary) refused before they are read, friction recordings in the wrong units or
inconsistent in themselves, and options that do not fit the data given (friction-only
options or an unknown strain effect for a strain data set). Each is one line naming the
file or key; no output folder is made and the data are left as they were."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from bad_input import calibrate_call, friction_csv, message, snapshot

T = np.arange(2000) * 0.002


# ------------------------------------------------------------------ files
def _csv(t, q, dq):
    return lambda p: friction_csv(p, t, q, dq, 0.1 * np.tanh(20 * np.cos(T)))


MEASURED_CASES = {  # case -> (how the file is made, what the line says)
    "/dev/zero": ("/dev/zero", "measured /dev/zero: is a character device"),
    "a FIFO": (lambda p: os.mkfifo(p), "is a FIFO (named pipe), not a regular file"),
    "a sparse 2 GB file": (lambda p: subprocess.run(["truncate", "-s", "2G", str(p)],
                                                    check=True), "a sparse file (2.00 GiB"),
    "a folder without manifest": (lambda p: p.mkdir(), "is a directory without manifest"),
    "a binary file": (lambda p: p.write_bytes(b"time_s,q\x00\x01" * 100), "NUL bytes"),
    "a first line over 64 KiB": (lambda p: p.write_text("x" * 70_000),
                                 "no line end in its first 64 KiB"),
    "time column twice too long": (_csv(2 * T, np.sin(T), np.cos(T)),
                                   "but 2.00 times it (a pure factor"),
    "velocity in deg/s": (_csv(T, np.sin(T), np.rad2deg(np.cos(T))), "looks like deg/s"),
    "velocity in rpm": (_csv(T, np.sin(T), np.cos(T) * 60 / (2 * np.pi)),
                        "looks like rpm"),
    "velocity of the wrong sign": (_csv(T, np.sin(T), -np.cos(T)), "a sign error"),
    "time in ms": (_csv(T * 1000, np.sin(T), np.cos(T)), "time_s looks like milliseconds"),
    "angle in degrees": (_csv(T, np.rad2deg(np.sin(T)), np.cos(T)),
                         "q_rad looks like degrees"),
}


@pytest.mark.parametrize("case", MEASURED_CASES)
def test_a_measured_file_is_refused_in_one_line_before_it_is_read(tmp_path, case):
    import resource

    make, named = MEASURED_CASES[case]
    p = Path(make) if isinstance(make, str) else tmp_path / "rec.csv"
    if not isinstance(make, str):
        make(p)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    msg = message(calibrate_call(p, tmp_path / "out"))
    assert named in msg, msg
    # no memory growth: the largest resident size grew by under 100 MiB
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - rss < 100 * 1024
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------ friction recordings
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
                                        + bytes(range(256)) * 8), p)[1], "not a text file"),
    ("header only", lambda p: (p.write_text("time_s,q_rad,dq_rad_per_s,tau_friction_Nm\n"),
                               p)[1], "no data rows"),
])
def test_inconsistent_friction_recordings_are_refused(tmp_path, case, make, words):
    csv = make(tmp_path / "rec.csv")
    msg = message(calibrate_call(csv, tmp_path / "out"))
    assert words in msg and str(csv) in msg, case
    assert not (tmp_path / "out").exists()


def test_too_few_samples_for_the_held_out_split(tmp_path):
    csv = friction_csv(tmp_path / "rec.csv", T[:150], np.sin(T[:150]), np.cos(T[:150]))
    msg = message(calibrate_call(csv, tmp_path / "out"))
    assert "split.n_blocks=10" in msg and "allowed: n_blocks <= 7" in msg


# ------------------------------------------------------------------ options for the data
def test_strain_data_set_refuses_friction_only_options(small, tmp_path):
    before = snapshot(small)
    msg = message(calibrate_call(small, tmp_path / "out", "split.n_blocks=5"))
    assert "split.n_blocks=5" in msg and str(small) in msg and "kind 1" in msg
    assert snapshot(small) == before and not (tmp_path / "out").exists()


def test_an_unknown_strain_candidate_is_refused_before_loading(small, tmp_path,
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
