"""The dynamic model along an operating profile (:mod:`swgsim.gear.profile`): paper eq. (1)-(6)
of :mod:`swgsim.gear.dynamics` with a time-varying desired speed and load, integrated by RK4 from
the steady state at the profile's start, the whole motion recorded.

:func:`simulate_profile` (optional acceleration feed-forward), :class:`ProfileResult`,
:func:`check_standstill_step` (the RK4 step at standstill, where the friction is stiffest).
Checks: the ring-down after a load step against the linearised torsional mode, the energy
balance along a reversal (tests/swgsim/test_profile.py, docs/PHYSICS.md sec. 1.8).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swgsim.gear import profile as pf
from swgsim.gear.dynamics import Batch, GearParams, SimResult, ke_batch, outputs, steady_state
from swgsim.gear.integrator import StageInputs, integrate
from swgsim.gear.modes import rk4_stable
from swgsim.gear.profile import Profile, max_load_nm


@dataclass
class ProfileResult(SimResult):
    """Result of :func:`simulate_profile`: a :class:`SimResult` from t = 0, plus the
    profile's inputs.

    Attributes
    ----------
    w_d : ndarray, shape (n_t,)
        Desired input speed [rad/s].
    load_nm : ndarray, shape (V, n_t)
        Load torque T_L at the output, positive resisting forward motion [N m].
    p_load : ndarray, shape (V, n_t)
        Power taken by the load, T_L q̇ with q̇ = −ω_out [W] (negative: the load drives).

    Notes
    -----
    ``p_in`` is T_m ω_in including the feed-forward torque; ``efficiency`` is
    mean(P_out) / mean(P_in) over the profile, meaningful only for a one-way profile.
    """

    w_d: np.ndarray | None = None
    load_nm: np.ndarray | None = None
    p_load: np.ndarray | None = None


def check_standstill_step(params: list[GearParams] | Batch, profile: Profile,
                          step_s: float) -> None:
    """Refuse an RK4 step that is unstable where the profile passes 0 rpm.

    There the friction's smooth sign has the slope ``(b0 + μ c |T_stiff| / cos α) / v_s + b1``
    on φ̇_b, a damping −slope / (sin²α J_out) [1/s] on ω_out [derived, eq. 5-6], with
    T_stiff at the profile's largest load.

    Parameters
    ----------
    params : list of GearParams or Batch
        The variants (V).
    profile : swgsim.gear.profile.Profile
    step_s : float
        Integrator step [s], 1 / (sample_rate_hz · substeps).

    Raises
    ------
    ValueError
        ``substeps: the RK4 step ... is unstable at 0 rpm ...`` with the step needed.
    """
    b = params if isinstance(params, Batch) else Batch.of(list(params))
    bk = b if "inv_tan_a" in b.fields else ke_batch(b)
    _, nk = profile.speed.knots()
    if np.all(nk > 0) or np.all(nk < 0):
        return
    t_stiff = max_load_nm(profile.load) / bk.c_out
    slope = (bk.b0_nm + bk.mu_c_cos * t_stiff) * bk.inv_v_smooth + bk.b1_nms
    lam = -slope * bk.inv_sin_a**2 / bk.j_out_kgm2
    if not rk4_stable(lam, step_s):
        need = int(np.ceil(step_s * float(np.max(-lam)) / 2.78))
        raise ValueError(f"substeps: the RK4 step {step_s:.3g} s is unstable at 0 rpm "
                         f"(friction damping {float(np.min(lam)):.4g} 1/s needs a step below "
                         f"{2.78 / float(np.max(-lam)):.3g} s); raise substeps or "
                         f"sample_rate_hz {need}-fold")


def simulate_profile(params: list[GearParams] | Batch, profile: Profile, phi_in0=0.0,
                     sample_rate_hz: float = 10e3, duration_s: float | None = None,
                     substeps: int = 2, feedforward: bool = False) -> ProfileResult:
    """Integrate many variants along an operating profile (RK4, fixed step), recorded
    from t = 0 with its transients.

    The speed loop tracks ω_d(t) of the profile; with ``feedforward`` the motor adds
    T_ff = (J_in + J_out / N²) dω_d/dt, the torque to accelerate the rigid drive train
    (friction and load not fed forward). The load enters eq. (1) as
    J_out ω̇_out = … + T_L with T_L(t, q, q̇), q = −φ_out (docs/PHYSICS.md sec. 1.8):
    a brake (today's ``simulate``, through :func:`rhs`), load steps or a link under
    gravity (added to :func:`rhs`'s ω̇_out). The start is :func:`steady_state` at the
    profile's initial speed and load.

    Parameters
    ----------
    params : list of GearParams or Batch
        One parameter set per variant (V variants).
    profile : swgsim.gear.profile.Profile
        Desired speed and load, the same for all variants.
    phi_in0 : float or ndarray, shape (V,)
        Input angle at t = 0 [rad].
    sample_rate_hz : float
        Output sample rate [Hz]; the integrator step is 1 / (substeps · rate).
    duration_s : float, optional
        Recorded length [s]; default the profile's duration.
    substeps : int
        RK4 steps per output sample, >= 1.
    feedforward : bool
        Add the acceleration feed-forward T_ff to the motor torque.

    Returns
    -------
    ProfileResult
        ``round(duration_s · sample_rate_hz)`` samples from t = 0.

    Raises
    ------
    ValueError
        A profile beyond the catalogue limits (:func:`swgsim.gear.profile.validate`), non-positive
        rates or duration, or an RK4 step unstable at standstill.
    """
    b = params if isinstance(params, Batch) else Batch.of(list(params))
    pf.validate(profile, float(np.max(b.j_out_kgm2)), float(np.min(b.ratio)))
    dur = profile.speed.duration_s if duration_s is None else duration_s
    if not sample_rate_hz > 0 or not dur > 0 or not (int(substeps) == substeps >= 1):
        raise ValueError("sample_rate_hz and duration_s must be > 0 and substeps an integer "
                         f">= 1, got {sample_rate_hz}, {dur}, {substeps}")
    bk = ke_batch(b)
    v, n, sub = bk.ratio.size, int(round(dur * sample_rate_hz)), int(substeps)
    h = 1.0 / (sample_rate_hz * sub)
    check_standstill_step(bk, profile, h)
    th = np.arange(2 * (n - 1) * sub + 1) * (h / 2)  # stage times
    wd_h, ad_h = pf.speed_at(profile, th)
    ad_l = pf.speed_at(profile, th, side="left")[1]  # the last stage takes left limits
    load = profile.load
    kind = ("opposing" if profile.opposing else
            "steps" if isinstance(load, pf.LoadSteps) else "gravity")
    t_opp = float(load.torque_nm) if kind == "opposing" else 0.0
    tl_h = pf.load_at(load, th) if kind == "steps" else None
    tl_l = pf.load_at(load, th, side="left") if kind == "steps" else None
    g_max = load.max_torque_nm if kind == "gravity" else 0.0
    q0 = load.q0_rad if kind == "gravity" else 0.0
    j_ff = bk.j_in_kgm2 + bk.j_out_kgm2 / bk.ratio**2
    ff_in = j_ff / bk.j_in_kgm2 if feedforward else None

    phi0 = np.broadcast_to(np.asarray(phi_in0, float), (v,)).copy()
    w0 = np.full(v, wd_h[0])
    x = steady_state(bk, w0, np.full(v, t_opp if kind == "opposing" else 0.0), phi0)
    if kind != "opposing":
        for _ in range(3):  # gravity depends on the start angle through the twist
            tl0 = tl_h[0] if kind == "steps" else g_max * np.cos(q0 - x[2])
            x = steady_state(bk, w0, np.broadcast_to(tl0, (v,)).astype(float), phi0)

    inputs = StageInputs(w_d=np.zeros(v), t_opposing=np.full(v, t_opp), w_d_stage=wd_h,
                         ff=ff_in, a_d=ad_h, a_d_left=ad_l,
                         t_load=tl_h, t_load_left=tl_l,
                         gravity_nm=g_max, q0_rad=q0)
    rec = integrate(bk, x, inputs, 0, n, sub, h)
    return _profile_result(rec, bk, profile, kind, sample_rate_hz, j_ff if feedforward else None)


def _profile_result(rec, bk, profile, kind, fs, j_ff) -> ProfileResult:
    n = rec.shape[2]
    time = np.arange(n) / fs
    w_d, a_d = pf.speed_at(profile, time)
    col = Batch({k: val[..., None] for k, val in bk.fields.items()})
    t_out, p_in, p_out = outputs(rec, col, w_d, 0.0)
    if j_ff is not None:
        p_in = p_in + j_ff[:, None] * a_d * rec[1]
    q, q_dot = -rec[2], -rec[3]
    if kind == "opposing":
        load = profile.load.torque_nm * np.tanh(q_dot * col.ratio * col.inv_v_smooth)
    elif kind == "steps":
        load = np.broadcast_to(pf.load_at(profile.load, time), q.shape).copy()
    else:
        load = profile.load.max_torque_nm * np.cos(q + profile.load.q0_rad)
    ok = bool(np.all(np.isfinite(rec)))
    eff = p_out.mean(axis=1) / p_in.mean(axis=1)
    return ProfileResult(time=time, states=rec, t_out=t_out, p_in=p_in, p_out=p_out,
                         efficiency=eff, success=ok,
                         message="ok" if ok else "non-finite states",
                         w_d=w_d, load_nm=load, p_load=load * q_dot)
