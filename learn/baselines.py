"""Scikit-learn baselines of the paper, Table VI.

=====  ==============================================  ==================================
name   estimator                                       paper Table VI
=====  ==============================================  ==================================
mlp    ``MLPClassifier(hidden_layer_sizes=(10,)*3)``   3 hidden layers x 10, ReLU
svm    ``SVC(kernel="rbf")``                           radial basis function kernel
rf     ``RandomForestClassifier(100, max_depth=7)``    100 trees of depth 7
knn    ``KNeighborsClassifier(n_neighbors=3)``         3 neighbours
nb     ``GaussianNB()``                                Gaussian distribution
=====  ==============================================  ==================================

Everything else is scikit-learn's default, as in the paper ("standard settings"). Each
estimator is wrapped in a :class:`~sklearn.pipeline.Pipeline` behind a
:class:`~sklearn.preprocessing.StandardScaler`. The paper does not say whether features
were scaled; scaling is our choice (it matters for MLP, SVM and KNN, whose paper scores
may reflect unscaled features) and ``scale=False`` switches it off.

The Hydra configs ``conf/model/<name>.yaml`` build the same pipelines through
:func:`make_pipeline`; a test checks that both routes give equal parameters.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

from sklearn.base import ClassifierMixin
from sklearn.ensemble import RandomForestClassifier
from sklearn.naive_bayes import GaussianNB
from sklearn.neighbors import KNeighborsClassifier
from sklearn.neural_network import MLPClassifier
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC

log = logging.getLogger(__name__)

#: Display names of the paper (Table VI), keyed by config name.
MODEL_LABELS = {"mlp": "MLP", "svm": "SVM", "rf": "RF", "knn": "KNN", "nb": "NB"}


def _mlp(random_state: int | None) -> MLPClassifier:
    return MLPClassifier(hidden_layer_sizes=(10, 10, 10), activation="relu",
                         random_state=random_state)


def _svm(random_state: int | None) -> SVC:
    return SVC(kernel="rbf", random_state=random_state)


def _rf(random_state: int | None) -> RandomForestClassifier:
    return RandomForestClassifier(n_estimators=100, max_depth=7, random_state=random_state)


def _knn(random_state: int | None) -> KNeighborsClassifier:
    return KNeighborsClassifier(n_neighbors=3)


def _nb(random_state: int | None) -> GaussianNB:
    return GaussianNB()


#: Factories of the paper's estimators (Table VI), keyed by config name.
PAPER_MODELS: dict[str, Callable[[int | None], ClassifierMixin]] = {
    "mlp": _mlp, "svm": _svm, "rf": _rf, "knn": _knn, "nb": _nb,
}


def make_pipeline(estimator: ClassifierMixin, name: str = "clf", scale: bool = True) -> Pipeline:
    """Wrap a classifier behind an optional :class:`StandardScaler`.

    This is the ``_target_`` of ``conf/model/*.yaml``.

    Parameters
    ----------
    estimator : classifier
        Any scikit-learn-compatible classifier (``fit`` / ``predict``).
    name : str, default "clf"
        Step name of the classifier in the pipeline (the model's config name).
    scale : bool, default True
        Standardise features (zero mean, unit variance, fitted on the training split).

    Returns
    -------
    sklearn.pipeline.Pipeline
        Steps ``[("scale", StandardScaler()), (name, estimator)]`` or ``[(name, estimator)]``.
    """
    steps = [("scale", StandardScaler())] if scale else []
    return Pipeline([*steps, (str(name), estimator)])


def make_model(name: str, random_state: int | None = None, scale: bool = True) -> Pipeline:
    """The paper's classifier ``name`` (Table VI) as a pipeline.

    Parameters
    ----------
    name : {"mlp", "svm", "rf", "knn", "nb"}
        Classifier.
    random_state : int, optional
        Seed of MLP, SVM and RF.
    scale : bool, default True
        See :func:`make_pipeline`.

    Returns
    -------
    sklearn.pipeline.Pipeline

    Raises
    ------
    ValueError
        For an unknown ``name``.
    """
    if name not in PAPER_MODELS:
        raise ValueError(f"model must be one of {sorted(PAPER_MODELS)}, got {name!r}")
    return make_pipeline(PAPER_MODELS[name](random_state), name=name, scale=scale)
