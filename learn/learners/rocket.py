"""MiniRocket + ridge classifier: the modern time-series peer of the torch nets.

MiniRocket (Dempster, Schmidt & Webb, KDD 2021) turns a multivariate series into about
10 000 proportion-of-positive-values features of random dilated convolutions; a
cross-validated ridge classifier on top is the method's standard head. The transform is
aeon's (``aeon.transformations.collection.convolution_based.MiniRocket``).

Same input convention as :mod:`learn.learners.nets`: (n, C, T) signals whose last ``n_aux``
channels are per-window scalars constant along time. The scalars bypass the transform
(a zero-sum convolution of a constant is zero) and are appended to the standardised
features, scaled by ``aux_weight``. A 2-D feature input skips the transform.

The classifier is also a scikit-learn transformer (:meth:`MiniRocketClassifier.transform`:
the features the ridge sees) and passes ``sklearn.utils.estimator_checks.check_estimator``
(``tests/learn/test_estimator_checks.py``); those checks feed 2-D data only, i.e. the
standardised-features path, not the MiniRocket transform.
"""

from __future__ import annotations

import logging

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, TransformerMixin
from sklearn.linear_model import RidgeClassifier, RidgeClassifierCV
from sklearn.preprocessing import StandardScaler
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

log = logging.getLogger(__name__)

#: Default ridge penalties (MiniRocket paper: 10 values log-spaced over 1e-3..1e3).
ALPHAS = tuple(float(a) for a in np.logspace(-3, 3, 10))


def _weights(sample_weight, n: int) -> np.ndarray | None:
    """Checked sample weights, shape (n,): finite, >= 0, not all zero (or None)."""
    if sample_weight is None:
        return None
    w = np.asarray(sample_weight, dtype=np.float64)
    if w.shape != (n,):
        raise ValueError(f"sample_weight must have shape ({n},), got {w.shape}")
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ValueError("sample_weight must be finite and >= 0")
    if not np.any(w > 0):
        raise ValueError("sample_weight must contain at least one non-zero weight")
    return w


class MiniRocketClassifier(ClassifierMixin, TransformerMixin, BaseEstimator):
    """MiniRocket features + ``RidgeClassifierCV``, scikit-learn compatible.

    Parameters
    ----------
    n_kernels : int
        Number of MiniRocket features (rounded by aeon to a multiple of 84).
    max_dilations_per_kernel : int
    alphas : sequence of float
        Ridge penalties tried by the classifier's efficient leave-one-out CV (training
        data only).
    n_aux : int
        Trailing scalar channels of a 3-D input.
    aux_weight : float
        Multiplier of the standardised scalars among the ~10 000 standardised features;
        > 1 lets the ridge use them at a lower penalty.
    n_jobs : int
        Threads of the transform.
    random_state : int or None

    Attributes
    ----------
    classes_ : ndarray, shape (n_classes,)
    n_features_in_ : int
        Features of a 2-D input, channels (signals + scalars) of a 3-D input.
    input_ndim_ : int
        2 or 3, the dimensions of the training input; later inputs must match.
    rocket_, scaler_, aux_scaler_ : fitted transform and scalers (those that apply)
    ridge_ : RidgeClassifierCV, or the RidgeClassifier of :meth:`refit_head`
    """

    def __init__(self, n_kernels=10_000, max_dilations_per_kernel=32,
                 alphas=ALPHAS, n_aux=0, aux_weight=10.0, n_jobs=1,
                 random_state=None):
        self.n_kernels = n_kernels
        self.max_dilations_per_kernel = max_dilations_per_kernel
        self.alphas = alphas
        self.n_aux = n_aux
        self.aux_weight = aux_weight
        self.n_jobs = n_jobs
        self.random_state = random_state

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.input_tags.three_d_array = True  # (n, C, T) signals
        return tags

    def _check_X(self, X) -> np.ndarray:
        """Input of a fitted model as float64 after scikit-learn's checks (finite, n > 0,
        ``n_features_in_``) and the dimensions of fit."""
        check_is_fitted(self, "ridge_")
        X = validate_data(self, X, reset=False, dtype=np.float64, allow_nd=True)
        if X.ndim != self.input_ndim_:
            raise ValueError(f"X must have {self.input_ndim_} dimensions as in fit, "
                             f"got shape {X.shape}")
        return X

    def _split(self, X):
        X = np.asarray(X, dtype=np.float64)
        if X.ndim == 2:
            return None, X
        c = X.shape[1] - self.n_aux
        return X[:, :c], X[:, c:, 0]

    def transform(self, X) -> np.ndarray:
        """Standardised features of a fitted model, shape (n, n_features)."""
        return self._features(self._check_X(X))

    def _features(self, X: np.ndarray, rocket: np.ndarray | None = None) -> np.ndarray:
        """Standardised features of ``X`` (``rocket``: its MiniRocket features, if known)."""
        sig, aux = self._split(X)
        parts = []
        if sig is not None:
            rocket = self.rocket_.transform(sig) if rocket is None else rocket
            parts.append(self.scaler_.transform(rocket))
        if aux is not None and aux.shape[1]:
            parts.append(self.aux_weight * self.aux_scaler_.transform(aux))
        return np.concatenate(parts, axis=1)

    def fit(self, X, y, sample_weight=None):
        """Fit the transform and the ridge on training windows.

        Parameters
        ----------
        X : array (n, C, T) or (n, F)
        y : array (n,)
        sample_weight : array (n,), optional
            Weights of the windows (e.g. to up-weight a few target windows), >= 0, not all
            zero; used by the feature scalers and the ridge alike, so that an integer
            weight acts as that many copies of the window.

        Returns
        -------
        self

        Raises
        ------
        ValueError
            On non-finite or empty ``X``, ``X`` not 2-D or 3-D, ``len(y) != n``,
            continuous ``y`` or invalid ``sample_weight``.
        """
        self.fit_transform(X, y, sample_weight=sample_weight)
        return self

    def fit_transform(self, X, y=None, sample_weight=None) -> np.ndarray:
        """:meth:`fit`, returning the standardised features of ``X`` that the ridge was
        fitted on, shape (n, n_features): :meth:`transform` of ``X`` without running the
        MiniRocket transform again (the k-shot refits of :meth:`refit_head` reuse them).

        Parameters and errors as :meth:`fit`; ``y`` is required.
        """
        from aeon.transformations.collection.convolution_based import MiniRocket

        X, y = validate_data(self, X, y, dtype=np.float64, allow_nd=True)
        if X.ndim not in (2, 3):
            raise ValueError(f"X must be (n, C, T) or (n, F); got shape {X.shape}")
        check_classification_targets(y)
        sample_weight = _weights(sample_weight, X.shape[0])
        self.input_ndim_ = X.ndim
        sig, aux = self._split(X)
        feats = None
        if sig is not None:
            self.rocket_ = MiniRocket(n_kernels=self.n_kernels,
                                      max_dilations_per_kernel=self.max_dilations_per_kernel,
                                      n_jobs=self.n_jobs, random_state=self.random_state)
            feats = self.rocket_.fit_transform(sig)
            self.scaler_ = StandardScaler().fit(feats, sample_weight=sample_weight)
        if aux is not None and aux.shape[1]:
            self.aux_scaler_ = StandardScaler().fit(aux, sample_weight=sample_weight)
        features = self._features(X, feats)
        self.ridge_ = RidgeClassifierCV(alphas=np.asarray(self.alphas)).fit(
            features, y, sample_weight=sample_weight)
        self.classes_ = self.ridge_.classes_
        return features

    def refit_head(self, X, y, *, y_source, source_features, replay: float = 1.0):
        """k-shot adaptation: refit only the ridge on the source windows plus k labelled
        windows of the target, with the fitted kernels, scalers and ridge penalty.

        The target windows are weighted so that together they weigh ``1 / replay`` times
        the source windows (the balance of the torch nets' fine-tuning with replay,
        :meth:`learn.learners.nets.TorchClassifier.fine_tune`); the penalty stays the one the
        leave-one-out CV chose on the source data, so nothing is chosen on the target.

        Parameters
        ----------
        X : array (k_total, C, T) or (k_total, F)
            Labelled target windows.
        y : array (k_total,)
        y_source : array (n,)
            Labels of the training windows.
        source_features : ndarray, shape (n, n_features)
            :meth:`transform` of the training windows (computed once for every k).
        replay : float
            Source windows per target window in weight, > 0.

        Returns
        -------
        self

        Raises
        ------
        ValueError
            ``replay`` <= 0 or shapes that do not match.
        """
        if not replay > 0:
            raise ValueError(f"replay must be > 0, got {replay}")
        f_t = self.transform(X)
        f_s = np.asarray(source_features)
        if f_s.shape[0] != len(y_source) or f_s.shape[1] != f_t.shape[1]:
            raise ValueError(f"source_features of shape {f_s.shape} do not match "
                             f"{len(y_source)} labels and {f_t.shape[1]} features")
        w_t = f_s.shape[0] / (replay * max(f_t.shape[0], 1))
        weight = np.concatenate([np.ones(f_s.shape[0]), np.full(f_t.shape[0], w_t)])
        self.ridge_ = RidgeClassifier(alpha=float(self.ridge_.alpha_)).fit(
            np.concatenate([f_s, f_t]), np.concatenate([np.asarray(y_source), np.asarray(y)]),
            sample_weight=weight)
        self.classes_ = self.ridge_.classes_
        return self

    def decision_function(self, X) -> np.ndarray:
        """Ridge scores, shape (n, n_classes); with two classes shape (n,), the score of
        ``classes_[1]`` (> 0: class 1; the ridge's targets are -1 / +1)."""
        features = self.transform(X)  # first: NotFittedError before ridge_ is looked up
        return self.ridge_.decision_function(features)

    def predict(self, X) -> np.ndarray:
        """Predicted labels, shape (n,)."""
        features = self.transform(X)
        return self.ridge_.predict(features)

    def predict_proba(self, X) -> np.ndarray:
        """Softmax of the ridge scores, shape (n, n_classes): a ranking, not calibrated.

        With two classes the scores of the two one-vs-rest ridges are -d and +d
        (d = :meth:`decision_function`), so the probability of ``classes_[1]`` is
        1 / (1 + exp(-2 d)).
        """
        d = self.decision_function(X)
        if d.ndim == 1:
            d = np.stack([-d, d], axis=1)
        d = np.exp(d - d.max(axis=1, keepdims=True))
        return d / d.sum(axis=1, keepdims=True)
