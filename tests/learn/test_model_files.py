"""A diagnosis model's file is bounded by what it unpacks to (issue 43, cause 7c): a
``.skops`` zip bomb with a card that matches it is refused from the sizes its zip
directory declares, before skops inflates a member; a real model still loads."""

from __future__ import annotations

import hashlib
import json
import zipfile

import numpy as np
import pytest


@pytest.fixture
def model_file(tmp_path):
    from sklearn.ensemble import HistGradientBoostingClassifier

    from learn.monitor.model import DiagnosisModel
    from learn.monitor.model_io import save_model

    clf = HistGradientBoostingClassifier(max_iter=2).fit(np.eye(4), [0, 1, 0, 1])
    return save_model(DiagnosisModel(["healthy", "x"], clf), tmp_path / "m", [])


def test_a_real_model_loads(model_file):
    from learn.monitor.model_io import load_model

    assert load_model(model_file).classes == ["healthy", "x"]


def test_a_zip_bomb_with_a_matching_card_refused_before_inflating(model_file, monkeypatch):
    import skops.io as sio

    from learn.monitor import model_io

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
