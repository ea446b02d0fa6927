"""Joint friction as an input of the simulation: the paper's law on the joint and the
effects beyond it.

The dynamics add an extra friction torque τ(t, q, q̇, q̈) [N m] in the joint coordinate
(gear output angle) to the paper-law friction of eq. (5)-(6). Its forms are model terms
(:class:`swgsim.gear.terms.Term`) that a calibration against measured joint friction fits
(:mod:`swgcal.friction`, which adds the fit: bounds, starts, probes, physical ranges)
and whose accepted list a data set takes as the option ``friction_effects``
(:func:`friction_effects_from_config`). A new effect, its form and its fit, enters
both with one :func:`register_effect` into the one registry, :data:`FRICTION_LIBRARY`
(:mod:`.effects`).

Modules: :mod:`.signals` (what friction terms see, the paper law), :mod:`.effects` (the
effect library: Stribeck, presliding, velocity lag, load-dependent Coulomb, drifts, ...),
:mod:`.ripples` (ripples over the joint angle in wave-generator orders),
:mod:`.simulation` (an effect list as the extra torque of the dynamics).
"""

from swgsim.gear.friction.effects import FRICTION_LIBRARY, make_effect, register_effect
from swgsim.gear.friction.signals import FrictionSignals, PaperLaw, Scales
from swgsim.gear.friction.simulation import (
    FrictionEffects,
    FrictionEffectsConfig,
    friction_effects_from_config,
    parse_effects,
)

__all__ = ["FRICTION_LIBRARY", "FrictionEffects", "FrictionEffectsConfig", "FrictionSignals",
           "PaperLaw", "Scales", "friction_effects_from_config", "make_effect", "parse_effects",
           "register_effect"]
