"""The condition monitor (swgmon): the rule's false-alarm rate against its design,
its bounds, bad input, and the monitor end to end on tiny lives (a planted step fault
detected and named, a sensor fault named as a sensor fault)."""

import dataclasses
import os
import types

import numpy as np
import pytest

from swgmon.assessment.sensor_check import NamingConfig
from swgmon.detection.laws import LawFit
from swgmon.detection.rule import (
    RuleConfig,
    check_commissioning,
    conformal_p,
    log_bet,
    log_bets,
    min_calibration,
    run_cusums,
    threshold,
)


def test_betting_function_integrates_to_one():
    from scipy.integrate import quad

    # p = exp(-u): f(p) dp = (1 − e^-u (1 + u)) / u² du, bounded; beyond u = 600 the
    # integrand is 1/u² to double precision (tail 1/600)
    val, _ = quad(lambda u: float(np.exp(log_bet(np.array([np.exp(-u)]))[0] - u)), 0, 600,
                  limit=400, points=[1, 10, 100])
    assert val + 1 / 600 == pytest.approx(1.0, abs=1e-8)


def test_false_alarm_rate_within_design_on_healthy_streams():
    """Healthy streams: calibration and stream from one distribution, fresh per stream.
    Design: one alarm per 2000 windows; Lorden's bound makes the rate at most that."""
    rule = RuleConfig(design_hours=2000 / 60)
    h = threshold(rule, 1.0)
    rng = np.random.default_rng(1)
    n_alarm, n_win = 0, 0
    for _ in range(40):
        cal = np.sort(rng.standard_t(4, size=120))
        x = rng.standard_t(4, size=20_000)
        lf = log_bets(conformal_p(x, cal, rng.uniform(size=x.size)), rule)
        n_alarm += len(run_cusums(lf, h, latch=False)[1])
        n_win += x.size
    assert 0 < n_alarm / n_win <= 1 / 2000
    # and the rule is not blind: a shift of one scale is caught within a few windows
    cal = np.sort(rng.normal(size=120))
    lf = log_bets(conformal_p(rng.normal(size=200) + 1.5, cal, rng.uniform(size=200)), rule)
    _, alarms = run_cusums(lf, h)
    assert alarms and alarms[0] < 60


def test_min_calibration_is_the_reach_bound():
    rule = RuleConfig()
    n = min_calibration(rule, 1.0)
    h = threshold(rule, 1.0)
    assert rule.max_delay_windows * log_bet(1 / (n + 1)) >= h
    assert rule.max_delay_windows * log_bet(1 / n) < h


def test_short_commissioning_refused_with_the_minimum():
    pts = np.repeat([[2000.0, 7.0], [4000.0, 7.0]], [80, 20], axis=0)
    with pytest.raises(ValueError, match=r"20 windows at 4000 rpm, 7 N m, at least 60"):
        check_commissioning(pts, RuleConfig(), 1.0)
    with pytest.raises(ValueError, match="no commissioning windows"):
        check_commissioning(pts[:0], RuleConfig(), 1.0)


def _stream(n=200, n_comm=120, hours=None, fs=10e3):
    from swgsim.datasets.schema import make_dataset

    meta = {"gear": np.ones(n, int), "fault": np.full(n, "healthy"), "variant": np.zeros(n, int),
            "severity": np.zeros(n), "position_deg": np.full(n, np.nan),
            "n_in_rpm": np.full(n, 4000.0), "t_out_nm": np.tile([7.0, 70.0], n // 2),
            "disturbed": np.ones(n, bool), "reference": np.zeros(n, bool),
            "efficiency": np.full(n, 0.7), "n_in_mean_rpm": np.full(n, 4000.0),
            "t_out_mean_nm": np.full(n, 7.0)}
    ds = make_dataset(np.zeros((n, 5, 600), np.float32), np.arange(600) / fs, meta)
    ds["hour"] = ("sample", np.arange(n) / 60.0 if hours is None else hours)
    ds["commissioning"] = ("sample", np.arange(n) < n_comm)
    return ds


MODEL = types.SimpleNamespace(sample_rate_hz=10e3, window_s=0.06,
                              points_range=np.array([[4000.0, 7.0], [4000.0, 70.0]]))


@pytest.mark.parametrize("ds, match", [
    (_stream(n_comm=0), "commissioning windows must be the first"),
    (_stream(hours=np.r_[np.arange(100), 50, np.arange(101, 200)] / 60.0),
     "hours must increase"),
    (_stream(fs=20e3), "sample rate"),
    (_stream(n_comm=40), "commissioning too short"),
])
def test_stream_refused_before_any_work(ds, match):
    from swgmon.advisories.stream import check_stream

    with pytest.raises(ValueError, match=match):
        check_stream(ds, MODEL, RuleConfig(), "s")


def test_stream_outside_the_models_operating_points_refused():
    from swgmon.advisories.stream import check_stream

    m = types.SimpleNamespace(**{**vars(MODEL), "points_range": np.array([[2000.0, 7.0],
                                                                           [3000.0, 70.0]])})
    with pytest.raises(ValueError, match="outside the model's training range"):
        check_stream(_stream(), m, RuleConfig(), "s")


TINY_STUDY = dict(seeds=[0], healthy_hours=10.0, commissioning_h=4.0, fault_life_h=2.0,
                  onset_window_h=[0.5, 1.0], growth_h=0.5, train_fault_h=0.5,
                  train_healthy_h=2.0, train_variants=2,
                  faults=["eccentric_wg", "sensor_offset_step"], gears=[3], detector_hours=2.0,
                  nuisances={})


def _offset_life(fault):
    """Gear 3's 5-h life (seed 9) with ``fault`` from the end of commissioning (4 h)."""
    from swgsim.datasets.schedule import LifeConfig

    return LifeConfig(hours=5.0, commissioning_h=4.0, life_seed=9, fault=fault)


def _heavier_tool_life():
    """Gear 3's 7-h life (seed 9) with a 10 % heavier tool from the end of commissioning."""
    from swgsim.datasets.conditions import ConditionsConfig
    from swgsim.datasets.schedule import LifeConfig

    return LifeConfig(hours=7.0, commissioning_h=4.0, life_seed=9,
                      conditions=ConditionsConfig(payload=[[4.0, 1.1]]))


#: The faults of test_offset_on_a_wg_bending_bridge_named_a_sensor_fault's lives.
OFFSET_VS_WG = [("sensor_offset_step", 4.0, 0.02, 1), ("eccentric_wg", 4.0, 0.1, None)]


@pytest.fixture(scope="module")
def tiny_banks(tiny_bench):
    """tiny_bench's plan and its gears' records, shared by its parts as in a worker (and
    with the worker's other tests of the bench: tests/conftest.py). The records of this
    module's own lives of gear 3 (an eccentric WG at its position, the heavier tool's
    loads) are asked for here, to be simulated with the evaluation's, in one batch."""
    from swgsim.datasets.life import LifeSimulator
    from swgsim.datasets.schedule import FaultOnset

    p, banks = tiny_bench
    for life in (_heavier_tool_life(), *(_offset_life(FaultOnset(f, h, s, sensor=b))
                                         for f, h, s, b in OFFSET_VS_WG)):
        LifeSimulator(p, 3, life, banks[3])  # asks for its records
    return tiny_bench


@pytest.fixture(scope="module")
def tiny_eval(tiny_banks):
    """The monitor's part of held-out gear 3 of tiny_bench (the diagnosis model with it)."""
    from swgmon.evaluation.evaluate import run_held_out
    from swgmon.evaluation.study import MonitorStudyConfig

    p, banks = tiny_banks
    return run_held_out(p, "tiny_bench", 3, MonitorStudyConfig(**TINY_STUDY), banks=banks)


def test_the_evaluation_is_the_same_whatever_its_chunk(tiny_banks, tiny_eval):
    """The fault lives simulated 7 windows at a time give tiny_eval's rows (120 at a time).
    Before each fork of the monitor drew its own p-value stream, forks shared one: a life's
    draws hung on what the lives before it had drawn, so on the chunk, and the eccentric
    WG's first life alarmed a window earlier at 7."""
    import pandas as pd

    from swgmon.evaluation.evaluate import run_held_out
    from swgmon.evaluation.study import MonitorStudyConfig

    p, banks = tiny_banks
    other = run_held_out(p, "tiny_bench", 3, MonitorStudyConfig(**TINY_STUDY,
                                                                windows_at_once=7),
                         banks=banks)
    for key in ("rows", "false_alarms", "curve"):
        pd.testing.assert_frame_equal(pd.DataFrame(other[key]), pd.DataFrame(tiny_eval[key]))


def test_planted_step_fault_detected_and_named(tiny_eval):
    import pandas as pd

    res = pd.DataFrame(tiny_eval["rows"])
    mon = res[res.detector == "monitor"].set_index(["fault", "severity", "onset"])
    ecc = mon.loc[("eccentric_wg", 0.1, "step")]
    assert ecc.detected and ecc.fault_after_1h == "eccentric_wg"
    assert 0 <= ecc.time_to_detect_h <= 0.5
    sen = mon.loc[("sensor_offset_step", 0.05, "step")]
    assert sen.detected and sen.fault_after_1h == "sensor_offset_step"
    assert sen.bridge_named == sen.bridge and sen.bridge in {f"s{i}" for i in range(5)}
    fa = pd.DataFrame(tiny_eval["false_alarms"]).set_index("detector")
    assert fa.loc["monitor", "false_alarms"] == 0
    assert pd.isna(fa.loc["monitor", "temperature_sensor_h"])  # no sensor named
    assert fa.loc["always", "false_alarms"] == 360


def test_per_window_detectors_beside_the_monitor(tiny_eval, tiny_banks, monkeypatch):
    """The paper's pipeline and the CNN run as monitors on the monitor's lives, each a part
    of its own: one row per life and detector, the same lives as the monitor's; their false
    alarms counted over detector_hours (2 h: 120 windows). Run after the monitor's part
    with its records, as in a worker, they simulate no record again."""
    import pandas as pd

    from swgmon.evaluation.evaluate import COMPARED, run_detectors
    from swgmon.evaluation.study import MonitorStudyConfig
    from swgsim.datasets.records import RecordBank

    res = pd.DataFrame(tiny_eval["rows"])
    lives = res.groupby(["fault", "severity", "onset"]).detector.apply(tuple)
    assert all(t == COMPARED for t in lives)
    simulated = []
    monkeypatch.setattr(RecordBank, "_simulate", lambda self, keys: simulated.append(keys))
    p, banks = tiny_banks
    parts = run_detectors(p, "tiny_bench", 3, MonitorStudyConfig(**TINY_STUDY),
                          ["paper_rf", "cnn_res"], banks=banks)
    assert simulated == []
    assert [p["detector"] for p in parts] == ["paper_rf", "cnn_res"]
    for part in parts:
        rows = pd.DataFrame(part["rows"])
        assert sorted(map(tuple, rows[["fault", "severity", "onset"]].values)) == sorted(
            lives.index)
        (fa,) = part["false_alarms"]
        assert fa["healthy_hours"] == 2.0 and 0 <= fa["false_alarms"] <= 120
        det = rows[rows.detected.astype(bool)]
        assert (det.fault_at_alarm != "healthy").all()
        assert (det.time_to_detect_h >= 0).all()


def test_the_detectors_training_set_holds_every_class_alike(tiny_banks):
    """detector_windows: every input kind asked for, one row per window, as many windows of
    each class the diagnosis model knows (the paper's balanced data set)."""
    from swgmon.evaluation.study import MonitorStudyConfig
    from swgmon.evaluation.training import classes, detector_windows

    p, banks = tiny_banks
    cfg = MonitorStudyConfig(**TINY_STUDY)
    x, y = detector_windows(p, banks, [1, 2], cfg, {"sel1", "raw_res"})
    names, counts = np.unique(y, return_counts=True)
    assert sorted(names) == sorted(classes(p, cfg))
    assert counts.min() == counts.max() > 0
    assert len(x["sel1"]) == len(x["raw_res"]) == len(y)


def test_monitor_app_end_to_end_on_a_tiny_life(tiny_eval, tmp_path, monkeypatch):
    """swgsim-monitor on a life written by swgsim-generate (preset tiny_life, gear 3: an
    eccentric WG of severity 0.1 from 6 h on) with the model trained without gear 3."""
    import json

    from swgcli import compose_app, dataset_preset
    from swgmon.advisories.task import run_monitor_app
    from swgmon.assessment.model_io import save_model
    from swgsim.datasets.config import dataset_config
    from swgsim.datasets.generate import generate

    cfg = dataset_config(dataset_preset("tiny_life"))
    cfg.gears = [g for g in cfg.gears if g.id == 3]
    generate(cfg, tmp_path / "life", progress=False)
    model = save_model(tiny_eval["model"], tmp_path / "model", [{"name": "tiny_bench"}])
    app = compose_app("monitor", [f"stream={tmp_path / 'life'}",
                                  f"diagnosis_model={model}",
                                  f"out_dir={tmp_path / 'out'}", "~logger"])
    monkeypatch.chdir(tmp_path)  # where a default tracking store would land
    out = run_monitor_app(app)
    assert not (tmp_path / "mlflow.db").exists()  # ~logger: no tracking
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["alarms"] == out["alarms"] and len(summary["alarms"]) == 1
    alarm = summary["alarms"][0]
    assert alarm["fault"] == "eccentric_wg" and 6.0 <= alarm["hour"] <= 6.5
    assert alarm["severity_low"] <= alarm["severity"] <= alarm["severity_high"]
    assert {"hour", "fault", "severity", "severity_low", "severity_high"} <= set(alarm)
    assert (tmp_path / "out" / "report.md").is_file()
    assert (tmp_path / "out" / "health.png").stat().st_size > 10_000


def test_the_namings_and_laws_numbers_are_logged_with_the_monitors_run(tiny_eval, tmp_path,
                                                                        monkeypatch):
    """``naming`` and ``normal.fit`` of swgsim-monitor (issue 84: every constant on
    record) reach the monitor and enter its MLflow run's parameters, each field by name."""
    import contextlib

    import swgmon.advisories.stream as stream
    import swgmon.advisories.task as task
    from swgcli import compose_app, dataset_preset
    from swgmon.assessment.model_io import save_model
    from swgsim.datasets.config import dataset_config
    from swgsim.datasets.generate import generate

    cfg = dataset_config(dataset_preset("tiny_life"))
    cfg.gears = [g for g in cfg.gears if g.id == 3]
    generate(cfg, tmp_path / "life", progress=False)
    model = save_model(tiny_eval["model"], tmp_path / "model", [{"name": "tiny_bench"}])
    logged, used = {}, []
    run = type("Run", (), {"log_metrics": lambda self, m: None,
                           "log_artifact": lambda self, f: None})()
    monkeypatch.setattr(task, "log_run", lambda *a, params, **k: (
        logged.update(params), contextlib.nullcontext(run))[1])
    monkeypatch.setattr(task, "check_tracking", lambda *a: None)
    once = stream._monitor_once
    monkeypatch.setattr(stream, "_monitor_once", lambda *a, **k: (
        used.append(a[9]), once(*a, **k))[1])  # naming, after prognosis
    task.run_monitor_app(compose_app("monitor", [
        f"stream={tmp_path / 'life'}", f"diagnosis_model={model}",
        f"out_dir={tmp_path / 'out'}", "naming.recur_h=12", "naming.prior_odds=2",
        "normal.fit.segment_k=2.5"]))
    assert logged["naming"]["recur_h"] == 12.0 and logged["naming"]["prior_odds"] == 2.0
    assert set(logged["naming"]) == set(dataclasses.asdict(NamingConfig()))
    assert logged["normal"]["fit"]["segment_k"] == 2.5
    assert set(logged["normal"]["fit"]) == set(dataclasses.asdict(LawFit()))
    assert used[0].recur_h == 12.0


def test_compiled_trees_equal_scikit_learn(tiny_eval):
    """The compiled walk of the trees gives scikit-learn's probabilities bit for bit, for
    one window and for a block, with a missing value (NaN) among them."""
    from swgmon.assessment.trees import CompiledTrees

    clf = tiny_eval["model"].classifier
    rng = np.random.default_rng(3)
    x = rng.normal(size=(300, clf.n_features_in_)) * 3
    x[:, -2:] = [4000.0, 70.0]
    x[4, 2] = np.nan
    ct = CompiledTrees(clf)
    np.testing.assert_array_equal(ct.predict_proba(x), clf.predict_proba(x))
    np.testing.assert_array_equal(ct.predict_proba(x[4:5]), clf.predict_proba(x[4:5]))


def test_one_window_at_a_time_equals_the_block_path(tiny_eval, tiny_banks):
    """GearMonitor.step, window by window, gives run()'s scores, p-values, CUSUMs and
    alarms (a CUSUM pushed over h by a shifted stretch: one alarm, then a restart)."""
    from swgmon.assessment.gear_monitor import GearMonitor
    from swgmon.detection.rule import RuleConfig
    from swgmon.evaluation.training import features_of
    from swgsim.datasets.life import LifeSimulator
    from swgsim.datasets.schedule import LifeConfig

    p, banks = tiny_banks
    sim = LifeSimulator(p, 3, LifeConfig(hours=5.0, commissioning_h=4.0, life_seed=9),
                        banks[3])
    f, pts, meta = features_of(sim, 0, len(sim))
    f[270:290] += 3 * f[:240].std(axis=0)  # a stretch no healthy window looks like
    rule = RuleConfig(design_hours=1.0)
    a, b = (GearMonitor(tiny_eval["model"], rule, 1.0, seed=5) for _ in range(2))
    for m in (a, b):
        m.commission(f[:240], pts[:240])
    blk, state = [], 0.0
    for i in range(240, 300, 20):  # blocks of 20: the flat-array walk, as step's
        blk.append(a.run(f[i:i + 20], pts[i:i + 20], meta["hour"][i:i + 20], latch=False,
                         start=state))
        state = 0.0 if blk[-1].alarms and blk[-1].alarms[-1] == 19 else blk[-1].cusums[-1]
    steps = [b.step(f[i], pts[i], meta["hour"][i]) for i in range(240, 300)]
    for k in ("score", "p", "cusums", "log_proba"):
        np.testing.assert_allclose(np.concatenate([getattr(t, k) for t in steps]),
                                   np.concatenate([getattr(t, k) for t in blk]),
                                   rtol=1e-12, atol=1e-12)
    alarms = [i for i, t in enumerate(steps) if t.alarms]
    assert alarms == [i + 20 * j for j, t in enumerate(blk) for i in t.alarms] and alarms
    with pytest.raises(ValueError, match="not seen at commissioning"):
        b.step(f[0], (1.0, 2.0), 5.0)


def test_one_bridge_fits_recover_planted_sensor_faults():
    """Least squares of sensor_check: an offset step on s2 and a gain drift on s4, planted
    in z-scores of noise, come back with their severities and leave noise behind; the
    mean shift left on the other bridges (rest) is small unless another bridge moved."""
    from swgmon.assessment.sensor_check import BLOCK, NamingConfig, fit_sensor_faults

    rest_max = NamingConfig().rest_max

    rng = np.random.default_rng(0)
    n, f = 40, 5 * BLOCK + 1
    mean = np.tile(rng.uniform(0.5, 2.0, f), (n, 1))
    std = np.tile(rng.uniform(0.01, 0.02, f), (n, 1))
    noise = rng.normal(size=(n, f))
    z = noise.copy()
    z[:, 2 * BLOCK] += 0.6 / std[:, 2 * BLOCK]  # offset +0.6 mV/V on s2
    fit = {(x.fault, x.bridge): x for x in fit_sensor_faults(z, mean, std)}
    off = fit[("sensor_offset_step", 2)]
    assert off.severity == pytest.approx(0.6, abs=3 * 0.02 / np.sqrt(n))
    assert np.sum(off.z ** 2) < 1.2 * np.sum(noise ** 2) < np.sum(z ** 2) / 5
    assert 0.5 < off.rest < rest_max  # the other bridges hold noise only: about 1
    z[:, 3 * BLOCK] += 3.0  # ... unless s3's offset moved too (an eccentric WG's pattern)
    moved = {(x.fault, x.bridge): x for x in fit_sensor_faults(z, mean, std)}
    assert moved[("sensor_offset_step", 2)].rest > 2 * rest_max
    z = noise.copy()
    cols = slice(4 * BLOCK, 5 * BLOCK - 1)
    z[:, cols] += -0.1 * mean[:, cols] / std[:, cols]  # gain 0.9 on s4
    gain = {(x.fault, x.bridge): x for x in fit_sensor_faults(z, mean, std)}
    assert gain[("sensor_gain_drift", 4)].severity == pytest.approx(0.1, abs=2e-3)
    assert np.sum(gain[("sensor_gain_drift", 4)].z ** 2) < 1.2 * np.sum(noise ** 2)
    with pytest.raises(ValueError, match="must be"):
        fit_sensor_faults(z[:, :-1], mean, std)



def test_a_drifting_gain_is_fitted_with_its_rate():
    """sensor_check.fit_sensor_faults with hours: a gain on s1 falling 0.01 an hour over
    two hours of windows comes back with its level at the last window and its rate, and
    leaves noise behind on s1's features; one level leaves the ramp there.
    The threshold of a level and a rate is the χ²₂ quantile 0.999."""
    from scipy.stats import chi2

    from swgmon.assessment.sensor_check import BLOCK, NamingConfig, fit_sensor_faults

    assert NamingConfig().least_reduction(2) == pytest.approx(chi2.ppf(0.999, 2), rel=1e-12)
    rng = np.random.default_rng(1)
    n, f = 120, 5 * BLOCK + 1
    hours = np.linspace(50.0, 52.0, n)
    mean = np.tile(rng.uniform(0.5, 2.0, f), (n, 1))
    std = np.tile(rng.uniform(0.01, 0.02, f), (n, 1))
    noise = rng.normal(size=(n, f))
    z = noise.copy()
    cols = slice(BLOCK, 2 * BLOCK - 1)
    loss = 0.01 * (hours - hours[0])  # 1 - g: 0 to 0.02
    z[:, cols] += -loss[:, None] * mean[:, cols] / std[:, cols]
    drift = {(x.fault, x.bridge): x for x in fit_sensor_faults(z, mean, std, hours)}
    level = {(x.fault, x.bridge): x for x in fit_sensor_faults(z, mean, std)}
    fit, one = drift[("sensor_gain_drift", 1)], level[("sensor_gain_drift", 1)]
    assert fit.severity == pytest.approx(0.02, abs=5e-4)
    assert fit.rate_per_h == pytest.approx(0.01, abs=5e-4)
    assert fit.plausible() and one.rate_per_h is None
    rest = [np.sum(x[:, cols] ** 2) for x in (fit.z, noise, one.z)]  # s1's features
    assert rest[0] < 1.05 * rest[1] < rest[2] / 1.25

def test_offset_on_a_wg_bending_bridge_named_a_sensor_fault(tiny_eval, tiny_banks):
    """An offset step on s1 alone (whose eccentric WG moves s1 and s3 oppositely) is named
    a sensor fault on s1; an eccentric WG is not explained by one bridge."""
    from swgmon.assessment.gear_monitor import GearMonitor
    from swgmon.assessment.naming import name
    from swgmon.evaluation.training import features_of
    from swgsim.datasets.life import LifeSimulator
    from swgsim.datasets.schedule import FaultOnset

    p, banks = tiny_banks
    mon = GearMonitor(tiny_eval["model"], RuleConfig(), 1.0)
    named = {}
    for fo in (FaultOnset(f, h, s, sensor=b) for f, h, s, b in OFFSET_VS_WG):
        sim = LifeSimulator(p, 3, _offset_life(fo), banks[3])
        f, pts, _ = features_of(sim, 0, len(sim))
        mon.commission(f[:240], pts[:240])
        _, lp = mon.scores(f[240:], pts[240:])
        named[fo.fault] = name(mon, mon.evidence(lp, mon.normal.index(pts[240:])),
                               f[240:], pts[240:])
    assert named == {"sensor_offset_step": ("sensor_offset_step", 1),
                     "eccentric_wg": ("eccentric_wg", None)}


def test_heavier_tool_recommissions_points_alike_in_block_step_and_replay(tiny_eval,
                                                                          tiny_banks):
    """A 10 % heavier tool from the end of commissioning (a simulated payload life): each
    point's windows beyond its load range gather until as many as commissioning gave its
    normal behaviour recommission it; on the bench's physics the laws hold at 7.7 N m,
    so that point's range grows and its mean stays, but not at 77 N m (one feature 2.7
    spreads off its law; a test on the combined p-value, 1 wherever both scores' exceed
    1/2, let it pass): that point is relearnt. Windows off the laws by a spread are
    relearnt. The block path, one window at a time and a fork's replay from
    commissioning give the same numbers and the same recommissionings."""
    from swgmon.assessment.gear_monitor import GearMonitor
    from swgmon.detection.normal import Conditions, Outside
    from swgmon.detection.rule import RuleConfig
    from swgmon.evaluation.training import features_of
    from swgsim.datasets.life import LifeSimulator

    p, banks = tiny_banks
    sim = LifeSimulator(p, 3, _heavier_tool_life(), banks[3])
    f, pts, meta = features_of(sim, 0, len(sim))
    cond, hour, tq = Conditions.of(meta), meta["hour"], meta["t_out_mean_nm"]
    temp = cond.temperature_c if cond.temperature_c is not None else [None] * len(f)
    rule = RuleConfig(design_hours=1.0)
    a, b = (GearMonitor(tiny_eval["model"], rule, 1.0, seed=5) for _ in range(2))
    for m in (a, b):
        m.commission(f[:240], pts[:240], cond[:240])
    c, mean0, std0 = a.fork(fresh_draws=True), a.normal.mean.copy(), a.normal.std.copy()
    blk, state = [], 0.0
    for i in range(240, 420, 20):
        blk.append(a.run(f[i:i + 20], pts[i:i + 20], hour[i:i + 20], cond[i:i + 20],
                         latch=False, start=state))
        state = 0.0 if blk[-1].alarms and blk[-1].alarms[-1] == 19 else blk[-1].cusums[-1]
    steps = [b.step(f[i], pts[i], hour[i], tq[i], temp[i]) for i in range(240, 420)]
    whole = c.run(f[240:], pts[240:], hour[240:], cond[240:], latch=False)
    for k in ("score", "p", "cusums", "outside"):
        one = np.concatenate([getattr(t, k) for t in steps])
        np.testing.assert_allclose(np.concatenate([getattr(t, k) for t in blk]), one,
                                   rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(getattr(whole, k), one, rtol=1e-12, atol=1e-12)
    events = [(i, k, r) for i, t in enumerate(steps) for _, k, r in t.recommissioned]
    assert events == whole.recommissioned
    assert events == [(i + 20 * j, k, r) for j, t in enumerate(blk)
                      for i, k, r in t.recommissioned]
    assert {(k, r) for _, k, r in events} == {(0, False), (1, True)}
    np.testing.assert_array_equal(a.normal.mean[0], mean0[0])
    assert np.abs((a.normal.mean[1] - mean0[1]) / std0[1]).max() > 2.0
    assert (a.normal.torque_range[:, 1] > 1.09 * a.normal.points[:, 1]).all()
    d = c.fork()  # the route: commissioning's own windows hold the laws, shifted ones not
    w = np.flatnonzero((pts[:240] == d.normal.points[0]).all(axis=1))
    own, s0 = d.normal.reference(f[w], pts[w], cond[w]), d.normal.std[0].copy()
    assert not d._recommission(0, own, tq[w])
    assert d._recommission(0, own + s0, tq[w])
    np.testing.assert_allclose(d.normal.mean[0], own.mean(axis=0) + s0)
    for i, k, _ in events:  # a recommissioned point's later windows are inside its range
        later = [j for j in range(i + 1, 180) if whole.op_index[j] == k]
        assert later and not (whole.outside[later] & Outside.LOAD).any()
    np.testing.assert_array_equal(a.normal.mean, c.normal.mean)
    np.testing.assert_array_equal(a.normal.torque_range, b.normal.torque_range)


def test_a_suspected_fault_keeps_every_point_and_the_severity_reads_unwidened(tiny_eval,
                                                                             tiny_banks):
    """After an alarm not explained away (a gear fault named) the monitor recommissions
    no point: the heavier tool's windows that relearn point 1 of a monitor without one
    leave every point as commissioning made it. An alarm sets the suspicion and clears
    what was gathered. Beyond the load range the severity regressors read the z-scores in
    commissioning's spread, not the detection's widened one, which shrinks them."""
    from swgmon.assessment.gear_monitor import GearMonitor
    from swgmon.assessment.model import design_matrix
    from swgmon.detection.normal import Conditions, Outside
    from swgmon.detection.rule import RuleConfig
    from swgmon.evaluation.training import features_of
    from swgsim.datasets.life import LifeSimulator

    p, banks = tiny_banks
    sim = LifeSimulator(p, 3, _heavier_tool_life(), banks[3])
    f, pts, meta = features_of(sim, 0, len(sim))
    cond, hour = Conditions.of(meta), meta["hour"]
    free, held = (GearMonitor(tiny_eval["model"], RuleConfig(design_hours=1.0), 1.0, seed=5)
                  for _ in range(2))
    for m in (free, held):
        m.commission(f[:240], pts[:240], cond[:240])
    mean0 = held.normal.mean.copy()
    held.fault_suspected = True
    w = slice(240, None)
    assert free.run(f[w], pts[w], hour[w], cond[w], latch=False).recommissioned
    tr = held.run(f[w], pts[w], hour[w], cond[w], latch=False)
    assert tr.recommissioned == [] and held.fault_suspected
    np.testing.assert_array_equal(held.normal.mean, mean0)
    beyond = np.flatnonzero((tr.outside & Outside.LOAD) != 0) + 240
    assert beyond.size
    x = held.inputs(f[beyond], pts[beyond], cond[beyond])
    z_wide = held.normal.z(f[beyond], pts[beyond], cond[beyond])
    np.testing.assert_array_equal(x, design_matrix(held.normal.unwidened().z(
        f[beyond], pts[beyond], cond[beyond]), pts[beyond]))
    assert np.abs(x[:, :-2]).sum() > np.abs(z_wide).sum()  # the widened spread shrinks them
    fresh = free.fork()
    fresh.fault_suspected, fresh.learning = False, {0: []}
    opi = fresh.normal.index(pts[w])
    out = np.full(len(opi), Outside.LOAD)
    assert fresh._learn(opi, out, fresh.normal.mean[opi], cond.torque_nm[w], [3]) is None
    assert fresh.fault_suspected and fresh.learning == {}


def test_a_window_without_its_reference_features_is_not_gathered_for_recommissioning(
        tiny_eval, tiny_banks):
    """A window whose features could not be brought to the reference condition (NaN where
    its temperature reading dropped out) is no evidence of a point's new normal: it is
    neither gathered nor clears what was gathered. Gathered, three such windows of 120
    gave a relearnt point a NaN mean, and the naming's least squares failed
    (LinAlgError: robot_joint, gear 3 held out, family ``all``, scored seeds)."""
    from swgmon.assessment.gear_monitor import GearMonitor
    from swgmon.detection.normal import Conditions, Outside
    from swgmon.detection.rule import RuleConfig
    from swgmon.evaluation.training import features_of
    from swgsim.datasets.life import LifeSimulator

    p, banks = tiny_banks
    f, pts, meta = features_of(LifeSimulator(p, 3, _heavier_tool_life(), banks[3]), 0, 420)
    cond = Conditions.of(meta)
    mon = GearMonitor(tiny_eval["model"], RuleConfig(design_hours=1.0), 1.0, seed=5)
    mon.commission(f[:240], pts[:240], cond[:240])
    k, nb = 1, mon.normal
    w = 240 + np.flatnonzero((pts[240:] == nb.points[k]).all(axis=1))
    n = int(nb.count[k])
    ref = nb.reference(f[w], pts[w], cond[w])[np.arange(n + 3) % len(w)]
    ref[[5, 6, 7]] = np.nan
    torque = np.full(n + 3, 1.1 * nb.points[k, 1])
    ev = mon._learn(np.full(n + 3, k), np.full(n + 3, Outside.LOAD), ref, torque, [])
    assert ev is not None and ev[:2] == (n + 2, k)
    assert np.isfinite(nb.mean[k]).all() and np.isfinite(nb.std[k]).all()


def test_beyond_the_load_range_only_the_novelty_scores():
    """A window whose acting load commissioning did not see at its point is scored by the
    novelty alone (the widened spread bounds the z-scores' size, not their direction);
    outside only in temperature or friction, both scores count (Bonferroni)."""
    from swgmon.assessment.gear_monitor import GearMonitor
    from swgmon.detection.normal import Outside
    from swgmon.detection.rule import RuleConfig, conformal_p

    mon = GearMonitor(None, RuleConfig(), 1.0)
    cal = np.sort(np.random.default_rng(0).normal(size=(99, 2)), axis=0)
    mon.calibration = {0: cal}
    score = np.tile([[10.0, 0.0]], (4, 1))  # evidence beyond every calibration window
    u = np.full(score.shape, 0.5)
    out = np.array([0, Outside.LOAD, Outside.TEMPERATURE | Outside.FRICTION,
                    Outside.LOAD | Outside.TEMPERATURE])
    p = mon.p_values(score, np.zeros(4, int), u, out)
    p_ev = conformal_p(score[:1, 0], cal[:, 0], u[:1, 0])[0]
    p_nov = conformal_p(score[:1, 1], cal[:, 1], u[:1, 1])[0]
    assert p_ev == 0.005 and 0.3 < p_nov < 0.7
    np.testing.assert_allclose(p, [2 * p_ev, p_nov, 2 * p_ev, p_nov])
    np.testing.assert_array_equal(mon.p_values(score, np.zeros(4, int), u), 2 * p_ev)


def test_commissioning_tracks_a_running_in_gear_friction(tiny_eval, tiny_banks):
    """A gear whose friction runs in during commissioning: the friction factor tracked
    over commissioning (as the run tracks it, here with a time constant of 0.5 h, short
    beside the run-in's 16 h) leaves the drift out of the efficiency's spread and hands
    its last value to the run; a gear that does not run in keeps its spread and a factor
    of 1. At a steady temperature: over a single warm-up the run-in is what the joint's
    friction law cannot be told from (tests/learn/test_real_day.py; with the catalogue's
    law, the simulator's, taken there the spread fell by more than half).
    Measured (no law): the spread 0.55 and 0.40 times, the factor 0.978 and 0.9997."""
    from swgmon.assessment.gear_monitor import GearMonitor
    from swgmon.detection.normal import EFFICIENCY, Conditions, NormalConfig
    from swgmon.detection.rule import RuleConfig
    from swgmon.evaluation.training import features_of
    from swgsim.datasets.conditions import ConditionsConfig, RunInConfig
    from swgsim.datasets.life import LifeSimulator
    from swgsim.datasets.schedule import LifeConfig

    p, banks = tiny_banks
    std, fr = {}, {}
    for run_in in (None, RunInConfig(drop=0.3, tau_h=16.0)):
        cond = ConditionsConfig(run_in=run_in, thermal=None, bridge_drift=None,
                                temperature_sensor=None)
        sim = LifeSimulator(p, 3, LifeConfig(hours=4.0, commissioning_h=4.0, life_seed=9,
                                             conditions=cond), banks[3])
        f, pts, meta = features_of(sim, 0, len(sim))
        for track in (0.0, 0.5):
            mon = GearMonitor(tiny_eval["model"], RuleConfig(design_hours=1.0), 1.0,
                              normal=NormalConfig(friction_track_h=track))
            mon.commission(f, pts, Conditions.of(meta))
            std[run_in is not None, track] = mon.normal.std[:, EFFICIENCY]
            fr[run_in is not None, track] = mon.friction
    assert (std[True, 0.5] < 0.67 * std[True, 0.0]).all()
    np.testing.assert_allclose(std[False, 0.5], std[False, 0.0], rtol=0.05)
    assert fr[True, 0.5] < 0.99 and abs(fr[False, 0.5] - 1.0) < 0.001
    assert fr[True, 0.0] == fr[False, 0.0] == 1.0


def test_every_event_kind_is_printed_in_one_line():
    """Each kind :meth:`StreamResult.events` gives (alarms of a gear fault, of a bridge's
    and the temperature sensor's fault, of an unexplained change, advisories,
    recommissionings) is one line by :func:`event_line`, which the app
    and report.md print; a kind it does not know is refused naming the kinds (issue 43,
    cause 1: a recommissioning printed as an alarm raised KeyError: 'fault')."""
    from swgmon.advisories.report import EVENT_KINDS, StreamResult, event_line
    from swgmon.detection.rule import Alarm

    gear = Alarm(6.2, 10, 4, "eccentric_wg", "eccentric_wg", 0.1, 0.08, 0.12)
    sensor = Alarm(7.0, 20, 18, "sensor_offset_step", "sensor_offset_step", 0.05, 0.04,
                   0.06, bridge="s1")
    adv = {"hour": 5.0, "index": 2, "condition": "temperature",
           "operating_point": [4000.0, 7.0], "friction_factor": 1.0,
           "advice": "the temperature left what commissioning saw at 4000 rpm, 7 N m: "
                     "recommission the monitor if the gear is known healthy"}
    rec = {"hour": 8.0, "index": 30, "operating_point": [4000.0, 7.0], "relearnt": False,
           "load_range_nm": [7.0, 7.7], "note": "the load at 4000 rpm, 7 N m stayed beyond"}
    hot = Alarm(7.5, 25, 22, "temperature_sensor", "temperature_sensor", -6.0, -9.0, -2.0)
    even = Alarm(7.8, 28, 26, "unexplained_change", "unexplained_change", 0.2, 0.18, 0.22)
    stuck = Alarm(7.9, 29, 27, "temperature_sensor", "temperature_sensor", *[np.nan] * 3)
    res = StreamResult(None, [gear, sensor, hot, even, stuck], [adv], 10, None, None, 12.3,
                       [rec])
    events = res.events()
    assert sorted({e["kind"] for e in events}) == sorted(EVENT_KINDS)
    lines = [event_line(e) for e in events]
    assert all("\n" not in s for s in lines)
    assert lines == [
        f"advisory at 5.00 h: {adv['advice']}",
        "alarm at 6.20 h: eccentric_wg (at the alarm: eccentric_wg), severity 0.1 "
        "[0.08, 0.12]",
        "alarm at 7.00 h: sensor_offset_step on bridge s1 (check that gauge) (at the alarm: "
        "sensor_offset_step), severity 0.05 [0.04, 0.06]",
        "alarm at 7.50 h: temperature_sensor (check the joint's temperature sensor; the "
        "monitor goes on without it) (at the alarm: temperature_sensor), severity -6 [-9, -2]",
        "alarm at 7.80 h: an unexplained change: the friction changed by +20.0 % [+18.0, "
        "+22.0] % evenly over the operating points (no gear fault's signature; was the joint "
        "re-greased? the monitor goes on from the new level)",
        "alarm at 7.90 h: temperature_sensor (check the joint's temperature sensor; the "
        "monitor goes on without it) (at the alarm: temperature_sensor), no severity",
        f"recommissioned at 8.00 h: {rec['note']}"]
    with pytest.raises(ValueError, match=r"event kind: 'x' is not one of \['gear_fault'"):
        event_line({"kind": "x", "hour": 1.0})


def test_a_sensor_fault_named_without_a_bridge_is_a_sensor_fault_not_a_gear_fault():
    """A sensor-fault class that no one bridge explains (``bridge`` None) is counted and
    printed as a sensor fault: before, only a named bridge or the temperature sensor made
    an alarm a sensor fault's, so this one was counted as a gear-fault alarm."""
    from swgmon.advisories.report import event_line
    from swgmon.detection.rule import Alarm

    al = Alarm(7.0, 20, 18, "sensor_offset_step", "sensor_offset_step", 0.05, 0.04, 0.06)
    assert al.sensor_fault and al.kind == "sensor_fault"
    assert Alarm(6.2, 10, 4, "root_tooth_crack", "root_tooth_crack", 0.1, 0.08, 0.12).kind \
        == "gear_fault"
    line = event_line({"kind": al.kind, **al.as_dict()})
    assert "no one bridge explains it" in line and "temperature sensor" not in line


def test_a_severity_interval_is_never_of_zero_width_where_the_windows_differ():
    """Training gears that agree to the digit (a sensor fault is the same on every gear:
    calibration errors 0, 0) left the interval [x, x]; the median's own spread over the
    alarm's windows keeps it open, and the line prints its bounds apart (issue 87)."""
    from swgmon.advisories.report import event_line
    from swgmon.assessment.model import DiagnosisModel
    from swgmon.detection.rule import Alarm

    class Column:  # a regressor reading the first input
        def predict(self, x):
            return x[:, 0]

    m = DiagnosisModel(["healthy", "sensor_offset_step"], None,
                       {"sensor_offset_step": (Column(), (0.0, 0.0))})
    x = np.c_[0.05 + 1e-5 * np.random.default_rng(3).standard_normal(40), np.zeros(40)]
    est, lo, hi = m.estimate("sensor_offset_step", x)
    assert lo < est < hi and hi - lo < 1e-4
    assert m.estimate("sensor_offset_step", np.c_[np.full(5, 0.05), np.zeros(5)])[1:] \
        == (0.05, 0.05)  # identical windows, no calibration error: nothing to widen by
    al = Alarm(7.0, 20, 18, "sensor_offset_step", "sensor_offset_step", est, lo, hi)
    lo_s, hi_s = event_line({"kind": al.kind, **al.as_dict()}).split("[")[1].split("]")[0] \
        .split(", ")
    assert lo_s != hi_s and float(lo_s) == pytest.approx(lo, rel=1e-3)


def test_a_resumed_evaluations_tables_keep_a_fresh_runs_columns(tmp_path):
    from learn.tasks.parts import Job, finished_parts, save_part
    from swgmon.evaluation.evaluate import to_frames

    job = Job("tiny", 3, None, "k1")
    part = {"key": "k1", "dataset": "tiny", "held_out_gear": 3,
            "rows": [{"fault": "root_crack", "detected": True, "alarm_h": 2.5, "cause": "x"}],
            "false_alarms": [{"gear": 3, "hours": 10.0, "detector": "monitor"}],
            "curve": [{"design_hours": 1000.0, "delay_h": 1.0, "afar": 0.0}]}
    (tmp_path / "parts").mkdir()
    save_part(tmp_path, job, part)
    (resumed,), todo = finished_parts(tmp_path, [job])
    assert todo == []
    for fresh, back in zip(to_frames([part]), to_frames([resumed]), strict=True):
        assert list(back.columns) == list(fresh.columns)


def test_a_fit_counts_at_the_chi2_quantile_of_its_parameters_and_level():
    """``naming.least_reduction(k)`` is the χ²_k quantile 1 − ``naming.fit_level``
    (0.999 by default); a lower level asks more of a fit, and a bridge without a fault is
    fitted at about that level (Monte Carlo of a one-parameter step in pure noise)."""
    from scipy.stats import chi2

    from swgmon.assessment.sensor_check import NamingConfig

    nc = NamingConfig()
    for k in (1, 2, 3):
        assert nc.least_reduction(k) == pytest.approx(chi2.ppf(0.999, k), rel=1e-9)
    assert NamingConfig(fit_level=1e-4).least_reduction(1) > nc.least_reduction(1)
    rng = np.random.default_rng(0)
    z = rng.standard_normal((20000, 30))  # 30 windows of one feature, no step in them
    reduction = 30 * z.mean(axis=1) ** 2  # the best step's lowering of Σ z²: χ²₁
    rate = np.mean(reduction >= NamingConfig(fit_level=0.01).least_reduction(1))
    assert 0.008 <= rate <= 0.012


def test_an_alarm_says_which_features_moved():
    """rule.moved_features: the largest mean z-scores, at least 1 sigma, the first
    always; event_line prints them after the alarm."""
    from swgmon.advisories.report import event_line
    from swgmon.detection.rule import Alarm, moved_features

    z = np.zeros((4, 5))
    z[:, 2], z[:, 4], z[:, 0] = -6.0, 1.5, 0.5
    names = ["a", "b", "efficiency", "c", "s1_h2"]
    assert moved_features(z, names) == [["efficiency", -6.0], ["s1_h2", 1.5]]
    assert moved_features(np.full((2, 5), 0.1), names, k=2) == [["a", 0.1]]
    al = Alarm(7.8, 28, 26, "unexplained_change", "unexplained_change", 0.2, 0.2, 0.2,
               moved=moved_features(z, names))
    line = event_line({"kind": al.kind, **al.as_dict()})
    assert line.endswith("; moved: efficiency -6.0 sigma, s1_h2 +1.5 sigma")


# ------------------------------------------------------------------ prognosis in the stream
#: The growing fault's life: tiny_life's gear 3, an eccentric wave generator growing by
#: Archard's law from 4.5 h on to its failure at severity 0.1 (the largest the tiny grid
#: trains) [choice: a wear coefficient that fails the gear within the 8 h life, at 7.67 h].
GROWING = dict(growth="archard", onset_h=4.5, severity=0.0,
               to_failure={"failure": 0.1, "wear_coeff_m_per_nm_rev": 7e-13})


@pytest.fixture(scope="module")
def growing_life(tiny_eval, tmp_path_factory):
    """The life (GROWING, 480 windows), its true failure hour, and the monitor's result
    on it with the prognosis off (None and disabled) and on (an estimate per 0.25 h, a
    prognosis per 0.5 h, valid after 0.5 h and 3 estimates)."""
    from threadpoolctl import threadpool_limits

    from swgcli import dataset_preset
    from swgmon.advisories.stream import monitor_stream
    from swgmon.prognosis.stream import StreamPrognosis
    from swgsim.datasets.config import dataset_config
    from swgsim.datasets.generate import generate
    from swgsim.datasets.growth import RunToFailure
    from swgsim.datasets.life import LifeSimulator
    from swgsim.datasets.plan import plan
    from swgsim.datasets.records import record_bank
    from swgsim.datasets.schema import load

    raw = dataset_preset("tiny_life")
    raw["life"]["fault"].update(GROWING)
    cfg = dataset_config(raw)
    cfg.gears = [g for g in cfg.gears if g.id == 3]
    folder = tmp_path_factory.mktemp("growing") / "life"
    generate(cfg, folder, progress=False)
    p = plan(cfg)
    failure_h = LifeSimulator(p, 3, cfg.life, record_bank(p, 3)).schedule.failure_h
    ds, model = load(folder), tiny_eval["model"]
    on = StreamPrognosis(enabled=True, every_h=0.5, min_track_h=0.5, min_estimates=3,
                         to_failure=RunToFailure(**GROWING["to_failure"]))
    with threadpool_limits(1):  # the trees' predictions on 2 shared cores: 16 times faster
        runs = {k: monitor_stream(ds, model, RuleConfig(), prognosis=v)
                for k, v in (("none", None), ("off", StreamPrognosis()), ("on", on))}
    return {"ds": ds, "folder": folder, "failure_h": float(failure_h), "config": on, **runs}


def test_prognoses_more_often_than_the_streams_windows_are_refused_before_work(growing_life,
                                                                             tiny_eval):
    """Issue 82, cause 1: prognosis.every_h inside (0, 1000] h set the number of prognoses
    (1e-9 h: 18.6 GB, the kernel's OOM killer); below the stream's window interval it is
    refused in one line, before the stream is monitored."""
    import dataclasses

    from swgmon.advisories.stream import monitor_stream

    many = dataclasses.replace(growing_life["config"], every_h=1e-9)
    with pytest.raises(ValueError, match=r"^prognosis.every_h must lie in \[0.0166667, "
                                         r"1000\] h \(at most a prognosis per window: the "
                                         r"stream's windows are 1 min apart\), got 1e-09$"):
        monitor_stream(growing_life["ds"], tiny_eval["model"], RuleConfig(), prognosis=many)


def test_more_prognoses_than_an_alarm_may_have_are_refused_before_work(growing_life,
                                                                      tiny_eval):
    """Issue 82: every_h was bounded by the median window step alone, and a stream's hours
    are not bounded: its last window 100 h after the others, at a prognosis a minute, made
    6,200 prognoses (9.8 s). Over the hours after the earliest alarm, more than
    ``max_prognoses`` (10,000) are refused in one line naming every_h and the count, before
    the stream is monitored."""
    import dataclasses

    from swgmon.advisories.stream import monitor_stream

    ds = growing_life["ds"].copy()
    hours = ds["hour"].values.astype(float)
    ds["hour"] = ds["hour"].copy(data=np.append(hours[:-1], hours[-1] + 200.0))
    every = dataclasses.replace(growing_life["config"], every_h=1 / 60)
    with pytest.raises(ValueError, match=r"^prognosis.every_h=0.0166667 h makes 1.22e\+04 "
                                         r"prognoses over the 204 h after the earliest alarm; "
                                         r"allowed: at most 10,000 an alarm \(every_h from "
                                         r"0.0204 h; prognosis.max_prognoses\)$"):
        monitor_stream(ds, tiny_eval["model"], RuleConfig(), prognosis=every)


def test_an_alarm_in_a_named_gear_faults_episode_keeps_its_name(growing_life, tiny_eval,
                                                                monkeypatch):
    """A growing fault alarms again and again; an alarm whose CUSUM rose at or before the
    previous one named a gear fault is that alarm again at its own hour, without the
    hypotheses weighed again (naming._weighed: twice per episode, not per alarm); the
    stream keeps the episode's first."""
    from threadpoolctl import threadpool_limits

    import swgmon.advisories.stream as stream
    import swgmon.assessment.naming as naming
    from swgmon.advisories.stream import monitor_stream

    weighed, named = [], []
    weigh, diagnose = naming._weighed, naming.diagnose

    def counted(*a, **k):
        weighed.append(1)
        return weigh(*a, **k)

    def kept(*a, **k):
        named.append(diagnose(*a, **k))
        return named[-1]

    monkeypatch.setattr(naming, "_weighed", counted)
    monkeypatch.setattr(stream, "diagnose", kept)
    with threadpool_limits(1):
        res = monitor_stream(growing_life["ds"], tiny_eval["model"], RuleConfig())
    episodes = 1 + sum(b.rise_index > a.index for a, b in zip(named[:-1], named[1:], strict=True))
    assert len(named) >= 3 and episodes < len(named)  # it alarmed again within the episode
    assert len(weighed) == 2 * episodes
    assert {a.fault for a in named} == {"eccentric_wg"} == {a.fault for a in res.alarms}
    for a, b in zip(named[:-1], named[1:], strict=True):
        if b.rise_index <= a.index:  # the same episode: the same alarm at a later hour
            assert b.hour > a.hour and (b.severity, b.moved) == (a.severity, a.moved)
    assert len(res.alarms) == 1 and res.alarms[0] == named[0]


def test_a_tracks_windows_read_at_once_are_read_as_block_by_block(growing_life, tiny_eval):
    """The prognosis reads every window after an alarm at once and estimates block by
    block (swgmon.prognosis.stream._follow); the slow reference, each block's windows
    read alone, gives the same inputs and the same estimates to the last bit."""
    from swgmon.advisories.stream import stream_features
    from swgmon.assessment.gear_monitor import GearMonitor
    from swgmon.detection.normal import Conditions

    ds, model = growing_life["ds"], tiny_eval["model"]
    feats = stream_features(ds)
    pts = np.stack([ds["n_in_rpm"].values, ds["t_out_nm"].values], axis=1)
    cond = Conditions.of({k: ds[k].values for k in ("t_out_mean_nm", "temperature_c")
                          if k in ds})
    n_c = int(ds["commissioning"].values.sum())
    mon = GearMonitor(model, RuleConfig(), 1.0)
    mon.commission(feats[:n_c], pts[:n_c], cond[:n_c])
    w = np.arange(n_c, len(feats))
    x = mon.inputs(feats[w], pts[w], cond[w], 1.0)
    read = model.reads("eccentric_wg", x)
    for b in range(0, len(w), 15):
        part = w[b:b + 15]
        alone = mon.inputs(feats[part], pts[part], cond[part], 1.0)
        assert np.array_equal(alone, x[b:b + 15])
        assert model.estimate("eccentric_wg", alone) == \
            model.estimate("eccentric_wg", read[b:b + 15])


def test_the_prognosis_interval_after_the_alarm_holds_the_true_failure_hour(growing_life):
    """Every valid prognosis made before the true failure (7.67 h) holds it within its
    5-95 % interval; the first, 0.5 h after the alarm with 2 estimates, is not yet valid
    and says so."""
    res, failure_h = growing_life["on"], growing_life["failure_h"]
    (alarm,) = res.alarms
    assert alarm.fault == "eccentric_wg" and 4.5 <= alarm.hour < failure_h
    events = res.prognosis.events
    assert events[0]["reason"].startswith("prognosis not yet valid") and not events[0]["valid"]
    before = [e for e in events if e["valid"] and e["hour"] < failure_h]
    assert len(before) >= 3
    for e in before:
        assert e["failure_h_q05"] <= failure_h <= e["failure_h_q95"], e
        assert e["remaining_h_q05"] <= e["remaining_h"] <= e["remaining_h_q95"]
    assert all(e["hour"] > alarm.hour and e["fault"] == alarm.fault for e in events)


def test_the_prognosis_is_written_and_off_leaves_every_output_as_it_was(growing_life,
                                                                         tmp_path):
    """Off (None or enabled false): summary.json, report.md and health.png byte for byte
    the same, no prognosis.png; on: the same alarms, summary.json's ``prognosis`` the
    events, a report line per valid one, the figure."""
    import json

    from swgmon.advisories.report import write_outputs

    files = {k: write_outputs(growing_life[k], tmp_path / k, "life")
             for k in ("none", "off", "on")}
    for name in ("summary", "report", "figure"):
        assert files["none"][name].read_bytes() == files["off"][name].read_bytes()
    assert "prognosis" not in files["off"] and not (tmp_path / "off" / "prognosis.png").exists()
    off, on = (json.loads((tmp_path / k / "summary.json").read_text()) for k in ("off", "on"))
    assert on.pop("prognosis") == json.loads(json.dumps(growing_life["on"].prognosis.events))
    assert on == off
    valid = [e for e in growing_life["on"].prognosis.events if e["valid"]]
    assert (tmp_path / "on" / "report.md").read_text().count("- prognosis at ") == len(valid)
    assert files["on"]["prognosis"].stat().st_size > 10_000


def test_no_prognosis_before_an_alarm(growing_life, tiny_eval, tmp_path):
    """The life cut before the fault's onset: no alarm, no prognosis, an empty list, no
    prognosis.png and no line of it in report.md."""
    from threadpoolctl import threadpool_limits

    from swgmon.advisories.report import write_outputs
    from swgmon.advisories.stream import monitor_stream

    ds = growing_life["ds"]
    healthy = ds.isel(sample=np.flatnonzero(ds["hour"].values < GROWING["onset_h"]))
    with threadpool_limits(1):
        res = monitor_stream(healthy, tiny_eval["model"], RuleConfig(),
                             prognosis=growing_life["config"])
    assert res.alarms == [] and res.prognosis.events == [] and res.prognosis.tracks == []
    files = write_outputs(res, tmp_path, "healthy")
    assert "prognosis" not in files and not (tmp_path / "prognosis.png").exists()
    assert "prognosis" not in (tmp_path / "report.md").read_text()


def test_a_planned_duty_outside_the_models_is_refused_by_the_app(growing_life, tiny_eval,
                                                                  tmp_path, monkeypatch,
                                                                  capsys):
    """swgsim-monitor (in-process, as its command line runs it) with a planned duty at
    9000 rpm (the model: 4000 rpm): exit 2, one line naming prognosis.planned.n_in_rpm,
    nothing written."""
    import sys

    import swgcli.monitor
    from swgmon.assessment.model_io import save_model

    model = save_model(tiny_eval["model"], tmp_path / "model", [{"name": "tiny_bench"}])
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", [
        "swgsim-monitor", f"stream={growing_life['folder']}", f"diagnosis_model={model}",
        f"out_dir={tmp_path / 'out'}", "~logger", "prognosis.enabled=true",
        "prognosis.planned=[{minutes: 60, n_in_rpm: 9000, t_acting_nm: 40, temp_c: 30}]"])
    capsys.readouterr()
    with pytest.raises(SystemExit) as info:
        swgcli.monitor.main()
    lines = [s for s in capsys.readouterr().err.splitlines() if s.strip()]
    assert info.value.code == 2 and len(lines) == 1, lines
    assert "prognosis.planned.n_in_rpm" in lines[0] and not (tmp_path / "out").exists()


def test_two_alarms_of_one_fault_keep_their_own_prognoses():
    """Two wear alarms (2 h and 5 h), both followed to the stream's end, their prognoses
    at overlapping hours: each track gets its own alarm's events, not the later one's."""
    from swgmon.prognosis.stream import StreamPrognoses

    tracks = [{"fault": "wear", "alarm_h": a, "hours": [a + 1.0], "severity": [0.1],
               "lo": [0.0], "hi": [0.2]} for a in (2.0, 5.0)]
    events = [{"hour": a + k, "fault": "wear", "alarm_h": a, "valid": True}
              for a in (2.0, 5.0) for k in (1.0, 2.0, 3.0)]
    prog = StreamPrognoses(events, tracks)
    first, second = (prog.of_track(t) for t in tracks)
    assert [e["hour"] for e in first] == [3.0, 4.0, 5.0]
    assert [e["hour"] for e in second] == [6.0, 7.0, 8.0]


def test_the_diagnosis_models_boosting_runs_on_one_openmp_thread_with_the_same_trees():
    """``one_thread`` (swgmon/assessment/model.py) limits the threads scikit-learn's gradient
    boosting asks OpenMP for to one and puts the limit back after (another OpenMP runtime
    loaded later, torch's, is not scikit-learn's and not limited); the trees fitted inside
    are those fitted with two threads (what makes the limit safe: the model does not
    depend on it)."""
    from sklearn.ensemble import HistGradientBoostingClassifier
    from sklearn.utils._openmp_helpers import _openmp_effective_n_threads  # what it asks
    from threadpoolctl import threadpool_limits

    from swgmon.assessment.model import one_thread

    two = min(2, os.cpu_count() or 1)
    rng = np.random.default_rng(0)
    x = rng.normal(size=(3000, 8))
    y = (x[:, 0] + x[:, 1] ** 2 > 1).astype(int) + (x[:, 2] > 1)
    proba = []
    with threadpool_limits(limits=2, user_api="openmp"):
        assert _openmp_effective_n_threads() == two
        for limit in (one_thread, lambda: threadpool_limits(limits=2, user_api="openmp")):
            with limit():
                assert _openmp_effective_n_threads() == (1 if limit is one_thread else two)
                clf = HistGradientBoostingClassifier(max_iter=30, random_state=0).fit(x, y)
                proba.append(clf.predict_proba(x))
        assert _openmp_effective_n_threads() == two
    np.testing.assert_array_equal(proba[0], proba[1])


def test_a_training_gears_severity_is_read_out_of_sample_for_the_prognosis_calibration(
        tmp_path):
    """``DiagnosisModel.without(g)`` (swgmon/assessment/model.py): the severity regressors
    fitted without training gear ``g`` - on its windows the estimate is out of sample, as
    on a held-out gear's - with the classifier and the intervals unchanged; a gear the
    model did not train on, and a loaded model, are refused."""
    from sklearn.ensemble import HistGradientBoostingRegressor

    from swgmon.assessment.model import fit_diagnosis
    from swgmon.assessment.model_io import load_model, save_model

    rng = np.random.default_rng(0)
    n = 600
    gear = np.repeat([1, 2], n // 2)
    fault = np.where(np.arange(n) % 2, "x", "healthy")
    severity = np.where(fault == "x", rng.uniform(0.1, 1.0, n), 0.0)
    # gear 2's feature reads the severity at a larger gain: its own regressor knows that
    x = np.column_stack([severity * np.where(gear == 1, 1.0, 1.5) + 0.01 * rng.normal(size=n),
                         (fault == "x") + 0.1 * rng.normal(size=n), np.ones(n), np.ones(n)])
    model = fit_diagnosis(x, fault, severity, gear, ["healthy", "x"], n_agg=10)
    # what training sets beside the fit (swgmon.evaluation.training.train_model)
    model.n_features, model.sample_rate_hz, model.window_s = 2, 10_000.0, 0.12
    out = model.without(2)
    assert out.classifier is model.classifier and out.classes == model.classes
    assert out.severity["x"][1] == model.severity["x"][1]  # the same interval
    on2 = x[(gear == 2) & (fault == "x")]
    alone = HistGradientBoostingRegressor(max_iter=100, early_stopping=False, random_state=0)
    m1 = (gear == 1) & (fault == "x")
    np.testing.assert_array_equal(out.severity["x"][0].predict(on2),
                                  alone.fit(x[m1], severity[m1]).predict(on2))
    truth = severity[(gear == 2) & (fault == "x")]
    err_in = np.abs(model.severity["x"][0].predict(on2) - truth).mean()
    err_out = np.abs(out.severity["x"][0].predict(on2) - truth).mean()
    assert err_out > 2 * err_in  # out of sample: gear 1's gain does not fit gear 2
    with pytest.raises(ValueError, match="no severity regressors fitted without gear 3"):
        model.without(3)
    loaded = load_model(save_model(model, tmp_path / "m", []))
    with pytest.raises(ValueError, match="a model loaded from a file saved without them"):
        loaded.without(1)
    kept = load_model(save_model(model, tmp_path / "k", [], without=True)).without(2)
    np.testing.assert_array_equal(kept.severity["x"][0].predict(on2),
                                  out.severity["x"][0].predict(on2))
    assert set(kept.reading) == set(out.reading)


def test_severity_folds_fit_one_regressor_a_fold_and_read_each_gear_out_of_it():
    """CV+'s folds (``fit_diagnosis``'s ``folds``, swgmon/assessment/model.py): four gears in
    two folds give two regressors, each gear's the one fitted without its fold (the same
    for both gears of a fold, fitted on the other fold's windows alone); 0 folds, one a
    gear as before; 1 fold refused."""
    from sklearn.ensemble import HistGradientBoostingRegressor

    from swgmon.assessment.model import fit_diagnosis, gear_folds

    rng = np.random.default_rng(1)
    n = 800
    gear = np.repeat([1, 2, 3, 4], n // 4)
    fault = np.where(np.arange(n) % 2, "x", "healthy")
    severity = np.where(fault == "x", rng.uniform(0.1, 1.0, n), 0.0)
    x = np.column_stack([severity + 0.05 * rng.normal(size=n),
                         (fault == "x") + 0.1 * rng.normal(size=n), np.ones(n), np.ones(n)])
    assert gear_folds([4, 2, 3, 1], 2) == [[1, 2], [3, 4]]
    assert gear_folds([1, 2, 3], 0) == gear_folds([1, 2, 3], 5) == [[1], [2], [3]]
    two = fit_diagnosis(x, fault, severity, gear, ["healthy", "x"], n_agg=10, folds=2)
    assert two.severity_without[1]["x"] is two.severity_without[2]["x"]
    assert two.severity_without[1]["x"] is not two.severity_without[3]["x"]
    other = (gear >= 3) & (fault == "x")
    alone = HistGradientBoostingRegressor(max_iter=100, early_stopping=False, random_state=0)
    np.testing.assert_array_equal(two.severity_without[1]["x"].predict(x[:50]),
                                  alone.fit(x[other], severity[other]).predict(x[:50]))
    each = fit_diagnosis(x, fault, severity, gear, ["healthy", "x"], n_agg=10)
    assert len({id(r["x"]) for r in each.severity_without.values()}) == 4
    with pytest.raises(ValueError, match="folds must be 0"):
        fit_diagnosis(x, fault, severity, gear, ["healthy", "x"], folds=1)


def test_the_health_figure_marks_every_crossing_and_every_event(tmp_path, monkeypatch):
    """Issue 87: a verdict a field engineer reads - ``health.png`` marks every upward
    crossing of the threshold (a second one too, not only the alarms') and every event
    of each kind the stream reports, with the legend outside the axes."""
    from types import SimpleNamespace

    import swgmon.advisories.figures as figures
    from swgmon.advisories.report import EVENT_KINDS

    assert figures.crossings(np.array([0, 5, 12, 3, 0, 13, 14, 2.0]), 11.7).tolist() == [2, 5]
    assert figures.crossings(np.array([12.0, 1.0, 11.7]), 11.7).tolist() == [0, 2]
    assert set(figures.EVENT_MARKS) == set(EVENT_KINDS)
    drawn = {}
    monkeypatch.setattr(figures, "save_figure", lambda fig, path, dpi: drawn.update(fig=fig))
    hours = np.arange(8.0)
    trace = SimpleNamespace(hour=hours, p=np.full(8, 0.5),
                            s=np.array([0, 5, 12, 3, 0, 13, 14, 2.0]))
    events = [{"kind": k, "hour": 1.0 + i} for i, k in enumerate(EVENT_KINDS)]
    figures.health_figure(trace, 11.7, events, 0.5, "eccentric_wg", tmp_path / "health.png")
    ax = drawn["fig"].axes[1]
    marks = [ln for ln in ax.get_lines() if ln.get_marker() == "v"]
    assert len(marks) == 1 and marks[0].get_xdata().tolist() == [2.0, 5.0]
    for i, k in enumerate(EVENT_KINDS):
        colour, style = figures.EVENT_MARKS[k]
        assert any(ln.get_xdata()[0] == 1.0 + i and ln.get_linestyle() == style
                   for ln in ax.get_lines()), k
    legend = ax.get_legend()
    assert {t.get_text() for t in legend.get_texts()} >= {k.replace("_", " ") for k in EVENT_KINDS}
    drawn["fig"].canvas.draw()
    assert legend.get_window_extent().x0 >= ax.get_window_extent().x1  # outside the data


def test_the_profile_interval_of_a_parabola_is_its_wilks_interval():
    """Issue 87: an unexplained change's friction factor gets a 90 % interval from the fit's
    profile of Σ z² (Wilks: a rise of 1.645² over the least): on an exact parabola of
    known curvature, centre and width come back; a flat profile gives none."""
    from swgmon.assessment.unexplained import profile_interval

    x = np.log(np.linspace(1.2, 1.4, 9))
    sigma, centre = 0.01, np.log(1.3)
    lo, hi = profile_interval(x, 50.0 + (x - centre) ** 2 / sigma ** 2)
    assert np.log(lo) == pytest.approx(centre - 1.6449 * sigma, abs=1e-6)
    assert np.log(hi) == pytest.approx(centre + 1.6449 * sigma, abs=1e-6)
    assert np.isnan(profile_interval(x, np.full(9, 3.0))).all()


def test_the_trade_off_curve_draws_the_studys_design_rates():
    """``monitor.study.curve_hours`` (issue 84: every constant on record) sets the
    trade-off curve's thresholds, those up to the rule's design rate; a list that does
    not increase is refused in one line naming the key."""
    from swgmon.evaluation.evaluate import _curve_thresholds
    from swgmon.evaluation.study import MonitorStudyConfig
    from swgsim.base.typed import check_tree

    cfg = MonitorStudyConfig(curve_hours=[2.0, 20.0, 1e5])
    t = _curve_thresholds(cfg)
    assert list(t) == [2.0, 20.0] and t[2.0] < t[20.0]
    with pytest.raises(ValueError, match=r"^monitor\.study\.curve_hours must be increasing"):
        check_tree(MonitorStudyConfig(curve_hours=[10.0, 3.0]), "monitor.study")


def test_the_rule_weighs_a_candidate_by_its_bayes_factor():
    """log_odds: the Bayes factor of Beta(xi, 1) p-values with xi uniform over the right
    candidates' exponents against the wrong ones', by quadrature; uniform p-values name
    the candidate, Beta(1/3, 1) ones (median p 0.125) do not (400 draws, seed 7);
    correlated windows count as fewer (an AR(1)'s effective number); the prior odds add
    their log."""
    from scipy.integrate import quad

    from swgmon.assessment.hypotheses import effective_windows, log_odds

    def log_marginal(m, s, a, b):  # ln of the mean of xi^m exp((1 - xi) s) over [a, b]
        peak = min(max(m / s, a), b)
        c = m * np.log(peak) + (1 - peak) * s
        val, _ = quad(lambda t: np.exp(m * np.log(t) + (1 - t) * s - c), a, b,
                      points=[peak], limit=200, epsabs=0, epsrel=1e-10)
        return np.log(val / (b - a)) + c

    rng = np.random.default_rng(7)
    for right, wrong in ((0.43, 0.23), (0.45, 0.1)):
        a, b = (np.log(2) / -np.log(m) for m in (right, wrong))
        for n in (1, 5, 30, 500):
            for xi in (1.0, 0.8, 0.4):
                p = rng.uniform(size=n) ** (1 / xi)
                x = -np.log(p)
                m = effective_windows(x)
                s = m * x.mean()
                want = log_marginal(m, s, a, 1.0) - log_marginal(m, s, 1e-9, b)
                assert log_odds(p, 1.0, right, wrong) == pytest.approx(want, abs=1e-3)
    named = [log_odds(rng.uniform(size=30), 1.0, 0.43, 0.23) > 0 for _ in range(400)]
    wrong = [log_odds(rng.uniform(size=30) ** 3, 1.0, 0.43, 0.23) > 0 for _ in range(400)]
    assert np.mean(named) >= 0.95 and np.mean(wrong) <= 0.05
    x = np.empty(2000)
    x[0], e = 0.0, rng.normal(size=2000)
    for i in range(1, 2000):
        x[i] = 0.9 * x[i - 1] + np.sqrt(1 - 0.81) * e[i]
    assert effective_windows(x) == pytest.approx(2000 * 0.1 / 1.9, rel=0.25)
    p = rng.uniform(size=30)
    assert log_odds(p, 10.0, 0.43, 0.23) - log_odds(p, 1.0, 0.43, 0.23) == \
        pytest.approx(np.log(10.0))


def test_a_hypothesis_of_ones_own_is_one_file_and_a_registration(tiny_eval, tiny_banks):
    """Issue 84: a hypothesis written outside the package (tests/hypothesis_example.py)
    and registered (``register_hypothesis``) is weighed with the built-in ones, in two
    worker processes (``travelling``), and names the windows it explains (every bridge's
    zero moved by one δ: no one bridge's fault explains that); a monitor whose
    ``naming.hypotheses`` leaves it out does not name them so. The candidates come with
    their evidence; an unknown name is refused in one line before any work."""
    import joblib
    from hypothesis_example import SupplyStep

    from swgmon.assessment.gear_monitor import GearMonitor
    from swgmon.assessment.hypotheses import HYPOTHESES, register_hypothesis, registered
    from swgmon.assessment.naming import _weighed, name
    from swgmon.detection.laws import BLOCK
    from swgmon.detection.normal import Conditions
    from swgmon.detection.rule import RuleConfig
    from swgmon.evaluation.training import features_of
    from swgsim.base.registry import travelling
    from swgsim.datasets.life import LifeSimulator
    from swgsim.datasets.schedule import LifeConfig

    p, banks = tiny_banks
    sim = LifeSimulator(p, 3, LifeConfig(hours=5.0, commissioning_h=4.0, life_seed=9),
                        banks[3])
    f, pts, meta = features_of(sim, 0, len(sim))
    cols = [c * BLOCK for c in range(5)]
    f[270:, cols] += 1.0 * f[:240, cols].std(axis=0).max()  # one δ on every bridge's zero
    built_in = NamingConfig(hypotheses=list(HYPOTHESES))
    register_hypothesis(SupplyStep())
    try:
        mons = [GearMonitor(tiny_eval["model"], RuleConfig(design_hours=1.0), 1.0, naming=n)
                for n in (built_in, NamingConfig())]
        cond, w, hours = Conditions.of(meta), slice(270, 300), meta["hour"][270:300]
        for m in mons:
            m.commission(f[:240], pts[:240], cond[:240])
        tr = mons[0].run(f[w], pts[w], hours, cond[w], latch=False)
        ev = mons[0].evidence(tr.log_proba, tr.op_index)
        named = joblib.Parallel(n_jobs=2)(joblib.delayed(travelling(name))(
            m, ev, f[w], pts[w], cond[w], 1.0, hours) for m in mons)
        weighed = _weighed(mons[1], ev, f[w], pts[w], cond[w], 1.0, hours)[3]
    finally:
        HYPOTHESES.pop("supply_step")
    assert named[1] == ("supply_step", None) and named[0][0] != "supply_step"
    assert weighed[-1][:3] == ["supply_step", "supply_step", None]
    assert weighed[-1][3] > 0.0  # its evidence (log posterior odds), with the alarm
    with pytest.raises(ValueError, match=r"^naming.hypotheses: 'no_such' is no hypothesis"):
        registered(NamingConfig(hypotheses=["no_such"]))
