"""The monitor's inputs: a stream it cannot take, a diagnosis model file that is none (not a
regular file, sparse, a pickle not trusted, a model card that does not match) and its
options. Each ends in one line naming the key or file (exit 2 from swgsim-monitor) before
any work, no output folder made."""

from __future__ import annotations

import os
import subprocess
import types
from pathlib import Path

import numpy as np
import pytest
from bad_input import app_line, message, small_model

from swgsim.datasets import schema as dsio


# ------------------------------------------------------------------ a stream
@pytest.fixture(scope="module")
def stream(life):
    return dsio.load(life)


def _model(ds):
    fs = float(ds.attrs["sample_rate_hz"])
    pts = np.stack([ds["n_in_rpm"].values, ds["t_out_nm"].values], axis=1)
    return types.SimpleNamespace(sample_rate_hz=fs, window_s=ds.sizes["time"] / fs,
                                 points_range=np.array([pts.min(0), pts.max(0)]),
                                 n_features=0)


def _hours(f):
    return lambda ds: ds.assign(hour=("sample", f(ds["hour"].values.copy())))


def _set(values):
    def f(h):
        h[:len(values)] = values
        return h
    return f


STREAM_CASES = {
    "negative hours": (_hours(lambda h: h - 5.0), "'hour' must be finite and >= 0"),
    "a NaN hour": (_hours(_set([0.0, np.nan])), "'hour' must be finite and >= 0"),
    "an infinite hour": (_hours(lambda h: np.r_[h[:-1], np.inf]), "finite and >= 0"),
    "hours going back": (_hours(_set([0.0, 1.0, 0.5])), "hours must increase"),
    "one window": (lambda ds: ds.isel(sample=[0]), "hours must increase"),
    "no commissioning": (lambda ds: ds.assign(commissioning=("sample", np.zeros(
        ds.sizes["sample"], bool))), "commissioning windows must be the first"),
    "commissioning late": (lambda ds: ds.assign(commissioning=("sample", np.r_[
        False, ds["commissioning"].values[1:]])), "commissioning windows must be the first"),
    "all commissioning": (lambda ds: ds.assign(commissioning=("sample", np.ones(
        ds.sizes["sample"], bool))), "has no windows after commissioning to monitor"),
    "a bridge missing": (lambda ds: ds.isel(sensor=[0, 1, 2, 3]), "bridges"),
    "no hour variable (a grid data set)": (lambda ds: ds.drop_vars("hour"), "'hour'"),
    "sample rate off": (lambda ds: ds.assign_attrs(sample_rate_hz=2 * ds.attrs[
        "sample_rate_hz"]), "sample rate"),
    "a load outside the model's range": (lambda ds: ds.assign(t_out_nm=ds["t_out_nm"] * 10),
                                         "outside the model's training range"),
}


@pytest.mark.parametrize("case", STREAM_CASES)
def test_a_stream_the_monitor_cannot_take_is_refused(stream, case):
    from swgmon.advisories.stream import check_stream
    from swgmon.detection.rule import RuleConfig

    spoil, named = STREAM_CASES[case]
    ds = spoil(stream.copy())
    msg = message(lambda: check_stream(ds, _model(stream), RuleConfig(min_normal_windows=2),
                                       "stream=life"))
    assert msg.startswith("stream=life") and named in msg, msg
    if named in ("sample rate", "outside the model's training range"):
        # a model refused for this stream: the same line names the command making one
        assert msg.endswith("; a model for it: swgsim-train experiment=own_joint "
                            "own_joint.stream=stream=life"), msg


# ------------------------------------------------------------------ a model file
def _pickled(obj):
    def make(p: Path):
        import joblib
        joblib.dump(obj, p)
    return make


MODEL_CASES = {
    "/dev/zero": ("/dev/zero", "is a character device, not a regular file"),
    "a FIFO": (lambda p: os.mkfifo(p), "is a FIFO"),
    "a folder": (lambda p: p.mkdir(), "is a folder"),
    "a sparse 3 GB file": (lambda p: subprocess.run(["truncate", "-s", "3G", str(p)],
                                                    check=True), "over the 2.00 GiB"),
    "a sparse 1 GB file": (lambda p: subprocess.run(["truncate", "-s", "1G", str(p)],
                                                    check=True), "a sparse file"),
    "random bytes": (lambda p: p.write_bytes(os.urandom(4096)), "is a pickle, which runs any "
                                                                  "code it names"),
    "a pickled dict": (_pickled({"model": 1}), "is a pickle, which runs any code it names"),
    "a trusted pickled dict": (_pickled({"model": 1}), "holds a dict, not a diagnosis model"),
    "a .skops without its card": (lambda p: p.with_suffix(".skops").write_bytes(b"x" * 64),
                                  "has no readable model card"),
    "a .skops changed after its card": ("changed", "SHA-256 differs"),
    "a card of another file": ("other card", "is not that of"),
    "missing": (lambda p: None, "no diagnosis model"),
}


def _skops_case(tmp_path: Path, case: str) -> Path:
    """A real model file and card, then spoiled."""
    from sklearn.ensemble import HistGradientBoostingClassifier

    from swgmon.assessment.model import DiagnosisModel
    from swgmon.assessment.model_io import save_model

    clf = HistGradientBoostingClassifier(max_iter=2).fit(np.eye(4), [0, 1, 0, 1])
    p = save_model(DiagnosisModel(["healthy", "x"], clf), tmp_path / "m", [])
    if case == "changed":
        data = bytearray(p.read_bytes())
        data[-20] ^= 1
        p.write_bytes(bytes(data))
    else:
        card = p.with_name("m.card.json")
        card.write_text(card.read_text().replace('"m.skops"', '"other.skops"'))
    return p


@pytest.mark.parametrize("case", MODEL_CASES)
def test_a_diagnosis_model_that_is_none_is_refused_before_reading(tmp_path, life, case):
    make, named = MODEL_CASES[case]
    if make in ("changed", "other card"):
        p = _skops_case(tmp_path, make)
    else:
        p = Path(make) if isinstance(make, str) else tmp_path / "model.joblib"
        if "skops" in case:
            p = p.with_suffix(".skops")
        if not isinstance(make, str):
            make(p)
    trust = ["trust_pickle=true"] if "trusted" in case else []
    line = app_line("monitor", [f"stream={life}", f"diagnosis_model={p}", *trust,
                                f"out_dir={tmp_path}/out", "~logger"], tmp_path)
    assert line.startswith("swgsim-monitor: error: ") and named in line, line
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------ options
OPTION_CASES = {  # case -> (overrides, the key the line must name)
    "monitor rule.design_hours=0": (["rule.design_hours=0"], "rule.design_hours"),
    "monitor rule.shift_sigma=-1": (["rule.shift_sigma=-1"], "rule.shift_sigma"),
    "monitor rule.max_delay_windows=0": (["rule.max_delay_windows=0"],
                                         "rule.max_delay_windows"),
    "monitor rule.min_normal_windows=1": (["rule.min_normal_windows=1"],
                                          "rule.min_normal_windows"),
    "monitor confirm_h=-1": (["confirm_h=-1"], "confirm_h"),
    "monitor naming.prior_odds=0": (["naming.prior_odds=0"], "naming.prior_odds"),
    "monitor naming.wrong_median_p above right": (["naming.wrong_median_p=0.45"],
                                                  "naming.wrong_median_p"),
    "monitor naming.virtual_windows even": (["naming.virtual_windows=8"],
                                            "naming.virtual_windows must be odd"),
    "monitor naming.drift_rate_points even": (["naming.drift_rate_points=12"],
                                              "naming.drift_rate_points must be odd"),
    "monitor naming.drift_fine_k=0": (["naming.drift_fine_k=0"], "naming.drift_fine_k"),
    "monitor normal.fit.segment_k=0": (["normal.fit.segment_k=0"], "normal.fit.segment_k"),
    "monitor an unknown hypothesis": (["naming.hypotheses=[nope]"],
                                      "naming.hypotheses: 'nope' is no hypothesis"),
    "monitor confirm_h=nan": (["confirm_h=nan"], "confirm_h"),
    "monitor an unknown rule key": (["rule.bogus=1"], "rule.bogus: unknown key"),
    "monitor an old key": (["rule.min_baseline=3"], "rule.min_normal_windows"),
    "monitor gear=9": (["gear=9", "diagnosis_model=MODEL"], "gear"),
}


@pytest.fixture(scope="module")
def any_model(tmp_path_factory) -> Path:
    """A file holding a small diagnosis model (the cases are refused before it is
    used)."""
    import joblib

    p = tmp_path_factory.mktemp("model") / "small.joblib"
    joblib.dump(small_model(), p)
    return p


@pytest.mark.parametrize("case", OPTION_CASES)
def test_a_bad_monitor_option_is_one_line(tmp_path, life, any_model, case):
    over, key = OPTION_CASES[case]
    over = [o.replace("MODEL", str(any_model)) for o in over]
    model = [] if any(o.startswith("diagnosis_model=") for o in over) else [
        f"diagnosis_model={tmp_path}/m.joblib"]
    base = [f"stream={life}", *model, "trust_pickle=true", "~logger"]
    line = app_line("monitor", [*base, f"out_dir={tmp_path}/out", *over], tmp_path)
    assert line.startswith("swgsim-monitor: error: ") and key in line, line
    assert not (tmp_path / "out").exists()
