"""A user's recording of a sensorized joint as a stream the condition monitor reads.

A *recording* is a table (CSV or Parquet, one row per sample) of a joint's bridges, speed
and torque, optionally angles, temperature, powers, stop flags and a clock; its *mapping*
(:class:`~swgsim.datasets.recording_mapping.RecordingMapping`) names columns, units,
operating points and commissioning. :func:`import_recording` checks both, cuts the
recording into windows (:func:`recording_stream`; arrays: :mod:`.recording_table`,
:mod:`.recording_checks`) and writes a schema-v1 stream. Segments, windows, points, stops,
variables: docs/DATASET.md, "Imported recordings"; user's guide docs/OWN_JOINT.md sec. 2-3.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from swgsim.datasets import recording_checks as rc
from swgsim.datasets import recording_table as rt
from swgsim.datasets.recording_mapping import (
    MAX_BRIDGE_MVV,
    SPEED_UNITS,
    Angle,
    RecordingMapping,
    mapping_columns,
    read_mapping,
    recording_mapping,
)
from swgsim.datasets.schema import (
    MANIFEST,
    SCHEMA_VERSION,
    TEMPERATURE_RANGE_C,
    make_dataset,
    write_shard,
)
from swgsim.files import ownership
from swgsim.files.digest import config_digest
from swgsim.files.ownership import atomic_write_json
from swgsim.files.provenance import git_revision, library_versions, package_version
from swgsim.gear.profile import MAX_INPUT_SPEED_RPM, MOMENTARY_PEAK_TORQUE_NM, RPM

log = logging.getLogger(__name__)

__all__ = ["APP", "MAX_POWER_W", "import_recording", "read_samples", "recording_stream",
           "write_stream"]

#: The app that writes imported streams (their ownership stamp's ``apps``).
APP = "swgsim-import"
#: Largest input or output power a power column may hold [W]: the product of the limits
#: the speed and torque columns are held to, the catalogue's 6500 rpm and momentary peak
#: 191 N m (:data:`~swgsim.gear.profile.MAX_INPUT_SPEED_RPM`,
#: :data:`~swgsim.gear.profile.MOMENTARY_PEAK_TORQUE_NM`), 130 kW: the output's largest
#: power at ratio 1; at the catalogue's ratio 100 a hundred times it, room for an input
#: power at an efficiency down to 1 %. Power in mW, or in W times a gain, lies beyond.
MAX_POWER_W = MAX_INPUT_SPEED_RPM * RPM * MOMENTARY_PEAK_TORQUE_NM


# ------------------------------------------------------------------ the table's samples
@dataclass
class Samples:
    """A recording's columns in the stream's units, checked (:func:`read_samples`): each
    shape (n,), the bridges (5, n) [mV/V]; ``clock`` [h for the unit ``h``, else s since
    the first row], the angles [rad], the speed [rpm]; None where not mapped."""

    time_s: np.ndarray
    clock: np.ndarray | None
    bridges_mvv: np.ndarray
    speed_rpm: np.ndarray
    torque_nm: np.ndarray
    phi_in: np.ndarray | None
    phi_out: np.ndarray | None
    temperature_c: np.ndarray | None
    p_in_w: np.ndarray | None
    p_out_w: np.ndarray | None
    stopped: np.ndarray | None  # bool: a row flagged by a ``stops`` column
    fmt: str
    sha256: str  # of the bytes parsed (read once: a file changed meanwhile is not mixed in)


def read_samples(path: str | os.PathLike, m: RecordingMapping,
                 max_bytes: int = rt.MAX_TABLE_BYTES, progress: bool = False) -> Samples:
    """Read a recording's mapped columns, convert them and check their values.

    Raises
    ------
    FileNotFoundError, ValueError
        One line naming the file or the column and the row
        (:func:`swgsim.datasets.recording_table.read_table`,
        :func:`~swgsim.datasets.recording_table.numeric`): a
        missing column, a non-numeric or non-finite value, a bridge beyond
        ±:data:`MAX_BRIDGE_MVV` mV/V, a speed beyond the catalogue's 6500 rpm, a torque
        beyond its momentary peak (191 N m), a temperature outside
        :data:`TEMPERATURE_RANGE_C`, a power beyond ±:data:`MAX_POWER_W` W.
    """
    cols = {c: k for k, c in mapping_columns(m).items()}
    df, fmt, digest = rt.read_table(path, cols, max_bytes, progress)
    stamp = m.clock.column if m.clock is not None and m.clock.unit == "datetime" else None
    v = {c: (rt.datetime_seconds if c == stamp else rt.flag if c in m.stops else rt.numeric)(
        df, c, k, fmt) for c, k in cols.items()}
    del df
    stopped = np.any([v[c] for c in m.stops], axis=0) if m.stops else None
    b = m.bridges
    mvv = np.stack([v[c] for c in b.columns])
    if b.unit == "counts":
        cal = np.array([[c.gain_mvv_per_count, c.offset_counts] for c in b.calibration])
        mvv = cal[:, :1] * (mvv - cal[:, 1:])
    for i, c in enumerate(b.columns):
        rt.check_limit(mvv[i], -MAX_BRIDGE_MVV, MAX_BRIDGE_MVV, c, f"bridges.columns[{i}]",
                       "mV/V", fmt, "raw counts (bridges.unit: counts, with a calibration), "
                       "or a wrong calibration or unit")
    speed = v[m.speed.column] * SPEED_UNITS[m.speed.unit]
    rt.check_limit(speed, -MAX_INPUT_SPEED_RPM, MAX_INPUT_SPEED_RPM, m.speed.column,
                   "speed.column", "rpm", fmt, "beyond the catalogue's maximum input speed "
                   "(rad/s given as rpm, or the output's speed?)")
    rt.check_limit(v[m.torque], -MOMENTARY_PEAK_TORQUE_NM, MOMENTARY_PEAK_TORQUE_NM, m.torque,
                   "torque", "N m", fmt, "beyond the catalogue's momentary peak torque (N mm?)")
    temp = None if m.temperature is None else v[m.temperature]
    if temp is not None:
        rt.check_limit(temp, *TEMPERATURE_RANGE_C, m.temperature, "temperature", "degC", fmt,
                       "a joint's temperature in degC (kelvin or degF?)")
    if m.power is not None:
        for c, key in ((m.power.input, "power.input"), (m.power.output, "power.output")):
            rt.check_limit(v[c], -MAX_POWER_W, MAX_POWER_W, c, key, "W", fmt,
                           "beyond the catalogue's speed times its momentary peak torque "
                           "(mW, or kW given as W?)")

    def angle(a: Angle | None) -> np.ndarray | None:
        if a is None:
            return None
        return v[a.column] * (2 * np.pi / a.counts_per_rev if a.unit == "counts" else 1.0)

    clock = None
    if m.clock is not None:
        c = v[m.clock.column]
        clock = c if m.clock.unit == "h" else c - c[0]
    return Samples(v[m.time], clock, mvv, speed, v[m.torque], angle(m.input_angle),
                   angle(m.output_angle), temp,
                   None if m.power is None else v[m.power.input],
                   None if m.power is None else v[m.power.output], stopped, fmt, digest)


# ------------------------------------------------------------------ windows and the stream
def _angles(s: Samples, m: RecordingMapping, starts: np.ndarray) -> dict[str, np.ndarray]:
    """The angle channels unwrapped inside each segment and checked against the speed and
    each other (:mod:`swgsim.datasets.recording_table`): name -> shape (n,) [rad]."""
    out = {}
    if s.phi_in is None:
        return out
    a = m.input_angle
    res = 2 * np.pi / a.counts_per_rev
    name = rt.column_name(a.column, "input_angle.column")
    out["phi_in_meas"] = rc.unwrap_segments(s.phi_in, starts, 2 * np.pi)
    rc.check_angle_turns(out["phi_in_meas"], s.speed_rpm, starts, res, name, s.fmt)
    rc.check_angle_speed(out["phi_in_meas"], s.speed_rpm, s.time_s, starts, res,
                         (name, rt.column_name(m.speed.column, "speed.column")), s.fmt)
    if s.phi_out is not None:
        o = m.output_angle
        out["phi_out_meas"] = rc.unwrap_segments(s.phi_out, starts, 2 * np.pi)
        rc.check_output_angle(out["phi_out_meas"], out["phi_in_meas"], starts, m.ratio,
                              2 * np.pi / o.counts_per_rev,
                              rt.column_name(o.column, "output_angle.column"), s.fmt)
    return out


def _hours(s: Samples, m: RecordingMapping, starts: np.ndarray, seg: np.ndarray,
           w0: np.ndarray) -> tuple[np.ndarray, float]:
    """Each window's hour and the hour of the recording's first row
    (DATASET.md, "Imported recordings").

    Raises
    ------
    ValueError
        A segment that begins before the previous one ended (hours not increasing).
    """
    first = starts[seg]
    if s.clock is None:
        base, h0 = (s.time_s[first] - s.time_s[0]) / 3600.0, 0.0
    elif m.clock.unit == "h":
        base, h0 = s.clock[first], float(s.clock[0])
    else:
        base, h0 = s.clock[first] / 3600.0, 0.0
    hour = base + (s.time_s[w0] - s.time_s[first]) / 3600.0
    bad = np.flatnonzero(np.diff(hour) <= 0)
    if bad.size:  # only with a clock column: the time column alone never goes back
        k = int(bad[0]) + 1
        raise ValueError(f"{rt.column_name(m.clock.column, 'clock.column')}, "
                         f"{rt.row_name(int(w0[k]), s.fmt)}: the window there is at "
                         f"{hour[k]:.6f} h, not after the one before ({hour[k - 1]:.6f} h): the "
                         "clock must count operating time (a segment begins before the "
                         "previous one ended)")
    return hour, h0


def _select(s: Samples, m: RecordingMapping, w0: np.ndarray, n_t: int, hour: np.ndarray,
            h0: float) -> tuple[np.ndarray, np.ndarray, dict]:
    """The windows taken (indices into ``w0``), their operating points (indices into the
    declared ones) and the counts of the summary; a window in a stop is never taken."""
    op = m.operating_points
    pts = np.asarray(op.points, float)
    sp, tq = rt.window_reduce(s.speed_rpm, w0, n_t), rt.window_reduce(s.torque_nm, w0, n_t)
    k = rt.assign_points(sp, rt.window_reduce(s.speed_rpm, w0, n_t, "min"),
                         rt.window_reduce(s.speed_rpm, w0, n_t, "max"), tq, pts,
                         op.speed_tolerance_rpm, op.torque_tolerance_nm)
    stopped = (np.zeros(w0.size, bool) if s.stopped is None
               else rt.window_reduce(s.stopped.astype(float), w0, n_t, "max") > 0)
    k[stopped] = -1
    cand = np.flatnonzero(k >= 0)
    if cand.size == 0:
        raise ValueError(f"operating_points: no window is at a declared point within "
                         f"{op.speed_tolerance_rpm:g} rpm and {op.torque_tolerance_nm:g} N m "
                         f"(steady); the windows' mean speeds span [{sp.min():.6g}, "
                         f"{sp.max():.6g}] rpm, their torques [{tq.min():.6g}, {tq.max():.6g}] "
                         f"N m; declared: {op.points}")
    take = cand[rt.thin(hour[cand], m.interval_min / 60.0, m.window_s / 3600.0)]
    comm = hour[take] - h0 < m.commissioning_h
    if not comm[0] or comm.all():
        raise ValueError(f"commissioning_h={m.commissioning_h:g}: "
                         + ("no window at a declared point lies in it" if not comm[0] else
                            f"it covers every window (the last at {hour[take[-1]]:.6g} h); "
                            "nothing is left to monitor"))
    names, counts = np.unique(k[take][comm], return_counts=True)
    unseen = np.setdiff1d(k[take], names)
    if unseen.size:  # the monitor has no normal behaviour there
        raise ValueError(f"commissioning_h={m.commissioning_h:g}: no commissioning window at "
                         f"operating_points.points[{unseen[0]}] {op.points[unseen[0]]}, which "
                         "later windows are at; lengthen the commissioning or drop the point")
    return take, k[take], {
        "windows_cut": int(w0.size), "stopped_windows": int(stopped.sum()),
        "outside_points": int(w0.size - stopped.sum() - cand.size),
        "windows": int(take.size), "commissioning_windows": {
            f"{pts[i, 0]:g} rpm, {pts[i, 1]:g} N m": int(c) for i, c in zip(names, counts,
                                                                              strict=True)},
        "hours": [float(hour[take[0]]), float(hour[take[-1]])],
        "speed_offset_rpm": float(np.max(np.abs(sp[take] - pts[k[take], 0]))),
        "mean_rpm": sp[take], "mean_nm": tq[take]}


def recording_stream(path: str | os.PathLike, m: RecordingMapping,
                     max_bytes: int = rt.MAX_TABLE_BYTES, progress: bool = False):
    """A recording as a stream in memory (DATASET.md, "Imported recordings"); nothing is written.

    Parameters
    ----------
    path : path-like
        The recording's table.
    m : RecordingMapping
    max_bytes : int
        Largest table read [bytes].
    progress : bool

    Returns
    -------
    (xarray.Dataset, dict)
        The stream (schema v1 with ``hour``, ``commissioning``, ``recording_row`` and,
        where the recording has them, ``temperature_c``, ``phi_in_meas``,
        ``phi_out_meas``) and a summary: ``rows``, ``segments``, ``sample_rate_hz``,
        ``window_samples``, ``windows_cut``, ``stopped_windows`` (in a stop, left out),
        ``outside_points`` (of the others), ``windows``,
        ``commissioning_windows`` per operating point, ``hours`` (first, last),
        ``speed_offset_rpm`` (the largest distance of a window's mean speed from its
        point's [rpm]: without an input angle the monitor fits at the point's speed).

    Raises
    ------
    FileNotFoundError, ValueError
        One line naming the column and the row (:func:`read_samples`, the checks of
        :mod:`swgsim.datasets.recording_table`), or no window at a declared point, no
        commissioning window or nothing after commissioning.
    """
    p = Path(path).expanduser()
    s = read_samples(p, m, max_bytes, progress)
    n = s.time_s.size
    clock_s = None if s.clock is None else (
        (s.clock - s.clock[0]) * 3600.0 if m.clock.unit == "h" else s.clock)
    names = (rt.column_name(m.time, "time"), None if m.clock is None
             else rt.column_name(m.clock.column, "clock.column"))
    starts = rc.segment_starts(s.time_s, clock_s, m.window_s, names, s.fmt)
    fs, n_t = rc.check_sampling(s.time_s, starts, m.window_s, m.sample_rate_hz,
                                m.rate_tolerance, names[0], s.fmt)
    angles = _angles(s, m, starts)
    w0, seg = rt.window_starts(starts, n, n_t)
    if w0.size == 0:
        longest = int(np.max(np.diff(np.append(starts, n))))
        raise ValueError(f"{names[0]}: no segment holds a whole window of {n_t} samples "
                         f"({m.window_s:g} s); the longest holds {longest}")
    hour, h0 = _hours(s, m, starts, seg, w0)
    take, point, info = _select(s, m, w0, n_t, hour, h0)
    win = w0[take]
    idx = win[:, None] + np.arange(n_t)  # (n_w, n_t) rows of each window
    comm = hour[take] - h0 < m.commissioning_h
    pts = np.asarray(m.operating_points.points, float)[point]
    meta = _window_meta(s, m, win, n_t, comm, pts, info)
    sig = s.bridges_mvv[:, idx].transpose(1, 0, 2)  # (n_w, 5, n_t)
    ds = make_dataset(sig, np.arange(n_t) / fs, meta,
                      {"config": _stream_config(p, m, n, s.sha256, fs, n_t),
                       "gear_id": int(m.gear),
                       "shard": f"gear{int(m.gear)}_recording.nc"})
    ds["hour"] = ("sample", hour[take], {"units": "h"})
    ds["commissioning"] = ("sample", comm)
    ds["recording_row"] = ("sample", win.astype(np.int64))
    if s.temperature_c is not None:
        ds["temperature_c"] = ("sample", rt.window_reduce(s.temperature_c, win, n_t),
                               {"units": "degC"})
    for k, v in angles.items():
        ds[k] = (("sample", "time"), v[idx], {"units": "rad"})
    ds.attrs.update({"content_sha256": rt.content_hash(ds), "package_version": package_version(),
                     "git_revision": git_revision()})
    return ds, {"recording": str(p), "rows": int(n), "segments": int(starts.size),
                "sample_rate_hz": fs, "window_samples": n_t, **info}


def _window_meta(s, m: RecordingMapping, win: np.ndarray, n_t: int, comm: np.ndarray,
                 pts: np.ndarray, info: dict) -> dict:
    """The windows' metadata (schema v1): commissioning's windows healthy at severity 0,
    the rest unknown; each window's operating point ``pts`` (n_w, 2) [rpm, N m], its mean
    speed and torque (taken out of ``info``), and its efficiency where the recording has
    both powers (NaN otherwise). ``win``: the windows' first rows, shape (n_w,)."""
    eff = np.full(win.size, np.nan)
    if s.p_in_w is not None:
        pin, pout = rt.window_reduce(s.p_in_w, win, n_t), rt.window_reduce(s.p_out_w, win, n_t)
        eff = np.divide(pout, pin, out=eff, where=pin != 0)
    return {"gear": np.full(win.size, m.gear), "fault": np.where(comm, "healthy", "unknown"),
            "variant": np.zeros(win.size, np.int64), "severity": np.where(comm, 0.0, np.nan),
            "position_deg": np.full(win.size, np.nan), "n_in_rpm": pts[:, 0],
            "t_out_nm": pts[:, 1], "disturbed": np.zeros(win.size, bool),
            "reference": np.zeros(win.size, bool), "efficiency": eff,
            "n_in_mean_rpm": info.pop("mean_rpm"), "t_out_mean_nm": info.pop("mean_nm")}


def _stream_config(p: Path, m: RecordingMapping, n: int, sha256: str, fs: float,
                   n_t: int) -> dict:
    """The stream's ``config`` attribute: the recording (file, ``n`` rows, its SHA-256),
    the mapping, the chain's sampling ``fs`` [Hz] and window of ``n_t`` samples, and the
    input sensor where the recording has one (as a profile data set names it); the
    mapping's ``stops`` left out when none, so that a stream keeps the config hash it had
    before stops were mapped."""
    plain = dataclasses.asdict(m)
    if not m.stops:
        del plain["stops"]
    config = {"name": f"recording {p.name}", "recording": {"file": p.name, "rows": int(n),
                                                           "sha256": sha256},
              "mapping": plain,
              "chain": {"sample_rate_hz": fs, "window_s": n_t / fs}}
    if m.input_angle is not None:
        config["profile"] = {"angles": {"input_counts_per_rev": m.input_angle.counts_per_rev}}
    return config


# ------------------------------------------------------------------ writing
def _survey(out: Path, overwrite: bool) -> ownership.Survey:
    """``out_dir`` checked (:func:`swgsim.files.ownership.check`); files of this project
    in it refused without ``overwrite``."""
    found = ownership.check(out, "out_dir", app=APP)  # another app's output refused
    if found.owned and not overwrite:
        raise ValueError(f"out_dir {out} holds {len(found.owned)} file(s) a run of this project "
                         "wrote (a stream or data set); pass overwrite=true to replace them, "
                         "or choose another out_dir")
    return found


def _unchanged_since(out: Path, found: ownership.Survey) -> None:
    """Under the claim of ``out`` (no other run can write there now): refuse if a file
    appeared, changed or went since ``found`` was surveyed, before the import's long read
    (another import into the same folder finished meanwhile, issue 43); nothing replaced."""
    now = ownership.survey(out)
    changed = sorted({*now.foreign, *(r for r in {*now.owned, *found.owned}
                                      if now.owned.get(r) != found.owned.get(r))})
    if changed:
        more = f" and {len(changed) - 1} more file(s)" if len(changed) > 1 else ""
        raise ValueError(f"out_dir {out}: {changed[0]}{more} written there by another run "
                         "since this import checked the folder; nothing was replaced: "
                         "import again (with overwrite=true to replace it) or choose "
                         "another out_dir")


def write_stream(ds, out_dir: str | os.PathLike, overwrite: bool = False,
                 found: ownership.Survey | None = None) -> dict:
    """Write a stream of :func:`recording_stream` as a data set: its shard, sidecar and
    ``manifest.json`` (last), each atomically and listed in the folder's ownership stamp
    (:mod:`swgsim.files.ownership`) before it is renamed into place.

    Parameters
    ----------
    ds : xarray.Dataset
    out_dir : path-like
    overwrite : bool
        Replace what a run of this project wrote there (a stream or a data set).
    found : swgsim.files.ownership.Survey, optional
        A survey of ``out_dir`` just made (:func:`swgsim.files.ownership.check`).

    Returns
    -------
    dict
        The manifest.

    Raises
    ------
    ValueError
        ``out_dir`` holds a file this project cannot show it wrote (named), or files of
        this project without ``overwrite``; before anything is touched. Or, checked again
        under the folder's claim right before writing, a file written, changed or removed
        there since ``found`` was made (another run's); nothing replaced.
    """
    out = Path(out_dir)
    found = _survey(out, overwrite) if found is None else found
    cfg = json.loads(ds.attrs["config"])
    name, chash = str(ds.attrs["shard"]), config_digest(cfg)
    with ownership.claim(out, APP, found=found, strict=True) as claim:
        _unchanged_since(out, found)
        if found.owned:
            claim.remove(found.owned)
        entry = {"sha256": write_shard(ds, out / name), "n_samples": int(ds.sizes["sample"]),
                 "content_sha256": str(ds.attrs["content_sha256"])}
        atomic_write_json((out / name).with_suffix(".json"), {**entry, "config_hash": chash})
        manifest = {"schema_version": SCHEMA_VERSION, "complete": True, "config_hash": chash,
                    "config": cfg, "seed": None, "n_shards": 1, "shards": {name: entry},
                    "content_sha256": hashlib.sha256(
                        entry["content_sha256"].encode()).hexdigest(),
                    "package_version": package_version(), "git_revision": git_revision(),
                    "library_versions": library_versions(), "n_samples": entry["n_samples"]}
        atomic_write_json(out / MANIFEST, manifest)
    return manifest


def import_recording(recording: str | os.PathLike,
                     mapping: RecordingMapping | Mapping[str, Any] | str | os.PathLike,
                     out_dir: str | os.PathLike, overwrite: bool = False,
                     max_bytes: int = rt.MAX_TABLE_BYTES, progress: bool = False) -> dict:
    """Import a recording as a stream the monitor reads (DATASET.md, "Imported recordings").

    Everything is checked before anything is written: the mapping, ``out_dir``
    (:func:`write_stream`'s refusals), the table and its windows
    (:func:`recording_stream`).

    Parameters
    ----------
    recording : path-like
        The table, CSV or Parquet.
    mapping : RecordingMapping, mapping or path-like
        The mapping, its plain data, or its YAML file (:func:`read_mapping`).
    out_dir : path-like
        The stream's folder.
    overwrite : bool
        Replace a stream or data set this project wrote there.
    max_bytes : int
        Largest table read [bytes] (default
        :data:`swgsim.datasets.recording_table.MAX_TABLE_BYTES`, 1 GiB).
    progress : bool

    Returns
    -------
    dict
        :func:`recording_stream`'s summary with ``out_dir`` and ``content_sha256``.

    Raises
    ------
    FileNotFoundError, ValueError
        One line naming the file, key, column or row.
    """
    if isinstance(mapping, RecordingMapping):
        m = mapping
    elif isinstance(mapping, Mapping):
        m = recording_mapping(mapping)
    else:
        m = read_mapping(mapping)
    out = Path(out_dir).expanduser()
    found = _survey(out, overwrite)
    ds, summary = recording_stream(recording, m, max_bytes, progress)
    manifest = write_stream(ds, out, overwrite, found)
    log.info("imported %s: %d windows -> %s", recording, summary["windows"], out)
    return {**summary, "out_dir": str(out), "content_sha256": manifest["content_sha256"]}
