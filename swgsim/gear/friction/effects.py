"""Library of friction effects: their forms, as inputs of the simulation.

Every effect is a :class:`~swgsim.gear.terms.Term` in the joint coordinate q (output angle
[rad]), the friction torque τ [N m] positive along q̇, ``sgn`` the smooth sign of the
velocity the friction law sees. :data:`FRICTION_LIBRARY` is the one registry of friction
effects for the simulator and the calibration alike, :func:`register_effect` the one way
into it, :func:`make_effect` makes an entry by its kind (the ``friction_effects`` option);
the fits are :mod:`swgcal.friction.library`'s. Forms, sources and the Legendre basis:
docs/PHYSICS.md sec. 5.3; the registry's design: ARCHITECTURE.md, "To add a calibration effect".
"""

from __future__ import annotations

from typing import Any

import numpy as np

from swgsim.base.registry import Registry, extends
from swgsim.gear.friction.ripples import FrictionRipple, PositionRipple
from swgsim.gear.friction.signals import FrictionSignals
from swgsim.gear.terms import Param, Term, linear_recurrence

__all__ = ["FRICTION_LIBRARY", "AsymmetricCoulomb", "Stribeck", "Presliding", "PositionRipple",
           "FrictionRipple", "LoadCoulomb", "GravityResidual", "Inertia", "ThermalDrift",
           "SensorDrift", "VelocityLag", "TransportDelay", "TemperatureFriction",
           "MeasuredVariable",
           "MIN_TEMPERATURE_SPAN_K", "make_effect", "register_effect", "dahl_state",
           "first_order_lag"]


# ---------------------------------------------------------------------------------------
# state integrators (exact on irregular sampling)


def dahl_state(q: np.ndarray, q_c: float, z0: float = 0.0) -> np.ndarray:
    """Normalised Dahl presliding state along a position path.

    dz/dq = (1 − z sgn(q̇)) / q_c (Dahl 1968 with exponent 1, written over displacement
    so that it is rate independent, as Dahl's model is). Integrated exactly per sample
    step: z_k = s + (z_{k−1} − s) exp(−``|Δq_k|`` / q_c), s = sgn(Δq_k). z approaches ±1
    after a travel of a few q_c in one direction.

    Parameters
    ----------
    q : ndarray, shape (n,)
        Joint angle [rad].
    q_c : float
        Characteristic presliding displacement [rad], > 0.
    z0 : float, default 0
        State before the first sample.

    Returns
    -------
    ndarray, shape (n,)
        z in [−1, 1].
    """
    if not q_c > 0:
        raise ValueError(f"q_c must be > 0 [rad], got {q_c}")
    dq = np.diff(np.asarray(q, float), prepend=q[0])
    a = np.exp(-np.abs(dq) / q_c)
    b = np.sign(dq) * (1.0 - a)
    return linear_recurrence(a, b, z0)


def first_order_lag(t: np.ndarray, u: np.ndarray, tau_s: float) -> np.ndarray:
    """First-order low-pass y' = (u − y) / τ on irregular samples (exact for u held
    constant over each step, taking the sample at the step's end), y_0 = u_0.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Time [s].
    u : ndarray, shape (n,)
        Input.
    tau_s : float
        Time constant [s], > 0.

    Returns
    -------
    ndarray, shape (n,)
    """
    if not tau_s > 0:
        raise ValueError(f"tau_s must be > 0 [s], got {tau_s}")
    dt = np.diff(np.asarray(t, float), prepend=t[0])
    a = np.exp(-dt / tau_s)
    return linear_recurrence(a, (1.0 - a) * np.asarray(u, float), float(u[0]))


# ---------------------------------------------------------------------------------------
# the library


class AsymmetricCoulomb(Term):
    """Direction-dependent Coulomb level: ``τ = Δc |sgn(v)|``, so the Coulomb level is
    b0 + Δc for q̇ > 0 and b0 − Δc for q̇ < 0 (Armstrong-Hélouvry et al. 1994;
    asymmetric friction of gravity-loaded robot joints)."""

    kind = "asymmetric_coulomb"
    linear = (Param("delta_c", "N m", "half the difference of the Coulomb levels (+ minus −)"),)
    description = "Coulomb level differs between the directions of motion"
    source = "Armstrong-Hélouvry, Dupont & Canudas de Wit 1994"

    def columns(self, sig: FrictionSignals, theta: np.ndarray) -> np.ndarray:
        return np.abs(sig.sgn)[:, None]


class Stribeck(Term):
    """Stribeck effect: τ = F_s sgn(v) exp(−(v / v_st)²), static friction above the
    Coulomb level decaying with speed (Armstrong-Hélouvry et al. 1994, Gaussian form)."""

    kind = "stribeck"
    linear = (Param("f_s", "N m", "static minus Coulomb friction"),)
    nonlinear = (Param("v_st", "rad/s", "Stribeck velocity", log=True),)
    description = "friction above the Coulomb level at low speed (Stribeck curve)"
    source = "Armstrong-Hélouvry et al. 1994; Stribeck 1902"

    def columns(self, sig: FrictionSignals, theta: np.ndarray) -> np.ndarray:
        return (sig.sgn * np.exp(-(sig.v_eff / theta[0]) ** 2))[:, None]


class Presliding(Term):
    """Presliding hysteresis (Dahl 1968): part F_d of the Coulomb level follows the
    Dahl state z over displacement instead of the velocity sign: τ = F_d (z − sgn),
    dz/dq = (1 − z sgn(q̇)) / q_c. With F_d = b0 the whole Coulomb level is of Dahl
    type; LuGre (Canudas de Wit et al. 1995) has the same steady state."""

    kind = "presliding"
    linear = (Param("f_d", "N m", "Coulomb part following the presliding state"),)
    nonlinear = (Param("q_c", "rad", "characteristic presliding displacement", log=True),)
    description = "friction builds up over a small displacement after each reversal"
    source = "Dahl 1968; Canudas de Wit et al. 1995 (LuGre); Armstrong-Hélouvry et al. 1994"

    def columns(self, sig, theta):
        states = sig.extra.get("states")
        if states is not None and self.name in states:  # one step of an integrator
            z = states[self.name]
        else:
            z = dahl_state(sig.q_rad, float(theta[0]))
        return (z - sig.sgn)[:, None]


def _instance(name: str | None) -> int:
    """k of an instance name ``kind#k`` (1 without suffix)."""
    return int(name.rsplit("#", 1)[1]) if name and "#" in name else 1


class _RangePolynomial(Term):
    """Smooth function of the joint angle over the calibrated range: Legendre
    polynomials P_a, P_b of x = (q − q_center) / q_half, x clipped to [−1, 1] (held
    constant outside the range, so that a simulation never extrapolates a polynomial).
    The Legendre basis is well conditioned however short the range; harmonics sin kq,
    cos kq of a short arc are nearly collinear and give cancelling, meaningless
    amplitudes. Instance k uses orders (first + 2(k − 1), first + 2k − 1)."""

    first_order = 1
    odd = False

    def __init__(self, name: str | None = None, q_center: float = 0.0, q_half: float = 1.0,
                 orders: tuple[int, int] | None = None) -> None:
        super().__init__(name)
        if not q_half > 0:
            raise ValueError(f"q_half must be > 0 [rad], got {q_half}")
        k = _instance(name)
        self.orders = tuple(int(o) for o in orders) if orders is not None else (
            self.first_order + 2 * (k - 1), self.first_order + 2 * k - 1)
        self.q_center, self.q_half = float(q_center), float(q_half)

    @classmethod
    def for_signals(cls, sig: FrictionSignals, name: str | None = None) -> Term:
        return cls(name, q_center=sig.scales.q_center, q_half=0.5 * sig.scales.q_span)

    @property
    def linear(self):  # type: ignore[override]
        a, b = self.orders
        return (Param(f"c{a}", "N m", f"coefficient of P{a}(x)"),
                Param(f"c{b}", "N m", f"coefficient of P{b}(x)"))

    def options(self) -> dict[str, Any]:
        return {"q_center": self.q_center, "q_half": self.q_half, "orders": list(self.orders)}

    def required_options(self) -> tuple[str, ...]:
        return ("q_center", "q_half")

    def columns(self, sig, theta):
        x = np.clip((sig.q_rad - self.q_center) / self.q_half, -1.0, 1.0)
        base = sig.sgn if self.odd else 1.0
        cols = []
        for o in self.orders:
            c = np.zeros(o + 1)
            c[o] = 1.0
            cols.append(base * np.polynomial.legendre.legval(x, c))
        return np.column_stack(cols)

    def derived(self, coef, theta):
        a, b = self.orders
        out = {f"c{a}": float(coef[0]), f"c{b}": float(coef[1])}
        # RMS over x uniform in [-1, 1]: ∫ P_n² dx / 2 = 1 / (2n + 1)
        out["rms"] = float(np.sqrt(coef[0] ** 2 / (2 * a + 1) + coef[1] ** 2 / (2 * b + 1)))
        return out

    def derived_units(self):
        a, b = self.orders
        return {f"c{a}": "N m", f"c{b}": "N m", "rms": "N m"}

    def primary(self):
        return ("rms",)


class LoadCoulomb(_RangePolynomial):
    """Load-dependent Coulomb friction, the μ F_n term of paper eq. (5). With a load
    signal (option ``use_load``): ``τ = μ sgn |load|``. Without one, the Coulomb level varies
    with the configuration-dependent (gravity) load, a smooth function of q over the
    calibrated range: τ = sgn (c_a P_a(x) + c_b P_b(x)), orders (1, 2) for the first
    instance, (3, 4), (5, 6) for repeats (see the base class for x)."""

    kind = "load_coulomb"
    description = "Coulomb level varying with the transmitted (gravity) load"
    source = "paper eq. (5) μ F_n; Armstrong-Hélouvry et al. 1994"
    first_order = 1
    odd = True

    def __init__(self, name: str | None = None, use_load: bool = False, **kwargs: Any) -> None:
        super().__init__(name, **kwargs)
        self.use_load = bool(use_load)

    @classmethod
    def for_signals(cls, sig: FrictionSignals, name: str | None = None) -> LoadCoulomb:
        if sig.load_nm is not None:
            return cls(name, use_load=True)
        return super().for_signals(sig, name)

    @property
    def linear(self):  # type: ignore[override]
        if self.use_load:
            return (Param("mu", "-", "friction per unit load torque"),)
        return super().linear

    def applicable(self, sig) -> bool:
        return sig.load_nm is not None if self.use_load else True

    def options(self) -> dict[str, Any]:
        return {"use_load": True} if self.use_load else super().options()

    def required_options(self) -> tuple[str, ...]:
        return () if self.use_load else super().required_options()

    def columns(self, sig, theta):
        if self.use_load:
            return (sig.sgn * np.abs(sig.load_nm))[:, None]
        return super().columns(sig, theta)

    def derived(self, coef, theta):
        return {"mu": float(coef[0])} if self.use_load else super().derived(coef, theta)

    def derived_units(self):
        return {"mu": "-"} if self.use_load else super().derived_units()

    def primary(self):
        return ("mu",) if self.use_load else ("rms",)


class GravityResidual(_RangePolynomial):
    """Configuration-dependent torque left by the rigid-body compensation the friction
    torque was identified with (README of the data: friction = joint torque minus the
    rigid-body model; a gravity-model error is a smooth function of the joint angles):
    τ = c_a P_a(x) + c_b P_b(x), orders (2, 3) for the first instance, (4, 5), (6, 7) for
    repeats (constant and linear parts are covered by the paper law's b3 sin(q + θ_b))."""

    kind = "gravity_residual"
    description = "configuration-dependent torque, same in both directions (model mismatch)"
    source = "rigid-body compensation of the data (README); paper eq. (5) b3 term"
    first_order = 2


class Inertia(Term):
    """Torque proportional to the acceleration, τ = J_a q̈: inertia not compensated by
    the rigid-body model the friction torque was identified with (model mismatch)."""

    kind = "inertia"
    linear = (Param("j_a", "kg m²", "uncompensated inertia"),)
    description = "torque proportional to q̈ (rigid-body model mismatch)"
    source = "rigid-body model compensation of the data (README); Armstrong-Hélouvry 1994"

    def columns(self, sig, theta):
        return sig.ddq_rad_s2[:, None]


class ThermalDrift(Term):
    """Coulomb level relaxing as the joint warms up: τ = d exp(−(t − t0)/T_th) sgn(v)
    (first-order thermal response of the warming joint; friction falls with lubricant
    temperature; docs/PHYSICS.md sec. 5; Armstrong-Hélouvry et al. 1994). The time
    constant is that of the warm-up, minutes to hours (:mod:`swgcal.friction.ranges`): on a
    recording shorter than it the drift is nearly a straight line, d and T_th trade off
    and are not pinned down, and the drift stays in the residual (probe ``time_odd``)."""

    kind = "thermal_drift"
    linear = (Param("d", "N m", "excess Coulomb level at t0"),)
    nonlinear = (Param("t_th", "s", "thermal time constant", log=True),)
    description = "friction level decays over time (warm-up)"
    source = "docs/PHYSICS.md sec. 5; Armstrong-Hélouvry et al. 1994"

    def columns(self, sig, theta):
        return (np.exp(-(sig.t_s - sig.scales.t0) / theta[0]) * sig.sgn)[:, None]


class SensorDrift(Term):
    """Zero drift of the torque measurement: τ = c (1 − exp(−(t − t0)/T_d)), a first-
    order warm-up of the gauges and amplifier (docs/PHYSICS.md sec. 5: gauge temperature
    drift)."""

    kind = "sensor_drift"
    linear = (Param("c", "N m", "final offset change"),)
    nonlinear = (Param("t_d", "s", "drift time constant", log=True),)
    description = "offset creeping over time, same in both directions"
    source = "docs/PHYSICS.md sec. 5 (gauge temperature drift)"

    def columns(self, sig, theta):
        return (1.0 - np.exp(-(sig.t_s - sig.scales.t0) / theta[0]))[:, None]


class VelocityLag(Term):
    """Frictional memory (Hess & Soom 1990): the friction law sees the velocity through
    a first-order lag, v = q̇ low-passed with time constant T_L. A transform term: it
    changes the velocity of every friction term after it (put first in the model)."""

    kind = "velocity_lag"
    nonlinear = (Param("t_lag", "s", "lag time constant", log=True),)
    is_transform = True
    description = "friction follows the velocity with a lag (frictional memory)"
    source = "Hess & Soom 1990; Armstrong-Hélouvry et al. 1994 (frictional memory)"

    def columns(self, sig, theta):  # pragma: no cover - transform only
        return np.zeros((sig.n, 0))

    def transform(self, sig: FrictionSignals, theta: np.ndarray) -> FrictionSignals:
        states = sig.extra.get("states")
        if states is not None and self.name in states:  # one step of an integrator
            return sig.replace(v_eff=states[self.name])
        return sig.replace(v_eff=first_order_lag(sig.t_s, sig.v_eff, float(theta[0])))


class MeasuredVariable(Term):
    """A measured variable the recording carries beside those the library knows (a
    column other than time, angle, velocity, acceleration, load, temperature and
    friction): τ = (x − x̄)(c_e + c_o sgn(v)), even and odd in the direction of motion.
    Instance k takes the k-th such column (its name: option ``column``): the loop can
    propose a variable nobody declared, and says which."""

    kind = "measured_variable"
    linear = (Param("c_even", "N m/unit", "torque per unit of the variable, both directions"),
              Param("c_odd", "N m/unit", "friction per unit of the variable (flips with v)"))
    description = "torque following a measured variable of the recording"
    source = "a column of the recording the library has no physics for (docs/calibration.md)"

    def __init__(self, name: str | None = None, column: str = "", mean: float = 0.0) -> None:
        super().__init__(name)
        self.column, self.mean = str(column), float(mean)

    @classmethod
    def for_signals(cls, sig: FrictionSignals, name: str | None = None) -> Term:
        cols = list(getattr(sig, "measured", {}) or {})
        k = _instance(name) - 1
        if k >= len(cols):
            return cls(name)
        return cls(name, column=cols[k], mean=float(np.mean(sig.measured[cols[k]])))

    @property
    def repeatable(self) -> int:
        return 1_000_000  # one per column: applicable() bounds it

    def applicable(self, sig) -> bool:
        return bool(self.column) and self.column in (getattr(sig, "measured", {}) or {})

    def options(self) -> dict[str, Any]:
        return {"column": self.column, "mean": self.mean}

    def required_options(self) -> tuple[str, ...]:
        return ("column",)

    def columns(self, sig, theta):
        if self.column not in sig.measured:
            raise ValueError(f"measured_variable needs the column {self.column!r}; these "
                             "signals carry none")
        x = sig.measured[self.column] - self.mean
        return np.column_stack([x, x * sig.sgn])

    def derived(self, coef, theta):
        return {"c_even": float(coef[0]), "c_odd": float(coef[1]),
                "size": float(np.hypot(coef[0], coef[1]))}

    def derived_units(self):
        return {"c_even": "N m/unit", "c_odd": "N m/unit", "size": "N m/unit"}

    def primary(self):
        return ("size",)


#: Smallest spread of a recording's temperature for ``temperature_friction`` to be tried
#: [K] [choice: a few steps of a joint's temperature sensor (0.0625 K on a UR3), and the
#: size at which a grease's viscosity changes by a few per cent].
MIN_TEMPERATURE_SPAN_K = 1.0


class TransportDelay(Term):
    """A transport delay d between the measured angle and the measured torque: the torque
    logged at time t belongs to the angle of time t − d, q(t − d) ≈ q − q̇ d (first order
    in d, exact at constant speed; a drive's current loop, filters and bus cycle delay the
    current that gives the torque). A transform term: every term after it sees the
    delayed angle, so a ripple's phase turns with speed by 2π q̇ d / P, opposite in the
    two directions of motion. d > 0: the torque lags the angle."""

    kind = "transport_delay"
    nonlinear = (Param("delay", "s", "transport delay from the angle to the torque"),)
    is_transform = True
    description = "the torque lags the angle by a transport delay (phase turning with speed)"
    source = ("a sampled drive's dead time (current loop, filters, bus cycle): Franklin, "
              "Powell & Workman, Digital Control of Dynamic Systems, 3rd ed., sec. 3.2")

    def columns(self, sig, theta):  # pragma: no cover - transform only
        return np.zeros((sig.n, 0))

    def transform(self, sig: FrictionSignals, theta: np.ndarray) -> FrictionSignals:
        return sig.replace(q_rad=sig.q_rad - sig.dq_rad_s * float(theta[0]))


class TemperatureFriction(Term):
    """Friction changing with the joint's measured temperature T (a recording's
    ``temperature_c`` column): τ = (T − T_ref) (k_c sgn(v) + k_v v), T_ref the
    recording's mean temperature (option ``t_ref_c``). The grease thins as it warms
    (its viscosity falls about exponentially with temperature, :mod:`swgsim.gear.thermal`),
    so a strain wave gear's running torque falls: the physical signs are k_v <= 0 and a
    net change at the reference speed v_ref (option ``v_ref``) <= 0."""

    kind = "temperature_friction"
    linear = (Param("k_c", "N m/K", "Coulomb level change per kelvin"),
              Param("k_v", "N m s/(rad K)", "viscous coefficient change per kelvin"))
    description = "friction level and viscous slope change with the measured temperature"
    source = ("grease viscosity against temperature (swgsim.gear.thermal); Harmonic Drive "
              "catalogues: no-load running torque falls as the gear warms")

    def __init__(self, name: str | None = None, t_ref_c: float = 20.0,
                 v_ref: float = 1.0) -> None:
        super().__init__(name)
        if not v_ref > 0:
            raise ValueError(f"v_ref must be > 0 [rad/s], got {v_ref}")
        self.t_ref_c, self.v_ref = float(t_ref_c), float(v_ref)

    @classmethod
    def for_signals(cls, sig: FrictionSignals, name: str | None = None) -> Term:
        t = sig.temperature_c
        t_ref = float(np.mean(t)) if t is not None else 20.0
        return cls(name, t_ref_c=t_ref, v_ref=sig.scales.v_ref)

    def applicable(self, sig) -> bool:
        t = getattr(sig, "temperature_c", None)
        return t is not None and float(np.ptp(t)) >= MIN_TEMPERATURE_SPAN_K

    def options(self) -> dict[str, Any]:
        return {"t_ref_c": self.t_ref_c, "v_ref": self.v_ref}

    def required_options(self) -> tuple[str, ...]:
        return ("t_ref_c",)

    def columns(self, sig, theta):
        if sig.temperature_c is None:
            raise ValueError("temperature_friction needs the joint's temperature (a "
                             "temperature_c column); these signals carry none")
        dt = sig.temperature_c - self.t_ref_c
        return np.column_stack([dt * sig.sgn, dt * sig.v_eff])

    def derived(self, coef, theta):
        k_c, k_v = float(coef[0]), float(coef[1])
        return {"k_c": k_c, "k_v": k_v, "k_ref": k_c + k_v * self.v_ref}

    def derived_units(self):
        return {"k_c": "N m/K", "k_v": "N m s/(rad K)", "k_ref": "N m/K"}

    def primary(self):
        return ("k_ref",)


FRICTION_LIBRARY: Registry[type[Term]] = Registry("friction effect", __name__,
                                                  "FRICTION_LIBRARY", (
    (cls.kind, cls) for cls in (
        AsymmetricCoulomb, Stribeck, Presliding, PositionRipple, FrictionRipple,
        LoadCoulomb, GravityResidual, Inertia, ThermalDrift, SensorDrift, VelocityLag,
        TransportDelay, TemperatureFriction, MeasuredVariable)
))
"""Kind -> effect class, the one registry of friction effects (ARCHITECTURE.md,
"To add a calibration effect"):
instantiate with :func:`make_effect`."""


def register_effect(cls: type[Term]) -> type[Term]:
    """Add a friction effect to :data:`FRICTION_LIBRARY`, for the simulator and the
    calibration (one call; usable as a class decorator).

    The class is the effect's form (a :class:`~swgsim.gear.terms.Term`: ``kind``, the
    parameters ``linear``/``nonlinear``, ``columns`` or ``transform``): a
    ``friction_effects`` entry of its kind then makes it
    (:func:`~swgsim.gear.friction.parse_effects`). When it is a
    :class:`swgcal.terms.FitTerm` too (``probes``, ``ranges`` with sources,
    ``bounds``/``starts``, ``signature``), every friction calibration built afterwards
    offers it. A class subclassing the one registered under its kind takes its place (a
    fit added to a form registered before); see docs/ARCHITECTURE.md, "To add a
    calibration effect: touch these files".

    Parameters
    ----------
    cls : subclass of Term
        With a ``kind`` not yet registered, or registered to a class it subclasses.

    Returns
    -------
    The class itself.

    Raises
    ------
    TypeError
        Not a :class:`~swgsim.gear.terms.Term` subclass.
    ValueError
        Its ``kind`` is taken (by this class, or by one it does not subclass).
    """
    if not (isinstance(cls, type) and issubclass(cls, Term)):
        raise TypeError(f"a friction effect must subclass swgsim.gear.terms.Term, got {cls!r}")
    held = FRICTION_LIBRARY.get(cls.kind)
    if held is not None and not extends(cls, held):
        raise ValueError(f"friction effect {cls.kind!r} is already registered "
                         f"({held.__qualname__}; only a subclass of it may take its place)")
    return FRICTION_LIBRARY.add(cls.kind, cls)


def make_effect(kind: str, name: str | None = None, **kwargs: Any) -> Term:
    """Instantiate the registered effect of a kind.

    Parameters
    ----------
    kind : str
        A key of :data:`FRICTION_LIBRARY`.
    name : str, optional
        Instance name (default ``kind``; ``kind#k`` for a repeat).
    **kwargs
        Constructor options (e.g. ``use_load``).

    Returns
    -------
    Term

    Raises
    ------
    KeyError
        Unknown kind; the message lists the registered ones.
    """
    try:
        cls = FRICTION_LIBRARY[kind]
    except KeyError:
        raise KeyError(f"unknown friction effect {kind!r}; the library has "
                       f"{sorted(FRICTION_LIBRARY)}") from None
    return cls(name, **kwargs)
