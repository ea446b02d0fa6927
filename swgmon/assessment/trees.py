"""A fitted histogram gradient-boosting classifier evaluated by a compiled walk of its trees.

scikit-learn's ``predict_proba`` walks its trees one by one from Python: with 200
iterations of 8 classes that is 1,600 calls, about 12 ms for one window and tens of
microseconds per tree whatever the batch (the monitor's evaluation spent 27 s of a 180-s
part there). :class:`CompiledTrees` stores every tree's nodes in flat arrays and walks them
window by window in one compiled loop (numba), adding the leaf values to the baseline in
scikit-learn's order (iterations, then classes) and turning them into probabilities with
the classifier's own link: the same numbers as ``predict_proba`` (tested bit for bit), for
one window or a life's.
"""

from __future__ import annotations

import numba
import numpy as np


class CompiledTrees:
    """Flat arrays of a fitted ``HistGradientBoostingClassifier`` (module docstring).

    Parameters
    ----------
    clf : sklearn.ensemble.HistGradientBoostingClassifier
        Fitted on numeric features (no categorical ones).

    Raises
    ------
    ValueError
        If the model has categorical splits.
    """

    def __init__(self, clf) -> None:
        self.clf = clf
        cols = {k: [] for k in ("feature_idx", "num_threshold", "left", "right", "is_leaf",
                                "value", "missing_go_to_left")}
        roots, cls, off = [], [], 0
        for iteration in clf._predictors:
            for k, tree in enumerate(iteration):
                n = tree.nodes
                if n["is_categorical"].any():
                    raise ValueError("categorical splits are not supported")
                roots.append(off)
                cls.append(k)
                for c in cols:
                    v = n[c].astype(np.int64) + off if c in ("left", "right") else n[c]
                    cols[c].append(v)
                off += len(n)
        self.feature = np.concatenate(cols["feature_idx"]).astype(np.int64)
        self.threshold = np.concatenate(cols["num_threshold"]).astype(np.float64)
        self.left = np.concatenate(cols["left"])
        self.right = np.concatenate(cols["right"])
        self.leaf = np.concatenate(cols["is_leaf"]).astype(bool)
        self.value = np.concatenate(cols["value"]).astype(np.float64)
        self.nan_left = np.concatenate(cols["missing_go_to_left"]).astype(bool)
        self.roots = np.asarray(roots, np.int64)
        self.tree_class = np.asarray(cls, np.int64)
        self.base = np.asarray(clf._baseline_prediction, np.float64).ravel()

    def raw(self, x: np.ndarray) -> np.ndarray:
        """Raw scores (n, n_classes): the baseline plus every tree's leaf value, in
        scikit-learn's order (``_raw_predict``)."""
        x = np.ascontiguousarray(x, dtype=np.float64)
        out = np.empty((x.shape[0], self.base.size))
        _walk(x, self.feature, self.threshold, self.left, self.right, self.leaf, self.value,
              self.nan_left, self.roots, self.tree_class, self.base, out)
        return out

    def predict_proba(self, x: np.ndarray) -> np.ndarray:
        """Class probabilities, shape (n, n_classes): the classifier's link of
        :meth:`raw`, as its own ``predict_proba``."""
        return self.clf._loss.predict_proba(self.raw(x))


@numba.njit(cache=True)
def _walk(x, feature, threshold, left, right, leaf, value, nan_left, roots, tree_class, base,
          out):
    """Every window's walk through each tree in turn (a NaN goes where training sent
    missing values), leaf values added to the baseline tree by tree: the same sums in the
    same order as window by window, with one tree's nodes in the cache for all windows
    (blocks of 1024 windows: 57 against 100 µs a window walked through all 1,600 trees,
    whose nodes do not fit a core's cache; docs/results/speed.md)."""
    for i in range(x.shape[0]):
        for k in range(base.size):
            out[i, k] = 0.0
            out[i, k] += base[k]
    for t in range(roots.size):
        c = tree_class[t]
        for i in range(x.shape[0]):
            nd = roots[t]
            while not leaf[nd]:
                v = x[i, feature[nd]]
                if np.isnan(v):
                    nd = left[nd] if nan_left[nd] else right[nd]
                elif v <= threshold[nd]:
                    nd = left[nd]
                else:
                    nd = right[nd]
            out[i, c] += value[nd]


__all__ = ["CompiledTrees"]
