"""The extension point: a classifier registered from outside the package runs in the
paper's study and lands in its results and report (docs/ARCHITECTURE.md, "To add a
classifier")."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from sklearn.base import BaseEstimator, ClassifierMixin

from learn import ModelSpec, StudyOptions, register_model, run_paper_study
from learn.learners import models as model_registry


class CentroidClassifier(ClassifierMixin, BaseEstimator):
    """Nearest class centroid on standardised features: a classifier learn does not know."""

    def fit(self, X, y):
        self.mean_, self.scale_ = X.mean(axis=0), X.std(axis=0) + 1e-12
        Z = (X - self.mean_) / self.scale_
        self.classes_ = np.unique(y)
        self.centroids_ = np.stack([Z[y == c].mean(axis=0) for c in self.classes_])
        return self

    def predict(self, X):
        Z = (X - self.mean_) / self.scale_
        d = ((Z[:, None, :] - self.centroids_[None]) ** 2).sum(axis=2)
        return self.classes_[np.argmin(d, axis=1)]


@pytest.fixture
def registered():
    """Register the classifier (removed from the registries after the test)."""
    yield register_model(ModelSpec("centroid", CentroidClassifier, label="Centroid"))
    model_registry.MODELS.pop("centroid")
    model_registry.MODEL_LABELS.pop("centroid")


def test_registered_classifier_runs_in_the_paper_study(registered, tiny_dataset, tmp_path):
    out = run_paper_study(tiny_dataset, tmp_path / "paper",
                          StudyOptions(tables=["VII"], models=["nb", "centroid"],
                                       figures=False), track=False, progress=False)
    res = out["results"]
    mine = res[res["model"] == "centroid"]
    assert len(mine) == 3 * 4  # Selections 1-3 of Table VII, 4 folds each
    assert set(res["model"]) == {"nb", "centroid"}
    # reached 0.771, 0.625, 0.375 on Selections 1-3 of the synthetic data set (chance 1/6):
    # bounds about 0.1 below
    acc = mine.groupby("selection")["test_accuracy"].mean()
    assert acc["selection1"] > 0.65 and acc.min() > 0.27
    csv = pd.read_csv(out["files"]["csv"])
    assert (csv["model"] == "centroid").sum() == 12
    assert "| | MLP | SVM | RF | KNN | NB | Centroid |" in out["files"]["tables"].read_text()


def test_registry_refuses_a_taken_name(registered):
    with pytest.raises(ValueError, match="registered already"):
        register_model(ModelSpec("rf", CentroidClassifier))
    with pytest.raises(ValueError, match="study.models must be among"):
        StudyOptions(models=["nope"]).check()
