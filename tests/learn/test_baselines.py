"""The baselines (swgmon.evaluation.baselines): a normal-behaviour regression with a MEWMA
chart and a PCA chart, commissioned on healthy windows of several duty points through a
warm-up; on fresh healthy windows they stay low, on a shift of a few features they rise,
and a missing temperature reading is taken as commissioning's mean."""

from __future__ import annotations

import numpy as np
import pytest

from swgmon.evaluation.baselines import BaselineConfig, PCAChart, RegressionMEWMA


def _windows(rng, n: int, shift: float = 0.0):
    """Eight features of three duty points through daily warm-ups: each feature a duty
    point's level plus a quadratic in the temperature, plus noise; ``shift`` sds added to
    three features."""
    duty = rng.integers(3, size=n)
    temp = 20.0 + 20.0 * (1.0 - np.exp(-(np.arange(n) % 600) / 120.0))
    level = np.array([[0.0] * 8, [1.0] * 8, [2.0] * 8])
    a, b = np.linspace(-0.05, 0.05, 8), np.linspace(0.0, 1e-3, 8)
    dt = temp - 20.0
    x = level[duty] + a * dt[:, None] + b * dt[:, None] ** 2 + 0.1 * rng.normal(size=(n, 8))
    x[:, :3] += 0.1 * shift
    return x, duty, temp


@pytest.mark.parametrize(("chart", "shift"), [(RegressionMEWMA, 2.0), (PCAChart, 10.0)])
def test_a_chart_stays_low_on_healthy_windows_and_rises_on_a_shift(chart, shift):
    """The regression sees a shift of 2 noise sds; the PCA, which knows no temperature,
    one of 10 (about the warm-up's own spread of a feature)."""
    rng = np.random.default_rng(0)
    c = chart(BaselineConfig()).fit(*_windows(rng, 3000))
    healthy = c.statistic(*_windows(rng, 2000))
    shifted = c.statistic(*_windows(rng, 2000, shift=shift))
    assert np.median(shifted) > 3 * np.median(healthy)
    assert np.quantile(shifted, 0.5) > np.quantile(healthy, 0.99)


def test_a_missing_reading_is_read_as_commissionings_mean():
    rng = np.random.default_rng(1)
    x, duty, temp = _windows(rng, 3000)
    c = RegressionMEWMA().fit(x, duty, temp)
    y, d, t = _windows(rng, 500)
    t[:] = np.nan
    s = c.statistic(y, d, t)
    assert np.all(np.isfinite(s))
    with pytest.raises(ValueError, match="must agree"):
        c.statistic(y, d[:-1], t)
