"""The nominal chain's prediction of measured strain windows, and their alignment.

:class:`StrainModel` simulates each operating point once (the dynamics over one input
revolution more than a window, plus one run per unit kinematic-error harmonic) and aligns
each window's WG angle ψ; :class:`Realigner` aligns each window's input angle (the torque
phase) for a given kinematic-error model and gives the raw basis of
:class:`~swgcal.strain.signals.StrainSignals` (:mod:`.problem`, module
docstring).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from swgsim.base.lazy import lazy_module
from swgsim.gear.chain import ChainSettings, SimulationChain
from swgsim.gear.dynamics import GearParams, rt1_size20
from swgsim.gear.dynamics import simulate as simulate_dynamics
from swgsim.gear.faults import ChainParams
from swgsim.gear.influence import torque_influence
from swgsim.sensing.effects import psi_rate

from .effects import KE_ORDERS

interpolate = lazy_module("scipy.interpolate")

__all__ = ["StrainModel", "Realigner"]


@dataclass
class _OPModel:
    """Steady trajectory of one operating point (see :class:`StrainModel`)."""

    n_in_rpm: float
    t_out_nm: float
    fs: float
    t0_s: float  # simulation time of window sample 0 at zero shift
    n_half: int  # ψ shifts searched by the alignment: half a WG revolution [samples]
    n_rev: int  # torque shifts searched: one input revolution [samples]
    psi: interpolate.CubicSpline
    phi_in: interpolate.CubicSpline
    t_out: interpolate.CubicSpline
    # "ke{k}_sin"/"_cos" -> ΔT per unit KE amplitude [N m/rad]
    d_t: dict[str, interpolate.CubicSpline]
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
        Gear (default: nominal RT1 size 20, :func:`swgsim.gear.dynamics.rt1_size20`).
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
        d_t = {nm: interpolate.CubicSpline(tl, v) for nm, v in d_t_long.items()}
        s_wg, h, _ = self._signals(psi, t_mean)
        opm = _OPModel(n_in_rpm=float(n_in_rpm), t_out_nm=float(t_out_nm), fs=float(fs), t0_s=t0,
                       n_half=n_half, n_rev=n_rev, psi=interpolate.CubicSpline(tl, psi),
                       phi_in=interpolate.CubicSpline(tl, res.states[0, 0]),
                       t_out=interpolate.CubicSpline(tl, t_out),
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
        """``Σ_c max(ỹ_c · p̃_c, 0)² / |p̃_c|²`` for candidate predictions pred (5, n_j, n_t)
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
        revolution at every sample, maximising ``Σ_c max(ỹ_c · p̃_c, 0)² / |p̃_c|²`` (tilde:
        mean removed per channel: invariant to per-channel positive gains and offsets),
        refined by a parabola through the neighbours. The torque phase follows in
        :class:`Realigner`.

        Parameters
        ----------
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


class Realigner:
    """Torque phase of every window for a given kinematic-error model, and the raw basis.

    For extra harmonics ``ke`` = ((order, a_sin, a_cos), ...), the torque of an operating
    point is T(t) = T_out(t) + Σ (a_sin ΔT_sin + a_cos ΔT_cos)(t); each window's time
    shift of T over one input revolution maximises ``Σ_c max(ỹ_c · p̃_c, 0)² / |p̃_c|²`` with
    p_c = s_wg,c + T h_c (ψ fixed), by matrix products of the shifted torque with
    per-channel vectors (no candidate signals are formed), refined by a parabola.
    Results are memoised per ``ke``.

    Parameters
    ----------
    opms : list of _OPModel
        One per operating point.
    op_of : ndarray of int, shape (n_w,)
    parts : dict
        :meth:`StrainModel.psi_parts` of all windows, arrays (n_w, 5, m).
    y : ndarray, shape (n_w, 5, n_t)
        Measured windows [mV/V].
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

    def _by_op(self) -> Iterator[tuple[int, _OPModel, np.ndarray]]:
        """(index, model, windows) of every operating point with windows."""
        for i, opm in enumerate(self.opms):
            ws = np.flatnonzero(self.op_of == i)
            if ws.size:
                yield i, opm, ws

    def objectives(self, ke: tuple) -> list[np.ndarray]:
        """The alignment objective of every window over its torque shifts.

        Returns
        -------
        list of ndarray
            Per window, shape (n_rev + 1,): ``Σ_c max(ỹ_c · p̃_c, 0)² / |p̃_c|²`` at the torque
            shifts 0, 1, ... samples over one input revolution [(mV/V)²]: the drop of the
            residual sum of squares with per-channel positive gains and offsets.
        """
        out: list[np.ndarray] = [np.empty(0)] * self.n_w
        n_t = self.n_t
        for i, opm, ws in self._by_op():
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
        for _, opm, ws in self._by_op():
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

    def unit(self, order: int) -> np.ndarray:
        """Unit responses ΔT_sin h, ΔT_cos h of an order at the alignment without extra
        harmonics, shape (2, n_w, 5, m) [mV/V / rad]."""
        if order in self._unit:
            return self._unit[order]
        sh = self()["shift_t"]
        out = np.empty((2, self.n_w, 5, self.m))
        for _, opm, ws in self._by_op():
            tt = self._times(sh, ws)
            for j, nm in enumerate((f"ke{order}_sin", f"ke{order}_cos")):
                out[j, ws] = opm.d_t[nm](tt).reshape(ws.size, 1, self.m) * self.parts["h"][ws]
        self._unit[order] = out
        return out
