"""Measured joint friction: recordings, signals and the paper-law baseline.

A friction recording (data kind 1) is a CSV with the columns of the project's real data
(``docs/DATASET.md``, "Friction recordings"): ``time_s`` [s], ``q_rad`` [rad],
``dq_rad_per_s`` [rad/s], optionally ``ddq_rad_per_s2`` [rad/s²] and ``load_Nm`` [N m],
and the target ``tau_friction_Nm`` [N m]. Sampling may be irregular.

The baseline is the paper's friction law, eq. (5), mapped to the joint coordinate q (the
gear output angle φ_out; the flank sliding velocity φ̇_b = −φ̇_out / sin α_tooth of
eq. (6) is proportional to q̇, so its constant factors fold into the coefficients):

    τ = b0 sgn(q̇) + b1 q̇ + b2 q̇³ + b3 sin(q + θ_b)

with the smooth sign sgn(q̇) = tanh(q̇ / v_s) and a small fixed v_s (default 1 % of the
99th percentile of |q̇|) so that least squares is well posed. b3 sin(q + θ_b) is fitted
linearly as A sin q + B cos q (b3 = hypot(A, B), θ_b = atan2(B, A)). The μ F_n term
needs a load signal; the recordings have none, so it lives in the effect library
(``load_coulomb``).
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.signal import savgol_filter

from .core import Param, Term

log = logging.getLogger(__name__)

__all__ = [
    "FrictionRecording",
    "FrictionSignals",
    "PaperLaw",
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
            load_nm=self.load_nm, v_eff=self.dq_rad_s, v_s=float(v_s), scales=Scales.of(self),
            gear_ratio=None if gear_ratio is None else float(gear_ratio))


@dataclass(frozen=True)
class Scales:
    """Data scales that set the bounds of nonlinear parameters.

    Attributes
    ----------
    v_ref : float
        99th percentile of |q̇| [rad/s].
    q_span : float
        max q − min q [rad].
    t0, t_span : float
        Start time and duration [s].
    dt_med : float
        Median sample interval [s].
    dq_med : float
        Median |Δq| per sample while moving [rad].
    q_center : float
        (max q + min q) / 2 [rad].
    """

    v_ref: float
    q_span: float
    t0: float
    t_span: float
    dt_med: float
    dq_med: float
    q_center: float = 0.0

    @classmethod
    def of(cls, rec: FrictionRecording) -> Scales:
        v = np.abs(rec.dq_rad_s)
        v_ref = float(np.percentile(v, 99))
        dq = np.abs(np.diff(rec.q_rad))
        moving = v[1:] > 0.05 * v_ref
        return cls(v_ref=v_ref, q_span=float(np.ptp(rec.q_rad)) or 1e-9, t0=float(rec.t_s[0]),
                   t_span=float(rec.t_s[-1] - rec.t_s[0]),
                   dt_med=float(np.median(np.diff(rec.t_s))),
                   dq_med=float(np.median(dq[moving])) if moving.any() else float(
                       np.median(dq) or 1e-9),
                   q_center=float(0.5 * (np.max(rec.q_rad) + np.min(rec.q_rad))))


@dataclass(frozen=True)
class FrictionSignals:
    """What friction terms see. ``v_eff`` is the velocity the friction law acts on
    (``dq_rad_s`` unless a transform term such as ``velocity_lag`` changed it).

    Attributes
    ----------
    t_s, q_rad, dq_rad_s, ddq_rad_s2, load_nm : ndarray, shape (n,)
        As in :class:`FrictionRecording` [s, rad, rad/s, rad/s², N m].
    v_eff : ndarray, shape (n,)
        Velocity seen by the friction law [rad/s].
    v_s : float
        Smooth-sign velocity [rad/s].
    scales : Scales
    extra : dict
        Integrator states of one time step (``{"states": {term name: state}}``).
    gear_ratio : float or None
        Reduction ratio N (wave-generator turns per output turn) when known [-].
    """

    t_s: np.ndarray
    q_rad: np.ndarray
    dq_rad_s: np.ndarray
    ddq_rad_s2: np.ndarray
    load_nm: np.ndarray | None
    v_eff: np.ndarray
    v_s: float
    scales: Scales
    extra: dict[str, Any] = field(default_factory=dict)
    gear_ratio: float | None = None

    @property
    def n(self) -> int:
        return int(self.t_s.shape[0])

    @property
    def sgn(self) -> np.ndarray:
        """Smooth sign tanh(v_eff / v_s), shape (n,)."""
        return np.tanh(self.v_eff / self.v_s)

    def replace(self, **changes: Any) -> FrictionSignals:
        return dataclasses.replace(self, **changes)


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


def load_friction_csv(path: str | Path, accel_window: int = 21) -> FrictionRecording:
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
    import csv

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"friction CSV not found: {path}")
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
    cols = {h: data[:, i] for i, h in enumerate(header)}
    use = list(REQUIRED_COLUMNS) + [c for c in OPTIONAL_COLUMNS if c in cols]
    ok = np.all(np.isfinite(np.column_stack([cols[c] for c in use])), axis=1)
    notes = []
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
    t = cols["time_s"][sel]
    q = cols["q_rad"][sel]
    dq = cols["dq_rad_per_s"][sel]
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


class PaperLaw(Term):
    """Paper eq. (5) on the joint: b0 sgn(q̇) + b1 q̇ + b2 q̇³ + b3 sin(q + θ_b)."""

    kind = "paper_law"
    linear = (
        Param("b0", "N m", "Coulomb level (smooth sign tanh(q̇/v_s))"),
        Param("b1", "N m s/rad", "viscous coefficient"),
        Param("b2", "N m s³/rad³", "cubic viscous coefficient"),
        Param("b3_sin", "N m", "b3 cos θ_b (coefficient of sin q)"),
        Param("b3_cos", "N m", "b3 sin θ_b (coefficient of cos q)"),
    )
    description = "paper eq. (5)-(6) mapped to the joint coordinate, smooth Coulomb sign"
    source = "paper eq. (5)-(6); Tuttle & Seering 1996"

    def columns(self, sig: FrictionSignals, theta: np.ndarray) -> np.ndarray:
        v = sig.v_eff
        q = sig.q_rad
        return np.column_stack([sig.sgn, v, v ** 3, np.sin(q), np.cos(q)])

    def derived(self, coef: np.ndarray, theta: np.ndarray) -> dict[str, float]:
        b0, b1, b2, a, b = (float(x) for x in coef)
        return {"b0": b0, "b1": b1, "b2": b2, "b3": float(np.hypot(a, b)),
                "theta_b": float(np.arctan2(b, a))}

    def derived_units(self) -> dict[str, str]:
        return {"b0": "N m", "b1": "N m s/rad", "b2": "N m s³/rad³", "b3": "N m",
                "theta_b": "rad"}

    def from_derived(self, b0: float, b1: float, b2: float, b3: float,
                     theta_b: float) -> np.ndarray:
        """Raw coefficients from (b0, b1, b2, b3, θ_b)."""
        return np.array([b0, b1, b2, b3 * np.cos(theta_b), b3 * np.sin(theta_b)])
