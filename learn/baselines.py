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

Everything else is scikit-learn's default, as in the paper ("standard settings").
:data:`PAPER_MODELS` is the one place of these settings: :func:`make_model` builds the
estimators from it, and :func:`model_config` gives the Hydra config (``_target_``) that
the apps register as ``model=<name>``. Each estimator is wrapped in a
:class:`~sklearn.pipeline.Pipeline`, behind a :class:`~sklearn.preprocessing.StandardScaler`
only if asked (``scale=True``): the paper does not scale its features.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from sklearn.base import ClassifierMixin
    from sklearn.pipeline import Pipeline

log = logging.getLogger(__name__)

#: Display names of the paper (Table VI), keyed by config name.
MODEL_LABELS = {"mlp": "MLP", "svm": "SVM", "rf": "RF", "knn": "KNN", "nb": "NB"}


#: The paper's estimators (Table VI): class path, settings beyond scikit-learn's
#: defaults, and whether they take ``random_state``.
PAPER_MODELS: dict[str, tuple[str, dict[str, Any], bool]] = {
    "mlp": ("sklearn.neural_network.MLPClassifier",
            {"hidden_layer_sizes": [10, 10, 10], "activation": "relu"}, True),
    "svm": ("sklearn.svm.SVC", {"kernel": "rbf"}, True),
    "rf": ("sklearn.ensemble.RandomForestClassifier", {"n_estimators": 100, "max_depth": 7},
           True),
    "knn": ("sklearn.neighbors.KNeighborsClassifier", {"n_neighbors": 3}, False),
    "nb": ("sklearn.naive_bayes.GaussianNB", {}, False),
}


def model_config(name: str, scale: bool = False, random_state: Any = "${seed}") -> dict:
    """Hydra config of a paper model: ``_target_: learn.baselines.make_pipeline``.

    Parameters
    ----------
    name : {"mlp", "svm", "rf", "knn", "nb"}
    scale : bool, default False
    random_state : int or str, default "${seed}"
        Seed, or an interpolation of the app's seed.

    Returns
    -------
    dict
        ``{_target_, name, scale, estimator: {_target_, **settings}}``.
    """
    path, settings, seeded = _paper_model(name)
    est = {"_target_": path, **settings}
    if seeded:
        est["random_state"] = random_state
    return {"_target_": "learn.baselines.make_pipeline", "name": name, "scale": scale,
            "estimator": est}


def _paper_model(name: str) -> tuple[str, dict[str, Any], bool]:
    if name not in PAPER_MODELS:
        raise ValueError(f"model must be one of {sorted(PAPER_MODELS)}, got {name!r}")
    return PAPER_MODELS[name]


def make_pipeline(estimator: ClassifierMixin, name: str = "clf", scale: bool = False) -> Pipeline:
    """Wrap a classifier behind an optional :class:`StandardScaler`.

    This is the ``_target_`` of ``conf/model/*.yaml``.

    Parameters
    ----------
    estimator : classifier
        Any scikit-learn-compatible classifier (``fit`` / ``predict``).
    name : str, default "clf"
        Step name of the classifier in the pipeline (the model's config name).
    scale : bool, default False
        Standardise features (zero mean, unit variance, fitted on the training split).

    Returns
    -------
    sklearn.pipeline.Pipeline
        Steps ``[("scale", StandardScaler()), (name, estimator)]`` or ``[(name, estimator)]``.
    """
    from sklearn.pipeline import Pipeline
    from sklearn.preprocessing import StandardScaler

    steps = [("scale", StandardScaler())] if scale else []
    return Pipeline([*steps, (str(name), estimator)])


def make_model(name: str, random_state: int | None = None, scale: bool = False) -> Pipeline:
    """The paper's classifier ``name`` (Table VI) as a pipeline.

    Parameters
    ----------
    name : {"mlp", "svm", "rf", "knn", "nb"}
        Classifier.
    random_state : int, optional
        Seed of MLP, SVM and RF.
    scale : bool, default False
        See :func:`make_pipeline`.

    Returns
    -------
    sklearn.pipeline.Pipeline

    Raises
    ------
    ValueError
        For an unknown ``name``.
    """
    import importlib

    path, settings, seeded = _paper_model(name)
    module, cls = path.rsplit(".", 1)
    kw = {k: tuple(v) if isinstance(v, list) else v for k, v in settings.items()}
    if seeded:
        kw["random_state"] = random_state
    est = getattr(importlib.import_module(module), cls)(**kw)
    return make_pipeline(est, name=name, scale=scale)
