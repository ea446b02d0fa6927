"""The gear's normal behaviour (learn/monitor/normal.py) against closed forms: features
that follow the load laws it assumes are carried to a load commissioning did not see,
and beyond commissioning's range the bridges' spread widens by the correction's own
size."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from learn.monitor.normal import BLOCK, EFFICIENCY, Conditions, NormalBehaviour, NormalConfig

LOADS = (7.0, 39.0, 70.0)  # N m, the duty points' loads at one speed
A_LOSS, B_LOSS = 1.2, 0.08  # loss torque A + B τ [N m], [-]


def _features(torque: np.ndarray, rng: np.random.Generator, noise: float = 1e-3
              ) -> np.ndarray:
    """Windows whose features follow the laws of the module docstring exactly (plus
    noise): offsets a line in τ, squared amplitudes and residual power quadratics in τ,
    the loss torque A + B τ."""
    n = len(torque)
    f = np.zeros((n, EFFICIENCY + 1))
    for c in range(5):
        j0 = c * BLOCK
        f[:, j0] = 0.1 * (c + 1) + 0.004 * torque
        for h in range(1, BLOCK - 1):
            f[:, j0 + h] = np.sqrt(1.0 + 0.05 * h * torque + 0.002 * torque ** 2)
        f[:, j0 + BLOCK - 1] = 0.5 * np.log10(0.01 + 1e-4 * torque ** 2)
    f[:, :EFFICIENCY] *= 1.0 + noise * rng.standard_normal((n, EFFICIENCY))
    f[:, EFFICIENCY] = torque / (torque + A_LOSS + B_LOSS * torque)
    f[:, EFFICIENCY] += 1e-4 * rng.standard_normal(n)
    return f


@pytest.fixture(scope="module")
def commissioned():
    rng = np.random.default_rng(0)
    commanded = np.repeat(LOADS, 60)
    acting = commanded + 1e-3 * rng.standard_normal(len(commanded))
    points = np.stack([np.full(len(commanded), 2000.0), commanded], axis=1)
    nb = NormalBehaviour.fit(_features(acting, rng), points, Conditions(acting))
    return nb, rng


def _windows(nb, rng, load_factor: float, n: int = 30):
    commanded = np.repeat(LOADS, n)
    acting = commanded * load_factor
    points = np.stack([np.full(len(commanded), 2000.0), commanded], axis=1)
    return _features(acting, rng), points, Conditions(acting)


def test_load_curves_carry_exact_laws_to_an_unseen_load(commissioned):
    """A 10 % heavier load at every point (77 N m: beyond every load commissioning saw):
    with the laws exact, the corrected features stay where commissioning's were
    (|z| of the noise), although uncorrected they move by many spreads."""
    nb, rng = commissioned
    f, p, cond = _windows(nb, rng, 1.1)
    trusted = dataclasses.replace(nb, config=NormalConfig(extrapolation_uncertainty=0.0))
    z = trusted.z(f, p, cond)
    raw = trusted.z(f, p, Conditions(p[:, 1]))  # as if the load had not changed
    assert np.percentile(np.abs(z), 99) < 4.0
    assert np.median(np.abs(raw)) > 20.0


def test_spread_widens_beyond_commissioning_only(commissioned):
    """Inside commissioning's range the z-scores are those of a trusted correction, bit
    for bit; beyond it the spread is sqrt(σ² + (κ u)²), u the correction from the
    range's edge to the window's load."""
    nb, rng = commissioned
    kappa = 0.7
    wide = dataclasses.replace(nb, config=NormalConfig(extrapolation_uncertainty=kappa))
    trusted = dataclasses.replace(nb, config=NormalConfig(extrapolation_uncertainty=0.0))
    f, p, cond = _windows(nb, rng, 1.0)
    inside = Conditions(np.clip(cond.torque_nm, *nb.torque_range[nb.index(p)].T))
    np.testing.assert_array_equal(wide.z(f, p, inside), trusted.z(f, p, inside))
    f, p, cond = _windows(nb, rng, 1.1)
    z, spread = wide.z_and_spread(f, p, cond)
    i = nb.index(p)
    edge = Conditions(np.where(cond.torque_nm > nb.torque_range[i, 1],
                               nb.torque_range[i, 1], nb.torque_range[i, 0]))
    ones = np.ones(len(f))
    u = nb._corrected(f, i, cond, ones) - nb._corrected(f, i, edge, ones)
    bridges = slice(0, EFFICIENCY)
    np.testing.assert_allclose(spread[:, bridges],
                               np.sqrt(nb.std[i, bridges] ** 2 + (kappa * u[:, bridges]) ** 2),
                               rtol=1e-12)
    np.testing.assert_array_equal(spread[:, EFFICIENCY], nb.std[i, EFFICIENCY])  # a law
    np.testing.assert_allclose(z * spread, trusted.z(f, p, cond) * nb.std[i], rtol=1e-9,
                               atol=1e-12)
    assert (np.abs(u[:, bridges]) > 10 * nb.std[i, bridges]).mean() > 0.5  # not small


def test_extrapolation_uncertainty_out_of_range_refused():
    with pytest.raises(ValueError, match="normal.extrapolation_uncertainty"):
        NormalConfig(extrapolation_uncertainty=-0.1).check()
