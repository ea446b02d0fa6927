"""The model registry and the paper's scikit-learn classifiers, Table VI.

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

:data:`MODELS` is the one registry of the classifiers a study can name: the paper's five
(:data:`PAPER_MODELS`) and any added with :func:`register_model`. Each estimator is
wrapped in a :class:`~sklearn.pipeline.Pipeline`, behind a
:class:`~sklearn.preprocessing.StandardScaler` only if asked (``scale=True``): the paper does
not scale its features.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from swgsim.base.registry import Registry

if TYPE_CHECKING:
    from sklearn.base import ClassifierMixin
    from sklearn.pipeline import Pipeline

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ModelSpec:
    """A classifier a study can name.

    Attributes
    ----------
    name : str
        Config name (``model=<name>``, the ``model`` column of results).
    estimator : str or callable
        Dotted path of a scikit-learn-compatible classifier class (or any callable that
        returns one), called with ``settings`` (and ``random_state``).
    settings : mapping
        Keyword arguments beyond the estimator's defaults (lists become tuples).
    seeded : bool
        Whether it takes ``random_state`` (the study's seed).
    label : str
        Display name in reports and figures; default the name in capitals.
    """

    name: str
    estimator: str | Callable[..., Any]
    settings: Mapping[str, Any] = field(default_factory=dict)
    seeded: bool = False
    label: str = ""

    def __post_init__(self) -> None:
        if not self.label:
            object.__setattr__(self, "label", self.name.upper())

    @property
    def target(self) -> str:
        """Dotted path of the estimator (the ``_target_`` of its Hydra config)."""
        e = self.estimator
        return e if isinstance(e, str) else f"{e.__module__}.{e.__qualname__}"

    def build(self, random_state: int | None = None):
        """A fresh, unfitted estimator with these settings."""
        import importlib

        cls = self.estimator
        if isinstance(cls, str):
            module, name = cls.rsplit(".", 1)
            cls = getattr(importlib.import_module(module), name)
        kw = {k: tuple(v) if isinstance(v, list) else v for k, v in self.settings.items()}
        if self.seeded:
            kw["random_state"] = random_state
        return cls(**kw)


#: Every registered classifier, by name (:func:`register_model`).
MODELS: Registry[ModelSpec] = Registry("learner", __name__, "MODELS")
#: Display name of every model, registered or a deep model of ``conf/model/*.yaml``.
MODEL_LABELS: Registry[str] = Registry("learner label", __name__, "MODEL_LABELS", {
    "mlp_torch": "MLP (torch)", "cnn": "CNN", "minirocket": "MiniRocket"}.items())


def register_model(spec: ModelSpec) -> ModelSpec:
    """Add a classifier to :data:`MODELS` (and its label to :data:`MODEL_LABELS`), e.g.
    from a user's package; the study runs it when named in ``study.models``.

    Parameters
    ----------
    spec : ModelSpec

    Returns
    -------
    ModelSpec
        ``spec``.

    Raises
    ------
    ValueError
        A name already registered (or a deep model's) or not a lower-case identifier.
    """
    if not spec.name.isidentifier() or spec.name != spec.name.lower():
        raise ValueError(f"model name must be a lower-case identifier, got {spec.name!r}")
    if spec.name in MODELS or spec.name in MODEL_LABELS:
        raise ValueError(f"model {spec.name!r} is registered already")
    MODEL_LABELS.add(spec.name, spec.label)
    return MODELS.add(spec.name, spec)


def model_label(name: str) -> str:
    """Display name of a model (:data:`MODEL_LABELS`); an unknown name is returned as is."""
    return MODEL_LABELS.get(name, name)


#: The paper's estimators (Table VI), in the order of its tables.
PAPER_MODELS: dict[str, ModelSpec] = {
    s.name: register_model(s) for s in (
        ModelSpec("mlp", "sklearn.neural_network.MLPClassifier",
                  {"hidden_layer_sizes": [10, 10, 10], "activation": "relu"}, seeded=True),
        ModelSpec("svm", "sklearn.svm.SVC", {"kernel": "rbf"}, seeded=True),
        ModelSpec("rf", "sklearn.ensemble.RandomForestClassifier",
                  {"n_estimators": 100, "max_depth": 7}, seeded=True),
        ModelSpec("knn", "sklearn.neighbors.KNeighborsClassifier", {"n_neighbors": 3}),
        ModelSpec("nb", "sklearn.naive_bayes.GaussianNB", {}),
    )
}


def model_config(name: str, scale: bool = False, random_state: Any = "${seed}") -> dict:
    """Hydra config of a registered model: ``_target_: learn.learners.models.make_pipeline``.

    Parameters
    ----------
    name : str
        A key of :data:`MODELS`.
    scale : bool, default False
    random_state : int or str, default "${seed}"
        Seed, or an interpolation of the app's seed.

    Returns
    -------
    dict
        ``{_target_, name, scale, estimator: {_target_, **settings}}``.

    Raises
    ------
    ValueError
        For a name not in :data:`MODELS`.
    """
    spec = get_model(name)
    est = {"_target_": spec.target, **spec.settings}
    if spec.seeded:
        est["random_state"] = random_state
    return {"_target_": "learn.learners.models.make_pipeline", "name": name, "scale": scale,
            "estimator": est}


def get_model(name: str) -> ModelSpec:
    """The registered model of that name.

    Raises
    ------
    ValueError
        Naming the registered models if ``name`` is unknown.
    """
    if name not in MODELS:
        raise ValueError(f"model must be one of {sorted(MODELS)}, got {name!r}")
    return MODELS[name]


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
    """The registered classifier ``name`` (:data:`MODELS`; the paper's: Table VI) as a
    pipeline.

    Parameters
    ----------
    name : str
        A key of :data:`MODELS`, e.g. "mlp", "svm", "rf", "knn", "nb".
    random_state : int, optional
        Seed of the seeded models (the paper's MLP, SVM and RF).
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
    return make_pipeline(get_model(name).build(random_state), name=name, scale=scale)
