"""The benchmark's statistics (swgmon.evaluation.statistics): exact binomial
intervals against their closed forms, pooled and worst-life rates, the conditional delay,
a life-clustered bootstrap that covers at its level, and thresholds matched to a
false-alarm rate."""

from __future__ import annotations

import numpy as np
import pytest

from swgmon.evaluation import statistics as st


def test_an_alarm_share_has_the_exact_clopper_pearson_interval():
    none = st.alarm_share([False] * 20, level=0.95)
    every = st.alarm_share([True] * 20, level=0.95)
    assert none.value == 0 and none.low == 0 and none.n == 20
    assert none.high == pytest.approx(1 - 0.025 ** (1 / 20), rel=1e-9)  # 0.168
    assert every.low == pytest.approx(0.025 ** (1 / 20), rel=1e-9) and every.high == 1
    one = st.alarm_share([True] + [False] * 19, level=0.95)
    assert one.low < 0.05 < one.high and np.isnan(st.alarm_share([], level=0.95).value)


def test_a_rate_per_1000_h_is_pooled_and_the_worst_life_stands_beside_it():
    pooled, worst, k = st.alarm_rate([0, 0, 9, 1], [200.0, 200.0, 200.0, 400.0])
    assert pooled == pytest.approx(1000 * 10 / 1000) and worst == pytest.approx(45.0)
    assert k == 9
    with pytest.raises(ValueError, match="hours > 0"):
        st.alarm_rate([1], [0.0])


def test_the_conditional_delay_takes_the_lives_detected_after_onset_alone():
    d = st.conditional_delay([0.5, 1.5, np.nan, -2.0, 1.0], seed=1, level=0.95)
    assert d.value == pytest.approx(1.0) and d.n == 3 and d.low <= 1.0 <= d.high
    assert st.conditional_delay([np.nan, -1.0], level=0.95).n == 0


def test_a_life_clustered_interval_covers_the_truth_at_about_its_level():
    """Lives of 30 prognoses each, covered with the life's own probability (mean 0.9, a
    life-to-life spread the windows cannot average out): the interval over 40 lives holds
    0.9 in 93-99 % of 200 repetitions (binomial bounds around 0.95 at 200 draws)."""
    rng = np.random.default_rng(0)
    held = 0
    for rep in range(200):
        p = np.clip(rng.normal(0.9, 0.05, 40), 0, 1)
        covered = rng.binomial(30, p)
        iv = st.life_bootstrap(covered, np.full(40, 30.0), n_boot=400, seed=rep, level=0.95)
        held += iv.low <= 0.9 <= iv.high
    assert 0.90 <= held / 200 <= 0.99, held


def test_a_threshold_matched_to_a_rate_gives_that_rate_on_the_lives_it_was_set_on():
    rng = np.random.default_rng(3)
    lives = [np.convolve(rng.normal(size=3000), np.ones(20) / 20, "same") for _ in range(10)]
    hours = np.full(10, 50.0)  # a window a minute
    thr = st.matched_threshold(lives, hours, per_1000h=20.0)  # 10 alarms in 500 h
    count = sum(st.upcrossings(s, thr) for s in lives)
    assert count <= 10
    below = np.unique(np.concatenate(lives))
    lower = below[below < thr][-1]
    assert sum(st.upcrossings(s, lower) for s in lives) > 10  # the lowest such
    assert st.upcrossings(np.array([2.0, 0.0, 2.0, np.nan, 2.0]), 1.0) == 3


def test_the_prognosis_coverage_per_bucket_carries_an_interval_over_lives():
    """Two lives in one bucket, one always covered, one never: PICP 0.5 over 20
    prognoses, but from two lives its bootstrap interval spans [0, 1] (a life's
    prognoses are not independent)."""
    import pandas as pd

    from swgmon.evaluation.prognosis_report import PrognosisTargets, bucket_table

    rows = []
    for seed, hit in ((0, True), (1, False)):
        for k in range(10):
            true = 50.0 - k
            rows.append({"dataset": "bench", "held_out_gear": 3, "seed": seed,
                         "fault": "eccentric_wg", "method": "growth", "valid": True,
                         "hour": 10.0 + k, "alarm_h": 10.0, "failure_h": 60.0,
                         "true_remaining_h": true, "remaining_h": true,
                         "remaining_h_q05": true - 1 if hit else true + 1,
                         "remaining_h_q95": true + 1 if hit else true + 2})
    b = bucket_table(pd.DataFrame(rows), PrognosisTargets()).iloc[0]
    assert b.n == 10 * 2 and b.lives == 2 and b.picp == 0.5
    assert b.picp_low == 0.0 and b.picp_high == 1.0
