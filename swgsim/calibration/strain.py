"""Calibration of the simulation chain against measured strain windows (data kind 2).

Input: a schema-v1 data set (``swgsim.data``) of bench windows, fault possibly
``"unknown"``, each with its operating point (``n_in_rpm``, ``t_out_nm``,
``n_in_mean_rpm``, ``t_out_mean_nm``). Output: a report of the fitted chain, the effects
the data need from the declared library (:mod:`.strain_effects`), the error before and
after on held-out windows, and the accepted effects as a simulation option
(``sensor_effects`` of :mod:`swgsim.measurement`, kinematic-error harmonics for
:class:`swgsim.dynamics.GearParams`).

Model of a window. The chain is deterministic and periodic in steady state, so each
operating point is simulated once (:class:`StrainModel`): the dynamics with φ_in(0) = 0
over one input revolution more than a window, plus one run per unit kinematic-error
harmonic (linear response of the output torque), all in one vectorised integration.
The bridge signals follow from the chain's influence coefficients,
s = w0 (A cos 2ψ + B sin 2ψ) + T_out(t) h(ψ) (paper Fig. 2, :mod:`swgsim.influence`).
A window has two unknown phases: the WG angle relative to the flexspline ψ (the gauge
pattern) and the input angle φ_in (the torque ripple of the kinematic error), which
advance at rates in the ratio 1 + 1/N and are independent at a window's start (the
output angle is their difference). Both are nuisances fitted per window on that
window's own data: ψ by cross-correlation of the gauge pattern over half a WG
revolution, then the torque phase over one input revolution, each at every sample with
an objective invariant to per-channel positive gains and offsets, refined by a parabola;
ψ(t) and T_out(t) are then cubic splines of the simulation at the two shifts. The
alignment uses the nominal chain (plus, for a kinematic-error candidate, its own
ripple: the torque phase is re-aligned, see :class:`_Realigner`), never a fitted effect
parameter, so held-out windows are aligned exactly like fit windows.

Fit and selection: :func:`swgsim.calibration.loop.calibrate` (separable least squares,
uncertainties from the Jacobian with an autocorrelation correction, acceptance on
evidence: held-out likelihood and effective BIC, physical ranges; 'unexplained' verdict).
Held-out data are whole windows chosen by metadata (per operating point: the last window
of the sequence is a test window, the middle one a validation window), or whole
operating points.

Limitations. Only relative gauge angles and relative channel gains are observable, and a
delay common to all channels is not (module :mod:`.strain_effects`). A kinematic-error
candidate re-aligns each window's input angle, so it can absorb part of a tone that is
not locked to the rotation but lies within ~10 % of k n_in / 60 at one speed. A
placement error of single grids inside a bridge (not a rigid rotation of the bridge)
leaks the WG pattern into a channel, e.g. order 2 of ψ into the full bridge s0; no
candidate models it, and ``ke_order2`` can absorb part of it. Holding out operating
points leaves the fit with fewer speeds: speed-dependent effects (low-pass) need at
least two speeds among the fit windows. A window's input angle is known modulo 180° only
unless the odd orders of the torque ripple rise above the noise (:mod:`.strain_align`;
at 1 % noise they do not for the nominal gear). Structure that no library effect
explains lowers the evidence of every candidate (fewer effective samples): with an
out-of-library tone at order 3.5 (0.012 mV/V, 2.5 times the noise), a 1.5°
misplacement of s2 was reported as too small (2 ln Λ 7.3) instead of accepted (2 ln Λ
117-186 without it).

Typical use::

    from swgsim.calibration.strain import calibrate_strain
    summary = calibrate_strain("data/bench_run_7", "reports/bench_run_7")
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import logging
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.interpolate import CubicSpline

from .. import data as dsio
from ..chain import ChainSettings, SimulationChain
from ..dynamics import GearParams, gear_with_ke, rt1_size20
from ..dynamics import simulate as simulate_dynamics
from ..faults import ChainParams
from ..influence import torque_influence
from ..measurement import psi_rate
from .loop import CalibrationResult, Problem, SelectionConfig, calibrate
from .report import UNCERTAINTY_METHOD, fmt_value, result_section, summarize, to_jsonable
from .report import param_rows as _rows
from .split import HeldOutSplit, group_split
from .strain_align import flipped_ke, input_angle_evidence
from .strain_checks import (
    caveat,
    result_extras,
    simulation_option,
    too_small_rows,
    withheld_parameters,
)
from .strain_effects import (
    KE_ORDERS,
    SENSORS,
    ChainBaseline,
    StrainSignals,
    strain_library,
    strain_probes,
)

log = logging.getLogger(__name__)

__all__ = [
    "StrainWindows",
    "StrainModel",
    "strain_windows",
    "strain_problem",
    "calibrate_strain",
    "summarize_strain",
    "render_strain_report",
    "strain_figures",
    "gear_with_ke",
    "IDENTIFIABILITY",
]

IDENTIFIABILITY = (
    "Declared degeneracies (no encoder angle in schema v1): the WG angle of each window is "
    "a nuisance fitted by alignment, so a delay common to all channels is a shift of that "
    "angle and cannot be identified (time_delay is a simulation option only, not a "
    "candidate); only relative gauge angles are observable (misplacements are relative to "
    "the alignment-weighted mean; the angle of a channel with < 1 % of the alignment "
    "weight is not estimated); a gain common to all channels is the baseline's "
    "gauge_gain (channel gains are relative to their mean). A window's input angle is "
    "known modulo 180° only unless odd orders of the torque ripple rise above the noise "
    "(alignment table); the phase of an odd kinematic-error harmonic is then known "
    "modulo π only.")


# ---------------------------------------------------------------------------------------
# measured windows


@dataclass(frozen=True)
class StrainWindows:
    """Measured strain windows and their operating points.

    Attributes
    ----------
    y : ndarray, shape (n_windows, 5, n_t)
        Bridge outputs s0..s4 [mV/V].
    time_s : ndarray, shape (n_t,)
        Time since the window start [s], uniform.
    n_in_rpm, t_out_nm : ndarray, shape (n_windows,)
        Operating point simulated for each window (desired values, or the acting means
        where the desired ones are missing) [rpm, N m].
    n_in_mean_rpm, t_out_mean_nm : ndarray, shape (n_windows,)
        Acting mean input speed and output torque [rpm, N m].
    sample : ndarray of int, shape (n_windows,)
        Index of each window in the data set (its place in the recording sequence).
    op : ndarray of int, shape (n_windows,)
        Operating-point index into ``ops``.
    ops : tuple of (float, float)
        Distinct operating points (n_in [rpm], T_out [N m]), sorted.
    name : str
    source : str or None
    """

    y: np.ndarray
    time_s: np.ndarray
    n_in_rpm: np.ndarray
    t_out_nm: np.ndarray
    n_in_mean_rpm: np.ndarray
    t_out_mean_nm: np.ndarray
    sample: np.ndarray
    op: np.ndarray
    ops: tuple[tuple[float, float], ...]
    name: str = "strain"
    source: str | None = None

    @property
    def fs(self) -> float:
        """Sample rate [Hz]."""
        return 1.0 / float(self.time_s[1] - self.time_s[0])

    @property
    def n_windows(self) -> int:
        return int(self.y.shape[0])

    @property
    def n_t(self) -> int:
        return int(self.y.shape[2])


def strain_windows(ds: Any, select: Mapping[str, Any] | None = None,
                   max_windows: int | None = None, name: str | None = None) -> StrainWindows:
    """Measured windows from a schema-v1 data set.

    Parameters
    ----------
    ds : xarray.Dataset or path-like
        A loaded data set or its directory (``manifest.json``).
    select : mapping, optional
        Per-sample variable -> value or list of values to keep, e.g.
        ``{"disturbed": False, "gear": 1}``.
    max_windows : int, optional
        Keep at most this many windows per operating point (the first in sequence).
    name : str, optional
        Name for the report; default the data set's ``name`` attribute, else its folder.

    Returns
    -------
    StrainWindows

    Raises
    ------
    ValueError
        A ``select`` key that is not a per-sample variable, no window left, non-finite
        signals, or an operating point with non-positive speed.
    """
    source = None
    if not hasattr(ds, "data_vars"):
        source = str(ds)
        ds = dsio.load(ds)
    else:
        source = ds.attrs.get("source_path")
    keep = np.ones(ds.sizes["sample"], bool)
    for k, v in (select or {}).items():
        if k not in dsio.PER_SAMPLE:
            raise ValueError(f"select: {k!r} is not a per-sample variable; allowed: "
                             f"{sorted(dsio.PER_SAMPLE)}")
        vals = v if isinstance(v, (list, tuple)) else [v]
        keep &= np.isin(ds[k].values, vals)
    idx = np.flatnonzero(keep)
    if idx.size == 0:
        raise ValueError(f"no window left after select={dict(select or {})}")
    y = np.asarray(ds["strain_signal"].values[idx], float)
    if not np.all(np.isfinite(y)):
        raise ValueError("strain_signal has non-finite values in the selected windows")
    n_des = np.asarray(ds["n_in_rpm"].values[idx], float)
    t_des = np.asarray(ds["t_out_nm"].values[idx], float)
    n_mean = np.asarray(ds["n_in_mean_rpm"].values[idx], float)
    t_mean = np.asarray(ds["t_out_mean_nm"].values[idx], float)
    n_op = np.where(np.isfinite(n_des), n_des, np.round(n_mean, 0))
    t_op = np.where(np.isfinite(t_des), t_des, np.round(t_mean, 1))
    if np.any(~np.isfinite(n_op)) or np.any(n_op <= 0):
        raise ValueError("every window needs a positive input speed (n_in_rpm or "
                         "n_in_mean_rpm)")
    if np.any(~np.isfinite(t_op)) or np.any(t_op < 0):
        raise ValueError("every window needs a load torque >= 0 (t_out_nm or t_out_mean_nm)")
    n_mean = np.where(np.isfinite(n_mean), n_mean, n_op)
    t_mean = np.where(np.isfinite(t_mean), t_mean, t_op)
    keys = [(float(a), float(b)) for a, b in zip(n_op, t_op, strict=True)]
    ops = tuple(sorted(set(keys)))
    op = np.array([ops.index(k) for k in keys])
    sel = np.arange(idx.size)
    if max_windows is not None:
        if int(max_windows) < 1:
            raise ValueError(f"max_windows must be >= 1, got {max_windows}")
        sel = np.sort(np.concatenate([np.flatnonzero(op == i)[:int(max_windows)]
                                      for i in range(len(ops))]))
    t = np.asarray(ds["time"].values, float)
    # the data set's own name (its attribute), else its folder
    nm = name or str(ds.attrs.get("name") or (Path(source).name if source else "strain"))
    return StrainWindows(y=y[sel], time_s=t, n_in_rpm=n_op[sel], t_out_nm=t_op[sel],
                         n_in_mean_rpm=n_mean[sel], t_out_mean_nm=t_mean[sel],
                         sample=idx[sel], op=op[sel], ops=ops, name=nm, source=source)


# ---------------------------------------------------------------------------------------
# the chain's prediction as a function of the window's time shift


@dataclass
class _OPModel:
    """Steady trajectory of one operating point (see :class:`StrainModel`)."""

    n_in_rpm: float
    t_out_nm: float
    fs: float
    t0_s: float  # simulation time of window sample 0 at zero shift
    n_half: int  # ψ shifts searched by the alignment: half a WG revolution [samples]
    n_rev: int  # torque shifts searched: one input revolution [samples]
    psi: CubicSpline
    phi_in: CubicSpline
    t_out: CubicSpline
    d_t: dict[str, CubicSpline]  # "ke{k}_sin"/"_cos" -> ΔT per unit KE amplitude [N m/rad]
    d_t_long: dict[str, np.ndarray]  # the same on the simulation grid, each (n_l,)
    p_psi_long: np.ndarray  # (5, n_l) s_wg(ψ) + T̄ h(ψ) on the simulation grid
    t_long: np.ndarray  # (n_l,) output torque on the simulation grid [N m]
    t_mean: float
    efficiency: float


class StrainModel:
    """The nominal chain's prediction of measured windows, per operating point.

    The WG angle relative to the flexspline, ψ = φ_in − φ_out, and the input angle φ_in
    advance at rates in the ratio 1 + 1/N, so their phases at a window's start are two
    independent unknowns (the output angle is their difference). The gauge pattern
    depends on ψ, the torque ripple (kinematic error) on φ_in: a window is the steady
    trajectory with ψ(t) taken at one time shift and T_out(t), φ_in(t) at another.

    Parameters
    ----------
    chain : SimulationChain, optional
        Chain with the sensor layout of the measured gear (default: nominal layout,
        default truss, built here: about 1.5 s).
    params : ChainParams, optional
        Gear (default: nominal RT1 size 20, :func:`swgsim.dynamics.rt1_size20`).
    ke_orders : tuple of int
        Orders of the unit kinematic-error responses (the ``ke_order{k}`` candidates).
    ke_unit_rad : float
        Amplitude of the unit KE harmonic [rad] (small: linear response).
    settle_s : float
        Transient simulated before the trajectory is used [s].
    """

    def __init__(self, chain: SimulationChain | None = None, params: ChainParams | None = None,
                 ke_orders: Sequence[int] = KE_ORDERS, ke_unit_rad: float = 1e-5,
                 settle_s: float = 0.1) -> None:
        if not ke_unit_rad > 0:
            raise ValueError(f"ke_unit_rad must be > 0 [rad], got {ke_unit_rad}")
        if not settle_s >= 0:
            raise ValueError(f"settle_s must be >= 0 [s], got {settle_s}")
        self.chain = chain if chain is not None else SimulationChain(settings=ChainSettings())
        self.params = params if params is not None else ChainParams(gear=rt1_size20())
        self.ke_orders = tuple(int(k) for k in ke_orders)
        self.ke_unit_rad = float(ke_unit_rad)
        self.settle_s = float(settle_s)
        self._cache: dict[tuple, _OPModel] = {}

    # -- simulation --------------------------------------------------------------------
    def _variants(self) -> tuple[list[GearParams], list[str]]:
        g = self.params.gear
        base_o, base_a, base_p = tuple(g.ke_orders), tuple(g.ke_amp_rad), tuple(g.ke_phase_rad)

        def with_extra(order, amp, ph):
            return dataclasses.replace(g, ke_orders=base_o + (order,), ke_amp_rad=base_a + (amp,),
                                       ke_phase_rad=base_p + (ph,))

        gears = [with_extra(1, 0.0, 0.0)]
        names = ["nominal"]
        for k in self.ke_orders:
            gears += [with_extra(k, self.ke_unit_rad, 0.0),
                      with_extra(k, self.ke_unit_rad, 0.5 * np.pi)]
            names += [f"ke{k}_sin", f"ke{k}_cos"]
        return gears, names

    def _signals(self, psi: np.ndarray, torque: np.ndarray | float
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """s_wg, h and ∂s/∂ψ at fixed torque, each shape (5, n), for ψ, T of shape (n,)."""
        p = self.params
        inf = self.chain.influence(p)
        c = p.tooth_factors(inf.theta)
        hw = np.deg2rad(self.chain.settings.contact_half_width_deg)
        cos2, sin2 = np.cos(2 * psi), np.sin(2 * psi)
        s_wg = p.w0_m * (inf.A[:, None] * cos2 + inf.B[:, None] * sin2)
        h = torque_influence(psi, inf.g, inf.theta, c, hw)
        eps = 1e-4
        dh = (torque_influence(psi + eps, inf.g, inf.theta, c, hw)
              - torque_influence(psi - eps, inf.g, inf.theta, c, hw)) / (2 * eps)
        dpsi = 2 * p.w0_m * (-inf.A[:, None] * sin2 + inf.B[:, None] * cos2) + torque * dh
        return s_wg, h, dpsi

    def op_model(self, n_in_rpm: float, t_out_nm: float, fs: float, n_t: int, n_lead: int,
                 n_tail: int) -> _OPModel:
        """Simulate (or fetch) the steady trajectory of an operating point.

        Parameters
        ----------
        n_in_rpm, t_out_nm : float
            Operating point [rpm, N m].
        fs : float
            Sample rate of the data [Hz].
        n_t, n_lead, n_tail : int
            Window length and the extension before/after it [samples].
        """
        key = (float(n_in_rpm), float(t_out_nm), float(fs), int(n_t), int(n_lead), int(n_tail))
        if key in self._cache:
            return self._cache[key]
        t_rev = 60.0 / float(n_in_rpm)
        n_rev = int(np.ceil(t_rev * fs)) + 2
        rate = float(psi_rate(n_in_rpm, self.params.gear.ratio))
        n_half = int(np.ceil(np.pi / rate * fs)) + 2
        t0 = (n_lead + 3) / fs
        span = t0 + (n_rev + n_t + n_tail + 6) / fs
        gears, names = self._variants()
        res = simulate_dynamics(gears, n_in_rpm, t_out_nm, 0.0, sample_rate_hz=fs,
                                window_s=span, settle_s=self.settle_s, substeps=1)
        if not res.success:
            raise RuntimeError(f"dynamic simulation failed at {n_in_rpm} rpm, {t_out_nm} N m: "
                               f"{res.message}")
        tl = res.time
        psi = res.psi[0]
        t_out = res.t_out[0]
        t_mean = float(t_out.mean())
        d_t_long = {nm: (res.t_out[i] - t_out) / self.ke_unit_rad
                    for i, nm in enumerate(names) if i > 0}
        d_t = {nm: CubicSpline(tl, v) for nm, v in d_t_long.items()}
        s_wg, h, _ = self._signals(psi, t_mean)
        opm = _OPModel(n_in_rpm=float(n_in_rpm), t_out_nm=float(t_out_nm), fs=float(fs), t0_s=t0,
                       n_half=n_half, n_rev=n_rev, psi=CubicSpline(tl, psi),
                       phi_in=CubicSpline(tl, res.states[0, 0]), t_out=CubicSpline(tl, t_out),
                       d_t=d_t, d_t_long=d_t_long, p_psi_long=s_wg + t_mean * h, t_long=t_out,
                       t_mean=t_mean, efficiency=float(res.efficiency[0]))
        self._cache[key] = opm
        return opm

    # -- alignment ---------------------------------------------------------------------
    @staticmethod
    def _best_shift(obj: np.ndarray) -> float:
        """Index of the maximum of a sampled objective, refined by a parabola."""
        j = int(np.argmax(obj))
        if 0 < j < obj.size - 1:
            a, b, c = obj[j - 1], obj[j], obj[j + 1]
            d = a - 2 * b + c
            if d < 0:
                return j + float(np.clip(0.5 * (a - c) / d, -0.5, 0.5))
        return float(j)

    @staticmethod
    def _corr_objective(pred: np.ndarray, yd: np.ndarray) -> np.ndarray:
        """Σ_c max(ỹ_c · p̃_c, 0)² / |p̃_c|² for candidate predictions pred (5, n_j, n_t)
        and the mean-free window yd (5, n_t): the fit with the best positive gain and any
        offset per channel (a negative gain would accept a pattern 90° off in ψ)."""
        n_t = yd.shape[-1]
        pm = pred.mean(axis=-1)
        den = np.maximum(np.einsum("cjt,cjt->cj", pred, pred) - n_t * pm ** 2, 1e-30)
        num = np.einsum("cjt,ct->cj", pred, yd)
        return (np.maximum(num, 0.0) ** 2 / den).sum(axis=0)

    def align_psi(self, opm: _OPModel, y: np.ndarray) -> np.ndarray:
        """WG-angle time shift of each window (nominal chain only).

        The pattern s_wg(ψ) + T̄ h(ψ) (mean torque) against the window over half a WG
        revolution at every sample, maximising Σ_c max(ỹ_c · p̃_c, 0)² / |p̃_c|² (tilde:
        mean removed per channel: invariant to per-channel positive gains and offsets),
        refined by a parabola through the neighbours. The torque phase follows in
        :class:`_Realigner`.

        Parameters
        ----------
        opm : _OPModel
        y : ndarray, shape (n_w, 5, n_t)
            Measured windows of this operating point [mV/V].

        Returns
        -------
        ndarray, shape (n_w,)
            Shift [s]: window sample k takes ψ at simulation time t0 + shift + k / fs.
        """
        n_w, _, n_t = y.shape
        i0 = int(round(opm.t0_s * opm.fs))
        seg = np.lib.stride_tricks.sliding_window_view(opm.p_psi_long, n_t, axis=1)[
            :, i0:i0 + opm.n_half + 1, :]  # (5, n_j, n_t)
        out = np.empty(n_w)
        for w in range(n_w):
            yd = y[w] - y[w].mean(axis=-1, keepdims=True)
            out[w] = self._best_shift(self._corr_objective(seg, yd)) / opm.fs
        return out

    def psi_parts(self, opm: _OPModel, shift_psi: np.ndarray, n_t: int, n_lead: int,
                  n_tail: int) -> dict[str, np.ndarray]:
        """The ψ-dependent parts of windows aligned at ``shift_psi``.

        Returns
        -------
        dict
            "s_wg", "h", "dh" (∂h/∂ψ), "dpsi_wg" (∂s_wg/∂ψ), each shape
            (n_w, 5, n_lead + n_t + n_tail) [mV/V, mV/V / N m, ...], and "psi" (n_w, m)
            [rad].
        """
        m = n_lead + n_t + n_tail
        shift_psi = np.asarray(shift_psi, float)
        n_w = shift_psi.size
        tp = (opm.t0_s + shift_psi[:, None] + (np.arange(m) - n_lead)[None, :] / opm.fs).ravel()
        psi = opm.psi(tp)
        s_wg, h, dpsi_h = self._signals(psi, 1.0)  # dpsi at T = 1: dpsi_wg + dh
        _, _, dpsi_wg = self._signals(psi, 0.0)

        def shape(a: np.ndarray) -> np.ndarray:
            return np.ascontiguousarray(a.reshape(5, n_w, m).transpose(1, 0, 2))

        return {"s_wg": shape(s_wg), "h": shape(h), "dh": shape(dpsi_h - dpsi_wg),
                "dpsi_wg": shape(dpsi_wg), "psi": psi.reshape(n_w, m)}


def _batched(seg: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Σ_t seg[j, t] a[w, c, t] for all shifts j, windows w, channels c: one matrix product
    (n_j, n_t) @ (n_t, n_w · 5), shape (n_j, n_w, 5)."""
    n_w, n_c, n_t = a.shape
    return (seg @ a.transpose(2, 0, 1).reshape(n_t, n_w * n_c)).reshape(-1, n_w, n_c)


class _Realigner:
    """Torque phase of every window for a given kinematic-error model, and the raw basis.

    For extra harmonics ``ke`` = ((order, a_sin, a_cos), ...), the torque of an operating
    point is T(t) = T_out(t) + Σ (a_sin ΔT_sin + a_cos ΔT_cos)(t); each window's time
    shift of T over one input revolution maximises Σ_c max(ỹ_c · p̃_c, 0)² / |p̃_c|² with
    p_c = s_wg,c + T h_c (ψ fixed), by matrix products of the shifted torque with
    per-channel vectors (no candidate signals are formed), refined by a parabola.
    Results are memoised per ``ke``.

    Parameters
    ----------
    model : StrainModel
    opms : list of _OPModel
        One per operating point.
    op_of : ndarray of int, shape (n_w,)
    parts : dict
        :meth:`StrainModel.psi_parts` of all windows, arrays (n_w, 5, m).
    y : ndarray, shape (n_w, 5, n_t)
        Measured windows [mV/V].
    n_lead : int
    """

    def __init__(self, model: StrainModel, opms: list[_OPModel], op_of: np.ndarray,
                 parts: dict[str, np.ndarray], y: np.ndarray, n_lead: int) -> None:
        self.model, self.opms, self.op_of = model, opms, np.asarray(op_of)
        self.parts, self.n_lead = parts, int(n_lead)
        self.n_w, _, self.n_t = y.shape
        self.m = parts["s_wg"].shape[-1]
        sl = slice(self.n_lead, self.n_lead + self.n_t)
        yd = y - y.mean(axis=-1, keepdims=True)
        s = parts["s_wg"][:, :, sl]
        h = parts["h"][:, :, sl]
        # per window and channel: Σ s ỹ, Σ s², Σ s, and the vectors multiplying T, T²
        self._a = (s * yd).sum(-1)
        self._s2 = (s * s).sum(-1)
        self._s1 = s.sum(-1)
        self._hy = h * yd  # (n_w, 5, n_t)
        self._sh = s * h
        self._h2 = h * h
        self._h = h
        self._memo: dict[tuple, dict[str, np.ndarray]] = {}
        self._unit: dict[int, np.ndarray] = {}

    def _torque_long(self, i: int, ke: tuple) -> np.ndarray:
        opm = self.opms[i]
        t = opm.t_long.copy()
        for k, a_s, a_c in ke:
            t += a_s * opm.d_t_long[f"ke{k}_sin"] + a_c * opm.d_t_long[f"ke{k}_cos"]
        return t

    def objectives(self, ke: tuple) -> list[np.ndarray]:
        """The alignment objective of every window over its torque shifts.

        Returns
        -------
        list of ndarray
            Per window, shape (n_rev + 1,): Σ_c max(ỹ_c · p̃_c, 0)² / |p̃_c|² at the torque
            shifts 0, 1, ... samples over one input revolution [(mV/V)²]: the drop of the
            residual sum of squares with per-channel positive gains and offsets.
        """
        out: list[np.ndarray] = [np.empty(0)] * self.n_w
        n_t = self.n_t
        for i, opm in enumerate(self.opms):
            ws = np.flatnonzero(self.op_of == i)
            if ws.size == 0:
                continue
            i0 = int(round(opm.t0_s * opm.fs))
            seg = np.ascontiguousarray(np.lib.stride_tricks.sliding_window_view(
                self._torque_long(i, ke), n_t)[i0:i0 + opm.n_rev + 1])  # (n_j, n_t)
            num = self._a[ws][None] + _batched(seg, self._hy[ws])
            sum_p = self._s1[ws][None] + _batched(seg, self._h[ws])
            sum_p2 = (self._s2[ws][None] + 2 * _batched(seg, self._sh[ws])
                      + _batched(seg * seg, self._h2[ws]))
            den = np.maximum(sum_p2 - sum_p ** 2 / n_t, 1e-30)
            obj = (np.maximum(num, 0.0) ** 2 / den).sum(axis=2)  # (n_j, n_ws)
            for j, w in enumerate(ws):
                out[w] = obj[:, j]
        return out

    def shifts(self, ke: tuple) -> np.ndarray:
        """Torque time shift of every window [s], shape (n_w,)."""
        obj = self.objectives(ke)
        return np.array([StrainModel._best_shift(obj[w]) / self.opms[self.op_of[w]].fs
                         for w in range(self.n_w)])

    def _times(self, shifts: np.ndarray, w: np.ndarray) -> np.ndarray:
        opm = self.opms[self.op_of[w[0]]]
        k = (np.arange(self.m) - self.n_lead)[None, :] / opm.fs
        return (opm.t0_s + shifts[w][:, None] + k).ravel()

    def __call__(self, ke: tuple = ()) -> dict[str, np.ndarray]:
        """Raw "s_t", "dpsi" (n_w, 5, m), "phi_in" (n_w, m) [rad] and "shift_t" (n_w,) [s]
        for extra harmonics ``ke``."""
        key = tuple((int(k), float(a), float(b)) for k, a, b in ke)
        if key in self._memo:
            return self._memo[key]
        sh = self.shifts(key)
        torque = np.empty((self.n_w, self.m))
        phi = np.empty((self.n_w, self.m))
        for i, opm in enumerate(self.opms):
            ws = np.flatnonzero(self.op_of == i)
            if ws.size == 0:
                continue
            tt = self._times(sh, ws)
            t = opm.t_out(tt)
            for k, a_s, a_c in key:
                t = t + a_s * opm.d_t[f"ke{k}_sin"](tt) + a_c * opm.d_t[f"ke{k}_cos"](tt)
            torque[ws] = t.reshape(ws.size, self.m)
            phi[ws] = opm.phi_in(tt).reshape(ws.size, self.m)
        p = self.parts
        out = {"s_t": torque[:, None, :] * p["h"],
               "dpsi": p["dpsi_wg"] + torque[:, None, :] * p["dh"],
               "phi_in": phi, "shift_t": sh}
        if len(self._memo) > 64:
            self._memo.clear()
        self._memo[key] = out
        return out

    def unit(self, order: int, ke: tuple = ()) -> np.ndarray:
        """Unit responses ΔT_sin h, ΔT_cos h of an order at the alignment for ``ke``,
        shape (2, n_w, 5, m) [mV/V / rad]."""
        if order in self._unit and not ke:
            return self._unit[order]
        sh = self(ke)["shift_t"]
        out = np.empty((2, self.n_w, 5, self.m))
        for i, opm in enumerate(self.opms):
            ws = np.flatnonzero(self.op_of == i)
            if ws.size == 0:
                continue
            tt = self._times(sh, ws)
            for j, nm in enumerate((f"ke{order}_sin", f"ke{order}_cos")):
                out[j, ws] = opm.d_t[nm](tt).reshape(ws.size, 1, self.m) * self.parts["h"][ws]
        if not ke:
            self._unit[order] = out
        return out


def _heldout_split(win: StrainWindows, heldout: str, validation: Sequence[int] | None,
                   test: Sequence[int] | None) -> tuple[np.ndarray, str]:
    """Roles of whole windows (0 fit, 1 validation, 2 test) and the description text."""
    n_w = win.n_windows
    role = np.zeros(n_w, int)
    if heldout == "windows":
        if validation is not None or test is not None:
            if validation is None or test is None:
                raise ValueError("give both validation and test (data-set sample indices) or "
                                 "neither")
            for what, lst, r in (("validation", validation, 1), ("test", test, 2)):
                bad = [s for s in lst if s not in set(win.sample.tolist())]
                if bad:
                    raise ValueError(f"{what} samples {bad} are not among the selected windows")
                role[np.isin(win.sample, list(lst))] = r
            how = "given lists"
        else:
            for i in range(len(win.ops)):
                w = np.flatnonzero(win.op == i)
                w = w[np.argsort(win.sample[w])]
                if w.size < 3:
                    raise ValueError(
                        f"heldout='windows' needs >= 3 windows per operating point (fit, "
                        f"validation, test); operating point {win.ops[i]} has {w.size}")
                role[w[-1]] = 2
                role[w[(w.size - 1) // 2]] = 1
            how = ("per operating point, the last window of the sequence is a test window "
                   "(drift must extrapolate) and the middle one a validation window")
        text = (f"Whole windows held out by metadata ({how}): validation samples "
                f"{win.sample[role == 1].tolist()}, test samples {win.sample[role == 2].tolist()}, "
                f"fit samples {win.sample[role == 0].tolist()}. Every window's WG angle is "
                "aligned on that window's own data with the nominal chain only (no effect "
                "parameter), so held-out windows are treated exactly like fit windows.")
    elif heldout == "operating_points":
        n_op = len(win.ops)
        if n_op < 3:
            raise ValueError(f"heldout='operating_points' needs >= 3 operating points, "
                             f"got {n_op}; use heldout='windows'")
        v = list(validation) if validation is not None else [n_op // 2]
        te = list(test) if test is not None else [n_op - 1]
        for what, lst in (("validation", v), ("test", te)):
            bad = [i for i in lst if not 0 <= int(i) < n_op]
            if bad:
                raise ValueError(f"{what} operating-point indices {bad} outside [0, {n_op})")
        if set(v) & set(te):
            raise ValueError(f"operating points {sorted(set(v) & set(te))} are both "
                             "validation and test")
        role[np.isin(win.op, v)] = 1
        role[np.isin(win.op, te)] = 2
        text = ("Whole operating points held out: validation "
                f"{[win.ops[i] for i in v]}, test {[win.ops[i] for i in te]} "
                "((n_in [rpm], T_out [N m])); the model must extrapolate to them.")
    else:
        raise ValueError(f"heldout must be 'windows' or 'operating_points', got {heldout!r}")
    if not (role == 0).any():
        raise ValueError("no fit windows left after holding out validation and test windows")
    return role, text


def strain_problem(win: StrainWindows, model: StrainModel | None = None, *,
                   heldout: str = "windows", validation: Sequence[int] | None = None,
                   test: Sequence[int] | None = None, candidates: Sequence[str] | None = None,
                   window_period_s: float | None = None,
                   f_c_bounds_hz: tuple[float, float] | None = None,
                   ke_bound_rad: float = 2e-3) -> Problem:
    """Calibration problem for measured strain windows.

    Parameters
    ----------
    win : StrainWindows
    model : StrainModel, optional
        Reused across calls to share simulated operating points.
    heldout : {"windows", "operating_points"}
        Hold out whole windows (default) or whole operating points.
    validation, test : sequence of int, optional
        Data-set sample indices (``heldout="windows"``) or operating-point indices
        (``"operating_points"``); default chosen by metadata (see module docstring).
    candidates : sequence of str, optional
        Library keys to try (default: all of :func:`strain_library`).
    window_period_s : float, optional
        Time between the starts of consecutive data-set samples, for the thermal drift
        [s]; default the window length (back-to-back windows).
    f_c_bounds_hz : (float, float), optional
        Range of the low-pass cut-off [Hz]; default half the highest order-2 frequency
        to 0.45 fs.
    ke_bound_rad : float, default 2e-3
        Bound of the extra kinematic-error coefficients [rad] (7 arcmin, far above the
        catalogue's about 1 arcmin in total).

    Returns
    -------
    Problem

    Raises
    ------
    KeyError
        Unknown candidate.
    ValueError
        Bad held-out settings, a window shorter than one WG half revolution, or bad bounds.
    """
    model = model if model is not None else StrainModel()
    fs, n_t, n_w = win.fs, win.n_t, win.n_windows
    ratio = float(model.params.gear.ratio)
    rate = psi_rate(win.n_in_mean_rpm, ratio)  # (n_w,)
    f2 = 2 * rate / (2 * np.pi)
    if n_t / fs < np.pi / rate.min():
        raise ValueError(f"windows of {n_t / fs * 1e3:.1f} ms are shorter than half a WG "
                         f"revolution ({np.pi / rate.min() * 1e3:.1f} ms): cannot align")
    lo, hi = f_c_bounds_hz if f_c_bounds_hz is not None else (0.5 * f2.max(), 0.45 * fs)
    if not 0 < lo < hi < 0.5 * fs:
        raise ValueError(f"f_c_bounds_hz must satisfy 0 < lo < hi < {0.5 * fs:g} Hz, got "
                         f"{(lo, hi)}")
    n_lead = int(np.ceil(6.0 / (2 * np.pi * lo) * fs)) + 4
    n_tail = int(np.ceil(np.max(np.arctan(f2 / lo) / (2 * np.pi * f2)) * fs)) + 6
    lib_all = strain_library(model.ke_orders)
    keys = list(candidates) if candidates is not None else list(lib_all)
    unknown = [k for k in keys if k not in lib_all]
    if unknown:
        raise KeyError(f"unknown strain effects {unknown}; library: {sorted(lib_all)}")
    role, held_text = _heldout_split(win, heldout, validation, test)

    parts: dict[str, np.ndarray] = {}
    shifts = np.empty(n_w)
    eff = np.empty(n_w)
    opms = []
    for i, (n_in, t_out) in enumerate(win.ops):
        ws = np.flatnonzero(win.op == i)
        opm = model.op_model(n_in, t_out, fs, n_t, n_lead, n_tail)
        opms.append(opm)
        sh = model.align_psi(opm, win.y[ws])
        for k, v in model.psi_parts(opm, sh, n_t, n_lead, n_tail).items():
            parts.setdefault(k, np.empty((n_w,) + v.shape[1:]))[ws] = v
        shifts[ws] = sh
        eff[ws] = opm.efficiency
    realign = _Realigner(model, opms, win.op, parts, win.y, n_lead)
    first = realign(())
    basis = {"s_wg": parts["s_wg"], "s_t": first["s_t"], "dpsi": first["dpsi"]}
    shifts_t = first["shift_t"]
    psi_w = parts["psi"][:, n_lead:n_lead + n_t]
    phi_w = first["phi_in"][:, n_lead:n_lead + n_t]

    # constraint weights: gains relative to the plain mean; misplacements relative to the
    # mean weighted like the alignment (sensitivity of the correlation to each channel)
    sl = slice(n_lead, n_lead + n_t)
    p = basis["s_wg"][:, :, sl] + basis["s_t"][:, :, sl]
    d = basis["dpsi"][:, :, sl]
    p = p - p.mean(-1, keepdims=True)
    d = d - d.mean(-1, keepdims=True)
    proj = (d * p).sum(-1, keepdims=True) / np.maximum((p * p).sum(-1, keepdims=True), 1e-30)
    w_mis = ((d - proj * p) ** 2).sum(-1).sum(0)  # (5,)
    w_mis = np.maximum(w_mis, 1e-12 * w_mis.max())
    weights = {"gain": np.ones(5), "misplacement": w_mis}

    period = float(window_period_s) if window_period_s is not None else n_t / fs
    if not period > 0:
        raise ValueError(f"window_period_s must be > 0 [s], got {window_period_s}")
    t_start = (win.sample - win.sample.min()) * period  # (n_w,)
    shape = (n_w, 5, n_t)
    wi = np.broadcast_to(np.arange(n_w)[:, None, None], shape).ravel()
    ci = np.broadcast_to(np.arange(5)[None, :, None], shape).ravel()
    ts = np.broadcast_to(win.time_s[None, None, :] - win.time_s[0], shape).ravel()
    sig = StrainSignals(
        raw=basis, n_lead=n_lead, n_t=n_t, fs=fs, window=wi, channel=ci, op=win.op[wi],
        t_s=ts, t_seq_s=t_start[wi] + ts,
        phi_in_rad=np.broadcast_to(phi_w[:, None, :], shape).ravel(),
        psi_rad=np.broadcast_to(psi_w[:, None, :], shape).ravel(),
        psi_rate=rate, n_in_rpm=win.n_in_mean_rpm, t_out_nm=win.t_out_mean_nm, ops=win.ops,
        w0_nom_m=float(model.params.w0_m), weights=weights, maps=(), ripple=realign, ke=(),
        ke_orders=model.ke_orders, ke_bound_rad=float(ke_bound_rad),
        f_c_bounds=(float(lo), float(hi)))
    y = win.y.reshape(-1).astype(float)
    # the diagnosis splits samples into halves of contiguous blocks of Problem.t: with
    # the time within the window, the halves are interleaved time slices of every window
    groups = wi
    split = group_split(groups, np.flatnonzero(role == 1).tolist(),
                        np.flatnonzero(role == 2).tolist())
    desc = dict(split.description)
    desc.update({"method": ("whole windows held out by metadata" if heldout == "windows" else
                            "whole operating points held out"),
                 "text": held_text,
                 "validation_samples": win.sample[role == 1].tolist(),
                 "test_samples": win.sample[role == 2].tolist(),
                 "fit_samples": win.sample[role == 0].tolist()})
    split = HeldOutSplit(split.fit, split.validation, split.test, desc)
    rng_psi0 = np.rad2deg(np.mod(psi_w[:, 0], np.pi))
    phi0 = np.rad2deg(np.mod(phi_w[:, 0], 2 * np.pi))
    meta = {
        "n_windows": n_w, "n_t": n_t, "sample_rate_hz": fs, "window_s": n_t / fs,
        "operating_points": [list(o) for o in win.ops],
        "windows_per_op": np.bincount(win.op, minlength=len(win.ops)).tolist(),
        "n_lead": n_lead, "n_tail": n_tail, "window_period_s": period,
        "alignment": [{"sample": int(s), "op": int(o), "shift_psi_s": float(sh),
                       "shift_torque_s": float(st), "psi0_deg": float(a),
                       "phi_in0_deg": float(b), "role": ("fit", "validation", "test")[r]}
                      for s, o, sh, st, a, b, r in zip(win.sample, win.op, shifts, shifts_t,
                                                       rng_psi0, phi0, role, strict=True)],
        "model_efficiency": eff.tolist(),
        "weights": {k: v.tolist() for k, v in weights.items()},
        "f_c_bounds_hz": [float(lo), float(hi)],
        "gear_ratio": ratio, "w0_nom_m": float(model.params.w0_m),
        "source": win.source,
    }
    return Problem(name=win.name, kind="strain", units="mV/V", signals=sig, y=y, t=ts,
                   baseline=(ChainBaseline.for_signals(sig),),
                   library={k: lib_all[k] for k in keys}, probes=strain_probes(), split=split,
                   meta=meta)


# ---------------------------------------------------------------------------------------
# summary, report, figures


def _alignment_se(result: CalibrationResult) -> np.ndarray:
    """Standard error of each window's WG angle from the alignment curvature [deg]:
    se(ψ0) = σ / sqrt(Σ_c |∂s_c/∂ψ ⊥ s_c|²), σ the final residual RMS."""
    sig: StrainSignals = result.problem.signals
    sl = slice(sig.n_lead, sig.n_lead + sig.n_t)
    p = sig.basis["s_wg"][:, :, sl] + sig.basis["s_t"][:, :, sl]
    d = sig.basis["dpsi"][:, :, sl]
    p = p - p.mean(-1, keepdims=True)
    d = d - d.mean(-1, keepdims=True)
    proj = (d * p).sum(-1, keepdims=True) / np.maximum((p * p).sum(-1, keepdims=True), 1e-30)
    info = ((d - proj * p) ** 2).sum(-1).sum(-1)  # (n_w,)
    return np.rad2deg(result.final.sigma / np.sqrt(np.maximum(info, 1e-30)))


def summarize_strain(result: CalibrationResult, source: str | None = None) -> dict[str, Any]:
    """Machine-readable summary of a strain calibration (``summary.json``).

    The keys of :func:`swgsim.calibration.report.summarize` (``rmse_before``,
    ``rmse_after`` on the test windows [mV/V], ``unexplained``, ``residual_signature``,
    ``iterations``, ...) with, for the strain side:

    * ``effects_added``: ``[{name, kind, params: {p: {value, stderr, unit, identifiable,
      flag}}, ...}]``;
    * ``heldout``: text; ``heldout_split``: the split as a dict;
    * ``sensor_effects``: accepted measurement effects as the option of
      :func:`swgsim.measurement.apply_sensor_effects`, per-channel values that the data
      cannot pin down set neutral (listed in ``withheld``);
    * ``simulation``: the option with a ``caveat`` (None, or why to use it with care:
      effects accepted in a run that ends unexplained) and ``withheld``;
    * ``too_small``: candidates rejected only for lack of evidence although their
      held-out gain is positive (:mod:`.strain_checks`); ``implausible``: candidates of
      the last iteration with very strong evidence but outside their physical range
      (they make the run ``unexplained``);
    * ``gear_ke_harmonics``: accepted kinematic-error harmonics for :func:`gear_with_ke`;
    * ``chain``: fitted baseline (w0, gauge gain) as chain overrides;
    * ``alignment``: per window the time shifts, WG angle at its start (mod 180°) and its
      s.e., input angle at its start (nominal chain, and re-aligned with the accepted
      kinematic-error harmonics) modulo the period the data decide (``phi_in0_period_deg``:
      360°, or 180° where the odd orders of the torque ripple are below the noise,
      :mod:`.strain_align`), with its s.e. and the evidence against a flip by 180°;
    * ``identifiability``: declared degeneracies and flagged parameters.
    """
    s = summarize(result, source)
    p = result.problem
    split_desc = s.pop("heldout")
    s["heldout"] = split_desc.get("text", "")
    s["heldout_split"] = split_desc
    for e in s["effects_added"]:
        for q in e["params"].values():
            q["stderr"] = q.get("std")
    s["baseline"]["params"] = {k: {**v, "stderr": v.get("std")}
                               for k, v in s["baseline"]["params"].items()}
    final = result.final
    withheld = withheld_parameters(result)
    sensor, ke = simulation_option(result, withheld)
    s.pop("friction_effects", None)
    s["sensor_effects"] = to_jsonable(sensor)
    s["gear_ke_harmonics"] = to_jsonable(ke)
    s["withheld"] = to_jsonable(withheld)
    s["too_small"] = to_jsonable(too_small_rows(result))
    s["implausible"] = list(result.implausible)
    base_term = next(t for t in final.terms if t.kind == "chain")
    base = {e.name: e.value for e in final.estimates_of(base_term.name).values()}
    gain = base.get("gauge_gain", float("nan"))
    s["chain"] = {"w0_m": base.get("w0_mm", float("nan")) * 1e-3, "gauge_gain": gain,
                  "note": ("w0_m -> ChainParams.w0_m; gauge_gain multiplies the gauge factor "
                           "(sensors.gauge_factor) of the whole layout")}
    s["simulation"] = {
        "sensor_effects": s["sensor_effects"], "gear_ke_harmonics": s["gear_ke_harmonics"],
        "call": ("swgsim.measurement.apply_sensor_effects(signals, time_s, n_in_rpm, "
                 "summary['sensor_effects'], t_start_s=..., n_lead=...)"),
        "caveat": caveat(result), "withheld": s["withheld"]}
    se = _alignment_se(result)
    ke_final = tuple((h["order"], float(th[0]), float(th[1])) for h, th in (
        (term.gear_harmonic(final.coefs[i], final.thetas[i]), final.thetas[i])
        for i, term in enumerate(final.terms) if hasattr(term, "gear_harmonic")))
    sig: StrainSignals = p.signals
    if ke_final and sig.ripple is not None:
        upd = sig.ripple(ke_final)
        phi_fin = np.rad2deg(np.mod(upd["phi_in"][:, sig.n_lead], 2 * np.pi))
    else:
        phi_fin = [a["phi_in0_deg"] for a in p.meta["alignment"]]
    phi0 = [a["phi_in0_deg"] for a in p.meta["alignment"]]
    ia0 = ia_f = None
    if sig.ripple is not None:
        sigma2 = max(final.sigma ** 2 * max(final.tau_int, 1.0), 1e-30)
        ia0 = input_angle_evidence(sig.ripple.objectives(()), sig.fs, sig.n_in_rpm, sigma2)
        odd = any(k % 2 for k, _, _ in ke_final)
        ia_f = (input_angle_evidence(
            sig.ripple.objectives(ke_final), sig.fs, sig.n_in_rpm, sigma2,
            flipped=sig.ripple.objectives(flipped_ke(ke_final)) if odd else None)
            if ke_final else ia0)
        phi0, phi_fin = ia0.reported(phi0), ia_f.reported(phi_fin)
    al = [dict(a, psi0_se_deg=float(x), phi_in0_deg=float(f0), phi_in0_final_deg=float(f))
          for a, x, f0, f in zip(p.meta["alignment"], se, phi0, phi_fin, strict=True)]
    if ia0 is not None:
        for w, a in enumerate(al):
            a.update(phi_in0_period_deg=float(ia0.period_deg[w]),
                     phi_in0_se_deg=float(ia0.se_deg[w]),
                     phi_in0_flip_evidence=float(ia0.flip_evidence[w]),
                     phi_in0_final_period_deg=float(ia_f.period_deg[w]),
                     phi_in0_final_flip_evidence=float(ia_f.flip_evidence[w]))
        s["input_angle_global_flip_evidence"] = ia_f.global_evidence
        for h in s["gear_ke_harmonics"]:
            h["phase_known_modulo_rad"] = (np.pi if h["order"] % 2 and not
                                           ia_f.global_evidence > 10.0 else 2 * np.pi)
    s["alignment"] = to_jsonable(al)
    s["data"].pop("alignment", None)
    flagged = [f"{e.term}.{e.name}: {e.flag}" for e in final.estimates if e.flag]
    s["identifiability"] = {"declared": IDENTIFIABILITY, "flagged": flagged,
                            "condition_number": final.cond}
    diag = result.diag_after
    s["noise_floor"] = diag.noise_floor
    s["rmse_over_noise_floor"] = (result.rmse_after / diag.noise_floor
                                  if diag.noise_floor and diag.noise_floor > 0 else None)
    s["order2"] = to_jsonable(order2_table(result))
    from .discovery import propose  # terms beyond the library (structured residual only)
    s["proposed"] = [q.as_dict() for q in propose(result)]
    return to_jsonable(s)


def _order2(sig: StrainSignals, x: np.ndarray) -> np.ndarray:
    """Amplitude and phase of the order-2 (ψ) component per window and channel: least
    squares of x on [1, cos 2ψ, sin 2ψ], shape (n_w, 5, 2) (amplitude [mV/V], phase
    [deg])."""
    n_w, n_t = sig.n_windows, sig.n_t
    xs = x.reshape(n_w, 5, n_t)
    psi = sig.psi_rad.reshape(n_w, 5, n_t)[:, 0]
    out = np.empty((n_w, 5, 2))
    for w in range(n_w):
        a = np.column_stack([np.ones(n_t), np.cos(2 * psi[w]), np.sin(2 * psi[w])])
        c, *_ = np.linalg.lstsq(a, xs[w].T, rcond=None)  # (3, 5)
        out[w, :, 0] = np.hypot(c[1], c[2])
        out[w, :, 1] = np.rad2deg(np.arctan2(c[2], c[1]))
    return out


def order2_table(result: CalibrationResult) -> list[dict[str, Any]]:
    """Order-2 (ψ) amplitude and phase per operating point and channel: measured, baseline
    and final model, mean over the windows of the operating point."""
    sig: StrainSignals = result.problem.signals
    pb, pa = result.predictions()
    m, b, a = (_order2(sig, x) for x in (result.problem.y, pb, pa))
    op_w = sig.op.reshape(sig.n_windows, -1)[:, 0]
    rows = []
    for i, o in enumerate(sig.ops):
        sel = op_w == i
        for c, s in enumerate(SENSORS):
            def mean_ap(z, sel=sel, c=c):
                amp = float(z[sel, c, 0].mean())
                ph = float(np.rad2deg(np.angle(np.mean(np.exp(1j * np.deg2rad(z[sel, c, 1]))))))
                return amp, ph
            rows.append({"n_in_rpm": o[0], "t_out_nm": o[1], "channel": s,
                         "measured": mean_ap(m), "baseline": mean_ap(b), "final": mean_ap(a)})
    return rows


def render_strain_report(result: CalibrationResult, summary: Mapping[str, Any],
                         figures: Mapping[str, str] | None = None) -> str:
    """Markdown report of a strain calibration.

    Parameters
    ----------
    result : CalibrationResult
    summary : mapping
        From :func:`summarize_strain`.
    figures : mapping of str to str, optional
        Figure key to a path relative to the report.
    """
    s = summary
    u = s["units"]
    d = s["data"]
    lines = [f"# Strain calibration report: {s['name']}", "",
             f"Measured data: `{s['source']}` (kind: strain, schema v1). {d['n_windows']} "
             f"windows of {fmt_value(d['window_s'] * 1e3, 3)} "
             f"ms at {fmt_value(d['sample_rate_hz'])} Hz; "
             "operating points (n_in [rpm], T_out [N m]) "
             + ", ".join(f"({o[0]:g}, {o[1]:g}) × {n}" for o, n in
                         zip(d["operating_points"], d["windows_per_op"], strict=True)) + ".", ""]
    lines += result_section(s, "nominal chain",
                            f"; difference-based noise floor {fmt_value(s['noise_floor'])} {u} "
                            f"(ratio "
                            f"{fmt_value(s['rmse_over_noise_floor'], 3)})")
    lines += result_extras(s)
    lines += ["## Held-out data", "", s["heldout"], ""]
    lines += ["## Baseline: nominal simulation chain", "", result.problem.baseline[0].description
              + ". Fitted on fit + validation windows:", "",
              "| parameter | value | s.e. | unit | identifiable |", "|---|---|---|---|---|"]
    lines += _rows(s["baseline"]["params"]) + [""]
    lines += ["In the final model (with the accepted effects):", "",
              "| parameter | value | s.e. | unit | identifiable |", "|---|---|---|---|---|"]
    lines += _rows(s["baseline"]["params_in_final_model"]) + [""]
    lines += ["WG angle of each window (alignment, nominal chain, per window on its own data; "
              "s.e. from the curvature with the final residual σ). The input angle φ_in is "
              "known modulo 360° only where the odd orders of the torque ripple rise above "
              "the noise (evidence 2 ln Λ against the peak 180° away > 10); elsewhere it is "
              "given modulo 180° (ambiguous: the order-2 ripple repeats every half "
              "revolution).", "",
              "| sample | role | operating point | ψ(0) mod 180° [deg] | s.e. [deg] | "
              "φ_in(0) [deg] (final model) | known modulo | 2 ln Λ (flip) |",
              "|---|---|---|---|---|---|---|---|"]
    for a in s["alignment"]:
        o = d["operating_points"][a["op"]]
        lines.append(f"| {a['sample']} | {a['role']} | {o[0]:g} rpm, {o[1]:g} N m | "
                     f"{fmt_value(a['psi0_deg'], 4)} | {fmt_value(a['psi0_se_deg'], 2)} | "
                     f"{fmt_value(a['phi_in0_final_deg'], 4)} | "
                     f"{fmt_value(a.get('phi_in0_final_period_deg'), 3)}° | "
                     f"{fmt_value(a.get('phi_in0_final_flip_evidence'), 3)} |")
    lines += ["", "## Selection", "",
              "Each iteration adds every library candidate to the current model and refits on "
              "the fit windows; candidates are ranked by validation RMSE. Accepted: the first "
              "with very strong evidence on the 2 ln B scale of Kass & Raftery (1995): "
              "held-out evidence 2 ln Λ (validation log-likelihood ratio, n/τ_int effective "
              f"samples) > {s['selection']['min_heldout_evidence']:g} and effective ΔBIC on "
              f"the fit windows < {s['selection']['max_delta_bic']:g}"
              + (f", validation gain > {100 * s['selection']['min_rel_improvement']:.2g} %"
                 if s['selection']['min_rel_improvement'] > 0 else "")
              + f", its primary parameter pinned down (rel. s.e. < "
              f"{s['selection']['max_rel_se']:g}) and every parameter inside its physical "
              "range (the effect's declared source).", ""]
    for it in s["iterations"]:
        lines += [f"### Iteration {it['index']}: model {' + '.join(it['model'])}, validation "
                  f"RMSE {fmt_value(it['val_rmse'])} {u}", ""]
        if not it["candidates"]:
            lines += ["(no candidates tried: iteration limit)", ""]
            continue
        lines += ["| rank | candidate | val. RMSE | gain | 2 ln Λ (held out) | ΔBIC | eff. ΔBIC "
                  "| status |", "|---|---|---|---|---|---|---|---|"]
        for r, c in enumerate(it["candidates"], 1):
            lines.append(f"| {r} | {c['name']} | {fmt_value(c['val_rmse'])} | "
                         f"{fmt_value(100 * c['rel_improvement'], 3)} % | "
                         f"{fmt_value(c.get('heldout_evidence'), 4)} "
                         f"| {fmt_value(c['delta_bic'], 5)} | "
                         f"{fmt_value(c['delta_bic_eff'], 4)} | {c['status']} |")
        lines.append("")
    lines += ["## Accepted effects", ""]
    if not s["effects_added"]:
        lines += ["None.", ""]
    for e in s["effects_added"]:
        lines += [f"### {e['name']}", "", f"{e['description']}. Signature: {e['signature']}. "
                  f"Source: {e['source']}.", "",
                  "| parameter | value | s.e. | unit | identifiable |", "|---|---|---|---|---|"]
        lines += _rows(e["params"]) + [""]
    lines += ["## Identifiability", "", s["identifiability"]["declared"], "",
              f"Condition number of the scaled JᵀJ of the final model: "
              f"{fmt_value(s['identifiability']['condition_number'], 3)}. Flagged parameters: "
              + ("; ".join(s["identifiability"]["flagged"]) or "none") + ".", ""]
    lines += ["## Residual diagnosis", "",
              "Probe scores: out-of-sample fraction of the residual mean square explained by a "
              "nonparametric model along one variable (structured above "
              f"{fmt_value(s['diagnosis_after']['threshold'])}).", "",
              "| probe | baseline residual | final residual |", "|---|---|---|"]
    pb, pa = s["diagnosis_before"]["probes"], s["diagnosis_after"]["probes"]
    for k in pb:
        lines.append(f"| {k} | {fmt_value(pb[k]['score'], 3)} | {fmt_value(pa[k]['score'], 3)} |")
    lines += ["", f"Baseline residual: {s['residual_signature_before']}", "",
              f"Final residual: {s['residual_signature']}", "",
              "Order-2 component of ψ (amplitude [mV/V] / phase [deg]) per operating point and "
              "channel, mean over its windows: how amplitude and phase change with speed and "
              "load.", "",
              "| n_in [rpm] | T_out [N m] | channel | measured | baseline | final |",
              "|---|---|---|---|---|---|"]
    for r in s["order2"]:
        def ap(x):
            return f"{x[0]:.4f} / {x[1]:+.1f}"
        lines.append(f"| {r['n_in_rpm']:g} | {r['t_out_nm']:g} | {r['channel']} | "
                     f"{ap(r['measured'])} | {ap(r['baseline'])} | {ap(r['final'])} |")
    lines.append("")
    from .discovery import proposals_section  # apart from the accepted effects
    lines += proposals_section(s.get("proposed", []))
    captions = {
        "order_spectrum": "Residual amplitude spectrum per channel against the order of the "
                          "input rotation (baseline grey, final colour), mean over windows.",
        "offsets": "Mean residual per window and channel along the recording sequence "
                   "(offsets, drift), baseline and final; held-out windows marked.",
        "channel_differences": "Channel differences s1−s3 and s2−s4 of a test window: measured, "
                               "baseline and final model, and their residuals.",
        "speed_load": "Order-2 (ψ) amplitude and phase per window against speed and load: "
                      "measured, baseline, final.",
        "overlay": "Measured signals of a test window with the baseline and final predictions.",
    }
    if figures:
        lines += ["## Figures", ""]
        for k, path in figures.items():
            lines += [f"![{k}]({path})", "", f"*{captions.get(k, k)}*", ""]
    lines += ["## As a simulation option", ""]
    if s["simulation"].get("caveat"):
        lines += [f"**Caveat.** {s['simulation']['caveat']}", ""]
    if s["withheld"]:
        lines += ["Set neutral here (not pinned down by the data): " + "; ".join(
            f"{w['effect']}.{w['parameter']} ({w['reason']})" for w in s["withheld"]) + ".", ""]
    lines += ["Measurement effects for `swgsim.measurement.apply_sensor_effects` "
              "(`sensor_effects` option):", "", "```json",
              json.dumps(s["sensor_effects"], indent=1), "```", "",
              "Kinematic-error harmonics for `swgsim.dynamics.gear_with_ke`: "
              + json.dumps(s["gear_ke_harmonics"]) + "; chain: w0 = "
              f"{fmt_value(s['chain']['w0_m'])} "
              f"m, gauge gain {fmt_value(s['chain']['gauge_gain'])}.", ""]
    lines += ["## Uncertainty", "", UNCERTAINTY_METHOD, "",
              f"Run time {fmt_value(s['elapsed_s'], 3)} s.", ""]
    return "\n".join(lines)


def strain_figures(result: CalibrationResult, out_dir: str | Path,
                   fmt: str = "png") -> dict[str, str]:
    """Diagnosis figures of a strain calibration.

    Parameters
    ----------
    result : CalibrationResult
    out_dir : path-like
        Folder for the figures (created).
    fmt : str, default "png"

    Returns
    -------
    dict of str to str
        Figure key -> file name (relative to ``out_dir``'s parent, for the report).
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    sig: StrainSignals = result.problem.signals
    n_w, n_t, fs = sig.n_windows, sig.n_t, sig.fs
    y = result.problem.y.reshape(n_w, 5, n_t)
    pb, pa = (x.reshape(n_w, 5, n_t) for x in result.predictions())
    rb, ra = y - pb, y - pa
    sp = result.problem.split
    role = np.zeros(n_w, int)
    role[np.unique(sig.window[sp.validation])] = 1
    role[np.unique(sig.window[sp.test])] = 2
    test_w = int(np.flatnonzero(role == 2)[0]) if (role == 2).any() else 0
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    figs: dict[str, str] = {}

    def save(fig, key):
        name = f"{key}.{fmt}"
        fig.savefig(out / name, dpi=110, bbox_inches="tight")
        plt.close(fig)
        figs[key] = f"{out.name}/{name}"

    # order spectrum relative to the input rotation
    fig, axes = plt.subplots(5, 1, figsize=(8, 9), sharex=True)
    win = np.hanning(n_t)
    freqs = np.fft.rfftfreq(n_t, 1 / fs)
    f_in = sig.n_in_rpm / 60.0
    grid = np.arange(0, 30.01, 0.05)
    for c in range(5):
        for r, col, lab in ((rb, "0.6", "baseline"), (ra, colors[c % len(colors)], "final")):
            spec = np.abs(np.fft.rfft(r[:, c] * win, axis=-1)) * 2 / win.sum()  # (n_w, n_f)
            amp = np.mean([np.interp(grid, freqs / f_in[w], spec[w]) for w in range(n_w)],
                          axis=0)
            axes[c].plot(grid, amp, color=col, lw=1, label=lab)
        axes[c].set_ylabel(f"{SENSORS[c]} [mV/V]")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("order relative to the input rotation")
    fig.suptitle("Residual amplitude spectrum (Hann), mean over windows")
    save(fig, "order_spectrum")

    # offsets and drift along the sequence
    t_start = sig.t_seq_s.reshape(n_w, 5, n_t)[:, 0, 0]
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6), sharey=True)
    for ax, r, title in ((axes[0], rb, "baseline residual"), (axes[1], ra, "final residual")):
        mean = r.mean(-1)
        for c in range(5):
            ax.plot(t_start, mean[:, c], "o-", ms=4, lw=0.8, color=colors[c % len(colors)],
                    label=SENSORS[c])
        for w in np.flatnonzero(role > 0):
            ax.axvline(t_start[w], color="r" if role[w] == 2 else "orange", lw=0.6, alpha=0.5)
        ax.set_title(title)
        ax.set_xlabel("time since the first window [s] (red: test, orange: validation)")
    axes[0].set_ylabel("mean residual [mV/V]")
    axes[1].legend(fontsize=8)
    save(fig, "offsets")

    # channel differences
    t_ms = np.arange(n_t) / fs * 1e3
    fig, axes = plt.subplots(2, 2, figsize=(10, 5.5), sharex=True)
    for j, (a, b) in enumerate(((1, 3), (2, 4))):
        lab = f"s{a}−s{b}"
        axes[0, j].plot(t_ms, y[test_w, a] - y[test_w, b], color="k", lw=0.8, label="measured")
        axes[0, j].plot(t_ms, pb[test_w, a] - pb[test_w, b], color="0.6", lw=1, label="baseline")
        axes[0, j].plot(t_ms, pa[test_w, a] - pa[test_w, b], color=colors[0], lw=1, label="final")
        axes[0, j].set_title(lab)
        axes[1, j].plot(t_ms, rb[test_w, a] - rb[test_w, b], color="0.6", lw=0.8)
        axes[1, j].plot(t_ms, ra[test_w, a] - ra[test_w, b], color=colors[0], lw=0.8)
        axes[1, j].set_xlabel("time in the window [ms]")
    axes[0, 0].set_ylabel("[mV/V]")
    axes[1, 0].set_ylabel("residual [mV/V]")
    axes[0, 0].legend(fontsize=8)
    save(fig, "channel_differences")

    # amplitude and phase with speed and load
    m, b, a = (_order2(sig, x.reshape(-1)) for x in (y, pb, pa))
    fig, axes = plt.subplots(2, 5, figsize=(13, 5))
    x_op = np.array([f"{sig.n_in_rpm[w]:.0f}/{sig.t_out_nm[w]:.0f}" for w in range(n_w)])
    order = np.lexsort((sig.t_out_nm, sig.n_in_rpm))
    for c in range(5):
        for z, mk, lab in ((m, "o", "measured"), (b, "x", "baseline"), (a, "+", "final")):
            axes[0, c].plot(x_op[order], z[order, c, 0], mk, label=lab, ms=6)
            axes[1, c].plot(x_op[order], z[order, c, 1], mk, ms=6)
        axes[0, c].set_title(SENSORS[c])
        axes[1, c].set_xlabel("n_in [rpm] / T_out [N m]")
        for ax in axes[:, c]:
            ax.tick_params(axis="x", labelrotation=60, labelsize=7)
    axes[0, 0].set_ylabel("order-2 amplitude [mV/V]")
    axes[1, 0].set_ylabel("order-2 phase [deg]")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    save(fig, "speed_load")

    # overlay of a test window
    fig, axes = plt.subplots(5, 1, figsize=(8, 9), sharex=True)
    for c in range(5):
        axes[c].plot(t_ms, y[test_w, c], color="k", lw=0.7, label="measured")
        axes[c].plot(t_ms, pb[test_w, c], color="0.6", lw=1, label="baseline")
        axes[c].plot(t_ms, pa[test_w, c], color=colors[0], lw=1, label="final")
        axes[c].set_ylabel(f"{SENSORS[c]} [mV/V]")
    axes[0].legend(fontsize=8, loc="upper right")
    axes[-1].set_xlabel("time in the window [ms]")
    save(fig, "overlay")
    return figs


# ---------------------------------------------------------------------------------------
# entry point


@contextlib.contextmanager
def _blas_threads(n: int | None):
    """Limit BLAS threads within the block (no-op without threadpoolctl or for None)."""
    if n is None:
        yield
        return
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - optional
        yield
        return
    with threadpool_limits(limits=int(n), user_api="blas"):
        yield

_PROBLEM_KEYS = ("heldout", "validation", "test", "candidates", "window_period_s",
                 "f_c_bounds_hz", "ke_bound_rad")
_SELECTION_KEYS = tuple(f.name for f in dataclasses.fields(SelectionConfig))


def calibrate_strain(data: Any, out_dir: str | Path | None, *, model: StrainModel | None = None,
                     select: Mapping[str, Any] | None = None, max_windows: int | None = None,
                     figures: bool = True, name: str | None = None,
                     blas_threads: int | None = 1, **options: Any) -> dict[str, Any]:
    """Calibrate the chain against a measured strain data set and write the report.

    Parameters
    ----------
    data : path-like or xarray.Dataset or StrainWindows
        A schema-v1 data-set directory (``manifest.json``), a loaded data set, or windows.
    out_dir : path-like or None
        Writes ``report.md``, ``summary.json`` and ``figures/``; None writes nothing.
    model : StrainModel, optional
        Reuse simulated operating points across calls (default: a new nominal model).
    select, max_windows
        Window selection, see :func:`strain_windows`.
    figures : bool, default True
    name : str, optional
    blas_threads : int or None, default 1
        BLAS threads during the calibration (through ``threadpoolctl`` where installed).
        Its products are small (hundreds × hundreds): one thread is fastest, and on
        shared cores threading costs 20× (measured); None leaves the setting alone.
    **options
        Problem options (``heldout``, ``validation``, ``test``, ``candidates``,
        ``window_period_s``, ``f_c_bounds_hz``; see :func:`strain_problem`) and selection
        settings (:class:`~swgsim.calibration.loop.SelectionConfig` fields, e.g.
        ``min_rel_improvement``, ``max_delta_bic``, ``max_iter``).

    Returns
    -------
    dict
        The summary (:func:`summarize_strain`), plus ``"_result"`` (the
        CalibrationResult object, not written to JSON).

    Raises
    ------
    TypeError
        An unknown option (the message lists the allowed ones).
    ValueError, KeyError
        See :func:`strain_windows`, :func:`strain_problem`.
    """
    t0 = time.perf_counter()
    unknown = sorted(set(options) - set(_PROBLEM_KEYS) - set(_SELECTION_KEYS))
    if unknown:
        raise TypeError(f"unknown options {unknown}; allowed: {sorted(_PROBLEM_KEYS)} and "
                        f"selection settings {sorted(_SELECTION_KEYS)}")
    win = data if isinstance(data, StrainWindows) else strain_windows(data, select, max_windows,
                                                                     name)
    prob_kw = {k: options[k] for k in _PROBLEM_KEYS if k in options}
    sel_kw = {k: options[k] for k in _SELECTION_KEYS if k in options}
    if "candidates" in prob_kw:
        sel_kw.setdefault("candidates", None)
    with _blas_threads(blas_threads):
        problem = strain_problem(win, model, **prob_kw)
        result = calibrate(problem, SelectionConfig(**sel_kw))
        summary = summarize_strain(result, win.source)
    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        figs = strain_figures(result, out / "figures") if figures else {}
        summary["figures"] = figs
        (out / "report.md").write_text(render_strain_report(result, summary, figs))
        dsio.atomic_write_json(out / "summary.json", summary)
    summary["wall_s"] = time.perf_counter() - t0
    summary["_result"] = result
    log.info("strain calibration of %s: test RMSE %.4g -> %.4g mV/V, added %s, unexplained %s",
             win.name, summary["rmse_before"], summary["rmse_after"],
             [e["name"] for e in summary["effects_added"]], summary["unexplained"])
    return summary
