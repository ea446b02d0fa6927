"""Features of paper Table III, eq. (7)-(9) (learn.inputs.features)."""

from __future__ import annotations

import numpy as np
import pytest
from data_sets import NEAR_ZERO_BRIDGES, built_once

from learn.inputs.features import (
    META_COLUMNS,
    extract_features,
    feature_names,
    iter_features,
    order_spectrum,
    paper_orders,
    reference_index,
)
from learn.inputs.features import _reference_index_frame as reference_index_merge
from swgcli import dataset_preset
from swgsim.datasets import generate as gen
from swgsim.datasets import schema as dsio
from swgsim.datasets.schema import PER_SAMPLE, make_dataset

FS = 10_000.0
N_TIME = 1200  # 4 revolutions at 2000 rpm (DFT order 0.25)


def _pair(reference_signal, sample_signal, eta=(0.8, 0.8), n_rpm=2000.0):
    """Data set of one reference window and one sample window (gear 1, one op point)."""
    meta = {k: np.zeros(2) for k in PER_SAMPLE}
    meta.update(gear=np.array([1, 1]), fault=np.array(["healthy", "eccentric_wg"]),
                variant=np.array([-1, 0]), n_in_rpm=np.full(2, n_rpm),
                t_out_nm=np.full(2, 39.0), disturbed=np.zeros(2, bool),
                reference=np.array([True, False]), efficiency=np.array(eta),
                n_in_mean_rpm=np.full(2, n_rpm), t_out_mean_nm=np.full(2, 39.0))
    t = np.arange(N_TIME) / FS
    return make_dataset(np.stack([reference_signal, sample_signal]), t, meta)


def _healthy(n_rpm=2000.0):
    t = np.arange(N_TIME) / FS
    theta = 2 * np.pi * n_rpm / 60 * t
    s = np.stack([1.0 + 0.1 * np.cos(2 * theta)]
                 + [0.5 + np.cos(2 * (theta - k * np.pi / 2)) for k in range(4)])
    return s, theta


@pytest.mark.parametrize("selection, n_features", [(1, 11), (2, 11 + 5 * 32), (3, 2 * 32 + 1)])
def test_shapes_and_names(synthetic_ds, selection, n_features):
    X, names, meta = extract_features(synthetic_ds, f"selection{selection}")
    n_ref = int(synthetic_ds["reference"].sum())
    assert X.shape == (synthetic_ds.sizes["sample"] - n_ref, n_features)
    assert X.dtype == np.float64 and np.isfinite(X).all()
    assert names == feature_names(selection) and len(set(names)) == n_features
    assert list(meta.columns) == ["sample", *META_COLUMNS]
    assert len(meta) == len(X) and not synthetic_ds["reference"].values[meta["sample"]].any()
    if selection == 1:
        assert names[0] == "m_rel_s0" and names[5] == "var_rel_s0" and names[10] == "eta_rel"
    if selection == 3:
        assert names[0] == "dft_rel_ds13_o0.25" and names[32] == "dft_rel_ds24_o0.25"
        assert names[-1] == "eta2_rel"



def test_the_selections_made_together_are_those_made_one_by_one(synthetic_ds):
    together = list(iter_features(synthetic_ds, [3, "selection1", 2]))
    for sel, feats in zip((3, 1, 2), together, strict=True):
        X, names, meta = extract_features(synthetic_ds, sel)
        np.testing.assert_array_equal(feats.X, X)
        assert feats.names == names and feats.meta.equals(meta)

def test_paper_orders():
    o = paper_orders()
    assert o.size == 32 and o[0] == 0.25 and o[-1] == 8.0
    assert paper_orders(4.0, 0.5).tolist() == [0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0]


@pytest.mark.parametrize("selection", [1, 2, 3])
def test_window_identical_to_reference_gives_one(selection):
    s, _ = _healthy()
    X, names, _ = extract_features(_pair(s, s.copy()), selection)
    ratios = [j for j, n in enumerate(names) if n != "eta2_rel"]
    np.testing.assert_allclose(X[0, ratios], 1.0, rtol=1e-12, atol=0)
    if selection == 3:
        assert X[0, names.index("eta2_rel")] == 0.0


def test_relative_mean_variance_efficiency_eq7_eq9():
    s, _ = _healthy()
    x = s.copy()
    x[2] = 2.0 * x[2]  # mean and variance of s2 scale by 2 and 4
    X1, n1, _ = extract_features(_pair(s, x, eta=(0.8, 0.9)), 1)
    assert X1[0, n1.index("m_rel_s2")] == pytest.approx(2.0)
    assert X1[0, n1.index("var_rel_s2")] == pytest.approx(4.0)
    assert X1[0, n1.index("m_rel_s1")] == pytest.approx(1.0)
    assert X1[0, n1.index("eta_rel")] == pytest.approx(0.9 / 0.8)
    X3, n3, _ = extract_features(_pair(s, x, eta=(0.8, 0.9)), 3)
    assert X3[0, n3.index("eta2_rel")] == pytest.approx(abs(1 - 0.9 / 0.8) ** 0.25)


def test_order_spectrum_recovers_amplitude():
    t = np.arange(N_TIME) / FS
    f_in = np.array([2000.0 / 60, 4000.0 / 60])
    x = np.stack([0.3 * np.cos(2 * np.pi * 2 * f[None] * t + 0.4) + 5.0 for f in f_in])[:, None]
    a = order_spectrum(x, t, f_in, paper_orders())  # (2, 1, 32)
    k2 = list(paper_orders()).index(2.0)
    np.testing.assert_allclose(a[:, 0, k2], 0.3, rtol=1e-3)
    assert (a[:, 0].argmax(axis=-1) == k2).all()
    # chunking does not change results (vectorised in chunks of windows)
    np.testing.assert_allclose(order_spectrum(x, t, f_in, paper_orders(), chunk_elements=1), a)


def _order_spectrum_by_terms(x, time_s, f_in_hz, orders):
    """The Hann-windowed order amplitudes summed term by term (the reference of
    learn.inputs.features.order_spectrum's blocked sums)."""
    n_time = x.shape[-1]
    w = 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(n_time) / n_time)
    xw = (x - x.mean(axis=-1, keepdims=True)) * w  # (N, C, T)
    phase = (2.0 * np.pi) * f_in_hz[:, None, None] * orders[None, :, None] * time_s
    re = np.matmul(xw, np.cos(phase).transpose(0, 2, 1))  # (N, C, K)
    im = np.matmul(xw, np.sin(phase).transpose(0, 2, 1))
    return np.hypot(re, im) * (2.0 / w.sum())


def test_the_blocked_order_spectrum_is_the_term_by_term_sums():
    """Random signals at three speeds, the paper's orders: the blocked sums (phase split
    into blocks, one batched product) equal the direct ones to round-off."""
    rng = np.random.default_rng(3)
    t = np.arange(N_TIME) / FS
    f_in = np.array([1000.0, 2500.0, 4000.0]) / 60
    x = rng.normal(size=(3, 5, N_TIME)) + 2.0
    np.testing.assert_allclose(order_spectrum(x, t, f_in, paper_orders()),
                               _order_spectrum_by_terms(x, t, f_in, paper_orders()),
                               rtol=1e-9, atol=1e-12)


def test_selection3_detects_planted_order1_harmonic_in_ds13():
    s, theta = _healthy()
    x = s.copy()
    x[1] += 0.05 * np.cos(theta + 1.0)  # order 1 on s1 only
    X, names, _ = extract_features(_pair(s, x), 3)
    ds13 = [j for j, n in enumerate(names) if n.startswith("dft_rel_ds13_")]
    ds24 = [j for j, n in enumerate(names) if n.startswith("dft_rel_ds24_")]
    assert names[ds13[int(np.argmax(X[0, ds13]))]] == "dft_rel_ds13_o1.00"
    assert X[0, names.index("dft_rel_ds13_o1.00")] > 20.0
    np.testing.assert_allclose(X[0, ds24], 1.0, rtol=1e-9)  # s2 - s4 untouched


def test_errors_name_parameter_and_allowed_values(synthetic_ds):
    with pytest.raises(ValueError, match="selection must be one of 1, 2, 3"):
        extract_features(synthetic_ds, "selection4")
    no_ref = synthetic_ds.isel(sample=~synthetic_ds["reference"].values)
    with pytest.raises(ValueError, match="no reference windows"):
        extract_features(no_ref, 1)
    gear3_ref = (synthetic_ds["reference"] & (synthetic_ds["gear"] == 3)).values
    with pytest.raises(ValueError, match="have no reference window"):
        extract_features(synthetic_ds.isel(sample=~gear3_ref), 1)


def test_the_coded_reference_pairs_are_the_merge(synthetic_ds):
    """The windows paired with their reference windows by integer key codes are those of
    the table merge (the slow path), in any order of the windows; two reference windows
    of one key are refused as by the merge."""
    order = np.random.default_rng(3).permutation(synthetic_ds.sizes["sample"])
    shuffled = synthetic_ds.isel(sample=order)
    for ds in (synthetic_ds, shuffled):
        fast, slow = reference_index(ds), reference_index_merge(ds)
        for a, b in zip(fast, slow, strict=True):
            assert np.array_equal(a, b) and a.dtype == b.dtype
    twice = synthetic_ds.copy()
    ref = twice["reference"].values.copy()
    ref[np.flatnonzero(~ref)[0]] = True  # a fault window of a key with a reference already
    twice["reference"] = ("sample", ref)
    with pytest.raises(ValueError, match="more than one reference window"):
        reference_index(twice)


def test_eq7_features_are_finite_and_bounded_on_the_tiny_grid(tmp_path_factory):
    """With the bridges' zero offsets (docs/PHYSICS.md sec. 4.4) eq. (7)'s relative means
    no longer divide by a bridge without a mean: on the tiny grid (the paper's gears,
    clean and disturbed) every feature of Selections 1 and 2 is finite and every relative
    mean within ±10, but where the offset drawn cancels the mean (NEAR_ZERO_BRIDGES).
    Without offsets m_rel of s1 and s3 reached 130-2200."""
    out = built_once(tmp_path_factory, "tiny_preset", lambda path: gen.generate(
        dataset_preset("tiny"), path, n_jobs=1, progress=False))
    ds = dsio.load(out)
    for feats in iter_features(ds, [1, 2]):
        assert np.all(np.isfinite(feats.X))
        gear = feats.meta["gear"].to_numpy()
        for b in range(5):
            col = feats.X[:, feats.names.index(f"m_rel_s{b}")]
            for g in (1, 2, 3):
                big = np.abs(col[gear == g]).max()
                assert (big > 10) == ((g, b) in NEAR_ZERO_BRIDGES), (g, b, big)
