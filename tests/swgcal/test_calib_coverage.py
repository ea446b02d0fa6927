"""Honest uncertainties: the 95 % intervals the calibration reports (estimate ± 1.96 s.e.,
s.e. from the Jacobian inflated by the residual's autocorrelation time τ_int,
:func:`swgcal.core.fit_terms`) cover the planted value in at least 85 % of the seeds.

Each seed draws a new trajectory and new AR(1) noise (ρ = 0.3, 1 % of the torque range:
τ_int ≈ 1.8, so uncorrected intervals would be √1.8 ≈ 1.35x too narrow) in the default
60 s recording; the loop runs with the planted effect as its only candidate, and the final
model's reported intervals are checked, one parameter at a time.

Measured with :func:`covered` over more seeds (60 seeds, 60 s): stribeck f_s 0.97, v_st
0.95, empirical s.d. / mean reported s.e. 1.00 and 1.05. In 30 s recordings (fewer slow
passes) f_s covered only 0.88 of 100 seeds (the other parameters 0.92-0.98), yet with the
trajectory held and only the noise redrawn its empirical s.d. was 0.95-1.13 times the
reported s.e.: the s.e. is right for the data at hand, and the shortfall comes from a few
short trajectories on which the nonlinear fit is biased by about one s.e.
"""

from __future__ import annotations

import numpy as np
import pytest

from swgcal import SelectionConfig, select_effects
from swgcal.friction import friction_problem
from swgcal.friction.synthetic import PLANTED, synthetic_recording

N_SEEDS = 12
EFFECTS = ("stribeck", "asymmetric_coulomb", "presliding", "velocity_lag")


def covered(kind: str, seed: int) -> dict[str, bool]:
    """Whether each checked parameter's reported 95 % interval holds the planted value."""
    rec, truth = synthetic_recording([{"kind": kind, "params": PLANTED[kind]["params"]}],
                                     rng=np.random.default_rng(1000 + seed))
    res = select_effects(friction_problem(rec, v_s=truth.v_s),
                         SelectionConfig(candidates=[kind]))
    assert res.added == [kind], (kind, seed, res.added)
    est = res.final.estimates_of(kind)
    return {name: abs(est[name].value - v) <= 1.96 * est[name].std
            for name, v in PLANTED[kind]["check"].items()}


@pytest.mark.parametrize("kind", EFFECTS)
def test_reported_intervals_cover_the_planted_value(kind):
    hits = [covered(kind, seed) for seed in range(N_SEEDS)]
    for name in hits[0]:
        rate = float(np.mean([h[name] for h in hits]))
        assert rate >= 0.85, (kind, name, rate)  # nominal 0.95: at most 1 miss in 12
