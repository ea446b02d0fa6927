"""Measured joint friction: recordings (data kind 1), loading and checks.

A friction recording (data kind 1) is a CSV with the columns of the project's real data
(``docs/DATASET.md``, "Friction recordings"): ``time_s`` [s], ``q_rad`` [rad],
``dq_rad_per_s`` [rad/s], optionally ``ddq_rad_per_s2`` [rad/s²] and ``load_Nm`` [N m],
and the target ``tau_friction_Nm`` [N m]. Sampling may be irregular.

The recording becomes the signals of the friction terms (:class:`swgsim.friction.FrictionSignals`,
smooth-sign velocity v_s by default 1 % of the 99th percentile of |q̇|, so that least
squares is well posed); the baseline is the paper's law on the joint
(:class:`swgsim.friction.PaperLaw`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.signal import savgol_filter

from swgsim.friction.signals import FrictionSignals, Scales

from .options import FrictionOptions

log = logging.getLogger(__name__)

__all__ = [
    "FrictionRecording",
    "load_friction_csv",
    "write_friction_csv",
    "estimate_acceleration",
    "REQUIRED_COLUMNS",
]

REQUIRED_COLUMNS = ("time_s", "q_rad", "dq_rad_per_s", "tau_friction_Nm")
OPTIONAL_COLUMNS = ("ddq_rad_per_s2", "load_Nm")


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
    name : str
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
    name: str = "recording"
    ddq_source: str = "measured"
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        n = self.t_s.shape[0]
        for f in ("q_rad", "dq_rad_s", "ddq_rad_s2", "tau_nm", "load_nm"):
            a = getattr(self, f)
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
            of |q̇|.
        v_s_rel : float, default 0.01
        gear_ratio : float, optional
            Reduction ratio N of the strain wave gear (wave-generator turns per output
            turn), when known: ripples over q are then labelled with wave-generator
            orders k = 2π / (period · N).

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
            gear_ratio=None if gear_ratio is None else float(gear_ratio))


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
        ``n_window`` < 5.
    """
    if n_window < 5:
        raise ValueError(f"n_window must be >= 5, got {n_window}")
    dt = float(np.median(np.diff(t_s)))
    tu = np.arange(t_s[0], t_s[-1] + 0.5 * dt, dt)
    vu = np.interp(tu, t_s, dq)
    w = n_window | 1
    if tu.size < w:
        w = tu.size - (1 - tu.size % 2)
    au = savgol_filter(vu, w, 2, deriv=1, delta=dt)
    return np.interp(t_s, tu, au)


#: Largest allowed RMS difference between ``dq_rad_per_s`` and the time derivative of
#: ``q_rad``, relative to the RMS of ``dq_rad_per_s`` [-]. The six real recordings in
#: ``shared/data/joint_friction`` lie at 0.02-0.12 (derivative noise); a velocity in deg/s
#: beside an angle in rad, a swapped column or a frozen angle gives about 1 or more.
DQ_CONSISTENCY_TOL = 0.5
#: Fewest rows a friction recording must keep after cleaning.
MIN_ROWS = 100


def load_friction_csv(path: str | Path,
                      accel_window: int = FrictionOptions.accel_window) -> FrictionRecording:
    """Read a friction CSV (data kind 1) and check that it is physically consistent.

    Parameters
    ----------
    path : str or Path
        CSV with the columns ``time_s, q_rad, dq_rad_per_s, tau_friction_Nm`` and
        optionally ``ddq_rad_per_s2`` and ``load_Nm``.
    accel_window : int, default 21
        Window of :func:`estimate_acceleration`, used when ``ddq_rad_per_s2`` is absent
        or identically zero (the Franka files).

    Returns
    -------
    FrictionRecording
        Rows with non-finite values are dropped, and rows repeating the previous time
        stamp; both are counted in ``notes``, with the measured velocity consistency.

    Raises
    ------
    FileNotFoundError
    ValueError
        Naming the file: not a text CSV, a required column missing, rows of another
        length, no usable rows or fewer than :data:`MIN_ROWS`, time going backwards, an
        angle that stays constant while the velocity does not, or a velocity that is
        not the derivative of the angle (relative RMS difference above
        :data:`DQ_CONSISTENCY_TOL`).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"friction CSV not found: {path}")
    header = _read_header(path)
    cols = _read_columns(path, header)
    notes: list[str] = []
    sel = _usable_rows(path, cols, notes)
    t = cols["time_s"][sel]
    q = cols["q_rad"][sel]
    dq = cols["dq_rad_per_s"][sel]
    _check_velocity(path, t, q, dq, notes)
    ddq = cols.get("ddq_rad_per_s2")
    if ddq is None or not np.any(ddq[sel]):
        acc = estimate_acceleration(t, dq, accel_window)
        source = f"estimated (Savitzky-Golay, quadratic, {accel_window} samples)"
    else:
        acc, source = ddq[sel], "measured"
    return FrictionRecording(
        t_s=t, q_rad=q, dq_rad_s=dq, ddq_rad_s2=acc,
        tau_nm=cols["tau_friction_Nm"][sel],
        load_nm=cols["load_Nm"][sel] if "load_Nm" in cols else None,
        name=path.stem, ddq_source=source, notes=tuple(notes))


def _read_header(path: Path) -> list[str]:
    """The header of a friction CSV, checked for the required columns and a data row."""
    import csv

    try:
        with path.open(newline="", encoding="utf-8") as fh:
            header = next(csv.reader(fh), [])
            has_rows = any(line.strip() for line in fh)
    except UnicodeDecodeError as e:
        raise ValueError(f"{path}: not a text CSV ({e.reason} at byte {e.start})") from None
    header = [h.strip() for h in header]
    missing = [c for c in REQUIRED_COLUMNS if c not in header]
    if missing:
        raise ValueError(f"{path}: not a friction CSV: missing columns {missing}; expected "
                         f"{list(REQUIRED_COLUMNS)} (+ optional {list(OPTIONAL_COLUMNS)}), "
                         f"found {header}")
    if not has_rows:
        raise ValueError(f"{path}: no data rows below the header")
    return header


def _read_columns(path: Path, header: list[str]) -> dict[str, np.ndarray]:
    """Every column of the CSV by its header name (all rows, as read)."""
    try:
        data = np.genfromtxt(path, delimiter=",", skip_header=1, dtype=float,
                             encoding="utf-8")
    except ValueError as e:
        first = str(e).strip().splitlines()
        raise ValueError(f"{path}: rows of another length than the header "
                         f"({first[-1].strip() if first else e})") from None
    if data.size == 0:
        raise ValueError(f"{path}: no data rows below the header")
    if data.ndim == 1:
        data = data[None, :]
    if data.shape[1] != len(header):
        raise ValueError(f"{path}: {data.shape[1]} columns per row, header names "
                         f"{len(header)}")
    return {h: data[:, i] for i, h in enumerate(header)}


def _usable_rows(path: Path, cols: dict[str, np.ndarray], notes: list[str]) -> np.ndarray:
    """Indices of the rows kept: finite values, time stamps increasing (rows repeating
    the previous one dropped); what was dropped is appended to ``notes``."""
    use = list(REQUIRED_COLUMNS) + [c for c in OPTIONAL_COLUMNS if c in cols]
    ok = np.all(np.isfinite(np.column_stack([cols[c] for c in use])), axis=1)
    if not ok.all():
        notes.append(f"dropped {int((~ok).sum())} of {len(ok)} rows with non-finite or "
                     "non-numeric values")
        log.warning("%s: %s", path.name, notes[-1])
    if not ok.any():
        raise ValueError(f"{path}: no usable rows: all {len(ok)} rows hold non-finite or "
                         "non-numeric values")
    t = cols["time_s"][ok]
    dt = np.diff(t)
    if np.any(dt < 0):
        k = int(np.flatnonzero(dt < 0)[0])
        raise ValueError(f"{path}: time_s goes backwards after {t[k]:g} s (to {t[k + 1]:g} "
                         "s); rows must be in time order")
    keep = np.concatenate([[True], dt > 0])
    if not keep.all():
        notes.append(f"dropped {int((~keep).sum())} rows repeating the previous time stamp")
        log.warning("%s: %s", path.name, notes[-1])
    sel = np.flatnonzero(ok)[keep]
    if sel.size < MIN_ROWS:
        raise ValueError(f"{path}: {sel.size} usable rows, at least {MIN_ROWS} needed")
    return sel


def _check_velocity(path: Path, t: np.ndarray, q: np.ndarray, dq: np.ndarray,
                    notes: list[str]) -> None:
    """The angle moves with the velocity and the velocity is its time derivative
    (:data:`DQ_CONSISTENCY_TOL`); the consistency is appended to ``notes``."""
    dq_rms = float(np.sqrt(np.mean(dq ** 2)))
    if np.ptp(q) <= 1e-12 * max(1.0, float(np.abs(q).max())) and dq_rms > 0:
        raise ValueError(f"{path}: q_rad stays at {q[0]:g} rad while dq_rad_per_s has RMS "
                         f"{dq_rms:.3g} rad/s; the angle must move with the velocity")
    if dq_rms > 0:
        mismatch = float(np.sqrt(np.mean((dq - np.gradient(q, t)) ** 2)) / dq_rms)
        if mismatch > DQ_CONSISTENCY_TOL:
            raise ValueError(
                f"{path}: dq_rad_per_s is not the time derivative of q_rad: their RMS "
                f"difference is {mismatch:.2f} of the velocity's RMS (allowed "
                f"{DQ_CONSISTENCY_TOL}); check units (rad, rad/s) and column order")
        notes.append(f"velocity consistency: RMS(dq - d/dt q) / RMS(dq) = {mismatch:.3f} "
                     f"(allowed {DQ_CONSISTENCY_TOL})")


def write_friction_csv(rec: FrictionRecording, path: str | Path) -> Path:
    """Write a recording as a friction CSV (data kind 1) readable by
    :func:`load_friction_csv`.

    Parameters
    ----------
    rec : FrictionRecording
    path : str or Path

    Returns
    -------
    Path
    """
    path = Path(path)
    cols = {"time_s": rec.t_s, "q_rad": rec.q_rad, "dq_rad_per_s": rec.dq_rad_s,
            "ddq_rad_per_s2": rec.ddq_rad_s2, "tau_friction_Nm": rec.tau_nm}
    if rec.load_nm is not None:
        cols["load_Nm"] = rec.load_nm
    data = np.column_stack(list(cols.values()))
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savetxt(path, data, delimiter=",", header=",".join(cols), comments="", fmt="%.10g")
    return path


