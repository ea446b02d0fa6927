"""The prognosis's scores (swgmon/prognosis/scores.py) against values worked by hand
from their definitions (Saxena et al. 2010; PHM08, Saxena et al. 2008)."""

from __future__ import annotations

import numpy as np
import pytest

from swgmon.prognosis.scores import (
    alpha_lambda,
    at_lambda,
    change_response,
    interval_hit,
    phm08_score,
    prognostic_horizon,
    relative_accuracy,
    remaining_fraction,
    share_bucket,
    share_bucket_label,
    share_buckets,
)


def test_a_perfect_predictor_has_ra_one_and_phm08_zero():
    t = np.array([10.0, 5.0, 0.5])
    assert relative_accuracy(t, t) == pytest.approx([1.0, 1.0, 1.0])
    assert phm08_score(t, t) == pytest.approx([0.0, 0.0, 0.0])
    assert alpha_lambda(t, t).all()


def test_relative_accuracy_by_hand():
    """r* 10 h: 12 h and 8 h both give 1 - 2/10 = 0.8; 25 h gives 1 - 15/10 = -0.5."""
    ra = relative_accuracy(np.array([10.0, 10.0, 10.0, 4.0]), np.array([12.0, 8.0, 25.0, np.inf]))
    assert ra[:3] == pytest.approx([0.8, 0.8, -0.5]) and ra[3] == -np.inf


def test_phm08_is_asymmetric_late_costs_more():
    """d = +10 h: e^1 - 1 = 1.71828; d = -13 h: e^1 - 1 as well; d = -10 h: e^(10/13) - 1."""
    s = phm08_score(np.full(3, 20.0), np.array([30.0, 7.0, 10.0]))
    assert s == pytest.approx([np.e - 1, np.e - 1, np.exp(10 / 13) - 1])
    assert phm08_score(np.array([20.0]), np.array([25.0]))[0] > \
        phm08_score(np.array([20.0]), np.array([15.0]))[0]


def test_alpha_lambda_boundary_cases():
    """alpha 0.2 at r* 10 h: 8 and 12 h on the cone's edges count, 7.99 and 12.01 do not."""
    t = np.full(4, 10.0)
    assert alpha_lambda(t, np.array([8.0, 12.0, 7.99, 12.01]), 0.2).tolist() == \
        [True, True, False, False]
    with pytest.raises(ValueError, match=r"^prognosis.scores.alpha must lie in \(0, 1\]"):
        alpha_lambda(t, t, 0.0)


def test_interval_coverage_and_buckets():
    assert interval_hit(np.array([5.0, 5.0, 5.0]), np.array([4.0, 5.0, 6.0]),
                        np.array([np.inf, 5.0, 9.0])).tolist() == [True, True, False]
    f = remaining_fraction(np.array([10.0, 12.0, 15.0, 18.0, 20.0]), np.full(5, 10.0),
                           np.full(5, 20.0))
    assert f == pytest.approx([1.0, 0.8, 0.5, 0.2, 0.0])
    assert share_bucket_label(f, 4).tolist() == ["[0.75, 1]", "[0.75, 1]", "[0.5, 0.75)",
                                                 "[0, 0.25)", "[0, 0.25)"]
    assert share_bucket_label(np.array([1.2, -0.1]), 4).tolist() == ["", ""]
    assert share_bucket_label(f, 2).tolist() == ["[0.5, 1]"] * 3 + ["[0, 0.5)"] * 2
    assert [share_bucket(x, 3) for x in (0.0, 0.34, 0.7, 1.0)] == [0, 1, 2, 2]
    assert share_buckets(4) == ["[0, 0.25)", "[0.25, 0.5)", "[0.5, 0.75)", "[0.75, 1]"]


def test_prognostic_horizon_by_hand():
    """Predictions at 10..18 h of a life failing at 20 h (t_P 10 h: band +-0.2 x 10 = 2 h):
    off by 5, 3, 1, 0.5, 0 h: the band is entered for good at 14 h, PH = 6 h; one more
    prediction off by 3 h at the end: PH 0."""
    h = np.array([10.0, 12.0, 14.0, 16.0, 18.0])
    true = 20.0 - h
    pred = true + np.array([5.0, 3.0, 1.0, 0.5, 0.0])
    assert prognostic_horizon(h, true, pred, 20.0, 0.2) == pytest.approx(6.0)
    assert prognostic_horizon(h, true, true, 20.0) == pytest.approx(10.0)
    pred[-1] += 3.0
    assert prognostic_horizon(h, true, pred, 20.0) == 0.0
    with pytest.raises(ValueError, match="increasing"):
        prognostic_horizon(h[::-1], true, pred, 20.0)


def test_the_prediction_at_half_life():
    """First prediction at 10 h, failure at 20 h: t_0.5 = 15 h, the last at or before it."""
    h = np.array([10.0, 12.0, 14.0, 15.0, 16.0])
    assert at_lambda(h, 20.0, 0.5) == 3 and at_lambda(h[:3], 20.0, 0.5) == 2
    assert at_lambda(h, 20.0, 0.0) == 0 and at_lambda(np.array([]), 20.0) is None
    assert at_lambda(np.array([21.0]), 20.0) is None


def test_the_response_to_a_change_against_the_twin_by_hand():
    """A heavier payload at 10 h (the law: earlier, sign -1). Paired prognoses at 9-13 h:
    equal before the change, the changed life's predicted failure earlier from 12 h on, so
    it moved, 2 h after the change; one later prognosis on the wrong side undoes it; a
    lighter payload (+1) reads the same pairs as not moved; nothing after the change (or
    only beyond 24 h) is not judged."""
    h = np.array([9.0, 10.5, 11.0, 12.0, 13.0])
    twin = np.array([20.0, 20.0, 20.0, 20.0, 20.0])
    changed = np.array([20.0, 20.1, 20.0, 19.0, 18.5])
    assert change_response(h, changed, twin, 10.0, -1.0) == (True, 2.0)
    moved, lag = change_response(h, changed, twin, 10.0, 1.0)
    assert moved is False and np.isnan(lag)
    back = np.array([20.0, 20.1, 20.0, 19.0, 20.5])
    assert change_response(h, back, twin, 10.0, -1.0)[0] is False
    assert change_response(h, changed, twin, 13.0, -1.0)[0] is None
    assert change_response(h, changed, twin, 10.0, -1.0, within_h=1.5)[0] is False
    assert change_response(h + 30.0, changed, twin, 10.0, -1.0)[0] is None
    with pytest.raises(ValueError, match="^prognosis.scores.law_sign must be -1 or 1"):
        change_response(h, changed, twin, 10.0, 0.0)
    with pytest.raises(ValueError, match="^change_response: the changed life's and the twin's"):
        change_response(h, changed[:2], twin, 10.0, -1.0)


def test_a_bad_input_is_one_line():
    with pytest.raises(ValueError, match="^relative_accuracy: true and predicted must have"):
        relative_accuracy(np.ones(2), np.ones(3))
    with pytest.raises(ValueError, match="^relative_accuracy: the true remaining hours"):
        relative_accuracy(np.zeros(2), np.ones(2))
