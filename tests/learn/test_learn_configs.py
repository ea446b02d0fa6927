"""Every option of the train config composes and instantiates (conf/, learn.learners.models)."""

from __future__ import annotations

from pathlib import Path

import pytest
from hydra.core.config_store import ConfigStore
from hydra.utils import instantiate
from omegaconf import OmegaConf
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler

from learn.learners.models import PAPER_MODELS, make_model
from learn.studies.protocols import PROTOCOLS
from swgcli import CONF_DIR, compose_app

CONF = Path(CONF_DIR)


def compose_train(overrides=()):
    return compose_app("train", overrides)


def _options(group: str) -> list[str]:
    """Options of a config group: YAML files in conf/ and nodes generated in Python."""
    import swgcli.schema  # noqa: F401  (registers the generated groups)

    stored = [n.removesuffix(".yaml") for n in ConfigStore.instance().list(group)]\
        if group in ConfigStore.instance().repo else []
    return sorted({*(p.stem for p in (CONF / group).glob("*.yaml")), *stored})


def _plain(params: dict) -> dict:
    return {k: list(v) if isinstance(v, tuple) else v for k, v in params.items()
            if k != "steps" and not hasattr(v, "get_params")}


@pytest.mark.parametrize("name", sorted(PAPER_MODELS))
def test_model_config_instantiates_to_paper_model(name):
    cfg = compose_train([f"model={name}", "seed=3"])
    est = instantiate(cfg.model, _convert_="all")
    assert isinstance(est, Pipeline)
    assert len(est.steps) == 1 and est.steps[-1][0] == name  # the paper scales nothing
    assert _plain(est.get_params()) == _plain(make_model(name, random_state=3).get_params())


#: The paper's Table VI, written out here (not read from learn): estimator class and the
#: settings it names; everything else is scikit-learn's default.
TABLE_VI = {
    "mlp": ("sklearn.neural_network.MLPClassifier",
            {"hidden_layer_sizes": (10, 10, 10), "activation": "relu"}),
    "svm": ("sklearn.svm.SVC", {"kernel": "rbf"}),
    "rf": ("sklearn.ensemble.RandomForestClassifier", {"n_estimators": 100, "max_depth": 7}),
    "knn": ("sklearn.neighbors.KNeighborsClassifier", {"n_neighbors": 3}),
    "nb": ("sklearn.naive_bayes.GaussianNB", {}),
}
#: The deep models, the only ones written as YAML (conf/model/*.yaml).
DEEP = {"mlp_torch": "learn.learners.nets.MLPClassifierTorch",
        "cnn": "learn.learners.nets.CNN1DClassifier",
        "minirocket": "learn.learners.rocket.MiniRocketClassifier"}


def _cls(path: str):
    import importlib

    module, name = path.rsplit(".", 1)
    return getattr(importlib.import_module(module), name)


def test_model_options_are_table_vi_and_the_deep_yaml_models():
    assert set(_options("model")) == set(TABLE_VI) | set(DEEP)
    assert {p.stem for p in (CONF / "model").glob("*.yaml")} == set(DEEP)
    assert list(PAPER_MODELS) == list(TABLE_VI)  # the paper's order of its tables


@pytest.mark.parametrize("name", sorted(TABLE_VI))
def test_model_option_is_the_table_vi_estimator(name):
    path, settings = TABLE_VI[name]
    est = instantiate(compose_train([f"model={name}", "seed=3"]).model, _convert_="all")[-1]
    assert type(est) is _cls(path)
    params, defaults = (_plain(p) for p in (est.get_params(), _cls(path)(**settings).get_params()))
    params.pop("random_state", None), defaults.pop("random_state", None)
    assert params == defaults  # Table VI's settings (a list from YAML for a tuple), else
    # scikit-learn's defaults


@pytest.mark.parametrize("name", sorted(DEEP))
def test_yaml_model_is_its_deep_estimator(name):
    est = instantiate(compose_train([f"model={name}"]).model, _convert_="all")[-1]
    assert type(est) is _cls(DEEP[name])


def test_table_vi_settings():
    assert make_model("rf")[-1].get_params()["n_estimators"] == 100
    assert make_model("rf")[-1].get_params()["max_depth"] == 7
    assert make_model("knn")[-1].get_params()["n_neighbors"] == 3
    assert make_model("mlp")[-1].get_params()["hidden_layer_sizes"] == (10, 10, 10)
    assert make_model("svm")[-1].get_params()["kernel"] == "rbf"
    assert not isinstance(make_model("nb")[0], StandardScaler)
    assert isinstance(make_model("nb", scale=True)[0], StandardScaler)
    with pytest.raises(ValueError, match="model must be one of"):
        make_model("xgb")


#: The paper's protocols (Sec. IV), written out here: scheme, disturbed, splits.
PAPER_PROTOCOLS = {
    "cv_clean": ("group_kfold", False, {"n_splits": 4}),
    "cv_disturbed": ("group_kfold", True, {"n_splits": 4}),
    "ood_clean": ("leave_one_gear", False, {"test_gears": [3, 1, 2]}),
    "ood_disturbed": ("leave_one_gear", True, {"test_gears": [3, 1, 2]}),
}


@pytest.mark.parametrize("name", sorted(PAPER_PROTOCOLS))
def test_protocol_config_matches_paper_protocol(name):
    assert set(PROTOCOLS) == set(PAPER_PROTOCOLS)
    p = OmegaConf.to_container(compose_train([f"protocol={name}", "seed=5"]).protocol,
                               resolve=True)
    scheme, disturbed, splits = PAPER_PROTOCOLS[name]
    assert p == {"name": name, "scheme": scheme, "disturbed": disturbed, "random_state": 5,
                 "n_splits": 4, "test_gears": None, **splits}


@pytest.mark.parametrize("group", ["stored", "features", "logger", "paths"])
def test_every_option_composes_and_resolves(group):
    for opt in _options(group):
        cfg = compose_train([f"{group}={opt}"])
        OmegaConf.to_container(cfg, resolve=True)  # every interpolation resolves
    assert compose_train().task == "study"


@pytest.mark.parametrize("experiment", [e for e in _options("experiment") if e != "transfer"])
def test_experiments_compose(experiment):
    cfg = compose_train([f"experiment={experiment}"])
    OmegaConf.to_container(cfg, resolve=True)
    table_protocol = {"table_vii": "cv_clean", "table_viii": "cv_disturbed",
                      "table_ix": "ood_clean", "table_x": "ood_disturbed"}
    if experiment in table_protocol:
        assert cfg.protocol.name == table_protocol[experiment]
