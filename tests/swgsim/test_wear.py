"""Wear and backlash in the dynamic model (swgsim/gear/dynamics.py ``backlash_rad``,
swgsim/gear/faults.py ``wear``, docs/PHYSICS.md sec. 8.1): the dead zone of the torque-twist
curve against its closed form, the torsional mode's √-law in the stiffness, the ring-down
of a worn gear against the linearised mode, the backlash-free arithmetic unchanged, and
the fault's registration and severity mapping.

Tolerances are set near the accuracy reached, measured with the tests' own settings; each
states it (python -m pytest tests/swgsim/test_wear.py).
"""

import dataclasses

import numpy as np
import pytest
from physics_reference import ring_down

from swgsim.gear import dynamics as dy
from swgsim.gear import modes
from swgsim.gear import profile as pf
from swgsim.gear import profile_dynamics as pd
from swgsim.gear.faults import (
    FAULTS,
    PAPER_CLASSES,
    WEAR_BACKLASH_ARCMIN,
    ChainParams,
    apply_fault,
    fault_classes,
)

ARCMIN = np.pi / (180.0 * 60.0)


def worn(s: float = 1.0, **overrides) -> dy.GearParams:
    """The nominal gear (with ``overrides``) worn to severity s."""
    return apply_fault(ChainParams(dy.rt1_size20(**overrides)), "wear", s).gear


def twist(p: dy.GearParams, states: np.ndarray) -> np.ndarray:
    """Δφ_k of eq. (3) without kinematic error from states of shape (5, n_t) [rad]."""
    return p.tan_alpha_in * (states[0] - states[2]) + states[2] / np.tan(p.alpha_tooth_rad)


def closed_form_twist(p: dy.GearParams, t_load: float) -> float:
    """Static twist at a load torque: c T_stiff(d) = T_L with T_stiff = k1 d + k2 d³ on the
    dead-zoned twist d, so Δφ_k = sgn(T_L) (g + d), g = c b / 2 [rad]."""
    r = np.roots([p.k2_nm_per_rad3, 0.0, p.k1_nm_per_rad, -abs(t_load) / p.c_out])
    d = float(r[np.argmin(np.abs(r.imag))].real)
    return float(np.sign(t_load)) * (p.backlash_twist_rad / 2 + d)


def test_quasi_static_torque_twist_curve_has_the_closed_form_dead_zone():
    """Standstill, load stepped -20 -> 20 N m in eight levels, each held 0.15 s (five time
    constants of the speed loop's integrator, which sets the input angle), worn gear
    (s = 1: k1, k2 a quarter, 3 arcmin backlash) beside the same gear without backlash.
    Coulomb friction and b3 are off (viscous b1 only), so friction vanishes at rest and
    the settled twist obeys c T_stiff(d) = T_L exactly.

    Reached: settled twists within 3.1e-5 of the gap (c b = 2.37e-3 rad) of the closed
    form, tolerance 1e-4; the two curves differ by sgn(T) g (the dead zone of width c b at
    zero torque) within 1.0e-6 of the gap, tolerance 1e-5; the slope between levels on
    each side equals the closed-form secant stiffness c (k1 + k2 (d1² + d1 d2 + d2²))
    within 4.5e-5, tolerance 2e-4.
    """
    quiet = {"ke_amp_rad": (0.0, 0.0, 0.0), "b3_nm": 0.0, "b0_nm": 0.0, "mu": 0.0,
             "b2_nms3": 0.0}
    p = worn(1.0, **quiet)
    q = dataclasses.replace(p, backlash_rad=0.0)
    assert p.backlash_rad == pytest.approx(3.0 * ARCMIN, rel=1e-12)
    hold, fs = 0.15, 10e3
    loads = (-20.0, -10.0, -3.0, -1.0, 1.0, 3.0, 10.0, 20.0)
    steps = tuple(((i + 1) * hold, t) for i, t in enumerate(loads[1:]))
    prof = pf.Profile(pf.SpeedProfile(0.0, (pf.Hold(hold * len(loads)),)),
                      pf.LoadSteps(loads[0], steps))
    res = pd.simulate_profile([p, q], prof, 0.0, sample_rate_hz=fs, substeps=1)
    ends = [int(round((i + 1) * hold * fs)) - 1 for i in range(len(loads))]
    tw_p = twist(p, res.states[:, 0])[ends]
    tw_q = twist(q, res.states[:, 1])[ends]
    gap = p.backlash_twist_rad
    np.testing.assert_allclose(tw_p, [closed_form_twist(p, t) for t in loads], rtol=0,
                               atol=1e-4 * gap)
    np.testing.assert_allclose(tw_q, [closed_form_twist(q, t) for t in loads], rtol=0,
                               atol=1e-4 * gap)
    np.testing.assert_allclose(tw_p - tw_q, np.sign(loads) * gap / 2, rtol=0, atol=1e-5 * gap)
    d = np.abs(tw_p) - gap / 2  # contact twist on the loaded flank
    for i in (0, 1, 2, 4, 5, 6):  # neighbouring levels on one side of zero
        slope = (loads[i + 1] - loads[i]) / (tw_p[i + 1] - tw_p[i])
        d1, d2 = d[i], d[i + 1]
        secant = p.c_out * (p.k1_nm_per_rad + p.k2_nm_per_rad3 * (d1 * d1 + d1 * d2 + d2 * d2))
        assert slope == pytest.approx(secant, rel=2e-4)


def tangent_stiffness(p: dy.GearParams, t_out: float, n_in: float = 2000.0) -> float:
    """k1 + 3 k2 d² at the steady twist d of ``steady_state`` [N m/rad]."""
    b = dy.ke_batch(dy.Batch.of([p]))
    x = dy.steady_state(b, np.array([n_in * dy.RPM]), np.array([t_out]), np.array([0.0]))
    d = abs(float(twist(p, x[:, 0]))) - p.backlash_twist_rad / 2
    return p.k1_nm_per_rad + 3 * p.k2_nm_per_rad3 * d * d


def natural_and_damped(p: dy.GearParams, t_out: float) -> tuple[float, float]:
    """|λ| and Im λ of the torsional mode of the linearisation at 2000 rpm [1/s]."""
    lam = modes.linear_eigenvalues(p, 2000.0, t_out)
    top = lam[np.argmax(lam.imag)]
    assert top.imag / (2 * np.pi) == pytest.approx(modes.torsional_mode(p, 2000.0, t_out)[0])
    return float(abs(top)), float(top.imag)


@pytest.mark.parametrize("t_out", [7.0, 39.0, 70.0])
def test_torsional_mode_follows_the_square_root_of_the_stiffness(t_out):
    """Bench (J_out 8.8e-3 kg m²), 2000 rpm, against the nominal gear. The natural
    frequency |λ| scales with √ of the tangent stiffness k1 + 3 k2 d² at the operating
    twist d: reached 1.1e-5 (k1 a quarter) and 1.0e-4 (wear: k1 and k2 a quarter),
    tolerance 3e-4. A quarter of k1 alone stiffens the gear under load (the larger twist
    raises the cubic term: tangent ratio 1.06-1.15, mode +3 to +7 %); wear leaves
    0.63-0.70 of the tangent stiffness, mode -17 to -21 %. The damped frequency of
    ``torsional_mode`` keeps the decay rate σ (output friction, unchanged), so
    ω_d² = ω_n² − σ² departs from the law: reached 0.09 % and 0.82 % (wear, 7 N m),
    tolerance 1 %. A linear spring (k2 = 0) with k1 a quarter: natural-frequency ratio
    0.49953 (the input's inertia and speed loop take part), tolerance 1e-3 of ½; the
    damped ratio is 0.468.
    """
    p = dy.rt1_size20()
    wn0, wd0 = natural_and_damped(p, t_out)
    for q in (dataclasses.replace(p, k1_nm_per_rad=p.k1_nm_per_rad / 4), worn(1.0)):
        wn, wd = natural_and_damped(q, t_out)
        law = np.sqrt(tangent_stiffness(q, t_out) / tangent_stiffness(p, t_out))
        assert wn / wn0 == pytest.approx(law, rel=3e-4)
        assert wd / wd0 == pytest.approx(law, rel=0.01)
    lin = dataclasses.replace(p, k2_nm_per_rad3=0.0)
    lin4 = dataclasses.replace(lin, k1_nm_per_rad=lin.k1_nm_per_rad / 4)
    ratio = natural_and_damped(lin4, t_out)[0] / natural_and_damped(lin, t_out)[0]
    assert ratio == pytest.approx(0.5, rel=1e-3)


@pytest.mark.parametrize("j_out, dec", [(8.8e-3, 1), (0.69, 5)])
def test_ring_down_of_a_worn_gear_matches_the_torsional_mode(j_out, dec):
    """Worn gear (s = 1, 3 arcmin backlash), load step 7 -> 39 N m at 2000 rpm: the
    torque stays one-signed, so the flanks never part and the linearisation holds. As in
    tests/swgsim/test_profile.py, the delivered torque from 2 to 8 decay times after the step is
    decomposed into six damped exponentials; its largest oscillatory one is the mode of
    ``torsional_mode`` at 39 N m (the twist stays above 6.6 g). Bench (287.8 Hz, 3.94 ms):
    frequency reached -0.38 %, decay time +1.2 %; robot link (39.8 Hz, 27.7 ms, 20 kHz
    decimated to 4 kHz): +0.07 %, -0.35 %. Tolerances 2 % (frequency), 3 % (decay time).
    """
    p = worn(1.0, j_out_kgm2=j_out, ke_amp_rad=(0.0, 0.0, 0.0), b3_nm=0.0)
    top, (f_hz, tau), res = ring_down(p, dec)
    tw = twist(p, res.states[:, 0])
    assert np.all(tw > p.backlash_twist_rad / 2)  # in contact on one flank throughout
    assert top.imag / (2 * np.pi) == pytest.approx(f_hz, rel=0.02)
    assert -1.0 / top.real == pytest.approx(tau, rel=0.03)


def test_backlash_zero_runs_the_backlash_free_arithmetic():
    """Bit-identical states and torques: a backlash-free batch, and the backlash-free rows
    of a batch with a worn variant (the dead zone of width 0 subtracts an exact zero).
    (Against the model before backlash existed, git HEAD, checked bit-identical outside
    the tests: docs/PHYSICS.md sec. 8.1.)"""
    p = dy.rt1_size20()
    q = dataclasses.replace(p, k1_nm_per_rad=0.7 * p.k1_nm_per_rad)
    alone = dy.simulate([p, q], [2000.0, 4000.0], [7.0, 39.0], [0.3, 1.0], window_s=0.01,
                        settle_s=0.01)
    mixed = dy.simulate([p, q, worn(1.0)], [2000.0, 4000.0, 2000.0], [7.0, 39.0, 7.0],
                        [0.3, 1.0, 0.0], window_s=0.01, settle_s=0.01)
    assert "half_gap" not in dy.ke_batch(dy.Batch.of([p, q])).fields
    np.testing.assert_array_equal(mixed.states[:, :2], alone.states)
    np.testing.assert_array_equal(mixed.t_out[:2], alone.t_out)
    with pytest.raises(ValueError, match="backlash_rad"):
        dy.simulate([dataclasses.replace(p, backlash_rad=-1e-4)], 2000.0, 7.0)


def test_steady_state_shifts_the_twist_by_half_the_gap():
    """At a load the start twist is the backlash-free one plus g = c b / 2 in the load's
    direction (exact up to rounding)."""
    p = worn(1.0)
    q = dataclasses.replace(p, backlash_rad=0.0)
    b = dy.ke_batch(dy.Batch.of([p, q]))
    x = dy.steady_state(b, np.full(2, 2000 * dy.RPM), np.full(2, 39.0), np.zeros(2))
    shift = twist(p, x[:, 0]) - twist(q, x[:, 1])
    assert shift == pytest.approx(p.backlash_twist_rad / 2, rel=1e-9)
    np.testing.assert_array_equal(x[4, 0], x[4, 1])  # the same torque


@pytest.mark.parametrize("s", [0.0, 0.5, 1.0])
def test_wear_is_registered_beside_the_paper_classes(s):
    """Registered after the paper's six classes, not among them; k1 and k2 scaled by
    1 − 0.75 s (a quarter at s = 1), backlash s · 3 arcmin; s = 0 returns the gear."""
    assert "wear" in FAULTS and fault_classes()[: len(PAPER_CLASSES)] == PAPER_CLASSES
    assert "wear" not in PAPER_CLASSES and len(PAPER_CLASSES) == 6
    assert FAULTS["wear"].severity_range == (0.0, 1.0) and not FAULTS["wear"].uses_position
    h = ChainParams(dy.rt1_size20())
    g = apply_fault(h, "wear", s).gear
    assert g.k1_nm_per_rad == pytest.approx((1 - 0.75 * s) * h.gear.k1_nm_per_rad, rel=1e-15)
    assert g.k2_nm_per_rad3 == pytest.approx((1 - 0.75 * s) * h.gear.k2_nm_per_rad3, rel=1e-15)
    assert g.backlash_rad == pytest.approx(s * WEAR_BACKLASH_ARCMIN * ARCMIN, rel=1e-12)
    assert WEAR_BACKLASH_ARCMIN == 3.0
    if s == 0.0:
        assert apply_fault(h, "wear", s) == h
    with pytest.raises(ValueError, match="severity"):
        apply_fault(h, "wear", 1.1)
