"""The gear of eq. (1) linearised at steady motion: its eigenvalues, the torsional mode
(the output inertia ringing on the gear's stiffness) and whether a fixed RK4 step is
stable for them.

The linearisation is by central differences of :func:`swgsim.gear.dynamics.rhs` about
:func:`swgsim.gear.dynamics.steady_state`, with the kinematic error left out (docs/PHYSICS.md
sec. 1.7). Used to choose the settling time before a window (:mod:`swgsim.datasets.plan`), to
refuse an RK4 step that is unstable (:mod:`swgsim.datasets.plan`,
:mod:`swgsim.gear.profile_dynamics`), and by the observability map.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from swgsim.gear.dynamics import RPM, Batch, GearParams, check_inputs, ke_batch, rhs, steady_state


def torsional_mode(params: GearParams, n_in_rpm: float, t_out_nm: float) -> tuple[float, float]:
    """Natural frequency and decay time of the torsional mode of eq. (1), linearised at
    steady motion.

    The torsional mode is the output inertia ringing on the gear's stiffness (the
    oscillatory eigenvalue of highest frequency; the others belong to the speed loop).
    Its frequency says whether the kinematic error's orders excite the gear below or above
    resonance; its decay time how long the start of :func:`swgsim.gear.dynamics.simulate`
    rings (the start, :func:`swgsim.gear.dynamics.steady_state`, leaves out the kinematic
    error). Bench (8.8e-3 kg m²): about 230-430 Hz and 4 ms over 7-70 N m; a robot link
    (0.69 kg m²): 30-60 Hz and 30 ms. With backlash the linearisation is at the contact
    twist (the flanks stay in contact while T_stiff keeps its sign), so the dead zone does
    not enter (docs/PHYSICS.md sec. 8.1).

    Parameters
    ----------
    params : GearParams
    n_in_rpm : float
        Input speed [rpm], > 0.
    t_out_nm : float
        Load torque [N m], >= 0.

    Returns
    -------
    f_hz : float
        Damped natural frequency Im λ / 2π [Hz].
    decay_s : float
        1 / (−Re λ) [s].

    Raises
    ------
    ValueError
        On non-positive speed or negative torque, an unstable linearisation or no
        oscillatory mode.
    """
    lam = linear_eigenvalues(params, n_in_rpm, t_out_nm)
    scale = float(np.max(np.abs(lam)))
    lam = lam[np.abs(lam) > 1e-9 * scale]  # drop the rigid rotation (zero eigenvalue)
    if np.any(lam.real >= 0):
        raise ValueError(f"the linearised gear is not stable at {n_in_rpm} rpm, "
                         f"{t_out_nm} N m (eigenvalues {np.round(lam, 3)})")
    if not np.any(np.abs(lam.imag) > 1e-9 * scale):
        raise ValueError(f"no oscillatory mode at {n_in_rpm} rpm, {t_out_nm} N m "
                         f"(eigenvalues {np.round(lam, 3)})")
    top = lam[np.argmax(lam.imag)]
    return float(top.imag / (2 * np.pi)), float(-1.0 / top.real)


def linear_eigenvalues(params: GearParams, n_in_rpm: float, t_out_nm: float) -> np.ndarray:
    """Eigenvalues of eq. (1) linearised at steady motion (kinematic error left out).

    Parameters
    ----------
    params : GearParams
    n_in_rpm : float
        Input speed [rpm], > 0.
    t_out_nm : float
        Load torque [N m], >= 0.

    Returns
    -------
    ndarray of complex, shape (5,)
        [1/s]; one is about zero (the rigid rotation).

    Raises
    ------
    ValueError
        On non-positive speed or negative torque.
    """
    check_inputs(n_in_rpm, t_out_nm)
    p = dataclasses.replace(params, ke_amp_rad=tuple(0.0 for _ in params.ke_amp_rad))
    b = ke_batch(Batch.of([p]))
    w_d = np.array([float(n_in_rpm) * RPM])
    t_load = np.array([float(t_out_nm)])
    x0 = steady_state(b, w_d, t_load, np.array([0.0]))
    jac = np.empty((5, 5))
    for j in range(5):  # central differences, step relative to the state's size
        h = 1e-7 * max(1.0, abs(float(x0[j, 0])))
        xp, xm = x0.copy(), x0.copy()
        xp[j] += h
        xm[j] -= h
        jac[:, j] = (rhs(0.0, xp, b, w_d, t_load) - rhs(0.0, xm, b, w_d, t_load))[:, 0] / (2 * h)
    return np.linalg.eigvals(jac)


def rk4_stable(lam: np.ndarray, step_s: float) -> bool:
    """Whether the classic RK4 step ``step_s`` is stable for the eigenvalues ``lam``.

    Parameters
    ----------
    lam : ndarray of complex
        Eigenvalues of the linearised system [1/s] (:func:`linear_eigenvalues`).
    step_s : float
        Integrator step [s], ``1 / (sample_rate_hz · substeps)`` in
        :func:`swgsim.gear.dynamics.simulate`.

    Returns
    -------
    bool
        True when every ``step_s · λ`` lies in RK4's stability region,
        ``|1 + z + z²/2 + z³/6 + z⁴/24| <= 1`` (up to 1e-9).
    """
    z = np.asarray(lam, complex) * float(step_s)
    return bool(np.all(np.abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24) <= 1 + 1e-9))
