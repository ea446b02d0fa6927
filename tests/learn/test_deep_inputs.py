"""learn.inputs.signals: shapes, reference normalisation, auxiliary scalars."""

from __future__ import annotations

import numpy as np
import pytest
from data_sets import make_toy_dataset, write_toy_dataset

from learn.inputs.signals import (
    AUX,
    ResidualSettings,
    build_input,
    normalise_signals,
    window_meta,
)
from swgsim.datasets.schema import load
from swgsim.gear.faults import PAPER_CLASSES


@pytest.fixture(scope="module")
def toy():
    return make_toy_dataset(n_variants=3, n_time=128)


@pytest.mark.parametrize(("kind", "n_ch"), [("raw", 5), ("diff", 3)])
def test_signal_input_shapes(toy, kind, n_ch):
    inp = build_input(toy, kind)
    n = int((~toy["reference"].values).sum())
    assert inp.X.shape == (n, n_ch + len(AUX), 128)
    assert inp.X.dtype == np.float32
    assert inp.n_aux == len(AUX)
    assert len(inp.y) == len(inp.meta) == n
    # scalar channels are constant along time
    assert np.all(inp.X[:, -inp.n_aux:, :] == inp.X[:, -inp.n_aux:, :1])
    # rows follow the data set, without reference windows
    assert not toy["reference"].values[inp.meta["sample"]].any()
    assert np.all(np.diff(inp.meta["sample"].to_numpy()) > 0)


def test_feature_inputs_and_filter(toy):
    from learn.inputs.features import paper_orders

    with pytest.raises(ValueError, match="features.order_step=0.25 needs windows of at least 4"):
        build_input(toy, "sel3", disturbed=True)  # 32 ms hold 1.07 revolutions at 2000 rpm
    sel3 = build_input(toy, "sel3", disturbed=True,
                       feature_kwargs={"orders": paper_orders(8.0, 1.0)})
    assert sel3.X.ndim == 2 and sel3.n_aux == 0
    assert sel3.meta["disturbed"].all()
    raw = build_input(toy, "raw", aux=(), disturbed=True)
    assert raw.X.shape[1] == 5 and raw.n_aux == 0
    np.testing.assert_array_equal(raw.meta["sample"], sel3.meta["sample"])


def test_reference_maps_to_zero_mean_unit_rms(toy):
    meta, refs = window_meta(toy)
    x = normalise_signals(toy, np.unique(refs), np.unique(refs))  # references themselves
    np.testing.assert_allclose(x.mean(axis=2), 0.0, atol=1e-5)
    np.testing.assert_allclose(np.sqrt((x ** 2).mean(axis=2)), 1.0, atol=1e-5)


def test_normalisation_removes_gear_gain_and_offset(toy):
    """A gear whose bridges have other gains and offsets gives the same input."""
    ds2 = toy.copy(deep=True)
    gear3 = ds2["gear"].values == 3
    sig = ds2["strain_signal"].values
    sig[gear3] = 1.7 * sig[gear3] + 0.3  # reference windows of gear 3 included
    a = build_input(toy, "raw").X
    b = build_input(ds2, "raw").X
    np.testing.assert_allclose(a, b, atol=1e-4)


def test_unknown_kind_and_missing_reference(toy):
    with pytest.raises(ValueError, match="unknown input"):
        build_input(toy, "spectrogram")
    with pytest.raises(ValueError, match="auxiliary"):
        build_input(toy, "raw", aux=("speed",))
    no_ref = toy.isel(sample=np.flatnonzero(~toy["reference"].values))
    with pytest.raises(ValueError, match="reference"):
        build_input(no_ref, "raw")


def test_synchronous_residual_cancels_gear_signature_and_keeps_fault():
    """A window = reference shifted in WG angle + other disturbance: residual ~ 0; a
    4th-harmonic fault term survives at its amplitude relative to the reference RMS."""
    from learn.inputs.signals import align_phase, harmonic_coefficients, synthesise

    fs, n_t, f_in, order = 10_000.0, 1200, 2000 / 60, 1.01
    t = np.arange(n_t) / fs
    rng = np.random.default_rng(0)

    def gear(psi0, fault=0.0, dist=0.0):
        psi = 2 * np.pi * order * f_in * t + psi0
        x = np.stack([0.12 * np.cos(2 * psi + 0.1 * c) + 0.004 * np.cos(4 * psi + c)
                      for c in range(5)])
        x += fault * np.cos(4 * psi + 0.3)
        for o in (0.25, 0.5, 1.0):  # eq. (10) sub-harmonics
            x += dist * rng.uniform(0.5, 1, (5, 1)) * np.sin(2 * np.pi * o * f_in * t + 1.0)
        return x

    kw = {"psi_order": order, "n_harmonics": 8}
    ref = harmonic_coefficients(gear(0.0, dist=0.01)[None], t, np.array([f_in]), **kw)
    win = harmonic_coefficients(np.stack([gear(1.234, dist=0.01), gear(2.5, 0.002, 0.01)]),
                                t, np.full(2, f_in), **kw)
    cr = np.repeat(ref, 2, axis=0)
    d = align_phase(win, cr)
    h = np.arange(1, 9)
    res = win[:, :, 1:] - cr[:, :, 1:] * np.exp(1j * h * d[:, None, None])
    assert np.abs(res[0]).max() < 1e-6  # healthy: nothing left
    np.testing.assert_allclose(np.abs(res[1, :, 3]), 0.002, rtol=1e-2)  # h = 4 fault term
    wave = synthesise(np.concatenate([np.zeros((2, 5, 1)), res], axis=2), n_points=64)
    assert wave.shape == (2, 5, 64) and np.abs(wave[0]).max() < 1e-5


def test_residual_inputs_shapes(toy):
    kw = {"residual": ResidualSettings(ratio=1e9, n_harmonics=6, n_points=32)}
    raw = build_input(toy, "raw_res", **kw)
    diff = build_input(toy, "diff_res", **kw)
    spec = build_input(toy, "res_spec", **kw)
    n = int((~toy["reference"].values).sum())
    assert raw.X.shape == (n, 5 + 2, 32) and diff.X.shape == (n, 3 + 2, 32)
    assert spec.X.shape == (n, 5 * 5 + 2) and spec.n_aux == 0
    assert np.isfinite(raw.X).all() and np.isfinite(spec.X).all()
    with pytest.raises(ValueError, match="Nyquist"):
        build_input(toy, "raw_res", residual=ResidualSettings(n_harmonics=200))


def test_basis_pseudo_inverse_where_lapacks_gesdd_fails():
    """A well-conditioned basis for which NumPy's SVD (gesdd) reports no convergence (a
    life window's mean speed on robot_joint): the pseudo-inverse still comes, exact."""
    from learn.inputs.signals import ResidualSettings, _basis_pinv

    rs = ResidualSettings()
    orders = tuple((1.01 * np.arange(1, rs.n_harmonics + 1)).tolist()
                   + list(rs.nuisance_orders))
    f0, n_t = 66.66625151195727, 1200
    pinv = _basis_pinv(f0, 0.0, 1e-4, n_t, orders)
    ang = 2 * np.pi * f0 * (1e-4 * np.arange(n_t))[:, None] * np.asarray(orders)[None, :]
    basis = np.concatenate([np.ones((n_t, 1)), np.cos(ang), np.sin(ang)], axis=1)
    np.testing.assert_allclose(pinv @ basis, np.eye(basis.shape[1]), atol=1e-12)


@pytest.mark.parametrize("aux", [AUX, ("eta_rel",), ()])
def test_raw_and_diff_are_the_documented_forms(toy, aux):
    """``raw``: each bridge (s - m_ref) / r_ref with the mean and RMS about it of the
    window's reference (same gear, operating point, disturbed flag), then the scalars as
    channels constant in time; ``diff``: (s0, Δs13, Δs24) of those normalised channels,
    then the same scalars
    (docs/learners_transfer.md, "Reference normalisation and the synchronous residual")."""
    from learn.inputs.signals import efficiency_features

    meta, refs = window_meta(toy, disturbed=True)
    samples = meta["sample"].to_numpy()
    sig = toy["strain_signal"].values.astype(np.float64)
    ref = sig[refs]  # (n, 5, T)
    m = ref.mean(axis=2, keepdims=True)
    r = np.sqrt(((ref - m) ** 2).mean(axis=2, keepdims=True))
    x = (sig[samples] - m) / r  # (n, 5, T)
    eta = toy["efficiency"].values
    rel = eta[samples] / eta[refs]
    eff = np.stack([np.abs(1 - rel) ** 0.25, rel - 1], axis=1)[:, [AUX.index(a) for a in aux]]
    np.testing.assert_allclose(efficiency_features(toy, samples, refs)[:, [
        AUX.index(a) for a in aux]], eff)
    raw = build_input(toy, "raw", aux=aux, disturbed=True)
    diff = build_input(toy, "diff", aux=aux, disturbed=True)
    n, n_t = len(samples), toy.sizes["time"]
    assert raw.X.shape == (n, 5 + len(aux), n_t) and diff.X.shape == (n, 3 + len(aux), n_t)
    assert raw.X.dtype == diff.X.dtype == np.float32
    assert raw.n_aux == diff.n_aux == len(aux)
    # float32 of signals of unit RMS: 1e-5 absolute
    np.testing.assert_allclose(raw.X[:, :5], x, atol=1e-5)
    want = np.stack([x[:, 0], x[:, 1] - x[:, 3], x[:, 2] - x[:, 4]], axis=1)
    np.testing.assert_allclose(diff.X[:, :3], want, atol=1e-5)
    for inp in (raw, diff):
        c = inp.X.shape[1] - len(aux)
        np.testing.assert_allclose(inp.X[:, c:], np.broadcast_to(
            eff[:, :, None], (n, len(aux), n_t)), rtol=1e-6, atol=1e-7)
    # a healthy window of any gear sits near its reference's scale: zero mean, RMS ~ 1
    healthy = (meta["fault"] == "healthy").to_numpy()
    rms = np.sqrt((raw.X[healthy, 1:5] ** 2).mean(axis=2))
    assert 0.8 < np.median(rms) < 1.25  # toy: noise and disturbance on unit ripple


def test_toy_dataset_is_schema_v1(tmp_path):
    path = write_toy_dataset(tmp_path / "toy", n_variants=3, n_time=64)
    ds = load(path)
    assert ds["strain_signal"].shape == (3 * 2 * 4 * (6 * 3 + 1), 5, 64)
    assert int(ds["reference"].sum()) == 3 * 2 * 4
    assert set(np.unique(ds["fault"].values)) == set(PAPER_CLASSES)
