"""The paper's five faults (Table I), and wear, as parameter transforms with severity and
position.

Faults map parameters to parameters, never signals to signals (docs/STYLE.md). Severity 0
reproduces the healthy gear exactly. Each fault states its severity range, the model it
manipulates (paper Table I) and its expected signature (paper Sec. II-C, Fig. 6).

================== =============== ======================= ============================
fault              model           severity s              transform
================== =============== ======================= ============================
reduced_damping    I/O dynamics    [0, 0.9]                b1 ← (1 − s) b1
reduced_stiffness  I/O dynamics    [0, 0.9]                k1 ← (1 − s) k1
eccentric_wg       flexspline      [0, 0.5] of w0          u_ecc = [s w0, θ, 0]
root_tooth_crack   flexspline      [0, 0.99]               k_bar ← (1 − s) k_bar at θ
tip_tooth_crack    flexspline      [0, 1]                  F_tooth ← (1 − s) F_tooth at θ
wear               I/O dynamics    [0, 1]                  k1, k2 ← (1 − 0.75 s) k1, k2;
                                                           backlash ← s · 3 arcmin
================== =============== ======================= ============================

``wear`` is not one of the paper's classes (:data:`PAPER_CLASSES`); docs/PHYSICS.md
sec. 8.1.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from swgsim.base.registry import Registry
from swgsim.gear.dynamics import GearParams

NO_ROOT_CRACK = None
"""Structure key (:meth:`ChainParams.root_crack_key`) of a flexspline without a root
crack: the one sentinel for "no root crack" wherever influences are keyed."""


@dataclass(frozen=True)
class ChainParams:
    """All parameters of one simulated gear variant.

    Attributes
    ----------
    gear : GearParams
        Dynamic I/O model parameters.
    w0_m : float
        Radial WG deflection at the major axis [m] (≈ module, 0.254 mm for size 20 with
        z_f = 200, docs/PHYSICS.md sec. 2).
    ecc_m, ecc_theta_rad : float
        WG eccentricity [m] and its direction in the flexspline frame [rad].
    root_crack_deg : float
        Position of a root tooth crack in the flexspline frame [deg] (NaN: none); the
        truss cuts the bars crossing the line just after the node nearest to it.
    root_crack_severity : float
        Fraction of the crack bars' stiffness lost, defined on the reference mesh [-]
        (:func:`mesh_severity` converts it for other meshes).
    tip_crack_deg : float
        Centre of a tip tooth crack in the flexspline frame [deg] (NaN: none).
    tip_crack_severity : float
        Fraction of the tooth force lost over the crack's arc [-].
    crack_width_deg : float
        Arc over which a tip crack removes tooth force [deg] (3 deg, about 1.7 tooth
        pitches of the 200-tooth flexspline, one node of the reference mesh).
    """

    gear: GearParams
    w0_m: float = 0.254e-3
    ecc_m: float = 0.0
    ecc_theta_rad: float = 0.0
    root_crack_deg: float = float("nan")
    root_crack_severity: float = 0.0
    tip_crack_deg: float = float("nan")
    tip_crack_severity: float = 0.0
    crack_width_deg: float = 3.0

    @property
    def has_root_crack(self) -> bool:
        """Whether the variant has a root crack of non-zero severity."""
        return self.root_crack_severity > 0.0 and not np.isnan(self.root_crack_deg)

    def root_crack_key(self) -> tuple[float, float] | None:
        """(position [deg], severity) of the root crack; :data:`NO_ROOT_CRACK` for none.

        The key of a flexspline structure: influence caches are keyed by it
        (:meth:`swgsim.gear.chain.SimulationChain.influence`)."""
        if not self.has_root_crack:
            return NO_ROOT_CRACK
        return (float(self.root_crack_deg), float(self.root_crack_severity))

    def tooth_factors(self, theta_rad: np.ndarray) -> np.ndarray:
        """Tooth-force factor c_i of each node, 1 − s × (share of its arc in the crack).

        Parameters
        ----------
        theta_rad : ndarray, shape (n_theta,)
            Node angles, uniformly spaced [rad].

        Returns
        -------
        ndarray, shape (n_theta,)
            1 everywhere without a tip crack; the lost load integrates to s times the crack
            arc whatever the mesh.
        """
        c = np.ones(theta_rad.size)
        if self.tip_crack_severity == 0.0 or np.isnan(self.tip_crack_deg):
            return c
        dth = np.rad2deg(2 * np.pi / theta_rad.size)
        d = (np.rad2deg(theta_rad) - self.tip_crack_deg + 180.0) % 360.0 - 180.0
        lo = np.maximum(d - dth / 2, -self.crack_width_deg / 2)
        hi = np.minimum(d + dth / 2, self.crack_width_deg / 2)
        overlap = np.clip(hi - lo, 0.0, None) / dth
        return c - self.tip_crack_severity * np.minimum(overlap, 1.0)


@dataclass(frozen=True)
class Fault:
    """A registered fault.

    Attributes
    ----------
    name : str
    model : str
        "I/O dynamics" or "flexspline" (paper Table I).
    severity_range : tuple of float
        Allowed closed range of severity.
    uses_position : bool
        Whether the fault has a circumferential position.
    apply : callable
        ``apply(params, severity, position_deg) -> ChainParams``.
    signature : str
        Expected signature in the signals (paper Sec. II-C).
    display : str
        Name in reports and figures (e.g. "eccentric WG"); default: the name with spaces.
    """

    name: str
    model: str
    severity_range: tuple[float, float]
    uses_position: bool
    apply: Callable[[ChainParams, float, float], ChainParams]
    signature: str
    display: str = ""

    def __post_init__(self) -> None:
        if not self.display:
            object.__setattr__(self, "display", self.name.replace("_", " "))


#: Mesh on which root-crack severities are defined (the default truss, 3 deg per node).
REFERENCE_N_THETA = 120


def angle_index(position_deg: float, n_theta: int) -> int:
    """Index of the node nearest to a position [deg] on a mesh of ``n_theta`` nodes."""
    return int(round(np.mod(position_deg, 360.0) / 360.0 * n_theta)) % n_theta


def mesh_severity(severity: float, n_theta: int) -> float:
    """Root-crack stiffness loss on a mesh of ``n_theta`` nodes with the same compliance.

    Cutting bars of a cell of width a to (1 − s) adds the compliance s / ((1 − s) k) ∝
    a s / (1 − s). Keeping it equal to that of the reference mesh (a_ref, s) makes the
    crack a physical defect rather than a mesh artefact:
    s' / (1 − s') = s / (1 − s) · a_ref / a.
    """
    if severity <= 0.0:
        return 0.0
    rho = severity / (1.0 - severity) * n_theta / REFERENCE_N_THETA
    return float(rho / (1.0 + rho))


def _damping(p, s, pos):
    g = dataclasses.replace(p.gear, b1_nms=p.gear.b1_nms * (1.0 - s))
    return dataclasses.replace(p, gear=g)


def _stiffness(p, s, pos):
    g = dataclasses.replace(p.gear, k1_nm_per_rad=p.gear.k1_nm_per_rad * (1.0 - s))
    return dataclasses.replace(p, gear=g)


def _eccentric(p, s, pos):
    if s == 0.0:
        return p
    return dataclasses.replace(p, ecc_m=s * p.w0_m, ecc_theta_rad=float(np.deg2rad(pos)))


def _root(p, s, pos):
    if s == 0.0:
        return p
    return dataclasses.replace(p, root_crack_deg=float(np.mod(pos, 360.0)),
                               root_crack_severity=s)


def _tip(p, s, pos):
    if s == 0.0:
        return p
    return dataclasses.replace(p, tip_crack_deg=float(np.mod(pos, 360.0)), tip_crack_severity=s)


def _healthy(p, s, pos):
    return p


#: Stiffness left by complete wear (s = 1), a fraction of nominal [-]: the damaged
#: wave-generator/flexspline interface of the wear study quoted in the issue "A joint in
#: motion" (a quarter of the nominal torsional stiffness; the study itself was not found
#: by search here, docs/PHYSICS.md sec. 8.1).
WEAR_STIFFNESS_LEFT = 0.25

#: Backlash (lost motion at the output) of complete wear (s = 1) [arcmin] [choice]: three
#: times the catalogue's 1 arcmin hysteresis loss of a new size-20, ratio-100 gear
#: (Harmonic Drive CSF/CSG catalogue, "Hysteresis Loss"; value not re-read here). Zhang et
#: al., Machines 13 (2025) 918, report backlash growing in accelerated life tests.
WEAR_BACKLASH_ARCMIN = 3.0


def _wear(p: ChainParams, s: float, pos: float) -> ChainParams:
    """Wear of severity s in [0, 1]: the whole torque-twist curve softened,
    k1, k2 ← (1 − (1 − WEAR_STIFFNESS_LEFT) s) k1, k2 (k2 in proportion, so the catalogue's
    K1/K3 shape is kept), and backlash ← backlash + s · WEAR_BACKLASH_ARCMIN (linear in s
    [choice]); the position is unused."""
    if s == 0.0:
        return p
    f = 1.0 - (1.0 - WEAR_STIFFNESS_LEFT) * s
    g = p.gear
    g = dataclasses.replace(g, k1_nm_per_rad=g.k1_nm_per_rad * f,
                            k2_nm_per_rad3=g.k2_nm_per_rad3 * f,
                            backlash_rad=g.backlash_rad
                            + s * float(np.deg2rad(WEAR_BACKLASH_ARCMIN / 60.0)))
    return dataclasses.replace(p, gear=g)


#: The registry of fault classes, in the schema's class order (healthy first): the one
#: place that lists them, with their display names. Extend it with :func:`register_fault`.
FAULTS: Registry[Fault] = Registry("gear fault", __name__, "FAULTS", (
    (f.name, f)
    for f in (
        Fault("healthy", "-", (0.0, 0.0), False, _healthy, "reference signals"),
        Fault("reduced_damping", "I/O dynamics", (0.0, 0.9), False, _damping,
              "hardly visible in the signals; efficiency rises (Fig. 6a, Table II)"),
        Fault("reduced_stiffness", "I/O dynamics", (0.0, 0.9), False, _stiffness,
              "torque ripple changes slightly, mostly in s0 (Fig. 6b)"),
        Fault("eccentric_wg", "flexspline", (0.0, 0.5), True, _eccentric,
              "offsets of the WG-bending pair and a changed, order-1 modulated shape (Fig. 6c)",
              display="eccentric WG"),
        Fault("root_tooth_crack", "flexspline", (0.0, 0.99), True, _root,
              "amplitudes change in all signals (Fig. 6d)", display="root crack"),
        Fault("tip_tooth_crack", "flexspline", (0.0, 1.0), True, _tip,
              "short deviations when a mesh zone passes the crack (Fig. 6e)",
              display="tip crack"),
    )
))

#: The paper's six classes (Table I and healthy), in the schema's order; registered
#: classes (``wear`` below, a user's) come after them.
PAPER_CLASSES: tuple[str, ...] = ("healthy", "reduced_damping", "reduced_stiffness",
                                  "eccentric_wg", "root_tooth_crack", "tip_tooth_crack")


def fault_classes() -> tuple[str, ...]:
    """Names of the registered classes, healthy first, in registration order."""
    return tuple(FAULTS)


def display_name(name: str) -> str:
    """Name of a class in reports and figures (its :attr:`Fault.display`); an
    unregistered label (e.g. ``"unknown"`` of measured data) is returned with spaces."""
    f = FAULTS.get(name)
    return f.display if f is not None else str(name).replace("_", " ")


def register_fault(fault: Fault) -> Fault:
    """Add a fault class to the registry (:data:`FAULTS`), e.g. from a user's package.

    The simulator, the data-set schema and the learners take their class list from the
    registry, so a registered fault can be given under ``dataset.variants`` at once.

    Parameters
    ----------
    fault : Fault
        Its ``apply`` maps healthy :class:`ChainParams` to faulty ones (parameters, never
        signals); severity 0 must return them unchanged.

    Returns
    -------
    Fault
        ``fault``, so that the call can decorate a module-level definition.

    Raises
    ------
    ValueError
        A name already registered or not a lower-case identifier, or a severity range
        that does not hold 0 (the healthy gear).
    """
    if not fault.name.isidentifier() or fault.name != fault.name.lower():
        raise ValueError(f"fault name must be a lower-case identifier, got {fault.name!r}")
    lo, hi = fault.severity_range
    if not (lo <= 0.0 <= hi):
        raise ValueError(f"fault {fault.name}: severity_range {fault.severity_range} must "
                         "hold 0 (the healthy gear)")
    return FAULTS.add(fault.name, fault)


#: Wear (docs/PHYSICS.md sec. 8.1): registered after the paper's classes, so the schema's
#: class order and :data:`PAPER_CLASSES` stay the paper's.
WEAR = register_fault(Fault(
    "wear", "I/O dynamics", (0.0, 1.0), False, _wear,
    "stiffness loss as reduced_stiffness (torsional mode down to about half at s = 1); the "
    "backlash shows only where the torque changes sign (reversals, zero load)"))


def get_fault(name: str, faults: Mapping[str, Fault] | None = None) -> Fault:
    """The registered fault of that name.

    Parameters
    ----------
    name : str
    faults : mapping, optional
        Where to look: default the registry :data:`FAULTS`; a data set's plan carries the
        faults it uses (:attr:`swgsim.datasets.plan.DatasetPlan.faults`), so that worker processes
        need no registration of their own.

    Raises
    ------
    ValueError
        Naming the allowed faults if ``name`` is unknown.
    """
    faults = FAULTS if faults is None else faults
    try:
        return faults[name]
    except KeyError:
        raise ValueError(f"unknown fault {name!r}; allowed: {sorted(faults)}") from None


def apply_fault(params: ChainParams, name: str, severity: float,
                position_deg: float = 0.0, *,
                faults: Mapping[str, Fault] | None = None) -> ChainParams:
    """Apply a registered fault to healthy parameters.

    Parameters
    ----------
    params : ChainParams
        Healthy gear.
    name : str
        A key of :data:`FAULTS` (or of ``faults``).
    severity : float
        Within the fault's ``severity_range`` (0 reproduces ``params`` exactly).
    position_deg : float
        Circumferential position in the flexspline frame [deg] (faults with a position).
    faults : mapping, optional
        See :func:`get_fault`.

    Raises
    ------
    ValueError
        Unknown fault, or severity outside its range.
    """
    f = get_fault(name, faults)
    lo, hi = f.severity_range
    if not (lo <= severity <= hi) or not np.isfinite(severity):
        raise ValueError(f"severity of {name} must lie in [{lo}, {hi}], got {severity}")
    return f.apply(params, float(severity), float(position_deg))
