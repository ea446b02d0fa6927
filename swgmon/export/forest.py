"""The exported classifier: a random forest on the stage's int16 inputs, through emlearn.

Trained on :func:`.reference.design_rows` of the training gears' windows, its
size set by the flash budget alone. emlearn's C compares ``x < t`` on int16 inputs where
scikit-learn compares ``x <= t``, so each threshold is exported as ⌊t⌋ + 1; the Python
model predicts as the C (each tree's class, then the first class with the most votes).
Node format, budget and refusals: ``docs/EXPORT.md``, "Method".
"""

from __future__ import annotations

import importlib.util
import math
import re
from pathlib import Path

import numpy as np

#: Estimators the C stage can run (emlearn's tree ensembles, classifiers).
SUPPORTED = ("RandomForestClassifier", "ExtraTreesClassifier", "DecisionTreeClassifier")
#: One decision node as emlearn's C holds it (``EmlTreesNode`` of ``eml_trees.h``: int8
#: feature index, int16 threshold and relative child jumps, C alignment).
NODE = np.dtype([("feature", np.int8), ("value", np.int16), ("left", np.int16),
                 ("right", np.int16)], align=True)
#: sizeof(EmlTreesNode) on Cortex-M [bytes].
NODE_BYTES = NODE.itemsize
#: emlearn's limits from its node: int16 relative child jumps, int8 feature index.
MAX_DECISION_NODES = int(np.iinfo(NODE["left"]).max)
MAX_FEATURES = int(np.iinfo(NODE["feature"]).max)
#: emlearn's ``EMTREES_MAX_CLASSES``, read from its installed ``eml_trees.h`` (not imported:
#: importing emlearn changes numpy's error state, :func:`~swgmon.export.import_emlearn`).
MAX_CLASSES = int(re.search(r"#define\s+EMTREES_MAX_CLASSES\s+(\d+)", Path(
    importlib.util.find_spec("emlearn").submodule_search_locations[0], "eml_trees.h"
).read_text()).group(1))


def check_representable(estimator) -> None:
    """Refuse a model the C stage cannot represent, in one line naming the limit.

    Raises
    ------
    ValueError
        An estimator other than :data:`SUPPORTED`, not fitted, with more than 127
        inputs or 30 classes, or a tree with more than 32767 decision nodes (emlearn's
        int16 node indices).
    """
    kind = type(estimator).__name__
    if kind not in SUPPORTED:
        raise ValueError(f"unsupported estimator {kind}: the C stage runs emlearn's tree "
                         f"ensembles ({', '.join(SUPPORTED)})")
    trees = getattr(estimator, "estimators_", None)
    trees = [estimator] if kind == "DecisionTreeClassifier" else trees
    if not trees or not hasattr(trees[0], "tree_"):
        raise ValueError(f"{kind} is not fitted")
    if estimator.n_features_in_ > MAX_FEATURES:
        raise ValueError(f"{estimator.n_features_in_} inputs: emlearn's int8 feature index "
                         f"allows at most {MAX_FEATURES}")
    if len(estimator.classes_) > MAX_CLASSES:
        raise ValueError(f"{len(estimator.classes_)} classes: emlearn allows at most "
                         f"{MAX_CLASSES} (EMTREES_MAX_CLASSES)")
    for i, t in enumerate(trees):
        n_dec = int(np.sum(t.tree_.children_left >= 0))
        if n_dec > MAX_DECISION_NODES:
            raise ValueError(f"tree {i} has {n_dec} decision nodes: emlearn's int16 node "
                             f"indices allow at most {MAX_DECISION_NODES}")


def leaves_for_budget(forest_bytes: int, n_trees: int) -> int:
    """``max_leaf_nodes`` per tree whose decision nodes fit ``forest_bytes`` of flash
    (L − 1 decision nodes of :data:`NODE_BYTES` each per tree; at least 2).

    Raises
    ------
    ValueError
        If the budget does not hold one split per tree.
    """
    leaves = forest_bytes // (NODE_BYTES * n_trees) + 1
    if leaves < 2:
        raise ValueError(f"forest_bytes={forest_bytes} holds no split for {n_trees} trees; "
                         f"allowed: >= {NODE_BYTES * n_trees}")
    return int(leaves)


def fit_forest(x: np.ndarray, y: np.ndarray, n_trees: int, forest_bytes: int,
               seed: int = 0):
    """A random forest on int16 design rows, sized by the flash budget.

    Parameters
    ----------
    x : ndarray of int16, shape (n, F + 2)
        :func:`.reference.design_rows` of the training gears.
    y : ndarray of int, shape (n,)
        Class index (0: healthy); every class must occur.
    n_trees : int
    forest_bytes : int
        Flash for the decision nodes [bytes].
    seed : int

    Returns
    -------
    sklearn.ensemble.RandomForestClassifier
    """
    from sklearn.ensemble import RandomForestClassifier

    rf = RandomForestClassifier(n_estimators=n_trees,
                                max_leaf_nodes=leaves_for_budget(forest_bytes, n_trees),
                                class_weight="balanced", random_state=seed, n_jobs=1)
    return rf.fit(np.asarray(x, float), y)


def predict(estimator, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Classes and P(healthy) as the C computes them (hard votes, first maximum).

    Parameters
    ----------
    estimator : fitted estimator of :data:`SUPPORTED`
    x : ndarray of int16, shape (n, F + 2)

    Returns
    -------
    classes : ndarray of int, shape (n,)
    p_healthy : ndarray, shape (n,)
        Share of trees voting class 0.
    """
    trees = getattr(estimator, "estimators_", [estimator])
    xf = np.asarray(x, np.float32)
    k = len(estimator.classes_)
    votes = np.zeros((len(xf), k), np.int64)
    for t in trees:
        leaf_cls = np.argmax(t.tree_.value[:, 0, :], axis=1)
        votes[np.arange(len(xf)), leaf_cls[t.apply(xf)]] += 1
    return np.argmax(votes, axis=1), votes[:, 0] / len(trees)


def to_c(estimator, name: str = "swg_forest") -> tuple[str, dict]:
    """The forest as emlearn "loadable" C code, thresholds as ⌊t⌋ + 1 (module docstring).

    Returns
    -------
    code : str
        C source (includes ``eml_trees.h``); defines ``<name>_predict_proba``.
    info : dict
        ``decision_nodes``, ``leaves``, ``trees``, ``node_bytes`` (flash of the nodes).

    Raises
    ------
    ValueError
        As :func:`check_representable`.
    """
    from swgmon.export import import_emlearn

    et = import_emlearn().trees

    check_representable(estimator)
    ests = getattr(estimator, "estimators_", [estimator])
    forest = et.flatten_forest([e.tree_ for e in ests], leaf="argmax", leaf_bits=0)
    nodes, roots, leaves = et.remove_duplicate_leaves(forest)
    for nd in nodes:
        if nd[0] == 0 and nd[2] == nd[3]:
            continue  # emlearn's dummy node of a one-leaf tree
        nd[1] = min(max(math.floor(nd[1]) + 1, -32767), 32767)
    code = et.generate_c_loadable((nodes, roots, leaves), name, estimator.n_features_in_,
                                  dtype="int16_t", classifier=True,
                                  n_classes=len(estimator.classes_), leaf_bits=0,
                                  include_proba=True)
    info = {"decision_nodes": len(nodes), "leaves": len(leaves), "trees": len(roots),
            "node_bytes": NODE_BYTES * len(nodes)}
    return code, info
