"""Closed-form references and slow reference paths shared by the physics tests and the
benchmarks (not a test module): the steady motion's closed form, one variant integrated by
scipy (:func:`simulate_reference`) and the gauge signals by one truss solve per time step
(:func:`signals_naive`), against which the fast paths are checked."""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from swgsim.gear import dynamics as dy
from swgsim.gear.chain import SimulationChain
from swgsim.gear.faults import ChainParams, angle_index, mesh_severity
from swgsim.gear.flexspline import factorize
from swgsim.gear.influence import contact_window
from swgsim.gear.sensors import signal_rows


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


def signals_naive(chain: SimulationChain, p: ChainParams, psi: np.ndarray, t_out: np.ndarray
                  ) -> np.ndarray:
    """Reference path: one sparse solve of the truss per time step.

    Builds the WG displacements and tooth forces of every time step, solves
    K_FF u_F = f_F − K_FP u_P with the (cracked) structure's factorisation and applies
    the gauge rows to u. Same result as :meth:`SimulationChain.signals_from_motion`, far
    slower.

    Returns
    -------
    ndarray, shape (5, n_t)
    """
    m = chain.model
    if p.has_root_crack:
        n = m.mesh.n_theta
        mc = m.cracked(angle_index(p.root_crack_deg, n),
                       mesh_severity(p.root_crack_severity, n))
        lu = factorize(mc.K[m.free][:, m.free])
        k_fp = mc.K[m.free][:, m.prescribed].tocsc()
    else:
        lu, k_fp = m.lu, m.K_FP
    rows = signal_rows(m, chain.layout)
    loads = m.unit_tooth_loads(chain.solver.alpha).tocsr()
    c = chain._tooth_factors(p)
    hw = np.deg2rad(chain.settings.contact_half_width_deg)
    wg_pos = np.searchsorted(m.prescribed, m.wg_dofs)
    out = np.empty((5, psi.size))
    share = chain.load_share(p, psi)
    for k in range(psi.size):
        w = (share[k] * contact_window(m.theta - psi[k], hw)
             + (2 - share[k]) * contact_window(m.theta - psi[k] - np.pi, hw)) * c
        f = loads @ (w / w.sum()) * t_out[k]
        u_p = np.zeros(m.prescribed.size)
        u_p[wg_pos] = m.wg_displacement(psi[k:k + 1], p.w0_m, p.ecc_m, p.ecc_theta_rad)[0]
        u = np.zeros(m.n_dof)
        u[m.free] = lu.solve(f[m.free] - k_fp @ u_p)
        u[m.prescribed] = u_p
        out[:, k] = rows @ u
    return out
