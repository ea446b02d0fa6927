"""Protocols of paper Sec. IV: splits from metadata, no leaks (learn.studies.protocols)."""

from __future__ import annotations

import numpy as np
import pytest

from learn.inputs.features import extract_features
from learn.learners.models import make_model
from learn.studies.protocols import PROTOCOLS, evaluate, make_splits, protocol_splits


@pytest.fixture(scope="module")
def meta(synthetic_ds):
    return extract_features(synthetic_ds, 1).meta


@pytest.mark.parametrize("protocol", sorted(PROTOCOLS))
def test_splits_have_no_leak(meta, protocol):
    splits = protocol_splits(meta, protocol, random_state=0)
    disturbed = PROTOCOLS[protocol].disturbed
    rows = np.flatnonzero(meta["disturbed"].to_numpy() == disturbed)
    assert len(splits) == (4 if protocol.startswith("cv") else 3)
    tested = np.concatenate([s.test for s in splits])
    assert np.array_equal(np.sort(tested), rows)  # every window of the flag tested once
    key = meta["gear"].astype(str) + "/" + meta["fault"] + "/" + meta["variant"].astype(str)
    for s in splits:
        assert len(np.intersect1d(s.train, s.test)) == 0
        assert np.array_equal(np.union1d(s.train, s.test), rows)
        assert (meta["disturbed"].iloc[s.train] == disturbed).all()
        # a (gear, fault, variant) group never straddles training and test
        assert not set(key.iloc[s.train]) & set(key.iloc[s.test])
        if protocol.startswith("ood"):
            held_out = int(s.name.removeprefix("gear"))
            assert set(meta["gear"].iloc[s.test]) == {held_out}
            assert held_out not in set(meta["gear"].iloc[s.train])
        else:  # stratified: every class in every test fold
            assert set(meta["fault"].iloc[s.test]) == set(meta["fault"])


def test_ood_order_and_labels_follow_paper(meta):
    splits = protocol_splits(meta, "ood_clean")
    assert [s.label for s in splits] == ["1,2 -> 3", "2,3 -> 1", "1,3 -> 2"]


def test_evaluate_beats_chance_and_counts(synthetic_ds):
    f = extract_features(synthetic_ds, 1)
    y = f.meta["fault"].to_numpy()
    splits = protocol_splits(f.meta, "ood_clean")
    r = evaluate(make_model("nb"), f.X, y, splits)
    assert r.train_accuracy.shape == r.test_accuracy.shape == (3,)
    assert r.confusion.sum() == sum(len(s.test) for s in splits)
    assert r.labels[0] == "healthy" and len(r.labels) == 6
    assert r.mean_test_accuracy > 0.5  # chance: 1/6


def test_bad_arguments(meta):
    with pytest.raises(ValueError, match="protocol must be one of"):
        protocol_splits(meta, "kfold")
    with pytest.raises(ValueError, match="scheme must be one of"):
        make_splits(meta, "shuffle", disturbed=False)
    with pytest.raises(ValueError, match="test gear 7 is not in the data"):
        make_splits(meta, "leave_one_gear", disturbed=False, test_gears=[7])


def test_training_accuracy_is_read_on_evenly_spaced_training_rows(monkeypatch):
    """At most TRAIN_ACCURACY_ROWS training windows, first and last among them, in proportion
    to each class; a split with fewer is read whole; the test windows always whole."""
    from learn.studies import protocols
    from learn.studies.protocols import Split, fit_split, training_accuracy_rows

    monkeypatch.setattr(protocols, "TRAIN_ACCURACY_ROWS", 40)
    train = np.arange(1, 201)  # 200 windows, two classes in blocks of 50
    rows = training_accuracy_rows(train)
    assert len(rows) == 40 and rows[0] == 1 and rows[-1] == 200
    assert np.all(np.diff(rows) > 0) and np.isin(rows, train).all()
    assert np.array_equal(training_accuracy_rows(train[:40]), train[:40])

    class Recorder:  # predicts class "a" and records how many windows it was asked for
        seen: list = []

        def get_params(self, deep=True):
            return {}

        def fit(self, X, y):
            return self

        def predict(self, X):
            Recorder.seen.append(len(X))
            return np.full(len(X), "a")

    X = np.zeros((260, 1))
    y = np.where((np.arange(260) // 50) % 2 == 0, "a", "b")
    out = fit_split(Recorder(), X, y, Split("s", "s", train, np.arange(201, 260)), ["a", "b"])
    assert Recorder.seen == [40, 59]
    assert out[0] == pytest.approx(np.mean(y[rows] == "a"))
    assert abs(out[0] - np.mean(y[train] == "a")) < 0.05
