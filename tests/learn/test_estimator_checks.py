"""scikit-learn's ``check_estimator`` on the torch nets and MiniRocket (issue 14), plus the
same contract on 3-D signal input, which ``check_estimator`` never feeds (its data are 2-D).

The estimators run with small settings (few epochs, narrow layers, 84 MiniRocket kernels);
the checks are scikit-learn's own. A check that cannot apply to an estimator would be
declared in ``NOT_APPLICABLE`` with the reason (``check_estimator(...,
expected_failed_checks=...)``); a declared check that passes fails this test, so the list
cannot go stale.
"""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.exceptions import NotFittedError
from sklearn.utils.estimator_checks import (
    check_estimator,
    check_sample_weight_equivalence_on_dense_data,
)

from learn.learners.nets import CNN1DClassifier, MLPClassifierTorch
from learn.learners.rocket import MiniRocketClassifier

pytestmark = pytest.mark.usefixtures("torch_one_thread")


FAST = {"max_epochs": 20, "batch_size": 32, "device": "cpu", "random_state": 0}

ESTIMATORS = {
    "mlp": MLPClassifierTorch(hidden=(16,), **FAST),
    "cnn": CNN1DClassifier(channels=(8,), kernel_sizes=(3,), strides=(1,), head_hidden=16,
                           **FAST),
    "minirocket": MiniRocketClassifier(n_kernels=84, random_state=0),
}

#: check name -> why it cannot apply to the estimator as configured
NOT_APPLICABLE: dict[str, dict[str, str]] = {
    "mlp": {},
    "cnn": {},
    "minirocket": {
        "check_sample_weight_equivalence_on_dense_data": (
            "the ridge penalty is chosen by efficient leave-one-out CV among several "
            "alphas: a window of integer weight w is left out whole, its w copies one at a "
            "time, so the chosen penalty differs (1000 vs 215 on the check's data); with "
            "one penalty the equivalence holds (test_minirocket_weights_are_repetitions)"),
    },
}


@pytest.mark.parametrize("name", list(ESTIMATORS))
def test_check_estimator(name):
    results = check_estimator(clone(ESTIMATORS[name]),
                              expected_failed_checks=NOT_APPLICABLE[name], on_fail=None,
                              on_skip=None)
    failed = [f"{r['check_name']}: {r['exception']!r}" for r in results
              if r["status"] == "failed"]
    assert not failed, "\n".join(failed)
    stale = [r["check_name"] for r in results
             if r["expected_to_fail"] and r["status"] == "passed"]
    assert not stale, f"declared not applicable but passed: {stale}"
    assert len(results) > 40  # the whole suite ran, not an early exit


def test_minirocket_weights_are_repetitions():
    """With a single ridge penalty (no CV), an integer sample weight acts as that many
    copies of the window, in the feature scalers and the ridge alike."""
    check_sample_weight_equivalence_on_dense_data(
        "MiniRocketClassifier", MiniRocketClassifier(n_kernels=84, alphas=(1.0,)))


# ------------------------------------------------------------------ 3-D signal input


def signals(n_per_class=12, n_classes=2, n_time=32, seed=0):
    """(n, 3, T): a sinusoid of 2, 4, ... periods per class in channel 0, noise in
    channel 1, one per-window scalar (n_aux = 1) in channel 2."""
    rng = np.random.default_rng(seed)
    t = np.arange(n_time) / n_time
    X = 0.3 * rng.standard_normal((n_classes * n_per_class, 3, n_time))
    y = np.repeat([f"c{c}" for c in range(n_classes)], n_per_class)
    for i, c in enumerate(np.repeat(np.arange(n_classes), n_per_class)):
        X[i, 0] += np.sin(2 * np.pi * 2 * (c + 1) * t + rng.uniform(0, 2 * np.pi))
        X[i, 2] = rng.standard_normal()
    return X.astype(np.float32), y


def _signal_models():
    small = {"max_epochs": 10, "batch_size": 8, "device": "cpu", "random_state": 0, "n_aux": 1}
    return {
        "mlp": MLPClassifierTorch(hidden=(16,), **small),
        "cnn": CNN1DClassifier(channels=(8,), kernel_sizes=(5,), strides=(1,), head_hidden=8,
                               **small),
        "minirocket": MiniRocketClassifier(n_kernels=84, n_aux=1, random_state=0),
    }


@pytest.mark.parametrize("name", list(_signal_models()))
def test_signal_input_contract(name):
    model = _signal_models()[name]
    X, y = signals()
    with pytest.raises(NotFittedError):
        model.predict(X)
    model.fit(X, y)
    assert model.n_features_in_ == 3
    d = model.decision_function(X)
    assert d.shape == (len(y),)  # binary: scikit-learn's one score per window
    pred = model.predict(X)
    np.testing.assert_array_equal(pred, model.classes_[(d > 0).astype(int)])
    proba = model.predict_proba(X)
    np.testing.assert_allclose(proba.sum(axis=1), 1.0, rtol=1e-6)
    np.testing.assert_array_equal(model.classes_[proba.argmax(axis=1)], pred)
    with pytest.raises(ValueError, match="features"):
        model.predict(X[:, :2])  # a channel fewer than in fit
    with pytest.raises(ValueError, match="dimensions"):
        model.predict(X[:, :, 0])  # 2-D input to a model fitted on 3-D
    bad = X.copy()
    bad[0, 0, 3] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        model.predict(bad)
    with pytest.raises(ValueError, match="NaN"):
        clone(model).fit(bad, y)


def test_length_is_checked_only_where_the_net_needs_it():
    X, y = signals()
    models = _signal_models()
    mlp = models["mlp"].fit(X, y)
    with pytest.raises(ValueError, match="time samples"):
        mlp.predict(X[:, :, :16])  # the flattened input fixes T
    cnn = models["cnn"].fit(X, y)
    assert cnn.predict(X[:, :, :16]).shape == (len(y),)  # avg pooling: any length


def test_adabn_is_deterministic_with_dropout():
    """AdaBN re-estimates only the batch-norm statistics: dropout stays off, so two
    adaptations on the same windows give the same net (before the fix they differed)."""
    X, y = signals(n_per_class=16, n_classes=3, n_time=24)
    X = X.reshape(len(X), -1)
    net = MLPClassifierTorch(hidden=(16, 16), dropout=0.5, max_epochs=2, device="cpu",
                             random_state=0)
    net.fit(X, y)
    a = net.adapt_bn(X + 0.3).predict_proba(X)
    b = net.adapt_bn(X + 0.3).predict_proba(X)
    np.testing.assert_array_equal(a, b)
