"""The fit of each built-in friction effect, registered in place of its form.

The forms are the simulator's (:mod:`swgsim.gear.friction.effects`,
:mod:`swgsim.gear.friction.ripples`, the paper law of :mod:`swgsim.gear.friction.signals`);
each class here subclasses one of them and :class:`~swgcal.terms.FitTerm`, adding its
residual signature, probes, physical ranges (:mod:`.ranges`), how often a model may hold
it, and its nonlinear parameters' bounds and starts. Importing this module registers each
with :func:`swgsim.gear.friction.register_effect` in place of its form. The signatures'
table: docs/PHYSICS.md sec. 5.3; the registry: ARCHITECTURE.md, "To add a calibration effect".
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from swgsim.gear.friction import effects as fx
from swgsim.gear.friction import ripples as rp
from swgsim.gear.friction import signals as fsig
from swgsim.gear.friction.signals import FrictionSignals

from ..periodogram import periodogram_peaks
from ..terms import FitTerm
from .ranges import (
    DISSIPATIVE_NM,
    LOAD_FRICTION_PER_LOAD,
    OPEN_CONFIGURATION_NM,
    OPEN_DIRECTION_NM,
    OPEN_INERTIA_KGM2,
    OPEN_MEASURED,
    OPEN_SENSOR_NM,
    OPEN_THERMAL_NM,
    PRESLIDING_DISPLACEMENT_RAD,
    PRESLIDING_PART_NM,
    RIPPLE_AMPLITUDE_NM,
    SENSOR_DRIFT_TIME_S,
    STRIBECK_EXCESS_NM,
    STRIBECK_VELOCITY_RAD_S,
    TEMPERATURE_FRICTION_PER_K,
    TEMPERATURE_VISCOUS_PER_K,
    THERMAL_TIME_S,
    TRANSPORT_DELAY_S,
    VELOCITY_LAG_S,
    ripple_order_range,
    ripple_period_range,
)

__all__ = [
    "PaperLaw",
    "AsymmetricCoulomb",
    "Stribeck",
    "Presliding",
    "PositionRipple",
    "FrictionRipple",
    "LoadCoulomb",
    "GravityResidual",
    "Inertia",
    "ThermalDrift",
    "SensorDrift",
    "VelocityLag",
    "TransportDelay",
    "TemperatureFriction",
    "MeasuredVariable",
]


class PaperLaw(fsig.PaperLaw, FitTerm):
    """The paper-law base model (:class:`swgsim.gear.friction.PaperLaw`), linear; its
    dissipative coefficients b0, b1 of their physical sign (a fit outside makes the run
    unphysical, :func:`swgcal.core.physical_check`)."""

    ranges = {"b0": DISSIPATIVE_NM, "b1": DISSIPATIVE_NM}


class AsymmetricCoulomb(fx.AsymmetricCoulomb, FitTerm):
    __doc__ = fx.AsymmetricCoulomb.__doc__
    signature = ("residual offset of the same sign in both directions of motion while "
                 "moving, vanishing at rest")
    probes = ("direction_offset",)
    ranges = {"delta_c": OPEN_DIRECTION_NM}


class Stribeck(fx.Stribeck, FitTerm):
    __doc__ = fx.Stribeck.__doc__
    signature = ("residual odd in the direction of motion, a bump at low ``|q̇|`` that decays "
                 "within v_st")
    probes = ("velocity",)
    ranges = {"f_s": STRIBECK_EXCESS_NM, "v_st": STRIBECK_VELOCITY_RAD_S}

    def bounds(self, sig: FrictionSignals) -> list[tuple[float, float]]:
        s = sig.scales
        return [(max(2.0 * sig.v_s, 1e-3 * s.v_ref), s.v_ref)]

    def starts(self, sig, residual, idx):
        return [np.array([f * sig.scales.v_ref]) for f in (0.03, 0.1, 0.3)]


class Presliding(fx.Presliding, FitTerm):
    __doc__ = fx.Presliding.__doc__
    signature = ("after each reversal of motion the residual shows a transient over the "
                 "travel since the reversal (hysteresis loop in torque vs position near "
                 "reversals), odd in direction")
    probes = ("travel_since_reversal", "velocity")
    ranges = {"f_d": PRESLIDING_PART_NM, "q_c": PRESLIDING_DISPLACEMENT_RAD}

    def bounds(self, sig):
        return [(1e-5 * sig.scales.q_span, 0.1 * sig.scales.q_span)]

    def starts(self, sig, residual, idx):
        return [np.array([f * sig.scales.q_span]) for f in (1e-4, 1e-3, 1e-2)]


class _RippleFit:
    """The fit of a ripple (:class:`swgsim.gear.friction.ripples.RippleTerm`): period bounds
    from the sampling of q, starts from the residual's periodogram, the physical range on
    the wave-generator order when the gear ratio is known (on the period otherwise)."""

    repeatable = 6
    harmonics: tuple[int, ...]
    gear_ratio: float | None
    odd: bool

    def __init__(self, name: str | None = None, harmonics: Sequence[int] = (1,),
                 gear_ratio: float | None = None) -> None:
        super().__init__(name, harmonics=harmonics, gear_ratio=gear_ratio)  # type: ignore[call-arg]
        rng = ({"order": ripple_order_range(self.gear_ratio)} if self.gear_ratio
               else {"period": ripple_period_range()})
        self.ranges = {"amplitude": RIPPLE_AMPLITUDE_NM, **rng}

    def bounds(self, sig):
        s = sig.scales
        lo = max(4.0 * s.dq_med, s.q_span / 2000.0)
        return [(lo * self.harmonics[-1], s.q_span / 2.0 * self.harmonics[0])]

    def starts(self, sig, residual, idx):
        lo, hi = self.bounds(sig)[0]
        h0 = self.harmonics[0]
        r = residual[idx] * (np.sign(sig.v_eff[idx]) if self.odd else 1.0)
        peaks = periodogram_peaks(sig.q_rad[idx], r, lo / h0, hi / h0, n_peaks=3)
        out = [np.array([p * h0]) for p, _ in peaks]
        return out or [np.array([np.sqrt(lo * hi)])]


class PositionRipple(_RippleFit, rp.PositionRipple, FitTerm):
    __doc__ = rp.PositionRipple.__doc__
    signature = "spectral peak of the residual over q, same sign in both directions"
    probes = ("position_periodic",)


class FrictionRipple(_RippleFit, rp.FrictionRipple, FitTerm):
    __doc__ = rp.FrictionRipple.__doc__
    signature = "spectral peak over q of the residual times sgn(q̇) (flips with direction)"
    probes = ("position_periodic_odd",)


class LoadCoulomb(fx.LoadCoulomb, FitTerm):
    __doc__ = fx.LoadCoulomb.__doc__
    signature = ("residual odd in direction with a slow trend over q: the two branches "
                 "(q̇ > 0, q̇ < 0) spread or close along q")
    probes = ("position_odd",)
    ranges = {"rms": OPEN_CONFIGURATION_NM, "mu": LOAD_FRICTION_PER_LOAD}

    @property
    def repeatable(self):  # type: ignore[override]
        return 1 if self.use_load else 3


class GravityResidual(fx.GravityResidual, FitTerm):
    __doc__ = fx.GravityResidual.__doc__
    signature = ("residual even in direction that varies slowly with q (both branches "
                 "shift together)")
    probes = ("position",)
    ranges = {"rms": OPEN_CONFIGURATION_NM}
    repeatable = 3


class Inertia(fx.Inertia, FitTerm):
    __doc__ = fx.Inertia.__doc__
    signature = ("residual correlates with q̈; for oscillating motion it draws loops "
                 "against q̇ whose sense flips with the sign of q̈")
    probes = ("acceleration",)
    ranges = {"j_a": OPEN_INERTIA_KGM2}


class _TimeConstantFit:
    """Bounds and starts of an effect whose one nonlinear parameter is a time constant:
    from 2 % to 10 times the recording's span, started at 0.1, 0.3 and 1 span."""

    def bounds(self, sig):
        return [(0.02 * sig.scales.t_span, 10.0 * sig.scales.t_span)]

    def starts(self, sig, residual, idx):
        return [np.array([f * sig.scales.t_span]) for f in (0.1, 0.3, 1.0)]


class ThermalDrift(_TimeConstantFit, fx.ThermalDrift, FitTerm):
    __doc__ = fx.ThermalDrift.__doc__
    signature = "residual odd in direction whose magnitude changes monotonically with time"
    probes = ("time_odd",)
    ranges = {"d": OPEN_THERMAL_NM, "t_th": THERMAL_TIME_S}


class SensorDrift(_TimeConstantFit, fx.SensorDrift, FitTerm):
    __doc__ = fx.SensorDrift.__doc__
    signature = "residual even in direction that creeps monotonically with time"
    probes = ("time",)
    ranges = {"c": OPEN_SENSOR_NM, "t_d": SENSOR_DRIFT_TIME_S}


class VelocityLag(fx.VelocityLag, FitTerm):
    __doc__ = fx.VelocityLag.__doc__
    signature = ("hysteresis of the residual against q̇: higher friction when "
                 "decelerating than when accelerating at the same speed")
    probes = ("velocity_hysteresis",)
    ranges = {"t_lag": VELOCITY_LAG_S}

    def bounds(self, sig):
        s = sig.scales
        return [(0.5 * s.dt_med, max(min(0.05 * s.t_span, 5.0), 2.0 * s.dt_med))]

    def starts(self, sig, residual, idx):
        lo, hi = self.bounds(sig)[0]
        return [np.array([np.clip(f * sig.scales.dt_med, lo, hi)]) for f in (2, 10, 50)]


class TransportDelay(fx.TransportDelay, FitTerm):
    __doc__ = fx.TransportDelay.__doc__
    signature = ("a ripple over q whose phase turns with the speed: its even and odd parts "
                 "(over the direction of motion) trade places as |q̇| changes")
    probes = ("position_periodic", "position_periodic_odd")
    ranges = {"delay": TRANSPORT_DELAY_S}
    acts_on = ("position_ripple", "friction_ripple")

    def bounds(self, sig):
        lo, hi = TRANSPORT_DELAY_S[:2]
        return [(2.5 * lo, 2.5 * hi)]  # wider than the range: a fit beyond it is seen

    def starts(self, sig, residual, idx):
        return [np.array([d]) for d in (-2e-3, 1e-3, 4e-3)]


class TemperatureFriction(fx.TemperatureFriction, FitTerm):
    __doc__ = fx.TemperatureFriction.__doc__
    signature = ("residual odd in the direction of motion that follows the measured "
                 "temperature (a step between a cold and a warm session)")
    probes = ("temperature_odd",)
    ranges = {"k_v": TEMPERATURE_VISCOUS_PER_K, "k_ref": TEMPERATURE_FRICTION_PER_K}


class MeasuredVariable(fx.MeasuredVariable, FitTerm):
    __doc__ = fx.MeasuredVariable.__doc__
    signature = "residual following a measured variable of the recording the library lacks"
    probes = ()
    ranges = {"size": OPEN_MEASURED}


for _fitted in (AsymmetricCoulomb, Stribeck, Presliding, PositionRipple, FrictionRipple,
                LoadCoulomb, GravityResidual, Inertia, ThermalDrift, SensorDrift, VelocityLag,
                TransportDelay, TemperatureFriction, MeasuredVariable):
    fx.register_effect(_fitted)  # in place of its form
