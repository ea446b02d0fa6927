"""Closed-form references and slow reference paths shared by the physics tests and the
benchmarks (not a test module): the steady motion's closed form, one variant integrated by
scipy (:func:`simulate_reference`), the gauge signals by one truss solve per time step
(:func:`signals_naive`; :func:`solve_displacements`, :func:`cracked`, the truss's coupling
block :func:`k_fp` and wave-generator displacements :func:`wg_displacement`) and of one
variant from its motion (:func:`signals_from_motion`), against which the fast paths are
checked; the energy and powers along a window (:func:`power_terms`) and the ring-down after
a load step (:func:`ring_down`, its poles by :func:`modes`); the bridges' drift at a
temperature written out (:func:`apply_bridge_drift`)."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from swgsim.gear import dynamics as dy
from swgsim.gear import profile as pf
from swgsim.gear import profile_dynamics as pd
from swgsim.gear.chain import SimulationChain
from swgsim.gear.faults import ChainParams, angle_index, mesh_severity
from swgsim.gear.flexspline import TrussModel, factorize
from swgsim.gear.influence import contact_window, torque_influence
from swgsim.gear.modes import torsional_mode
from swgsim.gear.sensors import signal_rows
from swgsim.sensing.bridge_drift import N_BRIDGES, REF_TEMP_C


def steady_motion(p: dy.GearParams, n_in_rpm: float, t_gear_nm: float) -> tuple[float, float]:
    """Efficiency and output wind-up of steady motion, from the module docstring's
    equations, independently of the simulator.

    The output balance c T_stiff = T_gear + T_fric / sin α with T_fric of eq. (5) at
    φ̇_b = ω_out / sin α (kinematic error and b3 left out) is solved by fixed-point steps;
    then η = T_gear / (c T_stiff) (P_in = P_out + T_fric φ̇_b, module docstring) and the
    wind-up δ = Δφ_k (N + 1) tan α / N of the output against the rigid gear.

    Returns
    -------
    eta : float
        T_gear ω_out / P_in [-].
    wind_up_rad : float
        δ [rad], > 0 for a driving gear.
    """
    sa, ca = np.sin(p.alpha_tooth_rad), np.cos(p.alpha_tooth_rad)
    v_b = n_in_rpm * dy.RPM / p.ratio / sa
    t_stiff = t_gear_nm / p.c_out
    for _ in range(50):
        t_fric = (p.b0_nm + p.b1_nms * v_b + p.b2_nms3 * v_b**3
                  + p.mu * p.c_out * abs(t_stiff) / ca) * np.tanh(v_b / p.v_smooth_rad_s)
        t_stiff = (t_gear_nm + t_fric / sa) / p.c_out
    d = brentq(lambda x: p.k1_nm_per_rad * x + p.k2_nm_per_rad3 * x**3 - t_stiff, 0, 1)
    return t_gear_nm / (p.c_out * t_stiff), d * (p.ratio + 1) * np.tan(p.alpha_tooth_rad) / p.ratio


def simulate_reference(params: dy.GearParams, n_in_rpm: float, t_out_nm: float,
                       phi_in0: float = 0.0, sample_rate_hz: float = 10e3,
                       window_s: float = 0.12, settle_s: float = 0.1,
                       rtol: float = 1e-10, atol: float = 1e-12) -> dy.SimResult:
    """One variant with ``scipy.integrate.solve_ivp`` (DOP853), for testing
    :func:`swgsim.gear.dynamics.simulate`: the same arguments and result for one variant.
    """
    dy.check_inputs(n_in_rpm, t_out_nm, sample_rate_hz, window_s, settle_s)
    bk = dy.ke_batch(dy.Batch.of([params]))
    w_d = np.array([n_in_rpm * dy.RPM])
    t_load = np.array([float(t_out_nm)])
    x0 = dy.steady_state(bk, w_d, t_load, np.array([phi_in0]))[:, 0]
    n_win = int(round(window_s * sample_rate_hz))
    n_set = int(round(settle_s * sample_rate_hz))
    t_eval = (n_set + np.arange(n_win)) / sample_rate_hz

    def f(t, y):
        return dy.rhs(t, y[:, None], bk, w_d, t_load)[:, 0]

    sol = solve_ivp(f, (0.0, t_eval[-1]), x0, method="DOP853", t_eval=t_eval,
                    rtol=rtol, atol=atol)
    rec = sol.y[:, None, :]
    return dy._result(rec, bk, w_d, t_load, sample_rate_hz, sol.success, sol.message)


def cracked(model: TrussModel, theta_index: int, severity: float) -> TrussModel:
    """A copy of ``model`` with the root-crack bars at ``theta_index`` scaled by
    (1 − severity): the naive reference path's structure (the fast path uses
    :class:`swgsim.gear.influence.Influence` with a Woodbury update instead)."""
    new = object.__new__(TrussModel)
    new.__dict__.update({k: v for k, v in model.__dict__.items()
                         if k in ("geometry", "mesh", "mer", "h", "theta", "n_st",
                                  "layer_r", "layer_z", "node_theta", "nodes_m",
                                  "n_nodes", "n_dof", "bars", "bar_kind")})
    k = model.k_bar.copy()
    k[model.root_crack_bars(theta_index)] *= 1.0 - severity
    new.k_bar = k
    return new


@functools.lru_cache(maxsize=8)
def k_fp(model: TrussModel):
    """Coupling block K_FP of ``model``'s stiffness, free rows and prescribed columns
    (``model.free``, ``model.prescribed``), shape (n_free, n_prescribed) [N/m], CSC; kept
    per model, as its factorisation is, so that a timed naive solve does not build it."""
    return model.K[model.free][:, model.prescribed].tocsc()


def wg_displacement(model: TrussModel, psi: np.ndarray, w0_m: float, ecc_m: float = 0.0,
                    ecc_theta: float = 0.0) -> np.ndarray:
    """Radial displacement of the inner rim nodes imposed by the wave generator.

    Parameters
    ----------
    model : TrussModel
    psi : ndarray, shape (n_t,)
        Wave-generator angle relative to the flexspline [rad].
    w0_m : float
        Radial deflection at the major axis [m].
    ecc_m, ecc_theta : float
        Eccentricity of the wave generator [m] and its direction [rad] in the
        flexspline frame (paper: u_ecc = [r, θ, 0]).

    Returns
    -------
    ndarray, shape (n_t, n_wg_dofs)
        u_r of ``model.wg_dofs`` [m], w0 cos 2(θ − ψ) + e cos(θ − θ_e).
    """
    n_rim = model.rim_stations.size
    th = np.tile(model.theta, n_rim)
    psi = np.atleast_1d(psi)[:, None]
    return w0_m * np.cos(2 * (th[None, :] - psi)) + ecc_m * np.cos(th - ecc_theta)[None, :]


def solve_displacements(model: TrussModel, f: np.ndarray, u_p: np.ndarray) -> np.ndarray:
    """Naive reference: solve K_FF u_F = f_F − K_FP u_P of ``model`` for each load case.

    Parameters
    ----------
    f : ndarray, shape (n_dof,) or (n_dof, n_cases)
        Nodal forces [N] (entries on prescribed DOFs are ignored).
    u_p : ndarray, shape (n_p,) or (n_p, n_cases)
        Prescribed displacements [m] in the order of ``model.prescribed``.

    Returns
    -------
    ndarray, shape (n_dof,) or (n_dof, n_cases)
        Displacements in cylindrical components [m].
    """
    rhs = f[model.free] - k_fp(model) @ u_p
    u = np.zeros((model.n_dof,) + np.shape(f)[1:])
    u[model.free] = model.lu.solve(np.asarray(rhs))
    u[model.prescribed] = u_p
    return u


def signals_naive(chain: SimulationChain, p: ChainParams, psi: np.ndarray, t_out: np.ndarray
                  ) -> np.ndarray:
    """Reference path: one sparse solve of the truss per time step.

    Builds the WG displacements and tooth forces of every time step, solves
    K_FF u_F = f_F − K_FP u_P with the (cracked) structure's factorisation and applies
    the gauge rows to u. Same result as :func:`signals_from_motion`, far slower.

    Returns
    -------
    ndarray, shape (5, n_t)
    """
    m = chain.model
    if p.has_root_crack:
        n = m.mesh.n_theta
        mc = cracked(m, angle_index(p.root_crack_deg, n),
                     mesh_severity(p.root_crack_severity, n))
        lu = factorize(mc.K[m.free][:, m.free])
        k_fp_m = mc.K[m.free][:, m.prescribed].tocsc()
    else:
        lu, k_fp_m = m.lu, k_fp(m)
    rows = signal_rows(m, chain.layout)
    loads = m.unit_tooth_loads(chain.solver.alpha).tocsr()
    c = p.tooth_factors(chain.influence(p).theta)
    hw = np.deg2rad(chain.settings.contact_half_width_deg)
    wg_pos = np.searchsorted(m.prescribed, m.wg_dofs)
    out = np.empty((5, psi.size))
    share = chain.load_share(p, psi)
    for k in range(psi.size):
        w = (share[k] * contact_window(m.theta - psi[k], hw)
             + (2 - share[k]) * contact_window(m.theta - psi[k] - np.pi, hw)) * c
        f = loads @ (w / w.sum()) * t_out[k]
        u_p = np.zeros(m.prescribed.size)
        u_p[wg_pos] = wg_displacement(m, psi[k:k + 1], p.w0_m, p.ecc_m, p.ecc_theta_rad)[0]
        u = np.zeros(m.n_dof)
        u[m.free] = lu.solve(f[m.free] - k_fp_m @ u_p)
        u[m.prescribed] = u_p
        out[:, k] = rows @ u
    return out


def signals_from_motion(chain: SimulationChain, p: ChainParams, psi: np.ndarray,
                        t_out: np.ndarray) -> np.ndarray:
    """Five bridge signals of one variant from its motion, by the chain's influences one
    variant at a time (what :meth:`SimulationChain.signals_batch` does for many).

    Parameters
    ----------
    chain : SimulationChain
    p : ChainParams
    psi : ndarray, shape (n_t,)
        WG angle relative to the flexspline [rad].
    t_out : ndarray, shape (n_t,)
        Acting output torque [N m].

    Returns
    -------
    ndarray, shape (5, n_t)
        s0..s4 [mV/V].
    """
    inf = chain.influence(p)
    s = p.w0_m * (inf.A[:, None] * np.cos(2 * psi) + inf.B[:, None] * np.sin(2 * psi))
    if p.ecc_m:
        s = s + p.ecc_m * (inf.Ex * np.cos(p.ecc_theta_rad)
                           + inf.Ey * np.sin(p.ecc_theta_rad))[:, None]
    h = torque_influence(psi, inf.g, inf.theta, p.tooth_factors(inf.theta),
                         np.deg2rad(chain.settings.contact_half_width_deg),
                         chain.load_share(p, psi))
    return (s + t_out[None, :] * h) + chain.layout.zero_offsets_mvv[:, None]


def power_terms(p: dy.GearParams, res: dy.SimResult, t_load_nm: np.ndarray) -> dict:
    """Energy [J] and powers [W] along simulated windows, shape (V, n_t) each, from the
    equations of the module docstring (eq. 2-6), written out independently of the simulator.

    Energy balance of eq. (1) [derived]: with the elastic energy V = k1 Δφ_k²/2 + k2 Δφ_k⁴/4
    and Δφ_k = tan α_in φ_in + c φ_out + φ_err(φ_in),

        d/dt (J_in ω_in²/2 + J_out ω_out²/2 + V)
            = T_m ω_in + T_stiff φ_err'(φ_in) ω_in − T_fric φ̇_b − P_load,

    P_load = T_load tanh(N ω_out / v_s) ω_out >= 0 delivered to the load, T_fric φ̇_b lost in
    the mesh. The second term is the power of the kinematic error: eq. (1) lets it strain
    the flexspline without a reaction torque on the input, so it is a source of its own
    next to the motor's T_m ω_in (0.2 % of it at 2000 rpm, 52 N m; the steady-state check
    of the module docstring leaves it out).
    """
    phi_in, w_in, phi_out, w_out, _ = res.states
    tl = np.asarray(t_load_nm, float)[:, None]
    c = p.c_out
    sa, ca = np.sin(p.alpha_tooth_rad), np.cos(p.alpha_tooth_rad)
    k, a, th = (np.asarray(v, float)[:, None, None]
                for v in (p.ke_orders, p.ke_amp_rad, p.ke_phase_rad))
    phi_err = c * (a * np.sin(k * phi_in + th)).sum(axis=0)
    dphi_err = c * (a * k * np.cos(k * phi_in + th)).sum(axis=0)  # d φ_err / d φ_in
    d = p.tan_alpha_in * phi_in + c * phi_out + phi_err
    t_stiff = p.k1_nm_per_rad * d + p.k2_nm_per_rad3 * d**3
    v_b = -w_out / sa
    t_fric = ((p.b0_nm + p.mu * c * np.abs(t_stiff) / ca) * np.tanh(v_b / p.v_smooth_rad_s)
              + (p.b1_nms + p.b2_nms3 * v_b**2) * v_b
              + p.b3_nm * np.sin(phi_out + p.theta_b_rad))
    return {
        "energy": (p.j_in_kgm2 * w_in**2 / 2 + p.j_out_kgm2 * w_out**2 / 2
                   + p.k1_nm_per_rad * d**2 / 2 + p.k2_nm_per_rad3 * d**4 / 4),
        "p_in": res.p_in,
        "p_ke": t_stiff * dphi_err * w_in,
        "p_fric": t_fric * v_b,
        "p_load": tl * np.tanh(w_out * p.ratio / p.v_smooth_rad_s) * w_out,
    }


def modes(y: np.ndarray, dt: float, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Poles [1/s] and amplitudes of y as a sum of ``order`` damped exponentials (matrix
    pencil: shift invariance of the Hankel matrix's leading right singular vectors)."""
    hank = np.lib.stride_tricks.sliding_window_view(y, y.size // 2 + 1)
    v = np.linalg.svd(hank, full_matrices=False)[2][:order].T
    z = np.linalg.eigvals(np.linalg.pinv(v[:-1]) @ v[1:]).astype(complex)
    amp = np.linalg.lstsq(z[None, :] ** np.arange(y.size)[:, None], y.astype(complex),
                          rcond=None)[0]
    return np.log(z) / dt, np.abs(amp)


def ring_down(p: dy.GearParams, dec: int):
    """Gear ``p`` at 2000 rpm under a load step 7 -> 39 N m at 10 ms, simulated at 20 kHz
    to 8.5 decay times after the step: the dominant oscillatory pole [1/s] of the
    delivered torque from 2 to 8 decay times after the step (six damped exponentials,
    every ``dec``-th sample), the predicted (frequency [Hz], decay time [s]) of
    ``torsional_mode`` at 39 N m, and the simulation."""
    f_hz, tau = torsional_mode(p, 2000.0, 39.0)
    fs, t_s = 20e3, 0.01
    prof = pf.Profile(pf.SpeedProfile(2000.0, (pf.Hold(t_s + 8.5 * tau),)),
                      pf.LoadSteps(7.0, ((t_s, 39.0),)))
    res = pd.simulate_profile([p], prof, 0.0, sample_rate_hz=fs, substeps=1)
    assert res.t_out[0, int(t_s * fs) - 1] == pytest.approx(7.0, rel=1e-9)  # steady before
    i0, i1 = int(round((t_s + 2 * tau) * fs)), int(round((t_s + 8 * tau) * fs))
    lam, amp = modes(res.t_out[0, i0:i1:dec] - 39.0, dec / fs, 6)
    osc = np.flatnonzero(lam.imag > 1.0)
    return lam[osc[np.argmax(amp[osc])]], (f_hz, tau), res


def _bridge_vector(x, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.shape != (N_BRIDGES,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be {N_BRIDGES} finite values, got shape {a.shape}")
    return a


def apply_bridge_drift(signals, temp_c, zero_mvv_per_k, span_per_k,
                       ref_c: float = REF_TEMP_C) -> np.ndarray:
    """Bridge outputs at the joint's temperature: (1 + span_c ΔT) s + zero_c ΔT
    (:mod:`swgsim.sensing.bridge_drift`; the data sets apply it per window through
    :meth:`swgsim.datasets.conditions.WindowConditions.bridge_gain_offset`).

    Parameters
    ----------
    signals : array_like, shape (W, 5, T)
        Bridge outputs s0..s4 of W windows of T samples at ``ref_c`` [mV/V].
    temp_c : array_like, shape (W,)
        Temperature of the gauges in each window [°C]
        (:func:`swgsim.gear.thermal.joint_temperature`).
    zero_mvv_per_k, span_per_k : array_like, shape (5,)
        One gear's coefficients (:func:`swgsim.sensing.bridge_drift.draw_bridge_drift`)
        [mV/V per K], [1/K].
    ref_c : float
        Reference temperature of the coefficients [°C] (20).

    Returns
    -------
    ndarray, shape (W, 5, T)
        Drifted outputs [mV/V], float64 (a new array).

    Raises
    ------
    ValueError
        Shapes other than above or values not finite.
    """
    x = np.asarray(signals, dtype=float)
    if x.ndim != 3 or x.shape[1] != N_BRIDGES:
        raise ValueError(f"signals must have shape (W, {N_BRIDGES}, T), got {x.shape}")
    t = np.asarray(temp_c, dtype=float)
    if t.shape != (x.shape[0],) or not np.all(np.isfinite(t)):
        raise ValueError(f"temp_c must be {x.shape[0]} finite values (one per window), "
                         f"got shape {t.shape}")
    zero = _bridge_vector(zero_mvv_per_k, "zero_mvv_per_k")
    span = _bridge_vector(span_per_k, "span_per_k")
    if not np.isfinite(ref_c):
        raise ValueError(f"ref_c must be finite, got {ref_c}")
    d = (t - ref_c)[:, None, None]  # (W, 1, 1)
    return (1.0 + span[None, :, None] * d) * x + zero[None, :, None] * d
