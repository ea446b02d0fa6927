"""Physical ranges of the friction-effect parameters, with their sources.

A calibration fit of a library effect whose characterising parameter falls outside its
range is not accepted as that effect (:meth:`~swgcal.core.Term.range_violations`, checked
by the selection loop). Each range is ``(low, high, source)`` in the unit of the derived
parameter, bounds inclusive, ``±inf`` for an open side, deliberately generous (about an
order of magnitude beyond what the sources report); the ripples' depend on the gear ratio
(:func:`ripple_order_range`, :func:`ripple_period_range`). Where each range comes from,
with full references: docs/calibration.md, "Physical ranges of the friction effects".
"""

from __future__ import annotations

import math

__all__ = [
    "INF",
    "VELOCITY_LAG_S",
    "THERMAL_TIME_S",
    "SENSOR_DRIFT_TIME_S",
    "STRIBECK_VELOCITY_RAD_S",
    "STRIBECK_EXCESS_NM",
    "PRESLIDING_DISPLACEMENT_RAD",
    "PRESLIDING_PART_NM",
    "LOAD_FRICTION_PER_LOAD",
    "OPEN_DIRECTION_NM",
    "OPEN_CONFIGURATION_NM",
    "OPEN_INERTIA_KGM2",
    "OPEN_THERMAL_NM",
    "OPEN_SENSOR_NM",
    "RIPPLE_AMPLITUDE_NM",
    "TRANSPORT_DELAY_S",
    "DISSIPATIVE_NM",
    "OPEN_MEASURED",
    "TEMPERATURE_VISCOUS_PER_K",
    "TEMPERATURE_FRICTION_PER_K",
    "GEAR_RATIO_CATALOGUE",
    "ripple_period_range",
    "ripple_order_range",
]

INF = math.inf

_SIN_ALPHA = math.sin(math.radians(20.0))  # tooth pressure angle, docs/PHYSICS.md sec. 1
_R_MIN, _R_MAX = 17.78e-3, 31.75e-3  # catalogue pitch radii, sizes 14-25 [m]

VELOCITY_LAG_S = (1e-4, 0.05, "frictional memory lasts ms to tens of ms: Hess & Soom 1990; "
                  "Armstrong-Hélouvry et al. 1994; Al-Bender, Lampaert & Swevers 2005")
THERMAL_TIME_S = (60.0, INF, "gear warm-up takes minutes to hours: catalogue data after "
                  "warm-up; Carvalho Bittencourt & Gunnarsson 2012")
SENSOR_DRIFT_TIME_S = (60.0, INF, "gauge zero drift follows part/amplifier temperature "
                       "(minutes); transducer creep specified over 30 min, OIML R 60")
STRIBECK_VELOCITY_RAD_S = (
    1e-5 * _SIN_ALPHA / _R_MAX, 0.1 * _SIN_ALPHA / _R_MIN,
    "contact Stribeck velocity 1e-5..0.1 m/s (Armstrong-Hélouvry et al. 1994) at the "
    "output via paper eq. (6), pitch radius 17.8-31.8 mm")
STRIBECK_EXCESS_NM = (0.0, INF, "static friction exceeds the Coulomb level "
                      "(Armstrong-Hélouvry et al. 1994)")
PRESLIDING_DISPLACEMENT_RAD = (1e-6, 2e-2, "contact presliding of micrometres (Armstrong-"
                               "Hélouvry et al. 1994; Al-Bender et al. 2005) plus wind-up and "
                               "lost motion of a few arcmin (catalogue)")
PRESLIDING_PART_NM = (0.0, INF, "the presliding part of the Coulomb level is positive "
                      "(Dahl 1968)")
LOAD_FRICTION_PER_LOAD = (0.0, 1.0, "load-dependent loss 1 - η, catalogue efficiency "
                          "67-77 % (docs/PHYSICS.md sec. 2)")
OPEN_DIRECTION_NM = (-INF, INF, "either direction may carry the higher Coulomb level "
                     "(Armstrong-Hélouvry et al. 1994); bounded by the Coulomb level, "
                     "which the term does not see")
OPEN_CONFIGURATION_NM = (0.0, INF, "configuration-dependent torque (paper eq. (5) b3 term, "
                         "rigid-body compensation); its bound needs the rigid-body model, "
                         "which the data do not carry")
OPEN_INERTIA_KGM2 = (-INF, INF, "the rigid-body model may under- or over-compensate the "
                     "inertia (reflected rotor inertia N² J_in, docs/PHYSICS.md sec. 2)")
OPEN_THERMAL_NM = (-INF, INF, "friction falls as the joint warms (d > 0) or rises as a "
                   "warm joint cools (d < 0); docs/PHYSICS.md sec. 5")
OPEN_SENSOR_NM = (-INF, INF, "zero drift of either sign (docs/PHYSICS.md sec. 5)")
RIPPLE_AMPLITUDE_NM = (0.0, INF, "ripple amplitude, non-negative by construction (Tuttle & "
                       "Seering 1996); its bound needs the Coulomb level")
DISSIPATIVE_NM = (0.0, INF, "Coulomb and viscous friction dissipate: b0, b1 >= 0 "
                  "(Armstrong-Hélouvry et al. 1994); b2 (the cubic) may bend the curve "
                  "either way and b3 is the gravity model's, both open")
OPEN_MEASURED = (0.0, INF, "a variable the library has no physics for: its size is open "
                 "(docs/calibration.md, issue 86); the report names it for a person to judge")
TRANSPORT_DELAY_S = (-0.02, 0.02, "a servo drive's dead time: a current loop, filters and "
                     "a bus cycle of 0.1-4 ms each (EtherCAT, CANopen cycles of 1 ms; "
                     "Franklin, Powell & Workman, sec. 3.2); either signal may be the later")
TEMPERATURE_VISCOUS_PER_K = (-INF, 0.0, "the grease's viscosity falls as it warms (Vogel 1921, "
                             "swgsim.gear.thermal): the viscous slope cannot rise with T")
TEMPERATURE_FRICTION_PER_K = (-INF, 0.0, "a strain wave gear's running torque falls as it "
                              "warms (catalogue no-load running torque against temperature, "
                              "docs/PHYSICS.md sec. 2)")
GEAR_RATIO_CATALOGUE = (30.0, 160.0)
"""Reduction ratios of the Harmonic Drive CSG/SHG series (30, 50, 80, 100, 120, 160)."""

_RIPPLE_SRC = ("between the tooth-mesh order 4(N + 1) of the wave generator and twice per "
               "output revolution (Tuttle & Seering 1996; docs/PHYSICS.md sec. 1)")


def ripple_order_range(gear_ratio: float) -> tuple[float, float, str]:
    """Physical range of a ripple's wave-generator order k = 2π / (period · N).

    Parameters
    ----------
    gear_ratio : float
        Reduction ratio N [-], > 1.

    Returns
    -------
    (low, high, source)
        Orders [-]: from twice per output revolution (2 / N) to the tooth-mesh order
        4 (N + 1) (docs/calibration.md, "Physical ranges of the friction effects").

    Raises
    ------
    ValueError
        ``gear_ratio`` not above 1.
    """
    if not gear_ratio > 1:
        raise ValueError(f"gear_ratio must be > 1, got {gear_ratio}")
    n = float(gear_ratio)
    return 2.0 / n, 4.0 * (n + 1.0), _RIPPLE_SRC


def ripple_period_range() -> tuple[float, float, str]:
    """Physical range of a ripple's period over the output angle when N is unknown.

    Returns
    -------
    (low, high, source)
        Periods [rad]: the tooth-mesh pitch of the finest catalogue gear, 2π / (4 (N + 1)
        N) with N = 160, up to half an output revolution, π
        (docs/calibration.md, "Physical ranges of the friction effects").
    """
    n = GEAR_RATIO_CATALOGUE[1]
    return (2.0 * math.pi / (4.0 * (n + 1.0) * n), math.pi,
            _RIPPLE_SRC + f", catalogue ratios N = {GEAR_RATIO_CATALOGUE[0]:g}-{n:g}")
