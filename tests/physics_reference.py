"""Closed-form references shared by the physics tests (not a test module)."""

import numpy as np
from scipy.optimize import brentq

from swgsim.gear import dynamics as dy


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
