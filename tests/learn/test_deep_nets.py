"""learn.learners.nets and learn.learners.rocket: scikit-learn contract, shapes, fitting a
separable toy set, fine-tuning and AdaBN."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from sklearn.base import clone

from learn.learners.nets import CNN1DClassifier, MLPClassifierTorch
from learn.learners.rocket import MiniRocketClassifier
from learn.learners.stacked import fit_seeds

pytestmark = pytest.mark.usefixtures("torch_one_thread")


def separable(n_per_class=20, n_time=64, n_aux=1, seed=0):
    """Three classes: a sinusoid of 4, 8 or 12 periods in channel 0 with random phase and
    noise; one scalar channel carrying noise only."""
    rng = np.random.default_rng(seed)
    t = np.arange(n_time) / n_time
    X, y = [], []
    for c in range(3):
        for _ in range(n_per_class):
            x = 0.3 * rng.standard_normal((2 + n_aux, n_time))
            x[0] += np.sin(2 * np.pi * (c + 1) * 4 * t + rng.uniform(0, 2 * np.pi))
            x[2:] = rng.standard_normal((n_aux, 1))
            X.append(x)
            y.append(f"c{c}")
    return np.asarray(X, dtype=np.float32), np.asarray(y)


TINY = {"max_epochs": 15, "batch_size": 16, "device": "cpu", "random_state": 0}


def spectrum(X):
    """(n, C, T) -> amplitude spectrum of channel 0 plus the scalar, (n, T // 2 + 2)."""
    return np.concatenate([np.abs(np.fft.rfft(X[:, 0], axis=1)), X[:, -1, :1]],
                          axis=1).astype(np.float32)


def _models():
    return [
        CNN1DClassifier(channels=(8, 8), kernel_sizes=(9, 9), strides=(2, 2), head_hidden=16,
                        n_aux=1, **TINY),
        MLPClassifierTorch(hidden=(32,), n_aux=1, **TINY),
    ]


# minimum test accuracy (chance 1/3); an MLP on time samples has no shift invariance and
# sees the sinusoids at random phases: 0.70 measured, so 0.55 for it
@pytest.mark.parametrize(("model", "features", "min_acc"),
                         [(_models()[0], False, 0.8), (_models()[1], True, 0.8),
                          (_models()[1], False, 0.55),
                          (CNN1DClassifier(channels=(8,), kernel_sizes=(5,), strides=(1,),
                                           head_hidden=16, pool="flatten", **TINY), True, 0.8)],
                         ids=["cnn-signals", "mlp-spectrum", "mlp-signals", "cnn-features"])
def test_fit_beats_chance_and_shapes(model, features, min_acc):
    X, y = separable()
    Xte, yte = separable(seed=1)
    if features:
        X, Xte = spectrum(X), spectrum(Xte)
    assert clone(model).get_params() == model.get_params()
    assert not hasattr(model, "module_")  # __init__ stores arguments only
    out = model.fit(X, y)
    assert out is model
    proba = model.predict_proba(Xte)
    assert proba.shape == (len(yte), 3)
    np.testing.assert_allclose(proba.sum(axis=1), 1.0, rtol=1e-5)
    assert list(model.classes_) == ["c0", "c1", "c2"]
    assert model.embed(Xte).shape[0] == len(yte)
    assert model.score(Xte, yte) > min_acc  # chance: 1/3


def test_same_seed_same_model():
    X, y = separable()
    a = _models()[0].fit(X, y).predict_proba(X)
    b = _models()[0].fit(X, y).predict_proba(X)
    np.testing.assert_array_equal(a, b)


def _no_dropout():
    """A CNN with a validation split, early stopping and augmentation, and an MLP; no
    dropout, whose masks alone fit_seeds draws otherwise than fit."""
    return [CNN1DClassifier(channels=(8, 8), kernel_sizes=(9, 9), strides=(2, 2),
                            head_hidden=16, n_aux=1, dropout=0.0, val_fraction=0.3,
                            patience=3, aug_gain=0.1, aug_crop=0.8, **TINY),
            MLPClassifierTorch(hidden=(32,), n_aux=1, dropout=0.0, **TINY)]


@pytest.mark.parametrize("est", _no_dropout(), ids=["cnn", "mlp"])
def test_fit_seeds_gives_each_seed_the_model_of_its_own_fit(est):
    """Stacked training keeps each copy's initial weights, split, batches, augmentation
    and early stopping: its outputs are those of a fit one by one, to rounding (an MLP's
    first bias before batch norm has no gradient but rounding, so its weights alone may
    differ; its outputs not)."""
    X, y = separable(30)
    groups = np.repeat(np.arange(len(y) // 5), 5)
    seeds = [0, 1, 2]
    stacked = fit_seeds(est, X, y, seeds, groups=groups)
    epochs = []
    for seed, m in zip(seeds, stacked, strict=True):
        one = clone(est).set_params(random_state=seed).fit(X, y, groups)
        assert m.random_state == seed
        assert [h["epoch"] for h in m.history_] == [h["epoch"] for h in one.history_]
        np.testing.assert_allclose([h["loss"] for h in m.history_],
                                   [h["loss"] for h in one.history_], rtol=1e-4)
        np.testing.assert_allclose(m.predict_proba(X), one.predict_proba(X), atol=1e-4)
        epochs.append(len(m.history_))
    if est.val_fraction > 0:  # early stopping ended one copy before the others
        assert min(epochs) < max(epochs) == est.max_epochs
    assert not np.allclose(stacked[0].predict_proba(X), stacked[1].predict_proba(X))


def test_fit_seeds_of_unequal_training_sets_fit_one_by_one():
    """Validation splits of whole groups of unequal size leave unequal training sets:
    their batches cannot stack, and each copy is its own fit, bit for bit."""
    X, y = separable(30)
    groups = np.r_[np.zeros(30, dtype=int), np.arange(1, len(y) - 29)]  # one big group
    est = CNN1DClassifier(channels=(8,), kernel_sizes=(9,), strides=(2,), head_hidden=8,
                          n_aux=1, val_fraction=0.3, **{**TINY, "max_epochs": 3})
    seeds = [0, 1, 2, 3, 4]
    sizes = {len(est._val_split(len(y), groups, np.random.default_rng(s))[0]) for s in seeds}
    assert len(sizes) > 1
    for seed, m in zip(seeds, fit_seeds(est, X, y, seeds, groups=groups), strict=True):
        one = clone(est).set_params(random_state=seed).fit(X, y, groups)
        np.testing.assert_array_equal(m.predict_proba(X), one.predict_proba(X))
    with pytest.raises(ValueError, match="seeds"):
        fit_seeds(est, X, y, [])


@pytest.mark.slow
def test_fit_seeds_compiled_gives_the_models_of_the_stacked_fit():
    """torch.compile of the stacked forward pass (tens of seconds to compile on a CPU):
    the same models to rounding, dropout and batch-norm statistics included."""
    X, y = separable(30)
    est = CNN1DClassifier(channels=(8, 8), kernel_sizes=(9, 9), strides=(2, 2),
                          head_hidden=16, n_aux=1, **TINY)
    compiled = fit_seeds(est, X, y, [0, 1], compile=True)
    for a, b in zip(compiled, fit_seeds(est, X, y, [0, 1]), strict=True):
        np.testing.assert_allclose(a.predict_proba(X), b.predict_proba(X), atol=1e-5)


def test_feature_input_and_early_stopping():
    X, y = separable()
    F = spectrum(X)
    groups = np.repeat(np.arange(len(y) // 2), 2)
    mlp = MLPClassifierTorch(hidden=(16,), val_fraction=0.25, patience=3, **TINY)
    mlp.fit(F, y, groups=groups)
    assert "val_loss" in mlp.history_[0]
    assert mlp.predict(F).shape == (len(y),)
    cnn = CNN1DClassifier(channels=(4,), kernel_sizes=(3,), strides=(1,), head_hidden=8, **TINY)
    assert cnn.fit(F, y).predict(F).shape == (len(y),)


def test_fine_tune_last_touches_head_only_and_adabn_keeps_weights():
    X, y = separable()
    m = _models()[0].fit(X, y)
    before = {k: v.clone() for k, v in m.module_.state_dict().items()}
    m.fine_tune(X[:6], y[:6], mode="last", steps=5, X_replay=X, y_replay=y)
    after = {k: v.clone() for k, v in m.module_.state_dict().items()}
    changed = {k for k in before if not torch.equal(before[k], after[k])}
    assert changed and all(k.startswith("head.") for k in changed)
    assert all(p.requires_grad for p in m.module_.parameters())  # restored
    m.fine_tune(X[:6], y[:6], mode="all", steps=3)
    after2 = m.module_.state_dict()
    assert any(not torch.equal(after[k], after2[k]) for k in after if k.startswith("features"))
    w = {k: v.clone() for k, v in m.module_.state_dict().items()}
    m.adapt_bn(X + 0.5)
    bn = {k for k, v in m.module_.state_dict().items() if not torch.equal(w[k], v)}
    assert bn and all("running" in k or "num_batches" in k for k in bn)
    with pytest.raises(ValueError, match="mode"):
        m.fine_tune(X, y, mode="middle")


def test_prepared_input_stands_for_the_windows_in_every_method():
    """prepare(X) is accepted wherever X is, by the net and by its fine-tuned copy (which
    keeps the statistics of fit), with the same results: the transfer study's cache."""
    import copy

    X, y = separable()
    Xte, _ = separable(seed=1)
    m = _models()[0].fit(X, y)
    p_te, p_tr = m.prepare(Xte), m.prepare(X)
    assert p_te.dtype == torch.float32 and tuple(p_te.shape) == Xte.shape
    assert m.prepare(p_te) is p_te
    np.testing.assert_array_equal(m.predict(p_te), m.predict(Xte))
    np.testing.assert_array_equal(m.predict_proba(p_te), m.predict_proba(Xte))
    a, b = copy.deepcopy(m), copy.deepcopy(m)
    a.fine_tune(X[:6], y[:6], steps=3, X_replay=X, y_replay=y, random_state=1)
    b.fine_tune(m.prepare(X[:6]), y[:6], steps=3, X_replay=p_tr, y_replay=y, random_state=1)
    np.testing.assert_array_equal(a.predict_proba(Xte), b.predict_proba(p_te))
    # a tensor is taken as prepared: raw windows as a tensor give other results
    assert not np.array_equal(m.predict_proba(torch.from_numpy(Xte)), m.predict_proba(Xte))


def test_minirocket_fits_separable_set():
    X, y = separable(n_time=64)
    Xte, yte = separable(n_time=64, seed=1)
    m = MiniRocketClassifier(n_kernels=84 * 3, n_aux=1, random_state=0)
    assert clone(m).get_params() == m.get_params()
    m.fit(X, y)
    assert m.transform(Xte).shape[0] == len(yte)
    assert m.predict_proba(Xte).shape == (len(yte), 3)
    assert m.score(Xte, yte) > 0.8


def test_minirocket_fit_transform_is_transform_of_the_fitted_model():
    """The training features that fit_transform hands back (and the k-shot ridge refits
    reuse) are those transform computes, and the model is the one fit makes."""
    X, y = separable(n_time=64)
    a = MiniRocketClassifier(n_kernels=84 * 3, n_aux=1, random_state=0)
    b = clone(a)
    f = a.fit_transform(X, y)
    b.fit(X, y)
    np.testing.assert_allclose(f, a.transform(X), rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(a.predict(X), b.predict(X))
    assert a.ridge_.alpha_ == b.ridge_.alpha_


@pytest.mark.parametrize("cls", [CNN1DClassifier, MLPClassifierTorch])
def test_bfloat16_nets_fit_the_separable_set_with_float32_outputs(cls):
    """Mixed precision (bfloat16 products, float32 weights and outputs) learns what
    float32 learns and hands back float32 probabilities that sum to one."""
    X, y = separable()
    Xte, yte = separable(seed=1)
    m = cls(n_aux=1, precision="bfloat16", **TINY).fit(X, y)
    assert m.precision_ == "bfloat16"
    assert next(m.module_.parameters()).dtype == torch.float32
    p = m.predict_proba(Xte)
    assert p.dtype == np.float32
    np.testing.assert_allclose(p.sum(axis=1), 1.0, rtol=1e-5)
    assert m.score(Xte, yte) > 0.8
    f32 = cls(n_aux=1, **TINY).fit(X, y)
    assert not np.array_equal(f32.predict_proba(Xte), p)  # the setting is used


def test_precision_auto_follows_the_hardware(monkeypatch):
    from learn.learners.devices import resolve_precision

    cpu = torch.device("cpu")
    assert resolve_precision("float32", cpu) == "float32"
    assert resolve_precision("bfloat16", cpu) == "bfloat16"
    monkeypatch.setattr(torch.backends.cpu, "get_cpu_capability", lambda: "AVX2")
    assert resolve_precision("auto", cpu) == "float32"
    monkeypatch.setattr(torch.backends.cpu, "get_cpu_capability", lambda: "AVX512")
    assert resolve_precision("auto", cpu) == "bfloat16"
    with pytest.raises(ValueError, match="precision must be one of"):
        resolve_precision("float16", cpu)
    with pytest.raises(ValueError, match="precision must be one of"):
        CNN1DClassifier(precision="half", **TINY).fit(*separable())
