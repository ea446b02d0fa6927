"""A diagnosis model's file is bounded by what it unpacks to (issue 43, cause 7c): a
``.skops`` zip bomb with a card that matches it is refused from the sizes its zip
directory declares, before skops inflates a member; a real model still loads."""

from __future__ import annotations

import hashlib
import json
import zipfile

import numpy as np
import pytest
from bad_input import small_model

from swgmon.assessment.model import read_through, reading_curve
from swgmon.assessment.model_io import load_model, save_model


@pytest.fixture
def model_file(tmp_path):
    return save_model(small_model(), tmp_path / "m", [])


def test_a_real_model_loads(model_file):
    assert load_model(model_file).classes == ["healthy", "x"]


def test_the_reading_curve_travels_with_the_model_and_reads_a_shrunk_regressor_true(
        tmp_path):
    """A regressor that reads 0.2 + 0.6 s (shrunk toward the middle, as the tip crack's
    across gears) read back through its curve gives s on average at every level; beyond
    the curve's ends one for one, and a flat top does not amplify; the curve is saved,
    loaded and refused when not increasing."""
    rng = np.random.default_rng(0)
    true = np.repeat(np.linspace(0.25, 1.0, 7), 300)
    pred = 0.2 + 0.6 * true + 0.03 * rng.standard_normal(true.size)
    curve = reading_curve(pred, true)
    back = read_through(curve, pred)
    assert max(abs(np.median(back[true == v]) - v) for v in np.unique(true)) < 0.01
    assert read_through(curve, np.array([curve[1][-1] + 0.05]))[0] == pytest.approx(1.05)
    flat = reading_curve(np.minimum(pred, 0.5), true)  # the regressor saturates at 0.5
    assert np.all(np.diff(flat[1]) > 0) and read_through(flat, np.array([0.6]))[0] < 1.2
    path = save_model(small_model(reading={"x": curve}), tmp_path / "c", [])
    got = load_model(path).reading["x"]
    assert np.array_equal(got[0], curve[0]) and np.array_equal(got[1], curve[1])
    bad = save_model(small_model(reading={"x": (curve[0], curve[1][::-1])}),
                     tmp_path / "b", [])
    with pytest.raises(ValueError, match="the reading curve of x must be two finite "
                                         "increasing arrays"):
        load_model(bad)


def test_a_zip_bomb_with_a_matching_card_refused_before_inflating(model_file, monkeypatch):
    import skops.io as sio

    from swgmon.assessment import model_io

    monkeypatch.setattr(model_io, "MAX_UNPACKED_BYTES", 4 * 2**20)
    with zipfile.ZipFile(model_file, "a", zipfile.ZIP_DEFLATED) as z:
        with z.open("padding.bin", "w") as f:  # 8 MiB of zeros: some 8 kB compressed
            for _ in range(8):
                f.write(bytes(2**20))
    card = model_file.with_name("m.card.json")
    c = json.loads(card.read_text())
    c["sha256"] = hashlib.sha256(model_file.read_bytes()).hexdigest()  # it matches
    card.write_text(json.dumps(c))

    def inflated(*a, **k):
        raise AssertionError("skops read the zip before its size was checked")
    monkeypatch.setattr(sio, "get_untrusted_types", inflated)
    monkeypatch.setattr(sio, "loads", inflated)
    with pytest.raises(ValueError, match=r"^diagnosis_model: .*m.skops unpacks to 8.\d MiB "
                       r"in \d+ members, over the 4 MiB") as info:
        model_io.load_model(model_file)
    assert "\n" not in str(info.value)


def _bad_parts():
    from sklearn.ensemble import HistGradientBoostingRegressor
    from sklearn.naive_bayes import GaussianNB

    nb = GaussianNB().fit(np.eye(4), [0, 1, 0, 1])  # of no type the gate refuses
    other = HistGradientBoostingRegressor(max_iter=2).fit(np.eye(3), [0.0, 0.1, 0.0])
    return {
        "another estimator as the classifier": (
            {"classifier": nb}, "the classifier must be a fitted "
                                "HistGradientBoostingClassifier of 2 classes on 4 inputs, got "
                                "GaussianNB"),
        "an int as the classifier": ({"classifier": 3}, "got int"),
        "classes reversed": ({"classes": ["x", "healthy"]},
                             "classes must be distinct names, healthy first"),
        "no severity regressor": ({"severity": {}},
                                  "a severity regressor for every class but healthy: "
                                  "missing ['x']"),
        "a regressor of other inputs": (
            {"severity": {"x": (other, (-0.02, 0.03))}},
            "the severity regressor of x must be a fitted HistGradientBoostingRegressor on "
            "4 inputs"),
    }


@pytest.mark.parametrize("case", list(_bad_parts()))
def test_a_card_matched_model_of_other_parts_is_refused_when_loaded(tmp_path, case):
    """Issue 82, cause 7: skops' defaults trust every scikit-learn estimator, so a model
    whose card matches loaded with another classifier, an int, its classes reversed or a
    fault without its regressor, and crashed after the whole stream (AttributeError,
    KeyError); now one line when it is loaded."""
    change, words = _bad_parts()[case]
    path = save_model(small_model(**change), tmp_path / "bad", [])  # its card matches it
    with pytest.raises(ValueError) as info:
        load_model(path)
    line = str(info.value)
    assert line.startswith(f"diagnosis_model: {path}: ") and words in line, line
    assert "\n" not in line


def test_a_trusted_pickle_of_a_model_from_before_the_reading_curve_reads_without_one(
        tmp_path):
    """A pickle restores the fields it was saved with: one saved before the reading curve
    has none and loads as a .skops file of then does, its estimates unchanged."""
    import joblib

    old = small_model()
    for name in ("reading", "reading_without"):
        del vars(old)[name]
    joblib.dump(old, tmp_path / "old.joblib")
    assert load_model(tmp_path / "old.joblib", trust_pickle=True).reading == {}
