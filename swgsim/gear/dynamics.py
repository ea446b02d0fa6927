"""Dynamic input/output model of the SWG, paper eq. (1)-(6) (Tuttle & Seering 1996 lineage).

States per variant: x = [φ_in, ω_in, φ_out, ω_out, ∫e_ω] (rad, rad/s, rad, rad/s, rad):
the nonlinear twist (eq. 3-4), its stiffness torque (eq. 2, with backlash a dead zone), the
kinematic error, friction on the flank sliding coordinate (eq. 5-6), a PI speed loop on
the input and the load on the output. :func:`simulate` integrates it by classical RK4 at a
fixed step (compiled in :mod:`swgsim.gear.integrator`), :func:`rhs` is the same right-hand
side on arrays, :func:`rt1_size20` fits the gear to the catalogue. Equations, energy
balance and its tests: docs/PHYSICS.md sec. 1.1-1.5 (profiles sec. 1.8, backlash sec. 8.1).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from swgsim.gear.integrator import StageInputs, integrate, rk4_record
from swgsim.gear.profile import RPM

#: Output inertia of the bench: flange and load coupling [kg m²] (public script seed,
#: docs/PHYSICS.md sec. 1); the default of :class:`GearParams` and of the data-set option
#: ``load.j_out_kgm2``.
J_OUT_BENCH_KGM2 = 8.8e-3


@dataclass(frozen=True)
class GearParams:
    """Parameters of the dynamic I/O model. Build with :func:`rt1_size20`.

    Attributes
    ----------
    ratio : float
        Catalogue gear ratio N [-] (100).
    alpha_tooth_rad : float
        Gear-tooth (pressure) angle [rad] (20 deg, docs/PHYSICS.md sec. 1).
    pitch_radius_m : float
        Flexspline pitch radius [m] (25.4 mm, size 20, docs/PHYSICS.md sec. 2).
    j_in_kgm2 : float
        Input inertia: WG 0.193e-4 (catalogue) + motor rotor 1.0e-4 [unverified] [kg m²].
    j_out_kgm2 : float
        Output inertia incl. flange and load coupling [kg m²] (:data:`J_OUT_BENCH_KGM2`).
    k1_nm_per_rad, k2_nm_per_rad3 : float
        Linear and cubic stiffness on Δφ_k [N m/rad], [N m/rad³] (eq. 2), fitted to
        catalogue K1, K3 (:func:`fit_stiffness`).
    b0_nm, b1_nms, b2_nms3, b3_nm, theta_b_rad : float
        Friction coefficients of eq. (5) in the flank coordinate [N m], [N m s/rad],
        [N m s³/rad³], [N m], [rad]; b1 from the catalogue no-load running torque.
    mu : float
        Coulomb coefficient of the tooth mesh [-] (eq. 5, lever r_p), from the catalogue
        efficiency at rated torque.
    v_smooth_rad_s : float
        Velocity scale of the smooth sign tanh(φ̇_b / v_s) [rad/s].
    ke_amp_rad : tuple of float
        Kinematic-error amplitudes at the output for orders ``ke_orders`` [rad]
        (about 1 arcmin peak to peak in total [unverified], docs/PHYSICS.md sec. 1).
    ke_orders : tuple of int
        Orders of the input angle (1, 2, 4).
    ke_phase_rad : tuple of float
        Phases of the kinematic-error harmonics [rad] [unverified, arbitrary fixed].
    kp_nms, ki_nm : float
        PI speed loop gains [N m s/rad], [N m/rad] (about 30 Hz bandwidth).
    backlash_rad : float
        Backlash (lost motion) at the output [rad], >= 0: the full width of the dead zone
        in the output angle at a held input, the quantity catalogues and wear studies
        state in arcmin. On the twist it is a dead zone of width c b
        (:attr:`backlash_twist_rad`, Δφ_k = c δ_out at a held input); 0 (default) is the
        paper's backlash-free gear (docs/PHYSICS.md sec. 8.1).
    """

    ratio: float = 100.0
    alpha_tooth_rad: float = np.deg2rad(20.0)
    pitch_radius_m: float = 25.4e-3
    j_in_kgm2: float = 1.193e-4
    j_out_kgm2: float = J_OUT_BENCH_KGM2
    k1_nm_per_rad: float = 2160.0
    k2_nm_per_rad3: float = 7.4e7
    b0_nm: float = 0.29
    b1_nms: float = 0.52
    b2_nms3: float = 5e-4
    b3_nm: float = 0.0174
    theta_b_rad: float = 0.0
    mu: float = 0.03
    v_smooth_rad_s: float = 0.05
    ke_amp_rad: tuple[float, ...] = (0.4e-4, 1.0e-4, 0.3e-4)
    ke_orders: tuple[int, ...] = (1, 2, 4)
    ke_phase_rad: tuple[float, ...] = (0.3, 1.1, 2.0)
    kp_nms: float = 0.0225
    ki_nm: float = 0.85
    backlash_rad: float = 0.0

    @property
    def tan_alpha_in(self) -> float:
        """tan α_in of eq. (4)."""
        return 1.0 / ((self.ratio + 1.0) * np.tan(self.alpha_tooth_rad))

    @property
    def c_out(self) -> float:
        """Lever of T_stiff on the output, N / ((N + 1) tan α_tooth) [-]."""
        return 1.0 / np.tan(self.alpha_tooth_rad) - self.tan_alpha_in

    @property
    def backlash_twist_rad(self) -> float:
        """Width of the dead zone on the twist Δφ_k, c · backlash_rad [rad]."""
        return self.c_out * self.backlash_rad


@dataclass(frozen=True)
class Catalogue:
    """Catalogue data of a size-20, ratio-100 SWG (docs/PHYSICS.md sec. 2, Schaeffler RT1 /
    Harmonic Drive CSG-20-100).

    Attributes
    ----------
    k1_nm_per_rad, k3_nm_per_rad : float
        Torsional stiffness K1 (low torque) and K3 (high torque) [N m/rad].
    t_low_nm, t_high_nm : float
        Torques at which the secant stiffness is matched to K1 and K3 [N m]: T1 = 7 N m
        (end of the K1 range) and 70 N m (the highest load of the study).
    no_load_torque_nm : float
        No-load running torque at the input at 2000 rpm [N m] (0.105).
    efficiency : float
        Efficiency at rated torque, 2000 rpm, 20 °C [-] (0.77).
    rated_torque_nm : float
        Rated torque at 2000 rpm [N m] (52).
    """

    k1_nm_per_rad: float = 16e3
    k3_nm_per_rad: float = 29e3
    t_low_nm: float = 7.0
    t_high_nm: float = 70.0
    no_load_torque_nm: float = 0.105
    efficiency: float = 0.77
    rated_torque_nm: float = 52.0
    speed_rpm: float = 2000.0


def fit_stiffness(cat: Catalogue, c_out: float) -> tuple[float, float]:
    """k1, k2 of eq. (2) from catalogue secant stiffnesses.

    Output torque T = c T_stiff(c δ) for an output wind-up δ, so the secant stiffness is
    K(δ) = k1 c² + k2 c⁴ δ² [derived]. Matching K(T_low / K1) = K1 and K(T_high / K3) = K3
    is linear in (k1, k2).

    Returns
    -------
    tuple of float
        k1 [N m/rad], k2 [N m/rad³].
    """
    d_l = cat.t_low_nm / cat.k1_nm_per_rad
    d_h = cat.t_high_nm / cat.k3_nm_per_rad
    a = np.array([[c_out**2, c_out**4 * d_l**2], [c_out**2, c_out**4 * d_h**2]])
    k1, k2 = np.linalg.solve(a, [cat.k1_nm_per_rad, cat.k3_nm_per_rad])
    return float(k1), float(k2)


def fit_friction(p: GearParams, cat: Catalogue) -> tuple[float, float]:
    """b1 and μ from the catalogue no-load torque and efficiency at rated torque.

    Steady state at speed ω_in: v = φ̇_b = ω_in / (N sin α). With A = b0 + b1 v + b2 v³
    (+ b3 averaging out), T_fric (1 − μ / (sin α cos α)) = A + μ T_load / cos α, and
    P_in = P_out + T_fric v [derived, docs/PHYSICS.md sec. 1.5]. No load gives T_fric from the
    running torque; rated load gives T_fric = T_load sin α (1/η − 1). Two linear
    equations in b1 and μ.

    Returns
    -------
    tuple of float
        b1 [N m s/rad], μ [-].
    """
    w_in = cat.speed_rpm * RPM
    sa, ca = np.sin(p.alpha_tooth_rad), np.cos(p.alpha_tooth_rad)
    v = w_in / (p.ratio * sa)
    tf_0 = cat.no_load_torque_nm * w_in / v
    tf_r = cat.rated_torque_nm * sa * (1 / cat.efficiency - 1)
    a0 = p.b0_nm + p.b2_nms3 * v**3
    # tf (1 - mu/(sa ca)) = a0 + b1 v + mu T / ca  ->  b1 v + mu (T/ca + tf/(sa ca)) = tf - a0
    m = np.array([[v, tf_0 / (sa * ca)],
                  [v, cat.rated_torque_nm / ca + tf_r / (sa * ca)]])
    b1, mu = np.linalg.solve(m, [tf_0 - a0, tf_r - a0])
    return float(b1), float(mu)


def rt1_size20(cat: Catalogue | None = None, **overrides) -> GearParams:
    """Nominal parameters of an RT1-T-like gear, size 20, ratio 100.

    Parameters
    ----------
    cat : Catalogue, optional
        Catalogue data to fit k1, k2, b1, μ to (default :class:`Catalogue`).
    **overrides
        Any :class:`GearParams` field, applied after the fit.
    """
    cat = cat or Catalogue()
    p = GearParams()
    k1, k2 = fit_stiffness(cat, p.c_out)
    p = dataclasses.replace(p, k1_nm_per_rad=k1, k2_nm_per_rad3=k2)
    b1, mu = fit_friction(p, cat)
    p = dataclasses.replace(p, b1_nms=b1, mu=mu)
    return dataclasses.replace(p, **overrides)


@dataclass
class KeHarmonic:
    """An extra kinematic-error harmonic: φ_err gains c · amp · sin(order · φ_in + phase).

    Attributes
    ----------
    order : int
        Order of the wave-generator angle, a positive integer.
    amp_rad : float
        Amplitude [rad], >= 0.
    phase_rad : float
        Phase [rad].
    """

    order: int
    amp_rad: float
    phase_rad: float = 0.0


def gear_with_ke(gear: GearParams,
                 harmonics: Sequence[KeHarmonic | Mapping[str, float]]) -> GearParams:
    """Gear parameters with extra kinematic-error harmonics appended.

    Parameters
    ----------
    gear : GearParams
    harmonics : sequence of KeHarmonic
        The data-set option ``gears[i].ke_extra``; a mapping ``{order, amp_rad,
        phase_rad}`` (``gear_ke_harmonics`` of a strain summary) is taken as one.

    Returns
    -------
    GearParams

    Raises
    ------
    ValueError
        A non-positive integer order or a negative amplitude.
    """
    o, a, p = list(gear.ke_orders), list(gear.ke_amp_rad), list(gear.ke_phase_rad)
    for h in harmonics:
        h = h if isinstance(h, KeHarmonic) else KeHarmonic(**h)
        k, amp = int(h.order), float(h.amp_rad)
        if k < 1 or k != float(h.order):
            raise ValueError(f"kinematic-error order must be a positive integer, got {h.order}")
        if not amp >= 0:
            raise ValueError(f"kinematic-error amp_rad must be >= 0 [rad], got {amp}")
        o.append(k)
        a.append(amp)
        p.append(float(h.phase_rad))
    return dataclasses.replace(gear, ke_orders=tuple(o), ke_amp_rad=tuple(a),
                               ke_phase_rad=tuple(p))


@dataclass
class Batch:
    """Parameters of many variants as arrays, shape (V,) each (one per variant)."""

    fields: dict[str, np.ndarray] = field(default_factory=dict)

    @classmethod
    def of(cls, params: list[GearParams]) -> Batch:
        """Stack a list of GearParams (scalar fields) into arrays."""
        b = cls({f.name: np.asarray([getattr(p, f.name) for p in params], dtype=float)
                 for f in dataclasses.fields(GearParams)})
        b.fields["tan_alpha_in"] = np.array([p.tan_alpha_in for p in params])
        b.fields["c_out"] = np.array([p.c_out for p in params])
        return b

    def __getattr__(self, name):
        try:
            return self.fields[name]
        except KeyError as e:
            raise AttributeError(name) from e


def _forces(x, b: Batch, t_load):
    """Stiffness torque, friction and motor-side quantities, vectorised over variants."""
    phi_in, phi_out, w_out = x[0], x[2], x[3]
    # kinematic error c sum_k A_k sin(k phi_in + th_k); ke arrays have shape (n_k, V)
    ke = (b.ke_amp_rad * np.sin(b.ke_orders * phi_in + b.ke_phase_rad)).sum(axis=0)
    dphi_k = b.tan_alpha_in * (phi_in - phi_out) + b.inv_tan_a * phi_out + b.c_out * ke
    gap = b.fields.get("half_gap")  # present only when some variant has backlash
    if gap is not None:  # dead zone: the teeth lose contact within ±g (sec. 8.1)
        dphi_k = dphi_k - np.clip(dphi_k, -gap, gap)
    t_stiff = (b.k1_nm_per_rad + b.k2_nm_per_rad3 * dphi_k * dphi_k) * dphi_k
    v_b = -w_out * b.inv_sin_a
    sgn = np.tanh(v_b * b.inv_v_smooth)
    # mu F_n r_p with F_n = |c T_stiff| / (r_p cos a)
    t_fric = ((b.b0_nm + b.mu_c_cos * np.abs(t_stiff)) * sgn
              + (b.b1_nms + b.b2_nms3 * v_b * v_b) * v_b
              + b.b3_nm * np.sin(phi_out + b.theta_b_rad))
    t_load_eff = t_load * np.tanh(-w_out * b.ratio * b.inv_v_smooth)
    return t_stiff, t_fric, t_load_eff, v_b


def rhs(t, x, b: Batch, w_d, t_load):
    """Right-hand side dx/dt of eq. (1), vectorised: x shape (5, V) -> (5, V).

    Parameters
    ----------
    t : float
        Time [s] (unused; the model is autonomous).
    x : ndarray, shape (5, V)
        States [φ_in, ω_in, φ_out, ω_out, ∫e_ω] [rad, rad/s, rad, rad/s, rad].
    b : Batch
        Parameters of V variants as built by :meth:`Batch.of` (arrays of shape (V,);
        the kinematic-error fields (V, n_k)), or as :func:`ke_batch` prepared it (its
        derived constants are added when missing; the same result).
    w_d : float or ndarray, shape (V,)
        Desired input speed [rad/s].
    t_load : float or ndarray, shape (V,)
        Load torque magnitude at the output [N m], opposing output motion.

    Returns
    -------
    ndarray, shape (5, V)
        [ω_in, ω̇_in, ω_out, ω̇_out, ω_d − ω_in] [rad/s, rad/s², rad/s, rad/s², rad/s].
    """
    if "inv_tan_a" not in b.fields:  # a batch straight from Batch.of
        b = ke_batch(b)
    t_stiff, t_fric, t_load_eff, _ = _forces(x, b, t_load)
    e_w = w_d - x[1]
    t_m = b.kp_nms * e_w + b.ki_nm * x[4]
    dw_in = (t_m - b.tan_alpha_in * t_stiff) / b.j_in_kgm2
    dw_out = (-b.c_out * t_stiff + t_fric * b.inv_sin_a + t_load_eff) / b.j_out_kgm2
    return np.stack([x[1], dw_in, x[3], dw_out, e_w])


def steady_state(b: Batch, w_d, t_load, phi_in0) -> np.ndarray:
    """Initial states near the steady state for a start angle φ_in0 (shape (5, V)).

    Solves the output balance c T_stiff = T_load + T_fric / sin α for the twist by a few
    fixed-point steps (kinematic error and b3 ignored), and starts the PI integrator at
    the torque that balances the input. With backlash the twist lies half the dead zone,
    g = c b / 2, further in the direction of T_stiff (at the middle of the gap for
    T_stiff = 0).
    """
    w_out = -w_d / b.ratio
    sa = np.sin(b.alpha_tooth_rad)
    v_b = -w_out / sa
    t_stiff = np.asarray(t_load, float) / b.c_out
    for _ in range(20):
        f_n = np.abs(b.c_out * t_stiff) / (b.pitch_radius_m * np.cos(b.alpha_tooth_rad))
        t_fric = (b.b0_nm + b.b1_nms * v_b + b.b2_nms3 * v_b**3
                  + b.mu * f_n * b.pitch_radius_m) * np.tanh(v_b / b.v_smooth_rad_s)
        t_stiff = (t_load + t_fric / sa) / b.c_out
    # invert T_stiff = k1 d + k2 d^3 for d (Newton)
    d = t_stiff / b.k1_nm_per_rad
    for _ in range(30):
        d = d - (b.k1_nm_per_rad * d + b.k2_nm_per_rad3 * d**3 - t_stiff) / (
            b.k1_nm_per_rad + 3 * b.k2_nm_per_rad3 * d**2)
    gap = _half_gap(b)
    if gap is not None:  # contact on the loaded flank: the twist crosses half the gap
        d = d + gap * np.sign(t_stiff)
    # d = (phi_in + N phi_out) / ((N + 1) tan a)  ->  phi_out
    phi_out = (d * (b.ratio + 1) * np.tan(b.alpha_tooth_rad) - phi_in0) / b.ratio
    integ = b.tan_alpha_in * t_stiff / b.ki_nm
    return np.stack([phi_in0, w_d, phi_out, w_out, integ]).astype(float)


@dataclass
class SimResult:
    """Result of a dynamic simulation (python-control style).

    Attributes
    ----------
    time : ndarray, shape (n_t,)
        Time since window start [s].
    states : ndarray, shape (5, V, n_t)
        φ_in, ω_in, φ_out, ω_out, ∫e_ω over the window.
    t_out : ndarray, shape (V, n_t)
        Acting output torque delivered by the gear, c T_stiff − T_fric / sin α [N m]
        (positive when it drives the load); this loads the flexspline.
    p_in, p_out : ndarray, shape (V, n_t)
        Mechanical power at input (T_m ω_in) and output (``|T_out ω_out|``) [W].
    efficiency : ndarray, shape (V,)
        mean(P_out) / mean(P_in) over the window [-].
    success : bool
    message : str
    """

    time: np.ndarray
    states: np.ndarray
    t_out: np.ndarray
    p_in: np.ndarray
    p_out: np.ndarray
    efficiency: np.ndarray
    success: bool = True
    message: str = ""

    @property
    def psi(self) -> np.ndarray:
        """Wave-generator angle relative to the flexspline, φ_in − φ_out, shape (V, n_t)."""
        return self.states[0] - self.states[2]


def outputs(x, b, w_d, t_load):
    t_stiff, t_fric, _, _ = _forces(x, b, t_load)
    t_m = b.kp_nms * (w_d - x[1]) + b.ki_nm * x[4]
    t_out = b.c_out * t_stiff - t_fric / np.sin(b.alpha_tooth_rad)
    return t_out, t_m * x[1], np.abs(t_out * x[3])


def check_inputs(n_in_rpm, t_out_nm, fs_hz: float = 1.0, duration_s: float = 1.0,
                 settle_s: float = 0.0) -> None:
    """Refuse a speed <= 0 rpm, a load < 0 N m, a non-finite one, a sample rate or window
    <= 0 or a negative settling time, in one line (:func:`simulate`'s inputs).

    Raises
    ------
    ValueError
        Naming the argument and its allowed range.
    """
    if np.any(~np.isfinite(n_in_rpm)) or np.any(np.asarray(n_in_rpm) <= 0):
        raise ValueError(f"n_in_rpm must be > 0 rpm, got {n_in_rpm}")
    if np.any(np.asarray(t_out_nm) < 0) or np.any(~np.isfinite(t_out_nm)):
        raise ValueError(f"t_out_nm must be >= 0 N m, got {t_out_nm}")
    if not fs_hz > 0 or not duration_s > 0 or not settle_s >= 0:
        raise ValueError("sample_rate_hz and window_s must be > 0 and settle_s >= 0, got "
                         f"{fs_hz}, {duration_s}, {settle_s}")


def simulate(params: list[GearParams] | Batch, n_in_rpm, t_out_nm, phi_in0=0.0,
             sample_rate_hz: float = 10e3, window_s: float = 0.12, settle_s: float = 0.1,
             substeps: int = 2, friction_effects=None) -> SimResult:
    """Integrate many variants at once (RK4, fixed step) and return the steady window.

    Parameters
    ----------
    params : list of GearParams or Batch
        One parameter set per variant (V variants).
    n_in_rpm : float or ndarray, shape (V,)
        Desired input speed n_in,d [rpm], > 0.
    t_out_nm : float or ndarray, shape (V,)
        Load torque T_out,d [N m], >= 0.
    phi_in0 : float or ndarray, shape (V,)
        Input angle at t = 0 [rad] (the window starts ``settle_s`` later).
    sample_rate_hz : float
        Output sample rate [Hz]; the integrator step is 1 / (substeps · rate).
    window_s : float
        Length of the recorded window after the transient [s].
    settle_s : float
        Transient discarded before the window [s].
    substeps : int
        RK4 steps per output sample.
    friction_effects : object, optional
        Extra friction at the output found by the calibration loop, e.g.
        :class:`swgsim.gear.friction.simulation.FrictionEffects`: ``torque(t, q, dq, ddq, z)``
        [N m, positive along q̇], ``state_derivative(t, q, dq, z)``, ``n_states`` and
        ``initial_state(shape, dq0)``, with q = φ_out. It enters as
        J_out ω̇_out = … − τ and lowers the delivered torque; acceleration-dependent terms
        see q̈ = 0 (add an inertia term to J_out instead). Its states are integrated with
        the gear's and not recorded.

    Returns
    -------
    SimResult
        Window of ``round(window_s · sample_rate_hz)`` samples.

    Raises
    ------
    ValueError
        On non-positive speed, negative torque or non-positive rates/durations.
    """
    check_inputs(n_in_rpm, t_out_nm, sample_rate_hz, window_s, settle_s)
    b = params if isinstance(params, Batch) else Batch.of(list(params))
    v = b.ratio.size
    w_d = np.broadcast_to(np.asarray(n_in_rpm, float) * RPM, (v,)).copy()
    t_load = np.broadcast_to(np.asarray(t_out_nm, float), (v,)).copy()
    phi0 = np.broadcast_to(np.asarray(phi_in0, float), (v,)).copy()
    bk = ke_batch(b)
    x = steady_state(bk, w_d, t_load, phi0)
    fx = friction_effects
    if fx is not None and fx.n_states:
        x = np.concatenate([x, fx.initial_state((v,), dq0=x[3])])

    n_win = int(round(window_s * sample_rate_hz))
    n_set = int(round(settle_s * sample_rate_hz))
    h = 1.0 / (sample_rate_hz * substeps)
    if fx is None:
        rec = integrate(bk, x, StageInputs(w_d=w_d, t_opposing=t_load), n_set, n_win,
                        substeps, h)
    else:
        rec = rk4_record(lambda j, xx, last=False: _rhs_effects(j * h / 2, xx, bk, w_d, t_load,
                                                                fx),
                         x, n_set, n_win, substeps, h)
    ok = bool(np.all(np.isfinite(rec)))
    res = _result(rec[:5], bk, w_d, t_load, sample_rate_hz, ok)
    if fx is not None:  # the delivered torque loses the extra friction
        t_rec = settle_s + res.time
        z = rec[5:] if rec.shape[0] > 5 else None
        tau = fx.torque(np.broadcast_to(t_rec, (v, n_win)), rec[2], rec[3], 0.0, z)
        res.t_out = res.t_out + tau  # steady state: c T_stiff − T_fric/sin α = T_load − τ
        res.p_out = np.abs(res.t_out * rec[3])
        res.efficiency = res.p_out.mean(axis=1) / res.p_in.mean(axis=1)
    return res


def _rhs_effects(t, x, b, w_d, t_load, fx):
    """:func:`rhs` plus extra output friction and its states (rows 5.. of x)."""
    d = rhs(t, x[:5], b, w_d, t_load)
    z = x[5:] if x.shape[0] > 5 else None
    tau = fx.torque(t, x[2], x[3], 0.0, z)
    d[3] = d[3] - tau / b.j_out_kgm2
    if z is not None:
        d = np.concatenate([d, fx.state_derivative(t, x[2], x[3], z)])
    return d


def ke_batch(b: Batch) -> Batch:
    """Batch with kinematic-error fields as (n_k, V) arrays and derived constants."""
    f = dict(b.fields)
    v = f["ratio"].size
    for n in ("ke_amp_rad", "ke_orders", "ke_phase_rad"):
        a = np.atleast_2d(np.asarray(f[n], dtype=float))
        f[n] = np.ascontiguousarray(np.broadcast_to(a, (v, a.shape[-1])).T)
    a = f["alpha_tooth_rad"]
    f["inv_tan_a"] = 1.0 / np.tan(a)
    f["inv_sin_a"] = 1.0 / np.sin(a)
    f["inv_v_smooth"] = 1.0 / f["v_smooth_rad_s"]
    f["mu_c_cos"] = f["mu"] * f["c_out"] / np.cos(a)
    gap = _half_gap(Batch(f))
    if gap is not None:
        f["half_gap"] = gap
    return Batch(f)


def _half_gap(b: Batch) -> np.ndarray | None:
    """Half the dead zone on the twist, c · backlash_rad / 2 [rad], shape (V,); None when
    no variant of the batch has backlash (the dead zone is skipped then, so a backlash-free
    batch runs the arithmetic of the model without it, bit for bit).

    Raises
    ------
    ValueError
        A negative or non-finite backlash.
    """
    if "half_gap" in b.fields:
        return b.fields["half_gap"]
    bl = b.fields.get("backlash_rad")
    if bl is None or not np.any(bl != 0.0):
        return None
    if not np.all(np.isfinite(bl)) or np.any(bl < 0.0):
        raise ValueError(f"backlash_rad must be finite and >= 0 [rad], got {bl}")
    return 0.5 * b.fields["c_out"] * bl


def _result(rec, bk, w_d, t_load, fs, ok, msg=""):
    n = rec.shape[2]
    # parameters broadcast against (V, n_t): (V,) -> (V, 1), (n_k, V) -> (n_k, V, 1)
    col = Batch({k: val[..., None] for k, val in bk.fields.items()})
    t_out, p_in, p_out = outputs(rec, col, w_d[:, None], t_load[:, None])
    eff = p_out.mean(axis=1) / p_in.mean(axis=1)
    return SimResult(time=np.arange(n) / fs, states=rec, t_out=t_out, p_in=p_in,
                     p_out=p_out, efficiency=eff, success=ok,
                     message=msg or ("ok" if ok else "non-finite states"))
