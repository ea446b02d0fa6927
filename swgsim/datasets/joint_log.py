"""A robot controller's log of its joints: temperatures, motor currents and speeds.

The format read is that of the UR3 CobotOps day (M. Tyrovolas, K. Aliev, D. Antonelli and
C. Stylios, "UR3 CobotOps", UCI Machine Learning Repository, 2024, doi:10.24432/C5J891,
CC BY 4.0): a Universal Robots UR3 (six joints, each a strain wave gear) read once a
second from its controller. Fields separated by ``;``, decimal commas, ISO 8601 time stamps,
trailing empty columns; the column names as published (``Temperature_T0`` for joint 0,
``cycle`` with a trailing space). The file is the user's: its path is an input, the
project holds no copy.

The table is read by :func:`swgsim.datasets.recording_table.read_table` (the reader of
``swgsim-import``; bounded, one refusal line naming the file, the column and the row);
here only the mapping of its columns to a :class:`JointLog`. An empty cell is a missing
reading (NaN; the UR3 day has 54 such rows); text where a number or a flag belongs is
refused, naming row and column. Steps over :data:`LOG_GAP_S` are the log's gaps
(:attr:`JointLog.gap_rows`), kept as they are: what the joint did there is unknown.

:func:`write_temperature_table` writes one joint's temperature as a table on operating
hours, ``hour,temperature_c``, which a simulated life replays
(``dataset.life.conditions.temperature_trace`` with ``mode: hours``,
:class:`swgsim.datasets.conditions.TemperatureTrace`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from swgsim.datasets import recording_table as rt
from swgsim.datasets.conditions import HOURS_TABLE_COLUMNS, TRACE_GAP_MIN
from swgsim.datasets.schema import TEMPERATURE_RANGE_C
from swgsim.files.ownership import atomic_write_bytes

__all__ = ["JOINTS", "LOG_COLUMNS", "LOG_GAP_S", "MAX_LOG_ROWS", "READING_RANGES", "JointLog",
           "read_joint_log", "write_joint_log", "write_temperature_table"]

#: Joints of the arm [-] (a UR3: base, shoulder, elbow, three wrists).
JOINTS = 6
#: Physical ranges of the log's readings, refused beyond in one line naming the column
#: and the row (a value outside is a fault of the sensor, a unit mistaken or a file
#: damaged): the joint temperature the importer takes
#: (:data:`swgsim.datasets.schema.TEMPERATURE_RANGE_C`); motor currents up to 100 A and
#: tool currents up to 10 A [choice: over ten times the UR3 day's largest, 6.8 A and
#: 0.6 A]; joint speeds up to 4 pi rad/s [choice: twice the fastest UR joint, a wrist's
#: 360 deg/s; the UR3 day's fastest 2.7 rad/s].
READING_RANGES = {"temperature": TEMPERATURE_RANGE_C, "current": (-100.0, 100.0),
                  "speed": (-4 * np.pi, 4 * np.pi), "tool_current": (-10.0, 10.0)}
#: Most readings (rows) of a joint log read: 1 million, 11.6 days at 1 Hz. What reads it
#: holds a few kB a reading: the reader about 2 kB (measured: 300 k rows, 631 MB), the
#: thermal calibration about 1.1 kB more (72 k and 288 k rows of a synthetic log: 268 and
#: 508 MB), and the audit of issue 82 found 4.5 GB at 1 M rows and a MemoryError at 3 M;
#: the bound keeps a log's calibration within about 4.5 GB [choice]. A longer log: one
#: file a week.
MAX_LOG_ROWS = 1_000_000
#: A time step longer than this is a gap of the log [s]: a temperature trace's,
#: :data:`swgsim.datasets.conditions.TRACE_GAP_MIN` (5 min: beyond a logger's hiccups of 9
#: and 31 s, short against a joint's thermal time constant) [choice].
LOG_GAP_S = TRACE_GAP_MIN * 60.0


def _joint_columns() -> dict[str, str]:
    cols = {"Timestamp": "time"}
    for j in range(JOINTS):
        cols[f"Current_J{j}"] = f"current[{j}]"
        cols["Temperature_T0" if j == 0 else f"Temperature_J{j}"] = f"temperature[{j}]"
        cols[f"Speed_J{j}"] = f"speed[{j}]"
    cols.update({"Tool_current": "tool_current", "cycle ": "cycle",
                 "Robot_ProtectiveStop": "protective_stop", "grip_lost": "grip_lost"})
    return cols


#: Column of the file -> the field it fills (as messages name it).
LOG_COLUMNS = _joint_columns()


@dataclass(frozen=True)
class JointLog:
    """A joint log, one row per reading, in the file's order.

    Attributes
    ----------
    name : str
        The file's stem.
    start : str
        The first time stamp, ISO 8601 as written.
    t_s : ndarray, shape (n,)
        Seconds since the first row, increasing [s].
    temperature_c : ndarray, shape (n, 6)
        Joint temperature sensors [°C] (resolution 0.0625 K in the UR3 day); NaN: missing.
    current_a : ndarray, shape (n, 6)
        Motor currents, signed [A]; NaN: missing.
    speed_rad_s : ndarray, shape (n, 6)
        Joint speeds, signed [rad/s]; NaN: missing.
    tool_current_a : ndarray, shape (n,)
        Tool flange current [A]; NaN: missing.
    cycle : ndarray of int, shape (n,)
        Pick-and-place cycle count [-].
    protective_stop, grip_lost : ndarray of bool, shape (n,)
        Event flags (a missing flag: False).
    gap_rows : ndarray of int, shape (g,)
        Rows that follow a step over :data:`LOG_GAP_S` (a gap before them).
    """

    name: str
    start: str
    t_s: np.ndarray
    temperature_c: np.ndarray
    current_a: np.ndarray
    speed_rad_s: np.ndarray
    tool_current_a: np.ndarray
    cycle: np.ndarray
    protective_stop: np.ndarray
    grip_lost: np.ndarray
    gap_rows: np.ndarray

    @property
    def n(self) -> int:
        """Rows [-]."""
        return int(self.t_s.size)


def read_joint_log(path: str | os.PathLike, max_bytes: int = rt.MAX_TABLE_BYTES) -> JointLog:
    """Read a joint log in the UR3 CobotOps format (module docstring).

    Parameters
    ----------
    path : path-like
        The CSV (``;``-separated, decimal commas).
    max_bytes : int
        Largest file read [bytes] (:data:`swgsim.datasets.recording_table.MAX_TABLE_BYTES`).

    Returns
    -------
    JointLog

    Raises
    ------
    ValueError
        One line naming the file and, where it applies, the column (with its field, e.g.
        ``column 'Current_J3' (current[3]), row 12 (line 14): 'x' is not a number``): no
        such file, not a table, a column missing, a cell not a number, a time stamp or a
        flag, a reading outside its physical range (:data:`READING_RANGES`), times not
        increasing, more than :data:`MAX_LOG_ROWS` rows (before they are parsed).
    """
    df, fmt, _ = rt.read_table(path, LOG_COLUMNS, max_bytes, sep=";", decimal=",",
                               max_cells=MAX_LOG_ROWS * len(LOG_COLUMNS))
    t_s = rt.datetime_seconds(df, "Timestamp", "time", fmt)
    back = np.flatnonzero(np.diff(t_s) <= 0)
    if back.size:
        raise ValueError(f"column 'Timestamp' (time), {rt.row_name(int(back[0]) + 1, fmt)}: "
                         f"{df['Timestamp'].iloc[back[0] + 1]!r} is not after the row "
                         "before; the times must increase")

    def column(c: str, quantity: str, unit: str) -> np.ndarray:  # a reading, in range
        x = rt.numeric(df, c, LOG_COLUMNS[c], fmt, True, ",")
        lo, hi = READING_RANGES[quantity]
        rt.check_limit(np.where(np.isfinite(x), x, lo), lo, hi, c, LOG_COLUMNS[c], unit, fmt,
                       f"a joint's {quantity.replace('_', ' ')} stays inside; a fault of "
                       "the sensor, a unit mistaken or a damaged file")
        return x

    def block(prefix: str, quantity: str, unit: str, t0: str | None = None) -> np.ndarray:
        names = [t0 if (j == 0 and t0) else f"{prefix}{j}" for j in range(JOINTS)]
        return np.column_stack([column(c, quantity, unit) for c in names])  # (n, 6)

    cycle = rt.numeric(df, "cycle ", "cycle", fmt, decimal=",")
    if np.any(cycle != np.round(cycle)):
        i = int(np.flatnonzero(cycle != np.round(cycle))[0])
        raise ValueError(f"column 'cycle ' (cycle), {rt.row_name(i, fmt)}: {cycle[i]:g} is "
                         "not a whole count")
    return JointLog(
        name=os.path.splitext(os.path.basename(os.fspath(path)))[0],
        start=str(df["Timestamp"].iloc[0]), t_s=t_s,
        temperature_c=block("Temperature_J", "temperature", "degC", "Temperature_T0"),
        current_a=block("Current_J", "current", "A"),
        speed_rad_s=block("Speed_J", "speed", "rad/s"),
        tool_current_a=column("Tool_current", "tool_current", "A"),
        cycle=cycle.astype(np.int64),
        protective_stop=rt.flag(df, "Robot_ProtectiveStop", "protective_stop", fmt,
                                missing=False),
        grip_lost=rt.flag(df, "grip_lost", "grip_lost", fmt, missing=False),
        gap_rows=np.flatnonzero(np.diff(t_s) > LOG_GAP_S) + 1)


def write_joint_log(log: JointLog, path: str | os.PathLike) -> None:
    """Write a joint log in the format :func:`read_joint_log` reads (``;``, decimal commas,
    ISO 8601 times from ``log.start``, the published column names, two trailing empty
    columns), atomically: a synthetic log as a file, e.g. for ``swgsim-calibrate``.

    Parameters
    ----------
    log : JointLog
    path : path-like
        The CSV written.
    """
    import pandas as pd

    stamps = (pd.Timestamp(log.start) + pd.to_timedelta(log.t_s, unit="s"))
    cols: dict[str, object] = {"Num": np.arange(1, log.n + 1),
                               "Timestamp": stamps.strftime("%Y-%m-%dT%H:%M:%S.%f").str[:-3]
                               + "Z"}
    for j in range(JOINTS):
        cols[f"Current_J{j}"] = log.current_a[:, j]
        cols["Temperature_T0" if j == 0 else f"Temperature_J{j}"] = log.temperature_c[:, j]
    for j in range(JOINTS):
        cols[f"Speed_J{j}"] = log.speed_rad_s[:, j]
    cols.update({"Tool_current": log.tool_current_a, "cycle ": log.cycle,
                 "Robot_ProtectiveStop": log.protective_stop, "grip_lost": log.grip_lost,
                 "": "", " ": ""})
    text = pd.DataFrame(cols).to_csv(sep=";", decimal=",", index=False, na_rep="")
    atomic_write_bytes(path, text.encode())


def write_temperature_table(log: JointLog, joint: int, path: str | os.PathLike,
                            keep_gaps: bool = False) -> np.ndarray:
    """Write one joint's temperature as a table on operating hours, ``hour,temperature_c``
    (comma-separated, decimal points; :data:`swgsim.datasets.conditions.HOURS_TABLE_COLUMNS`),
    atomically: what ``temperature_trace`` of mode ``hours`` replays on a life.

    Rows without a reading are left out. A gap of the log (:attr:`JointLog.gap_rows`) is
    cut by default: its time is not counted as operating hours, the row after it follows
    the one before it by the log's median step, and the temperature steps there by what
    the joint gained or lost meanwhile [choice: in the UR3 day the cycle count does not
    advance over its 5.2-h gap, 105 either side, so the robot did not operate; its joints
    come back 1.6-3.6 K warmer]. With ``keep_gaps`` the hours are the log's own and a life
    interpolates linearly across the gap.

    Parameters
    ----------
    log : JointLog
    joint : int
        The joint, 0-5.
    path : path-like
        The CSV written.
    keep_gaps : bool
        Count a gap's time as operating hours (default: cut it).

    Returns
    -------
    ndarray, shape (N, 2)
        The rows written: operating hours from 0 at the first reading [h], temperature
        [°C].

    Raises
    ------
    ValueError
        ``joint`` outside 0-5, fewer than one reading of that joint.
    """
    if not 0 <= int(joint) < JOINTS or int(joint) != joint:
        raise ValueError(f"joint must lie in [0, {JOINTS - 1}], got {joint}")
    t_s = np.asarray(log.t_s, float)
    if not keep_gaps and log.gap_rows.size:
        step = np.diff(t_s)
        cut = np.zeros_like(t_s)
        cut[log.gap_rows] = step[log.gap_rows - 1] - np.median(step)
        t_s = t_s - np.cumsum(cut)
    temp = log.temperature_c[:, int(joint)]
    ok = np.isfinite(temp)
    if not ok.any():
        raise ValueError(f"joint log {log.name!r}: joint {joint} has no temperature reading")
    rows = np.column_stack([(t_s[ok] - t_s[ok][0]) / 3600.0, temp[ok]])
    text = ",".join(HOURS_TABLE_COLUMNS) + "\n" + "".join(f"{h:.6f},{c:.4f}\n" for h, c in rows)
    atomic_write_bytes(path, text.encode())
    return rows
