"""Extension point: a calibration effect defined outside the packages.

The test defines a new friction effect in one class (its physics: the form and its
parameter, a :class:`swgsim.gear.terms.Term`; its fit: probes and physical range, a
:class:`swgcal.terms.FitTerm`) and registers it with one call into the one registry,
:func:`swgsim.gear.friction.register_effect`, editing nothing inside ``swgsim`` or
``swgcal``. The simulator then knows and plants it
(:func:`swgcal.friction.synthetic.synthetic_recording` goes through
:func:`swgsim.gear.friction.parse_effects`), and the unchanged calibration loop offers it as a
candidate among the whole library, accepts it on held-out evidence and recovers its
parameter.
"""

from __future__ import annotations

import numpy as np
import pytest

from swgcal import build_problem, calibrate
from swgcal.friction import friction_problem, library
from swgcal.friction.synthetic import synthetic_recording
from swgcal.terms import FitTerm
from swgsim.gear import friction
from swgsim.gear.friction import FRICTION_LIBRARY, make_effect, parse_effects, register_effect
from swgsim.gear.terms import Param, Term


class QuadraticDrag(FitTerm):
    """Quadratic (turbulent-churning) drag of the lubricant: τ = c_q q̇ |q̇| [N m]
    (splash losses grow with the square of the speed; an illustration, not a library
    effect)."""

    # the physics (what the simulator evaluates)
    kind = "quadratic_drag"
    linear = (Param("c_q", "N m s²/rad²", "quadratic drag coefficient"),)
    description = "drag growing with the square of the speed (lubricant churning)"
    source = "illustration for tests/swgcal/test_calib_effect_registry.py"

    def columns(self, sig, theta):
        return (sig.dq_rad_s * np.abs(sig.dq_rad_s))[:, None]

    # the fit (what the calibration adds)
    signature = "residual odd in q̇, growing like q̇|q̇| between the viscous and cubic terms"
    probes = ("velocity",)
    ranges = {"c_q": (0.0, np.inf, "drag opposes motion")}


@pytest.fixture
def quadratic_drag():
    register_effect(QuadraticDrag)
    try:
        yield QuadraticDrag
    finally:
        del FRICTION_LIBRARY[QuadraticDrag.kind]


def test_registering_twice_or_a_non_term_is_refused(quadratic_drag):
    with pytest.raises(ValueError, match="already registered"):
        register_effect(QuadraticDrag)
    with pytest.raises(TypeError, match="must subclass"):
        register_effect(dict)
    with pytest.raises(ValueError, match="already registered"):  # the simulator's side
        friction.effects.register_effect(QuadraticDrag)


def test_one_call_registers_the_physics_in_the_simulator(quadratic_drag):
    assert friction.FRICTION_LIBRARY["quadratic_drag"] is QuadraticDrag
    fx = friction.FrictionEffects([{"kind": "quadratic_drag", "params": {"c_q": 2.0}}],
                                  v_s=1e-3)
    dq = np.array([-0.5, 0.0, 0.5])
    np.testing.assert_allclose(fx(np.zeros(3), np.zeros(3), dq, np.zeros(3)),
                               [-0.5, 0.0, 0.5])


def test_an_effect_registered_from_outside_is_planted_found_and_recovered(quadratic_drag):
    c_q = 2.0  # [N m s²/rad²]: 1.9 N m at the top speed (0.97 rad/s), noise s.d. 0.022 N m
    rec, truth = synthetic_recording([{"kind": "quadratic_drag", "params": {"c_q": c_q}}],
                                     rng=np.random.default_rng(5))
    problem = build_problem(rec, v_s=truth.v_s)
    assert "quadratic_drag" in problem.library
    res = calibrate(problem)
    assert res.added == ["quadratic_drag"], [c.name for c in res.iterations[0].candidates[:4]]
    est = res.final.estimates_of("quadratic_drag")["c_q"]
    assert est.identifiable, est.flag
    assert abs(est.value - c_q) <= 1.96 * est.std, (est.value, est.std)
    assert est.value == pytest.approx(c_q, rel=0.1)
    assert not res.unexplained, res.residual_signature


def test_one_registration_serves_the_simulator_and_the_calibration(quadratic_drag):
    """One class registered once: the simulator's parse path makes it, the calibration's
    lookup offers it, and its kind is refused to any other class."""
    [(term, coef, _)] = parse_effects([{"kind": "quadratic_drag", "params": {"c_q": 2.0}}])
    assert type(term) is QuadraticDrag and coef.tolist() == [2.0]
    rec, truth = synthetic_recording([], duration_s=10, rng=np.random.default_rng(0))
    assert friction_problem(rec, v_s=truth.v_s).library["quadratic_drag"] is QuadraticDrag
    other = type("OtherDrag", (FitTerm,), {"kind": "quadratic_drag"})
    with pytest.raises(ValueError, match=r"'quadratic_drag' is already registered "
                                         r"\(QuadraticDrag; only a subclass"):
        register_effect(other)
    assert FRICTION_LIBRARY["quadratic_drag"] is QuadraticDrag


def test_the_built_ins_are_one_class_per_kind():
    """The simulator makes, and the calibration offers, the same class: the form with its
    fit (swgcal.friction.library registered it in place of swgsim's form)."""
    rec, truth = synthetic_recording([], duration_s=10, rng=np.random.default_rng(0))
    offered = friction_problem(rec, v_s=truth.v_s).library
    assert set(offered) == set(FRICTION_LIBRARY)
    for kind, cls in FRICTION_LIBRARY.items():
        assert offered[kind] is cls is getattr(library, cls.__name__), kind
        assert issubclass(cls, getattr(friction.effects, cls.__name__, Term)), kind
        assert type(make_effect(kind)) is cls, kind
    with pytest.raises(ValueError, match="'stribeck' is already registered"):
        register_effect(friction.effects.Stribeck)  # the form back in place of its fit


def test_a_form_alone_is_simulated_and_a_fit_added_later_takes_its_place():
    class Churn(Term):
        kind = "churn_test"
        linear = (Param("c_k", "N m s³/rad³", "made-up cubic drag"),)

        def columns(self, sig, theta):
            return (sig.dq_rad_s ** 3)[:, None]

    class FittedChurn(Churn, FitTerm):
        probes = ("velocity",)
        ranges = {"c_k": (0.0, np.inf, "drag opposes motion")}

    rec, truth = synthetic_recording([], duration_s=10, rng=np.random.default_rng(0))
    register_effect(Churn)
    try:
        assert type(make_effect("churn_test")) is Churn
        assert "churn_test" not in friction_problem(rec, v_s=truth.v_s).library
        with pytest.raises(ValueError, match=r"unknown friction effects \['churn_test'\]; "
                                             r"library \(the effects with a fit\): \['asym"):
            friction_problem(rec, v_s=truth.v_s, candidates=["churn_test"])
        register_effect(FittedChurn)
        assert type(make_effect("churn_test")) is FittedChurn
        assert friction_problem(rec, v_s=truth.v_s).library["churn_test"] is FittedChurn
        with pytest.raises(ValueError, match="already registered"):
            register_effect(Churn)
    finally:
        del FRICTION_LIBRARY["churn_test"]
    with pytest.raises(KeyError, match=r"^\"unknown friction effect 'churn_test'; the library "
                                       r"has \['asymmetric_coulomb', [^\n]*\]\"$"):
        make_effect("churn_test")
