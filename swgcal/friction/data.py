"""Measured joint friction: recordings (data kind 1), loading and checks.

A friction recording (data kind 1) is a CSV with the columns of the project's real data
(``docs/DATASET.md``, "Friction recordings"): ``time_s`` [s], ``q_rad`` [rad],
``dq_rad_per_s`` [rad/s], optionally ``ddq_rad_per_s2`` [rad/s²], ``load_Nm`` [N m] and
``temperature_c`` [°C], and the target ``tau_friction_Nm`` [N m]. Sampling may be
irregular. Any other column is named in the recording's notes (and so in the report) as
read but unused.

The recording becomes the signals of the friction terms
(:class:`swgsim.gear.friction.FrictionSignals`, :meth:`FrictionRecording.signals`).
"""

from __future__ import annotations

import contextlib
import csv
import io
import itertools
import logging
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from swgsim.base.lazy import lazy_module
from swgsim.datasets import recording_table as rt
from swgsim.files.inputs import check_text_file
from swgsim.gear.friction.signals import FrictionSignals, Scales
from swgsim.gear.profile import MAX_INPUT_SPEED_RPM, RPM

from .options import FrictionOptions

integrate = lazy_module("scipy.integrate")
signal = lazy_module("scipy.signal")

pd = lazy_module("pandas")

log = logging.getLogger(__name__)

__all__ = [
    "FrictionRecording",
    "VelocityConsistency",
    "load_friction_csv",
    "read_csv_header",
    "velocity_consistency",
    "velocity_scale",
    "scale_cause",
    "write_friction_csv",
    "estimate_acceleration",
    "REQUIRED_COLUMNS",
    "COLUMN_RANGES",
    "MAX_ROWS",
    "MISSING_CELLS",
]

REQUIRED_COLUMNS = ("time_s", "q_rad", "dq_rad_per_s", "tau_friction_Nm")
OPTIONAL_COLUMNS = ("ddq_rad_per_s2", "load_Nm", "temperature_c")


@dataclass(frozen=True)
class FrictionRecording:
    """One measured (or simulated) friction recording.

    Attributes
    ----------
    t_s : ndarray, shape (n,)
        Time, strictly increasing [s].
    q_rad, dq_rad_s, ddq_rad_s2 : ndarray, shape (n,)
        Joint angle [rad], velocity [rad/s], acceleration [rad/s²].
    tau_nm : ndarray, shape (n,)
        Friction torque [N m].
    load_nm : ndarray, shape (n,), optional
        Transmitted load torque [N m] (for the load-dependent Coulomb term).
    temperature_c : ndarray, shape (n,), optional
        The joint's measured temperature [°C] (for ``temperature_friction``).
    measured : dict of str to ndarray, shape (n,)
        Other measured variables the file carries, by column (for ``measured_variable``).
    ddq_source : str
        ``"measured"`` or how it was estimated.
    notes : tuple of str
        What loading found and did about the data (dropped rows, consistency measures);
        shown in the report.
    """

    t_s: np.ndarray
    q_rad: np.ndarray
    dq_rad_s: np.ndarray
    ddq_rad_s2: np.ndarray
    tau_nm: np.ndarray
    load_nm: np.ndarray | None = None
    temperature_c: np.ndarray | None = None
    measured: dict[str, np.ndarray] = field(default_factory=dict)
    name: str = "recording"
    ddq_source: str = "measured"
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        n = self.t_s.shape[0]
        arrays = {f: getattr(self, f) for f in ("q_rad", "dq_rad_s", "ddq_rad_s2", "tau_nm",
                                                 "load_nm", "temperature_c")}
        for f, a in {**arrays, **self.measured}.items():
            if a is not None and a.shape != (n,):
                raise ValueError(f"{f} has shape {a.shape}, expected ({n},) like t_s")
        if n < 50:
            raise ValueError(f"recording {self.name!r} has {n} samples, need at least 50")
        if not np.all(np.diff(self.t_s) > 0):
            raise ValueError(f"recording {self.name!r}: time_s must be strictly increasing")

    @property
    def n(self) -> int:
        return int(self.t_s.shape[0])

    def signals(self, v_s: float | None = None, v_s_rel: float = 0.01,
                gear_ratio: float | None = None) -> FrictionSignals:
        """Signals for the model terms (see :class:`FrictionSignals`).

        Parameters
        ----------
        v_s : float, optional
            Smooth-sign velocity [rad/s]; default ``v_s_rel`` times the 99th percentile
            of ``|q̇|``.
        gear_ratio : float, optional
            Reduction ratio N (wave-generator turns per output turn), when known: ripples
            over q are then labelled with wave-generator orders k = 2π / (period · N).

        Raises
        ------
        ValueError
            The joint never moves, ``v_s`` is not positive, or ``gear_ratio`` is not
            above 1.
        """
        if gear_ratio is not None and not gear_ratio > 1:
            raise ValueError(f"gear_ratio must be > 1 (wave-generator turns per output turn) "
                             f"or None, got {gear_ratio}")
        v_ref = float(np.percentile(np.abs(self.dq_rad_s), 99))
        if v_ref <= 0:
            raise ValueError(f"recording {self.name!r} never moves (|dq| = 0)")
        if v_s is None:
            v_s = v_s_rel * v_ref
        if not v_s > 0:
            raise ValueError(f"v_s must be > 0 [rad/s], got {v_s}")
        return FrictionSignals(
            t_s=self.t_s, q_rad=self.q_rad, dq_rad_s=self.dq_rad_s, ddq_rad_s2=self.ddq_rad_s2,
            load_nm=self.load_nm, v_eff=self.dq_rad_s, v_s=float(v_s),
            scales=Scales.of(self.t_s, self.q_rad, self.dq_rad_s),
            gear_ratio=None if gear_ratio is None else float(gear_ratio),
            temperature_c=self.temperature_c, measured=dict(self.measured))


#: Most points of the acceleration's uniform grid per sample of the recording
#: (:func:`estimate_acceleration`) [choice: gaps of a logger's hiccups pass, a recording
#: whose time stamps jump by hours is refused before its grid is allocated].
MAX_GRID_PER_SAMPLE = 10


def estimate_acceleration(t_s: np.ndarray, dq: np.ndarray, n_window: int = 21) -> np.ndarray:
    """Acceleration from an irregularly sampled velocity by a local quadratic fit.

    The velocity is interpolated linearly onto a uniform grid at the median sample
    interval, differentiated by a Savitzky-Golay filter (quadratic, ``n_window`` points;
    Savitzky & Golay 1964) and interpolated back.

    Parameters
    ----------
    t_s : ndarray, shape (n,)
        Time [s], strictly increasing.
    dq : ndarray, shape (n,)
        Velocity [rad/s].
    n_window : int, default 21
        Window length in median samples (odd, ≥ 5).

    Returns
    -------
    ndarray, shape (n,)
        Acceleration [rad/s²].

    Raises
    ------
    ValueError
        ``n_window`` < 5, or a grid of more than :data:`MAX_GRID_PER_SAMPLE` times the
        samples (a long gap in the time stamps; it is refused before it is allocated).
    """
    if n_window < 5:
        raise ValueError(f"n_window must be >= 5, got {n_window}")
    dt = float(np.median(np.diff(t_s)))
    n_grid = (t_s[-1] - t_s[0]) / dt + 1
    if n_grid > MAX_GRID_PER_SAMPLE * t_s.size:
        raise ValueError(f"time_s spans {t_s[-1] - t_s[0]:.4g} s at a median step of "
                         f"{dt:.3g} s: {n_grid:.3g} grid points to estimate the acceleration, "
                         f"over {MAX_GRID_PER_SAMPLE} times its {t_s.size} rows (a gap in "
                         "the time stamps); split the recording at the gap or give "
                         "ddq_rad_per_s2")
    tu = np.arange(t_s[0], t_s[-1] + 0.5 * dt, dt)
    vu = np.interp(tu, t_s, dq)
    w = n_window | 1
    if tu.size < w:
        w = tu.size - (1 - tu.size % 2)
    au = signal.savgol_filter(vu, w, 2, deriv=1, delta=dt)
    return np.interp(t_s, tu, au)


#: Consistency figure (:func:`velocity_consistency`) above which a recording is refused:
#: its velocity is not the time derivative of its angle [-]. Measured on the six real
#: recordings in ``shared/data/joint_friction``: 0.005-0.091 as published (0.091: the
#: spiral file's velocity offset, 9 % of its RMS); at most 0.091, 0.096 and 0.28 with the
#: angle rounded to a 14-, 12- or 10-bit output encoder (2π/16384, 2π/4096, 2π/1024 rad);
#: at most 0.091, 0.154 and 0.307 with the velocity low-passed by a causal second-order
#: Butterworth filter at 5, 2 or 1 Hz (zero-phase filtering changes nothing). Errors: a
#: velocity scaled by 2 or 1/2 gives 0.63-0.71, of the wrong sign 1.77-2.0, in deg/s
#: beside an angle in rad 6.6-7.4, q and dq swapped 1.01-6.7, dq and tau swapped
#: 0.56-28, an angle frozen half-way 0.74-0.95.
DQ_CONSISTENCY_TOL = 0.5
#: Consistency figure above which the check is unsure [-]: the recording is accepted, with
#: a note and one warning. Between this and :data:`DQ_CONSISTENCY_TOL` lie a lagging
#: velocity filter (1 Hz on the fastest real recording: 0.307), an angle of a few encoder
#: counts (10 bit on the smallest real excursion, 0.015 rad: 0.28) and a velocity scale
#: off by a factor 1.2-1.6 (|1 − k| / √k), which the figure cannot tell apart.
DQ_CONSISTENCY_SURE = 0.2
#: Fewest rows a friction recording must keep after cleaning.
MIN_ROWS = 100
#: Physical ranges of a friction recording's columns: column -> (lowest, highest, unit,
#: what it is). A finite value outside is refused in one line naming the file, the column
#: and the row (a fault of the sensor, a unit mistaken or a damaged file), before any
#: work. The six real recordings (``shared/data/joint_friction``) reach at most 181 s,
#: 1.26 rad, 0.38 rad/s, 0.063 rad/s² and 19.4 N m. Time: 1e10 s either side of zero
#: [choice: 317 years; a Unix time stamp, 1.7e9 s in 2024, fits]. Angle: 1e4 rad
#: [choice: 1600 turns, some 8000 times the real recordings' largest; beyond it the ten
#: significant digits :func:`write_friction_csv` writes resolve less than 1e-6 rad].
#: Velocity: the gear's catalogue input speed, 6500 rpm = 681 rad/s
#: (:data:`swgsim.gear.profile.MAX_INPUT_SPEED_RPM`), which bounds even a velocity taken
#: at the motor. Acceleration: 1e5 rad/s² [choice: 681 rad/s reached within 7 ms].
#: Friction and load torque: 1e4 N m [choice: 52 times the gear's momentary peak
#: torque, 191 N m (:data:`swgsim.gear.profile.MOMENTARY_PEAK_TORQUE_NM`), some 500
#: times the real recordings' largest]. Temperature: -40 to 150 degC, the range a joint's
#: temperature is read in everywhere in the project (a measured warm-up, docs/DATASET.md).
COLUMN_RANGES = {
    "time_s": (-1e10, 1e10, "s", "time"),
    "q_rad": (-1e4, 1e4, "rad", "joint angle"),
    "dq_rad_per_s": (-MAX_INPUT_SPEED_RPM * RPM, MAX_INPUT_SPEED_RPM * RPM, "rad/s",
                     "joint velocity"),
    "ddq_rad_per_s2": (-1e5, 1e5, "rad/s²", "joint acceleration"),
    "tau_friction_Nm": (-1e4, 1e4, "N m", "friction torque"),
    "load_Nm": (-1e4, 1e4, "N m", "load torque"),
    "temperature_c": (-40.0, 150.0, "degC", "joint temperature"),
}
#: Cells read as a missing reading (case and surrounding blanks ignored): their rows are
#: dropped, counted in the notes with the first of them; any other text where a number
#: belongs is refused naming the file, the column and the row. The empty cell and the
#: markers spreadsheets and pandas write (pandas' default ``na_values``, less the
#: ``1.#IND`` and ``1.#QNAN`` of old Windows C libraries) [choice].
MISSING_CELLS = frozenset({"", "nan", "-nan", "na", "n/a", "#n/a", "#n/a n/a", "#na",
                           "<na>", "null", "none"})
#: CSV records parsed at a time: one chunk of text is held, some 1.5 MB as Python strings
#: at the real recordings' 40-63 bytes a row [choice]. Reading a 102 MB file (1.6 M rows)
#: peaked at 1.39 times its size (tracemalloc), 8.81 times as a whole list of records.
_CHUNK_RECORDS = 1 << 12
#: Most data rows of a friction recording read: 500 000, 20 times the longest real one
#: (25 402 rows) and 17 min at 2 ms. The calibration (``swgsim-calibrate``) holds about
#: 6.5 kB a row: measured largest resident size 372 MB on franka_joint2_slow (25 390 rows)
#: and 2.15 GB on a synthetic recording of 300 000; the bound keeps it within about 3.5 GB
#: [choice], where the 2 GiB an input file may have (34 M rows of 63 bytes) would ask for
#: 220 GB. A longer recording: calibrate on a stretch of it, or on every k-th row.
MAX_ROWS = 500_000


def load_friction_csv(path: str | Path,
                      accel_window: int = FrictionOptions.accel_window) -> FrictionRecording:
    """Read a friction CSV (data kind 1) and check that it is physically consistent.

    Parameters
    ----------
    path : str or Path
        CSV (RFC 4180: quoted fields allowed; UTF-8, with or without a byte-order mark)
        with the columns ``time_s, q_rad, dq_rad_per_s, tau_friction_Nm`` and optionally
        ``ddq_rad_per_s2``, ``load_Nm`` and ``temperature_c``, in any order; any other
        column is named in ``notes`` as read but unused.
    accel_window : int, default 21
        Window of :func:`estimate_acceleration`, used when ``ddq_rad_per_s2`` is absent
        or identically zero (the Franka files).

    Returns
    -------
    FrictionRecording
        Rows with a missing reading (an empty cell or a marker of :data:`MISSING_CELLS`)
        or a non-finite value are dropped, and rows repeating the previous time stamp;
        both are counted in ``notes`` (and logged) with the first such row, beside the
        measured velocity consistency (:func:`velocity_consistency`), which says so
        where it is unsure.

    Raises
    ------
    FileNotFoundError
    ValueError
        Naming the file (and, for a cell, the column and the row with its line): not a
        UTF-8 text CSV, a column named twice, a required column missing, rows of another
        length than the header, more than :data:`MAX_ROWS` rows (refused as they are
        read), text where a number belongs, a value outside its column's physical range
        (:data:`COLUMN_RANGES`), no usable rows or fewer than :data:`MIN_ROWS`, time
        going backwards, an angle that stays constant while the velocity does not, or a
        velocity that is not the derivative of the angle (consistency figure above
        :data:`DQ_CONSISTENCY_TOL` after discounting the angle's quantisation).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"friction CSV not found: {path}")
    cols, row = _read_columns(path)
    _check_ranges(path, {c: x for c, x in cols.items() if c in COLUMN_RANGES}, row)
    notes: list[str] = []
    known = REQUIRED_COLUMNS + OPTIONAL_COLUMNS
    others = [h for h in read_csv_header(path) if h and h not in known]
    sel = _usable_rows(path, cols, row, notes)

    def kept(x: np.ndarray) -> np.ndarray:  # no copy where every row is kept
        return x if sel is None else x[sel]

    t = kept(cols["time_s"])
    q = kept(cols["q_rad"])
    dq = kept(cols["dq_rad_per_s"])
    _check_velocity(path, t, q, dq, notes)
    ddq = cols.get("ddq_rad_per_s2")
    if ddq is None or not np.any(kept(ddq)):
        try:
            acc = estimate_acceleration(t, dq, accel_window)
        except ValueError as e:
            raise ValueError(f"{path}: {e}") from None
        source = f"estimated (Savitzky-Golay, quadratic, {accel_window} samples)"
    else:
        acc, source = kept(ddq), "measured"
    measured = _measured(others, cols, kept, notes)
    return FrictionRecording(
        t_s=t, q_rad=q, dq_rad_s=dq, ddq_rad_s2=acc,
        tau_nm=kept(cols["tau_friction_Nm"]),
        load_nm=kept(cols["load_Nm"]) if "load_Nm" in cols else None,
        temperature_c=kept(cols["temperature_c"]) if "temperature_c" in cols else None,
        measured=measured, name=path.stem, ddq_source=source, notes=tuple(notes))


def _measured(others: list[str], cols: dict[str, np.ndarray],
              kept: Callable[[np.ndarray], np.ndarray], notes: list[str]
              ) -> dict[str, np.ndarray]:
    """The columns beyond the known ones that are measured variables (a finite number on
    every kept row, not constant), offered to the loop as ``measured_variable``; each
    other one named in ``notes`` with why it is not used."""
    out, why = {}, {}
    for h in others:
        x = kept(cols[h]) if h in cols else None
        if x is None:
            why[h] = "text where a number belongs"
        elif not np.all(np.isfinite(x)):
            why[h] = "missing or non-finite on kept rows"
        elif not np.ptp(x) > 0:
            why[h] = "constant"
        else:
            out[h] = x
    if out:
        notes.append(f"column(s) {list(out)}: measured variables, offered to the loop as "
                     "measured_variable")
    if why:
        notes.append("column(s) not used: " + ", ".join(f"{h} ({w})" for h, w in why.items()))
    return out


def read_csv_header(path: str | Path) -> list[str]:
    """Column names in the header row of a CSV file, as a CSV reader reads them.

    Parameters
    ----------
    path : str or Path
        UTF-8 text (a byte-order mark, as Excel's "CSV UTF-8" writes, is skipped); RFC
        4180 quoting is undone (``"time_s"`` names ``time_s``).

    Returns
    -------
    list of str
        The names, stripped of surrounding blanks; empty for an empty file.

    Raises
    ------
    ValueError
        Naming the file: not UTF-8 text, or not readable as CSV.
    """
    rows = _head_rows(Path(path))
    return [h.strip() for h in rows[0]] if rows else []


def _head_rows(path: Path) -> list[list[str]]:
    """The header record of ``path``, from a bounded read of its head
    (:data:`swgsim.files.inputs.HEADER_BYTES`); a regular file under
    :data:`swgsim.files.inputs.MAX_INPUT_BYTES` checked first."""
    head = check_text_file(path, "friction CSV")
    end = min((i for i in (head.find(b"\n"), head.find(b"\r")) if i >= 0), default=-1)
    line = head if end < 0 else head[:end]
    with _not_csv(path):
        return list(itertools.islice(csv.reader(io.StringIO(line.decode("utf-8-sig"))), 1))


@contextlib.contextmanager
def _not_csv(path: Path) -> Iterator[None]:
    """A decoding or CSV error within the block as a one-line ValueError naming ``path``."""
    try:
        yield
    except UnicodeDecodeError as e:
        raise ValueError(f"{path}: not a text CSV (UTF-8 expected; {e.reason}: "
                         f"{e.object[e.start:e.end]!r})") from None
    except csv.Error as e:
        raise ValueError(f"{path}: not a text CSV ({e})") from None


def _line_of(path: Path, record: int) -> int:
    """The line on which record number ``record`` (0: the header) of the CSV ends."""
    with path.open(newline="", encoding="utf-8-sig") as fh:
        reader = csv.reader(fh)
        for _ in itertools.islice(reader, record + 1):
            pass
        return reader.line_num


def _check_header(path: Path, header: list[str]) -> None:
    """Each column named once and the required ones present."""
    named = [h for h in header if h]
    twice = sorted({h for h in named if named.count(h) > 1})
    if twice:
        raise ValueError(f"{path}: column(s) {twice} named more than once in the header "
                         f"{header}; each column must be named once")
    missing = [c for c in REQUIRED_COLUMNS if c not in header]
    if missing:
        raise ValueError(f"{path}: not a friction CSV: missing columns {missing}; expected "
                         f"{list(REQUIRED_COLUMNS)} (+ optional {list(OPTIONAL_COLUMNS)}), "
                         f"found {header}")


def _numbers(path: Path, cells: np.ndarray, column: str, row0: int,
             record_of: Callable[[int], int]) -> np.ndarray:
    """A chunk's cells of one column as floats, NaN where a cell is missing
    (:data:`MISSING_CELLS`); other text refused naming the column and the row (``row0``:
    the chunk's first data row; ``record_of``: a chunk row's CSV record number)."""
    x = np.asarray(pd.to_numeric(cells, errors="coerce"), dtype=float)
    for k in np.flatnonzero(np.isnan(x)):
        if str(cells[k]).strip().lower() not in MISSING_CELLS:
            raise ValueError(
                f"{path}: column {column!r}, row {row0 + k} (line "
                f"{_line_of(path, record_of(int(k)))}): {cells[k]!r} is not a number (a "
                "missing reading is an empty cell, NaN or n/a: its row is dropped)")
    return x


def _read_columns(path: Path) -> tuple[dict[str, np.ndarray], Callable[[int], str]]:
    """The known columns of the CSV by name (data rows, as floats; NaN where a cell is a
    missing reading) and how messages name a data row (``row 12 (line 14)``), after
    checking the header, the row lengths and that every other cell is a number.

    The records are parsed :data:`_CHUNK_RECORDS` at a time: what is held is the columns
    as floats and one chunk of text (issue 82: the whole file as lists of strings took
    ten times its size)."""
    _head_rows(path)  # the bounded checks of check_text_file, before any full read
    known = REQUIRED_COLUMNS + OPTIONAL_COLUMNS
    with _not_csv(path), path.open(newline="", encoding="utf-8-sig") as fh:
        reader = csv.reader(fh)
        header = [h.strip() for h in next(reader, [])]
        _check_header(path, header)
        width = len(header)
        use = {h: i for i, h in enumerate(header) if h in known}
        others = {h: i for i, h in enumerate(header) if h and h not in known}
        parts: dict[str, list[np.ndarray]] = {h: [] for h in [*use, *others]}
        blanks: list[np.ndarray] = []  # record numbers of blank lines
        record, n_body, n_bad, first_bad = 1, 0, 0, None
        while chunk := list(itertools.islice(reader, _CHUNK_RECORDS)):
            if "\0" in "".join(itertools.chain.from_iterable(chunk)):
                raise ValueError(f"{path}: not a text CSV (it holds NUL bytes: a binary "
                                 "file)")
            kind = np.array([0 if not "".join(r).strip() else 1 if len(r) == width else 2
                             for r in chunk], dtype=np.int8)  # blank, a row, another length
            rows = np.flatnonzero(kind == 1)
            if (kind == 0).any():
                blanks.append(record + np.flatnonzero(kind == 0))
            bad = np.flatnonzero(kind == 2)
            if n_body + int((kind != 0).sum()) > MAX_ROWS:
                k = int(np.flatnonzero(kind != 0)[MAX_ROWS - n_body])
                raise ValueError(
                    f"{path}: more than {MAX_ROWS} data rows (line "
                    f"{_line_of(path, record + k)} is row {MAX_ROWS}); the calibration holds "
                    "about 6.5 kB a row: calibrate on a stretch of the recording, or on "
                    "every k-th row")
            if bad.size and first_bad is None:
                first_bad = (record + int(bad[0]), len(chunk[bad[0]]))
            n_bad += bad.size
            cells = None
            if not n_bad and rows.size:
                cells = np.array([chunk[k] for k in rows], dtype=object)
                for h, i in use.items():
                    parts[h].append(_numbers(path, cells[:, i], h, n_body,
                                             lambda k, b=record, r=rows: b + int(r[k])))
                for h, i in list(others.items()):  # a measured variable, or text: unused
                    x = np.asarray(pd.to_numeric(cells[:, i], errors="coerce"), dtype=float)
                    if np.isnan(x).sum() > sum(str(c).strip().lower() in MISSING_CELLS
                                               for c in cells[:, i]):
                        del others[h]
                        parts[h] = []
                    else:
                        parts[h].append(x)
            n_body += rows.size + bad.size
            record += len(chunk)
            chunk = cells = None  # one chunk's text in hand, not two
    if not n_body:
        raise ValueError(f"{path}: no data rows below the header")
    if first_bad is not None:
        raise ValueError(f"{path}: rows of another length than the header: line "
                         f"{_line_of(path, first_bad[0])} has {first_bad[1]} fields, the "
                         f"header names {width} ({n_bad} of {n_body} rows differ)")
    blank = np.concatenate(blanks) if blanks else np.empty(0, np.int64)

    def row(i: int) -> str:  # data row i (blank lines not counted) -> its record, line
        r = i + 1
        while (nxt := i + 1 + int(np.searchsorted(blank, r, "right"))) != r:
            r = nxt
        return f"row {i} (line {_line_of(path, r)})"

    return {h: np.concatenate(p) for h, p in parts.items() if p}, row


def _check_ranges(path: Path, cols: dict[str, np.ndarray], row: Callable[[int], str]
                  ) -> None:
    """Every finite value inside its column's physical range (:data:`COLUMN_RANGES`):
    refused in one line naming the file, the column and the row
    (:func:`swgsim.datasets.recording_table.check_limit`, the importer's check)."""
    for c, x in cols.items():
        lo, hi, unit, what = COLUMN_RANGES[c]
        try:
            rt.check_limit(np.where(np.isfinite(x), x, lo), lo, hi, c, what, unit, "csv",
                           "beyond a joint's physical range: a fault of the sensor, a "
                           "unit mistaken or a damaged file", row=row)
        except ValueError as e:
            raise ValueError(f"{path}: {e}") from None


def _usable_rows(path: Path, cols: dict[str, np.ndarray], row: Callable[[int], str],
                 notes: list[str]) -> np.ndarray | None:
    """Indices of the rows kept (None: all of them): finite values, time stamps
    increasing (rows repeating the previous one dropped); what was dropped is appended
    to ``notes``, how many and the first (``row`` names a data row)."""
    use = list(REQUIRED_COLUMNS) + [c for c in OPTIONAL_COLUMNS if c in cols]
    n = cols["time_s"].size
    ok = np.ones(n, dtype=bool)
    for c in use:
        ok &= np.isfinite(cols[c])
    if not ok.all():
        i = int(np.flatnonzero(~ok)[0])
        which = [c for c in use if not np.isfinite(cols[c][i])]
        notes.append(f"dropped {int((~ok).sum())} of {n} rows with a missing or non-finite "
                     f"value (the first: {row(i)}, column {', '.join(which)})")
        log.warning("%s: %s", path.name, notes[-1])
    if not ok.any():
        raise ValueError(f"{path}: no usable rows: all {n} rows hold non-finite or "
                         "missing values")
    t = cols["time_s"][ok]
    dt = np.diff(t)
    if np.any(dt < 0):
        k = int(np.flatnonzero(dt < 0)[0])
        raise ValueError(f"{path}: time_s goes backwards after {t[k]:g} s (to {t[k + 1]:g} "
                         f"s, {row(int(np.flatnonzero(ok)[k + 1]))}); rows must be in time "
                         "order")
    keep = np.concatenate([[True], dt > 0])
    sel = None if ok.all() and keep.all() else np.flatnonzero(ok)[keep]
    if not keep.all():
        i = int(np.flatnonzero(ok)[np.flatnonzero(~keep)[0]])
        notes.append(f"dropped {int((~keep).sum())} rows repeating the previous time stamp "
                     f"(the first: {row(i)}, {cols['time_s'][i]:g} s)")
        log.warning("%s: %s", path.name, notes[-1])
    kept = n if sel is None else sel.size
    if kept < MIN_ROWS:
        raise ValueError(f"{path}: {kept} usable rows, at least {MIN_ROWS} needed")
    return sel


@dataclass(frozen=True)
class VelocityConsistency:
    """How far a velocity is from the time derivative of an angle
    (:func:`velocity_consistency`); all figures are dimensionless.

    Attributes
    ----------
    figure : float
        ``hypot(shape, offset)``; compared with :data:`DQ_CONSISTENCY_SURE` and
        :data:`DQ_CONSISTENCY_TOL`.
    shape : float
        RMS of the angle minus the integrated velocity, after the best-fit offset and
        linear drift, relative to the geometric mean of the RMS excursions (about the
        mean) of the angle and of the integrated velocity.
    offset : float
        The fitted drift, a constant velocity offset, relative to the RMS velocity.
    quantisation : float
        Part of ``shape`` expected from rounding the angle alone: (resolution / √12)
        relative to the same excursion.
    resolution_rad : float
        Smallest step between distinct angle values [rad] (the encoder count, or the
        file's printed precision).
    """

    figure: float
    shape: float
    offset: float
    quantisation: float
    resolution_rad: float


def velocity_consistency(t_s: np.ndarray, q_rad: np.ndarray,
                         dq_rad_s: np.ndarray) -> VelocityConsistency:
    """Compare an angle with the time integral of a velocity.

    The velocity is integrated by the cumulative trapezoid rule (irregular sampling is
    fine) and subtracted from the angle; the best-fit offset and linear drift (a
    constant velocity offset: sensor bias, time-stamp skew) are removed from the
    difference by least squares. Integrating averages the angle's quantisation and the
    velocity's noise instead of amplifying them as differentiating the angle does; a
    velocity filter lagging by τ adds about τ·RMS(q̇) relative to the excursion. (The
    white noise of an independent velocity sensor integrates to a random walk, so a
    very long recording of a noisy tachometer scores higher; a velocity derived from
    the angle integrates back to it.)

    ``shape`` is normalised by the geometric mean of both excursions, so that a
    velocity (or angle) scaled by k gives ``|1 − k| / √k`` whichever column is wrong (k = 2
    or 1/2: 0.71, k = 180/π: 7.4), a sign error 2 and an unrelated column at least √2;
    ``offset`` catches what the drift could absorb (on an angle ramp, a wrong scale or
    sign is all drift).

    Parameters
    ----------
    t_s : ndarray, shape (n,)
        Time, strictly increasing [s].
    q_rad : ndarray, shape (n,)
        Angle [rad], not constant.
    dq_rad_s : ndarray, shape (n,)
        Velocity [rad/s], not identically zero.

    Returns
    -------
    VelocityConsistency
        Figures are infinite (or NaN) where the angle is constant or the velocity zero.
    """
    integral = integrate.cumulative_trapezoid(dq_rad_s, t_s, initial=0.0)
    basis = np.column_stack([np.ones_like(t_s), t_s - t_s.mean()])
    coef, *_ = np.linalg.lstsq(basis, q_rad - integral, rcond=None)
    rest = q_rad - integral - basis @ coef
    excursion = np.sqrt(_rms(q_rad - q_rad.mean()) * _rms(integral - integral.mean()))
    steps = np.diff(np.unique(q_rad))
    resolution = float(steps.min()) if steps.size else 0.0
    with np.errstate(divide="ignore", invalid="ignore"):  # inf: constant angle, zero velocity
        shape = float(_rms(rest) / excursion)
        offset = float(abs(coef[1]) / np.float64(_rms(dq_rad_s)))
        quantisation = float(resolution / np.sqrt(12) / excursion)
    return VelocityConsistency(figure=float(np.hypot(shape, offset)), shape=shape,
                               offset=offset, quantisation=quantisation,
                               resolution_rad=resolution)


#: Largest RMS of q_rad - q0 - (integral of dq) / k, relative to the angle's excursion, at
#: which a velocity k times the angle's derivative is named a pure factor (a noisy
#: tachometer or a lagging filter leave more) [-].
PURE_FACTOR_TOL = 0.02

#: Factors with a likely cause: velocity / (derivative of the angle) -> the cause.
_FACTORS = {
    180 / np.pi: "dq_rad_per_s looks like deg/s: divide it by 57.3",
    np.pi / 180: "q_rad looks like degrees: multiply it by pi/180",
    60 / (2 * np.pi): "dq_rad_per_s looks like rpm: multiply it by 2 pi/60",
    1000.0: "time_s looks like milliseconds: divide it by 1000",
    1e-3: "dq_rad_per_s looks like mrad/s, or time_s like kiloseconds",
}


def velocity_scale(t_s: np.ndarray, q_rad: np.ndarray, dq_rad_s: np.ndarray) -> float | None:
    """The factor k when a velocity is a pure multiple of an angle's time derivative.

    Fits ``q = q0 + (integral of dq) / k`` by least squares (no drift: a velocity offset
    is not a pure factor) and accepts k when the rest is at most
    :data:`PURE_FACTOR_TOL` of the angle's RMS excursion.

    Parameters
    ----------
    t_s : ndarray, shape (n,)
        Time, strictly increasing [s].
    q_rad : ndarray, shape (n,)
        Angle [rad].
    dq_rad_s : ndarray, shape (n,)
        Velocity [rad/s].

    Returns
    -------
    float or None
        k = velocity / (dq/dt) (2.0: the velocity twice the derivative, or the time
        column twice too long; -1: a sign error), or None if no pure factor fits.
    """
    integral = integrate.cumulative_trapezoid(dq_rad_s, t_s, initial=0.0)
    basis = np.column_stack([integral - integral.mean(), np.ones_like(t_s)])
    coef, *_ = np.linalg.lstsq(basis, q_rad, rcond=None)
    excursion = _rms(q_rad - q_rad.mean())
    if not (excursion > 0 and coef[0] != 0 and np.isfinite(coef[0])):
        return None
    rest = _rms(q_rad - basis @ coef) / excursion
    return float(1.0 / coef[0]) if rest <= PURE_FACTOR_TOL else None


def scale_cause(k: float) -> str:
    """The likely cause of a velocity ``k`` times the angle's derivative, in words."""
    sign = "" if k > 0 else "a sign error (dq_rad_per_s or q_rad reversed)"
    m = abs(k)
    if abs(m - 1) < 0.02:
        return sign + "; flip the sign of dq_rad_per_s (or of q_rad)"
    for f, why in _FACTORS.items():
        if abs(m / f - 1) < 0.02:
            return (sign + " and " if sign else "") + why
    return ((sign + ", and " if sign else "") + f"likely time_s is {_factor(m)} times too "
            f"long (its unit or sample clock) or dq_rad_per_s's unit is not rad/s: divide "
            f"dq_rad_per_s by {_factor(m)} if it is the velocity that is wrong")


def _factor(k: float) -> str:
    return f"{k:.2f}" if 0.1 <= abs(k) < 100 else f"{k:.4g}"


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def _check_velocity(path: Path, t: np.ndarray, q: np.ndarray, dq: np.ndarray,
                    notes: list[str]) -> None:
    """The angle moves with the velocity and the velocity is its time derivative
    (:func:`velocity_consistency`): refused above :data:`DQ_CONSISTENCY_TOL` once the
    angle's quantisation is discounted (in quadrature), noted as unsure with one warning
    above :data:`DQ_CONSISTENCY_SURE`; the figures are appended to ``notes``."""
    dq_rms = _rms(dq)
    if np.ptp(q) <= 1e-12 * max(1.0, float(np.abs(q).max())) and dq_rms > 0:
        raise ValueError(f"{path}: q_rad stays at {q[0]:g} rad while dq_rad_per_s has RMS "
                         f"{dq_rms:.3g} rad/s; the angle must move with the velocity")
    if dq_rms == 0:
        return  # a joint that never moves is refused by FrictionRecording.signals
    c = velocity_consistency(t, q, dq)
    beyond_rounding = float(np.sqrt(max(c.figure ** 2 - c.quantisation ** 2, 0.0)))
    parts = (f"RMS(q - integral of dq) {c.shape:.3f} of the excursion after offset and drift, "
             f"velocity offset {c.offset:.3f} of RMS(dq)")
    if c.quantisation >= 0.01:
        parts += (f", of which the angle's {c.resolution_rad:.3g} rad resolution explains "
                  f"{c.quantisation:.3f}")
    if beyond_rounding > DQ_CONSISTENCY_TOL:
        k = velocity_scale(t, q, dq)
        if k is not None:
            raise ValueError(
                f"{path}: dq_rad_per_s is not the time derivative of q_rad but {_factor(k)} "
                f"times it (a pure factor: consistency figure {c.figure:.2f}, allowed "
                f"{DQ_CONSISTENCY_TOL}); {scale_cause(k)}")
        raise ValueError(
            f"{path}: dq_rad_per_s is not the time derivative of q_rad: consistency figure "
            f"{c.figure:.2f} ({parts}; allowed {DQ_CONSISTENCY_TOL}); check units (rad, "
            "rad/s), sign and column order")
    if c.figure > DQ_CONSISTENCY_SURE:
        notes.append(
            f"velocity consistency unsure: figure {c.figure:.3f} ({parts}); above "
            f"{DQ_CONSISTENCY_SURE} a lagging velocity filter, an angle of few encoder counts "
            "or a velocity scale off by 1.2-1.6x look alike (refused above "
            f"{DQ_CONSISTENCY_TOL} once the angle's resolution is discounted); check units "
            "and that dq_rad_per_s is the time derivative of q_rad")
        log.warning("%s: %s", path.name, notes[-1])
    else:
        notes.append(f"velocity consistency: figure {c.figure:.3f} ({parts}; unsure above "
                     f"{DQ_CONSISTENCY_SURE}, refused above {DQ_CONSISTENCY_TOL})")


def write_friction_csv(rec: FrictionRecording, path: str | Path) -> Path:
    """Write a recording as a friction CSV (data kind 1) readable by
    :func:`load_friction_csv`."""
    path = Path(path)
    cols = {"time_s": rec.t_s, "q_rad": rec.q_rad, "dq_rad_per_s": rec.dq_rad_s,
            "ddq_rad_per_s2": rec.ddq_rad_s2, "tau_friction_Nm": rec.tau_nm}
    if rec.load_nm is not None:
        cols["load_Nm"] = rec.load_nm
    if rec.temperature_c is not None:
        cols["temperature_c"] = rec.temperature_c
    cols.update(rec.measured)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savetxt(path, np.column_stack(list(cols.values())), delimiter=",", header=",".join(cols),
               comments="", fmt="%.10g")
    return path


