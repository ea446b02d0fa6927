"""Unsupervised domain adaptation for feature classifiers: CORAL.

The torch nets' adaptation (AdaBN: batch-norm statistics re-estimated on unlabelled
target windows) is a method of the nets (:meth:`learn.learners.nets.TorchClassifier.adapt_bn`);
feature models get CORAL here. In the transfer comparison both see the held-out gear's
unlabelled healthy windows (:mod:`learn.studies.kshot`): what a real gear offers. The
source statistics are those of every class, the target's of the healthy class alone, so
both align a mixture to one of its components; the report says so.
"""

from __future__ import annotations

import numpy as np
from sklearn.base import clone


class CoralClassifier:
    """CORAL (Sun, Feng & Saenko, AAAI 2016) around any feature classifier.

    Features are standardised with the source statistics; the source features are
    whitened with their own covariance and re-coloured with the target's (both + ``reg``
    times the identity), their mean moved to the target's; the classifier is trained on
    them and applied to standardised target features. Target labels are never used.

    Parameters
    ----------
    estimator : classifier
        Unfitted; cloned.
    reg : float
        Ridge added to both covariances (CORAL's identity term).
    """

    def __init__(self, estimator, reg: float = 1.0):
        self.estimator = estimator
        self.reg = reg

    @staticmethod
    def _sqrtm(c: np.ndarray, inverse: bool = False) -> np.ndarray:
        w, v = np.linalg.eigh(c)
        w = np.clip(w, 1e-12, None)
        return (v * (w ** (-0.5 if inverse else 0.5))) @ v.T

    def fit(self, X, y, X_target):
        """Fit on labelled source ``(X, y)`` aligned to unlabelled ``X_target`` (2-D)."""
        X = np.asarray(X, dtype=np.float64)
        Xt = np.asarray(X_target, dtype=np.float64)
        self.mean_ = X.mean(axis=0)
        sd = X.std(axis=0)
        self.scale_ = np.where(sd > 1e-12, sd, 1.0)
        zs = (X - self.mean_) / self.scale_
        zt = (Xt - self.mean_) / self.scale_
        eye = self.reg * np.eye(X.shape[1])
        cs = np.cov(zs, rowvar=False) + eye
        ct = np.cov(zt, rowvar=False) + eye
        a = self._sqrtm(cs, inverse=True) @ self._sqrtm(ct)
        zs_aligned = (zs - zs.mean(axis=0)) @ a + zt.mean(axis=0)
        self.estimator_ = clone(self.estimator).fit(zs_aligned, y)
        self.classes_ = self.estimator_.classes_
        return self

    def predict(self, X) -> np.ndarray:
        return self.estimator_.predict((np.asarray(X, dtype=np.float64) - self.mean_)
                                       / self.scale_)
