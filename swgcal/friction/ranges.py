"""Physical ranges of the friction-effect parameters, with their sources.

A calibration fit of a library effect whose characterising parameter falls outside the
range below is not accepted as that effect (:meth:`~swgcal.core.Term.
range_violations`, checked by the selection loop): the residual then holds structure
the effect absorbs without being it (a "velocity lag" of 0.6 s is no frictional memory,
a "thermal drift" of 3.6 s no warm-up). Each range is ``(low, high, source)`` in the
unit of the derived parameter, bounds inclusive, ``±inf`` for an open side. The
ranges are deliberately generous (about an order of magnitude beyond the values the
sources report): they reject what is not the named physics, not what is unusual.

Where a range comes from, in the joint coordinate q (gear output angle):

* **Frictional memory** (``velocity_lag.t_lag``): friction follows a change of the
  sliding velocity with a lag of milliseconds to some tens of milliseconds (Hess &
  Soom 1990, ASME J. Tribology 112: lags of milliseconds in lubricated line contacts;
  reviewed as frictional memory by Armstrong-Hélouvry, Dupont & Canudas de Wit 1994,
  Automatica 30(7); modelled with memory/presliding time scales of the same order by
  Lampaert, Swevers & Al-Bender 2002, IEEE TAC 47(4), and the generalised Maxwell-slip
  model of Al-Bender, Lampaert & Swevers 2005, IEEE TAC 50(11)). Range 0.1 ms - 50 ms.
* **Thermal time constant** (``thermal_drift.t_th``): the lubricant temperature of a
  gear unit follows the heat balance of its housing; warm-up until friction settles
  takes minutes to hours (catalogue efficiency and no-load running torque of strain wave
  gears are stated at a given temperature after warm-up, docs/PHYSICS.md sec. 2; warm-up
  identification on robot joints runs over tens of minutes to hours: Carvalho
  Bittencourt & Gunnarsson 2012, ASME J. Dyn. Syst. Meas. Control 134(5)). Range from
  60 s up.
* **Sensor drift time constant** (``sensor_drift.t_d``): zero drift of strain-gauge
  torque sensing follows the temperature of the gauged part and of the amplifier
  (minutes); creep of strain-gauge transducers is specified over 30 min (OIML R 60,
  load cells). Range from 60 s up.
* **Stribeck velocity** (``stribeck.v_st``): 1e-5 to 0.1 m/s at the sliding contact
  (Armstrong-Hélouvry et al. 1994, their table of friction parameters), mapped to the
  output by the flank sliding of paper eq. (6), q̇ = v sin α_tooth / R, with α_tooth =
  20° and the catalogue pitch radii R = 17.8-31.8 mm of sizes 14-25 (docs/PHYSICS.md
  sec. 1-2): 1.1e-4 to 1.9 rad/s.
* **Presliding displacement** (``presliding.q_c``): micrometres at the contact
  (Armstrong-Hélouvry et al. 1994; Al-Bender et al. 2005), 1e-5 to 1e-3 rad at the
  output by the same mapping, plus the torsional wind-up of the flexspline under the
  friction torque (catalogue K1 = 4.7e3-3.1e4 N m/rad, about 1e-4 rad per N m) and the
  hysteresis loss / lost motion of a few arcmin (1 arcmin = 2.9e-4 rad) of strain wave
  gears in the Harmonic Drive catalogues. Range 1e-6 to 2e-2 rad (about 70 arcmin,
  room for compliance of the joint beyond the gear).
* **Ripple period** (``position_ripple`` / ``friction_ripple``): a ripple of the gear
  lies between the tooth-mesh order of the wave generator (two contact zones sweeping
  the circular spline's z_c = 2(N + 1) teeth: order 4(N + 1)) and twice per output
  revolution (order 2 / N: output bearing, a gravity-model error; once per revolution
  is the paper law's b3 sin(q + θ_b)); kinematic error sits at orders 1, 2, 4 (Tuttle &
  Seering 1996, IEEE T-RA 12(3); docs/PHYSICS.md sec. 1). With the gear ratio N known
  the range is on the wave-generator order k = 2π / (period · N); without it, on the
  period, for the catalogue ratios N = 30-160 (Harmonic Drive CSG/SHG series).
* **Signs**: static friction exceeds the Coulomb level (Stribeck curve falling with
  speed, Armstrong-Hélouvry et al. 1994), so ``stribeck.f_s`` >= 0; the presliding
  part of the Coulomb level is a part of it, ``presliding.f_d`` >= 0; the load-dependent
  loss per unit load ``load_coulomb.mu`` is 1 − η of the gear, 0.2-0.35 for the
  catalogue efficiencies of 67-77 % at rated torque (docs/PHYSICS.md sec. 2), range
  0-1. Amplitudes whose bound needs quantities the term does not see (the Coulomb
  level, the rigid-body model) are declared open, with that reason.
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
        4 (N + 1) (module docstring).

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
        N) with N = 160, up to half an output revolution, π (module docstring).
    """
    n = GEAR_RATIO_CATALOGUE[1]
    return (2.0 * math.pi / (4.0 * (n + 1.0) * n), math.pi,
            _RIPPLE_SRC + f", catalogue ratios N = {GEAR_RATIO_CATALOGUE[0]:g}-{n:g}")
