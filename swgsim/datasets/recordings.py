"""A user's recording of a sensorized joint as a stream the condition monitor reads.

A *recording* is a table (CSV or Parquet, one row per sample) of a joint's five bridges,
its input speed and output torque, optionally its input and output angles, the joint's
temperature, the input and output power, and a clock (operating hours or wall-clock
time). A small YAML, the *mapping* (:class:`RecordingMapping`), names its columns and
units and declares the gear's operating points and commissioning period;
:func:`import_recording` checks both before any work, cuts the recording into windows and
writes them as a schema-v1 stream (``docs/DATASET.md``, "Imported recordings"), the
same a life of ``swgsim-generate`` is, so that ``swgsim-monitor`` reads it. The user's
guide is ``docs/OWN_JOINT.md``; an example mapping is ``examples/own_joint_mapping.yaml``.

How the windows are made (:mod:`swgsim.datasets.recording_table` does the array work):

* **segments**: a new segment begins where the clock advances by more than one window
  since the previous row (a logger's bursts); inside a segment the time column advances
  by the sample period (within ``rate_tolerance``), a longer gap is refused;
* **windows**: each segment is cut from its first row into consecutive windows of
  ``round(window_s * rate)`` samples; a window's ``hour`` is the clock at its segment's
  first row plus the time since that row (operating hours as the clock column counts
  them; with a wall clock or none, hours since the recording's first row);
* **operating points**: a window is at a declared point (``n_in_rpm``, ``t_out_nm`` of
  the stream, the keys of the monitor's normal behaviour) when its mean speed and mean
  torque lie within the tolerances of it and every sample's speed within the speed
  tolerance (a steady window); other windows are counted and left out;
* **interval**: of the windows at a point, the first is taken, then each first one at
  least ``interval_min`` minutes of operation (less one window) after the last taken;
* **commissioning**: the windows of the first ``commissioning_h`` hours, known healthy.

Per window the stream holds the bridges (mV/V; raw counts through each bridge's
calibration, ``mV/V = gain * (count - offset)``), ``n_in_mean_rpm`` and ``t_out_mean_nm``
(the means of the speed and torque columns), ``efficiency`` (mean output power over mean
input power, NaN without power columns or where the input power averages to zero), the
angle channels ``phi_in_meas`` and ``phi_out_meas`` [rad] (unwrapped inside each segment,
on the window's samples), ``temperature_c`` (the window's mean), ``hour``,
``commissioning`` and ``recording_row`` (the table row of the window's first sample).
``fault`` is ``healthy`` in commissioning (declared so) and ``unknown`` after it;
``severity`` 0 and NaN likewise.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from swgsim.base.typed import allowed, build, check_finite, complete
from swgsim.datasets import recording_table as rt
from swgsim.datasets.schedule import LifeConfig
from swgsim.datasets.schema import MANIFEST, SCHEMA_VERSION, SENSORS, make_dataset, write_shard
from swgsim.files import ownership
from swgsim.files.digest import config_digest, sha256_file
from swgsim.files.ownership import atomic_write_json
from swgsim.files.provenance import git_revision, library_versions, package_version
from swgsim.gear.chain import ChainSettings
from swgsim.gear.dynamics import GearParams
from swgsim.gear.profile import MAX_INPUT_SPEED_RPM, MOMENTARY_PEAK_TORQUE_NM

log = logging.getLogger(__name__)

__all__ = ["Angle", "BridgeCalibration", "Bridges", "Clock", "MAX_BRIDGE_MVV",
           "MAX_MAPPING_BYTES", "OperatingPoints", "Power", "RecordingMapping", "Speed",
           "TEMPERATURE_RANGE_C", "check_mapping", "import_recording", "read_mapping",
           "recording_mapping", "recording_stream", "write_stream"]

#: Units of the bridge columns.
BRIDGE_UNITS = ("mV/V", "counts")
#: Units of the speed column and their factor to rpm.
SPEED_UNITS = {"rpm": 1.0, "rad/s": 60.0 / (2 * np.pi)}
#: Units of an angle column.
ANGLE_UNITS = ("rad", "counts")
#: Units of the clock column: operating hours, seconds, or wall-clock time stamps.
CLOCK_UNITS = ("h", "s", "datetime")
#: Largest bridge output accepted [mV/V]: a full-bridge of gauges of factor 2 at 5000
#: µm/m gives 10 mV/V, beyond a flexspline's elastic strain (the paper's bridges stay
#: under 1 mV/V); a larger value is raw counts or another unit.
MAX_BRIDGE_MVV = 10.0
#: Joint temperatures accepted [degC]: beyond a grease's and a gauge's range; a value
#: outside is kelvin or degF.
TEMPERATURE_RANGE_C = (-50.0, 150.0)
#: Largest mapping YAML read [bytes].
MAX_MAPPING_BYTES = 1 << 20
#: The app that writes imported streams (their ownership stamp's ``apps``).
APP = "swgsim-import"


@dataclass
class BridgeCalibration:
    """One bridge's raw counts to mV/V: ``mV/V = gain_mvv_per_count * (count -
    offset_counts)``."""

    gain_mvv_per_count: float
    offset_counts: float = 0.0


@dataclass
class Bridges:
    """The five bridge columns, s0..s4 in order (``docs/DATASET.md``)."""

    columns: list[str] = field(default_factory=lambda: list(SENSORS))
    unit: str = "mV/V"   # mV/V or counts (then a calibration per bridge)
    calibration: list[BridgeCalibration] = field(default_factory=list)


@dataclass
class Speed:
    """The input (wave-generator) speed column, positive where the input angle grows."""

    column: str = "n_in_rpm"
    unit: str = "rpm"    # rpm or rad/s


@dataclass
class Angle:
    """An angle column: the input (drive) shaft's, or the output encoder's."""

    column: str
    counts_per_rev: int = field(metadata=allowed(1, 2**32, "sensor counts per revolution"))
    unit: str = "rad"    # rad or counts


@dataclass
class Clock:
    """The clock column: operating hours (``h``), seconds (``s``) or wall-clock time
    stamps (``datetime``, ISO 8601)."""

    column: str
    unit: str = "h"


@dataclass
class Power:
    """Input and output power columns [W], both positive when the motor drives the load."""

    input: str
    output: str


@dataclass
class OperatingPoints:
    """The gear's operating points, [n_in_rpm, t_out_nm] each, and how near a window's
    speed and torque must be to count as at one (module docstring)."""

    points: list[list[float]]
    speed_tolerance_rpm: float = field(default=100.0, metadata=allowed(0.0, 1000.0))
    torque_tolerance_nm: float = field(default=3.0, metadata=allowed(0.0, 100.0))


@dataclass
class RecordingMapping:
    """A recording's columns and units and how its windows are made (module docstring;
    ``docs/OWN_JOINT.md``).

    Attributes
    ----------
    operating_points : OperatingPoints
    commissioning_h : float
        The first hours of the recording, known healthy [h].
    time : str
        Time column [s].
    bridges, speed : Bridges, Speed
    torque : str
        Output torque column [N m].
    input_angle, output_angle : Angle or None
    temperature : str or None
        Joint temperature column [degC].
    clock : Clock or None
        None: the time column counts operating time.
    power : Power or None
    gear : int
        The gear's id in the stream.
    ratio : float
        Gear ratio N (the output angle's check).
    window_s : float
        Window length [s] (the data sets' default).
    interval_min : float
        Minutes of operation between windows taken (0: every window).
    sample_rate_hz : float or None
        The logger's nominal rate [Hz]; None: from the time column's median step.
    rate_tolerance : float
        Largest relative deviation of a time step from the sample period.
    """

    operating_points: OperatingPoints
    commissioning_h: float = field(metadata=allowed(0.0, 1e6, "h"))
    time: str = "time_s"
    bridges: Bridges = field(default_factory=Bridges)
    speed: Speed = field(default_factory=Speed)
    torque: str = "t_out_nm"
    input_angle: Angle | None = None
    output_angle: Angle | None = None
    temperature: str | None = None
    clock: Clock | None = None
    power: Power | None = None
    gear: int = field(default=1, metadata=allowed(0, None, "the stream's gear id"))
    ratio: float = field(default=GearParams.ratio, metadata=allowed(1.0, 1000.0))
    window_s: float = field(default=ChainSettings.window_s, metadata=allowed(0.0, 10.0, "s"))
    interval_min: float = field(default=LifeConfig.interval_min,
                                metadata=allowed(0.0, 1440.0, "min"))
    sample_rate_hz: float | None = field(default=None, metadata=allowed(1.0, 1e7, "Hz"))
    rate_tolerance: float = field(default=0.01, metadata=allowed(0.0, 0.5))


def _one_of(value: str, options, key: str) -> None:
    if value not in options:
        raise ValueError(f"{key}: must be one of {', '.join(options)}, got {value!r}")


def check_mapping(m: RecordingMapping) -> None:
    """Refuse a mapping that cannot be right, before any work.

    Raises
    ------
    ValueError
        One line naming the key: a unit not of its list, a calibration missing or not
        one per bridge (or a zero gain), not five bridge columns, a column mapped twice,
        no operating point, a point not [speed, torque] or beyond the catalogue's limits,
        two points whose tolerances overlap, a window or commissioning period of zero.
    """
    b = m.bridges
    _one_of(b.unit, BRIDGE_UNITS, "bridges.unit")
    if len(b.columns) != len(SENSORS):
        raise ValueError(f"bridges.columns: {len(b.columns)} columns; the five bridges "
                         f"s0..s4 in order")
    if b.unit == "counts" and len(b.calibration) != len(SENSORS):
        raise ValueError(f"bridges.calibration: {len(b.calibration)} entries; with "
                         "unit counts one {gain_mvv_per_count, offset_counts} per bridge")
    for i, c in enumerate(b.calibration):
        if c.gain_mvv_per_count == 0:
            raise ValueError(f"bridges.calibration[{i}].gain_mvv_per_count: 0")
    _one_of(m.speed.unit, tuple(SPEED_UNITS), "speed.unit")
    for k in ("input_angle", "output_angle"):
        if getattr(m, k) is not None:
            _one_of(getattr(m, k).unit, ANGLE_UNITS, f"{k}.unit")
    if m.output_angle is not None and m.input_angle is None:
        raise ValueError("output_angle: needs input_angle (the wave generator's "
                         "angle is the input's less the output's)")
    if m.clock is not None:
        _one_of(m.clock.unit, CLOCK_UNITS, "clock.unit")
    seen: dict[str, str] = {}
    for key, col in _columns(m).items():
        if col in seen:
            raise ValueError(f"{key}: column {col!r} is mapped twice (also "
                             f"{seen[col]})")
        seen[col] = key
    if m.window_s <= 0 or m.commissioning_h <= 0:
        raise ValueError(f"{'window_s' if m.window_s <= 0 else 'commissioning_h'}: "
                         "must be > 0")
    _check_points(m.operating_points, "operating_points")


def _check_points(op: OperatingPoints, key: str) -> None:
    """Declared operating points: [speed, torque] within the catalogue, boxes apart."""
    if not op.points:
        raise ValueError(f"{key}.points: empty; declare the gear's operating points as "
                         "[[n_in_rpm, t_out_nm], ...]")
    for i, p in enumerate(op.points):
        if len(p) != 2:
            raise ValueError(f"{key}.points[{i}]: {p}; a point is [n_in_rpm, t_out_nm]")
        if abs(p[0]) > MAX_INPUT_SPEED_RPM or abs(p[1]) > MOMENTARY_PEAK_TORQUE_NM:
            raise ValueError(f"{key}.points[{i}]: {p} beyond the catalogue's "
                             f"{MAX_INPUT_SPEED_RPM:g} rpm and {MOMENTARY_PEAK_TORQUE_NM:g} N m")
    pts = np.asarray(op.points, float)
    for i in range(len(pts)):
        for j in range(i):
            if (abs(pts[i, 0] - pts[j, 0]) <= 2 * op.speed_tolerance_rpm
                    and abs(pts[i, 1] - pts[j, 1]) <= 2 * op.torque_tolerance_nm):
                raise ValueError(f"{key}.points[{i}]: {op.points[i]} lies within twice the "
                                 f"tolerances of points[{j}] {op.points[j]}: a window could "
                                 "be at both; lower speed_tolerance_rpm or torque_tolerance_nm")


def _columns(m: RecordingMapping) -> dict[str, str]:
    """Mapping key -> column name of every column the mapping reads."""
    out = {"time": m.time, **{f"bridges.columns[{i}]": c for i, c in enumerate(m.bridges.columns)},
           "speed.column": m.speed.column, "torque": m.torque}
    for k in ("input_angle", "output_angle"):
        if getattr(m, k) is not None:
            out[f"{k}.column"] = getattr(m, k).column
    if m.temperature is not None:
        out["temperature"] = m.temperature
    if m.clock is not None:
        out["clock.column"] = m.clock.column
    if m.power is not None:
        out.update({"power.input": m.power.input, "power.output": m.power.output})
    return out


def recording_mapping(cfg: Mapping[str, Any]) -> RecordingMapping:
    """The typed mapping of plain data (a YAML's), every key and value checked.

    Raises
    ------
    ValueError
        One line naming the key by its full name: unknown (with the allowed ones),
        missing, of the wrong type, out of its range, not finite, or
        :func:`check_mapping`.
    """
    if not isinstance(cfg, Mapping):
        raise ValueError(f"must be a mapping of keys (time, bridges, speed, ...), got "
                         f"{type(cfg).__name__}")
    m = build(complete(cfg, RecordingMapping, ""), RecordingMapping)
    for f in dataclasses.fields(m):
        check_finite(getattr(m, f.name), f.name)
    check_mapping(m)
    return m


def read_mapping(path: str | os.PathLike) -> RecordingMapping:
    """Read a mapping YAML (a regular file of at most :data:`MAX_MAPPING_BYTES`).

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    ValueError
        ``<path>: <full key>: ...`` (:func:`recording_mapping`), or the file is not YAML.
    """
    import yaml

    p = rt.check_file(path, "mapping", MAX_MAPPING_BYTES)
    try:
        cfg = yaml.safe_load(p.read_text(encoding="utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError) as e:
        raise ValueError(f"mapping {p}: not YAML ({str(e).splitlines()[0]})") from None
    try:
        return recording_mapping(cfg if cfg is not None else {})
    except ValueError as e:
        raise ValueError(f"mapping {p}: {e}") from None



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
    fmt: str


def read_samples(path: str | os.PathLike, m: RecordingMapping,
                 max_bytes: int = rt.MAX_TABLE_BYTES, progress: bool = False) -> Samples:
    """Read a recording's mapped columns, convert them and check their values.

    Raises
    ------
    FileNotFoundError, ValueError
        One line naming the file or the column and the row (:func:`swgsim.datasets.
        recording_table.read_table`, :func:`~swgsim.datasets.recording_table.numeric`): a
        missing column, a non-numeric or non-finite value, a bridge beyond
        ±:data:`MAX_BRIDGE_MVV` mV/V, a speed beyond the catalogue's 6500 rpm, a torque
        beyond its momentary peak (191 N m), a temperature outside
        :data:`TEMPERATURE_RANGE_C`.
    """
    cols = {c: k for k, c in _columns(m).items()}
    df, fmt = rt.read_table(path, cols, max_bytes, progress)
    stamp = m.clock.column if m.clock is not None and m.clock.unit == "datetime" else None
    v = {c: (rt.datetime_seconds if c == stamp else rt.numeric)(df, c, k, fmt)
         for c, k in cols.items()}
    del df
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
                   None if m.power is None else v[m.power.output], fmt)


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
    out["phi_in_meas"] = rt.unwrap_segments(s.phi_in, starts, 2 * np.pi)
    rt.check_angle_turns(out["phi_in_meas"], s.speed_rpm, starts, res, name, s.fmt)
    rt.check_angle_speed(out["phi_in_meas"], s.speed_rpm, s.time_s, starts, res,
                         (name, rt.column_name(m.speed.column, "speed.column")), s.fmt)
    if s.phi_out is not None:
        o = m.output_angle
        out["phi_out_meas"] = rt.unwrap_segments(s.phi_out, starts, 2 * np.pi)
        rt.check_output_angle(out["phi_out_meas"], out["phi_in_meas"], starts, m.ratio,
                              2 * np.pi / o.counts_per_rev,
                              rt.column_name(o.column, "output_angle.column"), s.fmt)
    return out


def _hours(s: Samples, m: RecordingMapping, starts: np.ndarray, seg: np.ndarray,
           w0: np.ndarray) -> tuple[np.ndarray, float]:
    """Each window's hour and the hour of the recording's first row (module docstring).

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
                         f"{rt.rowrt.column_name(int(w0[k]), s.fmt)}: the window there is at "
                         f"{hour[k]:.6f} h, not after the one before ({hour[k - 1]:.6f} h): the "
                         "clock must count operating time (a segment begins before the "
                         "previous one ended)")
    return hour, h0


def _select(s: Samples, m: RecordingMapping, w0: np.ndarray, n_t: int, hour: np.ndarray,
            h0: float) -> tuple[np.ndarray, np.ndarray, dict]:
    """The windows taken (indices into ``w0``), their operating points (indices into the
    declared ones) and the counts of the summary."""
    op = m.operating_points
    pts = np.asarray(op.points, float)
    sp, tq = rt.window_reduce(s.speed_rpm, w0, n_t), rt.window_reduce(s.torque_nm, w0, n_t)
    k = rt.assign_points(sp, rt.window_reduce(s.speed_rpm, w0, n_t, "min"),
                         rt.window_reduce(s.speed_rpm, w0, n_t, "max"), tq, pts,
                         op.speed_tolerance_rpm, op.torque_tolerance_nm)
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
        "windows_cut": int(w0.size), "outside_points": int(w0.size - cand.size),
        "windows": int(take.size), "commissioning_windows": {
            f"{pts[i, 0]:g} rpm, {pts[i, 1]:g} N m": int(c) for i, c in zip(names, counts,
                                                                              strict=True)},
        "hours": [float(hour[take[0]]), float(hour[take[-1]])],
        "speed_offset_rpm": float(np.max(np.abs(sp[take] - pts[k[take], 0]))),
        "mean_rpm": sp[take], "mean_nm": tq[take]}


def recording_stream(path: str | os.PathLike, m: RecordingMapping,
                     max_bytes: int = rt.MAX_TABLE_BYTES, progress: bool = False):
    """A recording as a stream in memory (module docstring); nothing is written.

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
        ``window_samples``, ``windows_cut``, ``outside_points``, ``windows``,
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
    starts = rt.segment_starts(s.time_s, clock_s, m.window_s, names, s.fmt)
    fs, n_t = rt.check_sampling(s.time_s, starts, m.window_s, m.sample_rate_hz,
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
    eff = np.full(win.size, np.nan)
    if s.p_in_w is not None:
        pin, pout = rt.window_reduce(s.p_in_w, win, n_t), rt.window_reduce(s.p_out_w, win, n_t)
        eff = np.divide(pout, pin, out=eff, where=pin != 0)
    meta = {"gear": np.full(win.size, m.gear), "fault": np.where(comm, "healthy", "unknown"),
            "variant": np.zeros(win.size, np.int64), "severity": np.where(comm, 0.0, np.nan),
            "position_deg": np.full(win.size, np.nan), "n_in_rpm": pts[:, 0],
            "t_out_nm": pts[:, 1], "disturbed": np.zeros(win.size, bool),
            "reference": np.zeros(win.size, bool), "efficiency": eff,
            "n_in_mean_rpm": info.pop("mean_rpm"), "t_out_mean_nm": info.pop("mean_nm")}
    config = {"name": f"recording {p.name}", "recording": {"file": p.name, "rows": int(n),
                                                           "sha256": sha256_file(p)},
              "mapping": dataclasses.asdict(m),
              "chain": {"sample_rate_hz": fs, "window_s": n_t / fs}}
    if m.input_angle is not None:  # the input sensor, as a profile data set names it
        config["profile"] = {"angles": {"input_counts_per_rev": m.input_angle.counts_per_rev}}
    sig = s.bridges_mvv[:, idx].transpose(1, 0, 2)  # (n_w, 5, n_t)
    ds = make_dataset(sig, np.arange(n_t) / fs, meta,
                      {"config": config, "gear_id": int(m.gear),
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
        this project without ``overwrite``; before anything is touched.
    """
    out = Path(out_dir)
    found = _survey(out, overwrite) if found is None else found
    cfg = json.loads(ds.attrs["config"])
    name, chash = str(ds.attrs["shard"]), config_digest(cfg)
    with ownership.claim(out, APP, found=found, strict=True) as claim:
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
    """Import a recording as a stream the monitor reads (module docstring).

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
        Largest table read [bytes] (default :data:`swgsim.datasets.recording_table.
        MAX_TABLE_BYTES`, 1 GiB).
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
