"""The mapping of a user's recording: its columns and units, the gear's operating points
and commissioning period, checked before any work (:mod:`swgsim.datasets.recordings`
imports the recording with it; the user's guide is ``docs/OWN_JOINT.md``, an example
``examples/own_joint_mapping.yaml``).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from swgsim.base.typed import allowed, build, check_tree, complete
from swgsim.base.user_yaml import clip, user_yaml
from swgsim.datasets import recording_table as rt
from swgsim.datasets.schedule import LifeConfig
from swgsim.datasets.schema import MAX_BRIDGE_MVV, SENSORS
from swgsim.gear.chain import ChainSettings
from swgsim.gear.dynamics import GearParams
from swgsim.gear.profile import MAX_INPUT_SPEED_RPM, MOMENTARY_PEAK_TORQUE_NM

__all__ = ["ANGLE_UNITS", "Angle", "BRIDGE_UNITS", "BridgeCalibration", "Bridges",
           "CLOCK_UNITS", "Clock", "MAX_BRIDGE_MVV", "MAX_MAPPING_BYTES", "OperatingPoints",
           "Power", "RecordingMapping", "SPEED_UNITS", "Speed",
           "mapping_columns", "read_mapping", "recording_mapping"]

#: Units of the bridge columns.
BRIDGE_UNITS = ("mV/V", "counts")
#: Units of the speed column and their factor to rpm.
SPEED_UNITS = {"rpm": 1.0, "rad/s": 60.0 / (2 * np.pi)}
#: Units of an angle column.
ANGLE_UNITS = ("rad", "counts")
#: Units of the clock column: operating hours, seconds, or wall-clock time stamps.
CLOCK_UNITS = ("h", "s", "datetime")
#: Largest mapping YAML read [bytes].
MAX_MAPPING_BYTES = 1 << 20


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
    stops : list of str
        Event flag columns during which the joint is stopped (a protective stop, an
        emergency stop): true/false, or numbers, nonzero true. A window holding a flagged
        row is left out of the stream (a stopped joint has no load cycle to judge); none:
        every window is operation.
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
    stops: list[str] = field(default_factory=list)
    clock: Clock | None = None
    power: Power | None = None
    gear: int = field(default=1, metadata=allowed(0, None, "the stream's gear id"))
    ratio: float = field(default=GearParams.ratio, metadata=allowed(1.0, 1000.0))
    window_s: float = field(default=ChainSettings.window_s, metadata=allowed(0.0, 10.0, "s"))
    interval_min: float = field(default=LifeConfig.interval_min,
                                metadata=allowed(0.0, 1440.0, "min"))
    sample_rate_hz: float | None = field(default=None, metadata=allowed(1.0, 1e7, "Hz"))
    rate_tolerance: float = field(default=0.01, metadata=allowed(0.0, 0.5))

    def check(self, where: str) -> None:
        """Refuse a mapping that cannot be right, before any work (run by
        :func:`swgsim.base.typed.check_tree`; its fields' ranges are their metadata).

        Parameters
        ----------
        where : str
            Full name of the mapping for messages (``""``: a mapping file's root, its keys
            by their names alone).

        Raises
        ------
        ValueError
            One line naming the key: a unit not of its list, a calibration missing or not
            one per bridge (or a zero gain), not five bridge columns, a column mapped
            twice, no operating point, a point not [speed, torque] or beyond the
            catalogue's limits, two points whose tolerances overlap, a window or
            commissioning period of zero.
        """
        pre = f"{where}." if where else ""
        b = self.bridges
        _one_of(b.unit, BRIDGE_UNITS, f"{pre}bridges.unit")
        if len(b.columns) != len(SENSORS):
            raise ValueError(f"{pre}bridges.columns: {len(b.columns)} columns; the five bridges "
                             f"s0..s4 in order")
        if b.unit == "counts" and len(b.calibration) != len(SENSORS):
            raise ValueError(f"{pre}bridges.calibration: {len(b.calibration)} entries; with "
                             "unit counts one {gain_mvv_per_count, offset_counts} per bridge")
        for i, c in enumerate(b.calibration):
            if c.gain_mvv_per_count == 0:
                raise ValueError(f"{pre}bridges.calibration[{i}].gain_mvv_per_count: 0")
        _one_of(self.speed.unit, tuple(SPEED_UNITS), f"{pre}speed.unit")
        for k in ("input_angle", "output_angle"):
            if getattr(self, k) is not None:
                _one_of(getattr(self, k).unit, ANGLE_UNITS, f"{pre}{k}.unit")
        if self.output_angle is not None and self.input_angle is None:
            raise ValueError(f"{pre}output_angle: needs input_angle (the wave generator's "
                             "angle is the input's less the output's)")
        if self.clock is not None:
            _one_of(self.clock.unit, CLOCK_UNITS, f"{pre}clock.unit")
        seen: dict[str, str] = {}
        for key, col in mapping_columns(self).items():
            if col in seen:
                raise ValueError(f"{pre}{key}: column {col!r} is mapped twice (also "
                                 f"{seen[col]})")
            seen[col] = key
        if self.window_s <= 0 or self.commissioning_h <= 0:
            raise ValueError(f"{pre}{'window_s' if self.window_s <= 0 else 'commissioning_h'}: "
                             "must be > 0")
        _check_points(self.operating_points, f"{pre}operating_points")


def _one_of(value: str, options, key: str) -> None:
    if value not in options:
        raise ValueError(f"{key}: must be one of {', '.join(options)}, got {value!r}")


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


def mapping_columns(m: RecordingMapping) -> dict[str, str]:
    """Mapping key -> column name of every column the mapping reads."""
    out = {"time": m.time, **{f"bridges.columns[{i}]": c for i, c in enumerate(m.bridges.columns)},
           "speed.column": m.speed.column, "torque": m.torque}
    for k in ("input_angle", "output_angle"):
        if getattr(m, k) is not None:
            out[f"{k}.column"] = getattr(m, k).column
    if m.temperature is not None:
        out["temperature"] = m.temperature
    out.update({f"stops[{i}]": c for i, c in enumerate(m.stops)})
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
        :meth:`RecordingMapping.check`.
    """
    if not isinstance(cfg, Mapping):
        raise ValueError(f"must be a mapping of keys (time, bridges, speed, ...), got "
                         f"{type(cfg).__name__}")
    m = build(complete(cfg, RecordingMapping, ""), RecordingMapping)
    check_tree(m, "")  # NaN and infinity, then RecordingMapping.check
    return m


def read_mapping(path: str | os.PathLike) -> RecordingMapping:
    """Read a mapping YAML (a regular file of at most :data:`MAX_MAPPING_BYTES`).

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    ValueError
        ``<path>: <full key>: ...`` (:func:`recording_mapping`), or the file is not YAML,
        gives a key twice or expands to too many values
        (:func:`swgsim.base.user_yaml.user_yaml`); one line, clipped.
    """
    p = rt.check_file(path, "mapping", MAX_MAPPING_BYTES)
    cfg = user_yaml(p, "mapping")
    try:
        return recording_mapping(cfg if cfg is not None else {})
    except ValueError as e:
        raise ValueError(clip(f"mapping {p}: {e}")) from None
