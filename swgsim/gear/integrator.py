"""The fixed-step RK4 integrator of the gear model, eq. (1)-(6) of the paper, compiled.

One integrator serves the steady window (:func:`swgsim.gear.dynamics.simulate`) and the
operating profile (:func:`swgsim.gear.profile_dynamics.simulate_profile`): the desired speed
and the extra torques are inputs per stage time, constant for a steady window. Each variant
is integrated on its own with scalar arithmetic (numba), so a batch of a few variants costs
microseconds per step instead of the ~40 µs of Python overhead per right-hand side that the
array form (:func:`swgsim.gear.dynamics.rhs`, kept for the linearisation, for extra friction
effects and as the tests' reference) pays. Same model, same step, same stage times: the two
agree to rounding (tests/swgsim/test_integrator.py).

RK4 is the classic fourth-order Runge-Kutta method (Hairer, Nørsett and Wanner, *Solving
Ordinary Differential Equations I*, 2nd ed., Springer 1993, sec. II.1, table 1.2).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np

# rows of the parameter matrix handed to the kernel, in this order
PARAM_ROWS = ("tan_alpha_in", "inv_tan_a", "c_out", "k1_nm_per_rad", "k2_nm_per_rad3",
              "inv_sin_a", "inv_v_smooth", "b0_nm", "mu_c_cos", "b1_nms", "b2_nms3", "b3_nm",
              "theta_b_rad", "ratio", "kp_nms", "ki_nm", "j_in_kgm2", "j_out_kgm2")


@dataclass
class StageInputs:
    """What drives the gear at each RK4 stage time j h / 2, j = 0 .. 2 n_steps.

    Attributes
    ----------
    w_d : ndarray, shape (V,)
        Desired input speed common to all stages [rad/s] (0 for a profile).
    w_d_stage : ndarray, shape (n_stage,), optional
        Desired input speed added per stage [rad/s] (none for a steady window).
    t_opposing : ndarray, shape (V,)
        Magnitude of the load opposing output motion, smoothed like the friction [N m].
    ff : ndarray, shape (V,), optional
        Feed-forward gain on the desired acceleration, (J_in + J_out/N²) / J_in [-]
        (0: none).
    a_d, a_d_left : ndarray, shape (n_stage,), optional
        Desired input acceleration at each stage, right and left limits [rad/s²].
    t_load, t_load_left : ndarray, shape (n_stage,), optional
        Load torque driving the output, right and left limits [N m] (load steps).
    gravity_nm, q0_rad : float
        A link under gravity, T_L = gravity_nm cos(q0 − φ_out) [N m] (0: none).
    """

    w_d: np.ndarray
    t_opposing: np.ndarray
    w_d_stage: np.ndarray | None = None
    ff: np.ndarray | None = None
    a_d: np.ndarray | None = None
    a_d_left: np.ndarray | None = None
    t_load: np.ndarray | None = None
    t_load_left: np.ndarray | None = None
    gravity_nm: float = 0.0
    q0_rad: float = 0.0


def integrate(bk, x0: np.ndarray, inputs: StageInputs, n_skip: int, n_rec: int, sub: int,
              h: float) -> np.ndarray:
    """Integrate V variants by RK4 and record the states at every output sample.

    Parameters
    ----------
    bk : swgsim.gear.dynamics.Batch
        Parameters with the derived constants (:func:`swgsim.gear.dynamics.ke_batch`).
    x0 : ndarray, shape (5, V)
        Start states [φ_in, ω_in, φ_out, ω_out, ∫e_ω].
    inputs : StageInputs
        Speed, loads and feed-forward per stage; per-stage arrays cover at least
        2 sub (n_skip + n_rec − 1) + 1 stages.
    n_skip, n_rec : int
        Output samples integrated but not recorded, then recorded.
    sub : int
        RK4 steps per output sample, >= 1.
    h : float
        Step [s].

    Returns
    -------
    ndarray, shape (5, V, n_rec)
        States at samples n_skip .. n_skip + n_rec − 1.
    """
    v = x0.shape[1]
    par = np.ascontiguousarray(np.stack([np.broadcast_to(bk.fields[k], (v,))
                                         for k in PARAM_ROWS]), dtype=float)
    gap = bk.fields.get("half_gap")
    n_stage = 2 * sub * (n_skip + n_rec - 1) + 1
    zero = np.zeros(v)

    def stage(a):  # a per-stage input, or zeros when absent
        if a is None:
            return np.zeros(n_stage)
        a = np.asarray(a, float)
        if a.size < n_stage:
            raise ValueError(f"a stage input holds {a.size} stages, {n_stage} needed")
        return np.ascontiguousarray(a[:n_stage])
    drive = np.stack([stage(inputs.w_d_stage), stage(inputs.a_d), stage(inputs.a_d_left),
                      stage(inputs.t_load), stage(inputs.t_load_left)])
    rec = np.empty((5, v, n_rec))
    _rk4(par, np.ascontiguousarray(bk.ke_amp_rad, float),
         np.ascontiguousarray(bk.ke_orders, float), np.ascontiguousarray(bk.ke_phase_rad, float),
         zero if gap is None else np.ascontiguousarray(gap, float), gap is not None,
         np.ascontiguousarray(x0, float), np.broadcast_to(inputs.w_d, (v,)).astype(float),
         np.broadcast_to(inputs.t_opposing, (v,)).astype(float),
         zero if inputs.ff is None else np.broadcast_to(inputs.ff, (v,)).astype(float),
         drive, float(inputs.gravity_nm), float(inputs.q0_rad), n_skip, sub, h, rec)
    return rec


def rk4_record(f: Callable, x: np.ndarray, n_skip: int, n_rec: int, sub: int,
               h: float) -> np.ndarray:
    """The same RK4 on arrays for any right-hand side ``f(j, x, last)`` at stage time j h / 2
    (``last``: the step's end, where inputs take left limits); used where the right-hand side
    is Python (extra friction effects) and by the tests as the reference of :func:`integrate`.

    Returns
    -------
    ndarray, shape (n_x, V, n_rec)
        States at samples n_skip .. n_skip + n_rec − 1.
    """
    rec = np.empty((x.shape[0], x.shape[1], n_rec))
    for k in range(n_skip + n_rec):
        if k >= n_skip:
            rec[:, :, k - n_skip] = x
        if k == n_skip + n_rec - 1:
            break
        for s in range(sub):
            j = 2 * (k * sub + s)
            k1 = f(j, x)
            k2 = f(j + 1, x + h / 2 * k1)
            k3 = f(j + 1, x + h / 2 * k2)
            k4 = f(j + 2, x + h * k3, last=True)
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return rec


@numba.njit(cache=True)
def _deriv(p, ke_a, ke_k, ke_p, gap, has_gap, xs, w_d, t_opp, ff, a_d, t_l, g, q0, out):
    """dx/dt of one variant (parameter column p), :func:`swgsim.gear.dynamics.rhs` in scalars."""
    phi_in, w_in, phi_out, w_out, integ = xs[0], xs[1], xs[2], xs[3], xs[4]
    ke = 0.0
    for i in range(ke_a.shape[0]):
        ke += ke_a[i] * np.sin(ke_k[i] * phi_in + ke_p[i])
    dphi = p[0] * (phi_in - phi_out) + p[1] * phi_out + p[2] * ke
    if has_gap:
        dphi = dphi - min(max(dphi, -gap), gap)
    t_stiff = (p[3] + p[4] * dphi * dphi) * dphi
    v_b = -w_out * p[5]
    sgn = np.tanh(v_b * p[6])
    t_fric = ((p[7] + p[8] * abs(t_stiff)) * sgn + (p[9] + p[10] * v_b * v_b) * v_b
              + p[11] * np.sin(phi_out + p[12]))
    t_load_eff = t_opp * np.tanh(-w_out * p[13] * p[6])
    e_w = w_d - w_in
    t_m = p[14] * e_w + p[15] * integ
    out[0] = w_in
    out[1] = (t_m - p[0] * t_stiff) / p[16] + ff * a_d
    inv_j_out = 1.0 / p[17]
    dw_out = (-p[2] * t_stiff + t_fric * p[5] + t_load_eff) / p[17] + t_l * inv_j_out
    if g != 0.0:
        dw_out += g * np.cos(q0 - phi_out) * inv_j_out
    out[3] = dw_out
    out[2] = w_out
    out[4] = e_w


@numba.njit(cache=True)
def _rk4(par, ke_a, ke_k, ke_p, gap, has_gap, x0, w_d, t_opp, ff, drive, g, q0, n_skip, sub, h,
         rec):
    n_rec = rec.shape[2]
    k1, k2, k3, k4 = np.empty(5), np.empty(5), np.empty(5), np.empty(5)
    xs, xt = np.empty(5), np.empty(5)
    for v in range(x0.shape[1]):
        p, a, kk, ph = par[:, v], ke_a[:, v], ke_k[:, v], ke_p[:, v]
        for i in range(5):
            xs[i] = x0[i, v]
        for k in range(n_skip + n_rec):
            if k >= n_skip:
                for i in range(5):
                    rec[i, v, k - n_skip] = xs[i]
            if k == n_skip + n_rec - 1:
                break
            for s in range(sub):
                j = 2 * (k * sub + s)
                wd0, wd1 = w_d[v] + drive[0, j], w_d[v] + drive[0, j + 1]
                wd2 = w_d[v] + drive[0, j + 2]
                _deriv(p, a, kk, ph, gap[v], has_gap, xs, wd0, t_opp[v], ff[v], drive[1, j],
                       drive[3, j], g, q0, k1)
                for i in range(5):
                    xt[i] = xs[i] + h / 2 * k1[i]
                _deriv(p, a, kk, ph, gap[v], has_gap, xt, wd1, t_opp[v], ff[v], drive[1, j + 1],
                       drive[3, j + 1], g, q0, k2)
                for i in range(5):
                    xt[i] = xs[i] + h / 2 * k2[i]
                _deriv(p, a, kk, ph, gap[v], has_gap, xt, wd1, t_opp[v], ff[v], drive[1, j + 1],
                       drive[3, j + 1], g, q0, k3)
                for i in range(5):
                    xt[i] = xs[i] + h * k3[i]
                _deriv(p, a, kk, ph, gap[v], has_gap, xt, wd2, t_opp[v], ff[v], drive[2, j + 2],
                       drive[4, j + 2], g, q0, k4)
                for i in range(5):
                    xs[i] = xs[i] + h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i])
