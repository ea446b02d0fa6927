"""The benchmark of issue 83 (swgmon.evaluation.benchmark): its design checked
before any work, a lot of gear instances split into trained and held out, and, end to end
on the tiny bench, the monitor and both baselines on lives of a benchmark family at a
threshold matched on design lives of training instances."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from swgcli import dataset_preset
from swgmon.evaluation import benchmark as bm
from swgmon.evaluation.study import MonitorStudyConfig
from swgmon.evaluation.training import train_model
from swgsim.datasets import plan as P
from swgsim.datasets.records import record_bank

TINY = MonitorStudyConfig(commissioning_h=3.0, train_healthy_h=2.0, train_variants=2,
                          faults=["eccentric_wg"], interval_min=1.0, fault_life_h=2.0,
                          onset_window_h=[0.5, 1.0], family_growth_h=2.0)


@pytest.mark.parametrize(("change", "words"), [
    ({"held_out": 11}, "held_out must leave at least two training instances"),
    ({"design_instances": 9}, "design_instances must lie within the 8 training instances"),
    ({"families": ["typo"]}, "families: ['typo']; allowed: warm_up, hall"),
    ({"seeds": [1000]}, "seeds [1000] are scored seeds"),
    ({"design_seeds": [300]}, "design_seeds must differ from seeds"),
    ({"healthy_hours": 2.0}, "healthy_hours must exceed study.commissioning_h"),
])
def test_a_bad_design_is_refused_in_one_line_before_any_work(change, words):
    cfg = bm.BenchmarkConfig(study=TINY, **change)
    with pytest.raises(ValueError) as e:
        cfg.check()
    assert words in str(e.value) and "\n" not in str(e.value)


def test_the_lot_is_split_into_trained_and_held_out_instances():
    cfg = bm.BenchmarkConfig()
    train, held = bm.instances(cfg)
    assert train == list(range(1, 9)) and held == [9, 10, 11, 12]
    p = bm.population_plan(P.plan(dataset_preset("tiny_bench")), cfg)
    assert [g.id for g in p.config.gears] == list(range(1, 13))


def test_the_fault_lives_spread_over_instances_and_seeds_evenly():
    cfg = bm.BenchmarkConfig()
    p = bm.population_plan(P.plan(dataset_preset("tiny_bench")), cfg)
    faults = bm.gear_faults(p, cfg)
    assert len(faults) == 5
    drawn = [f for g in bm.instances(cfg)[1] for s in cfg.seeds
             for f in bm.life_faults(p, cfg, g, s)]
    assert len(drawn) == 20 and {f: drawn.count(f) for f in faults} == dict.fromkeys(faults, 4)
    g = bm.instances(cfg)[1][0]  # one instance lives every fault over the five seeds
    assert sorted(f for s in cfg.seeds for f in bm.life_faults(p, cfg, g, s)) == sorted(faults)
    with pytest.raises(ValueError, match=r"fault_lives must be at most the 5 gear faults"):
        bm.life_faults(p, bm.BenchmarkConfig(fault_lives=6), g, 300)


def test_a_benchmark_whose_records_cannot_fit_is_refused_before_any_work():
    cfg = bm.BenchmarkConfig(families=["warm_up"], healthy_hours=30.0)
    p = bm.population_plan(P.plan(dataset_preset("tiny_bench")), cfg)
    need = bm.part_memory(p, cfg)
    assert need > 0
    bm.check_memory({"tiny": p}, cfg, 2, available=2 * need + (1 << 31))
    with pytest.raises(ValueError) as e:
        bm.check_memory({"tiny": p}, cfg, 2, available=need)
    assert "benchmark.n_jobs=2" in str(e.value) and "\n" not in str(e.value)


def test_a_bank_releases_its_fault_records_and_keeps_the_healthy_ones():
    from swgsim.datasets.schedule import DutyPoint

    p = P.plan(dataset_preset("tiny_bench"))
    bank = record_bank(p, int(p.config.gears[0].id))
    dp = DutyPoint(2000.0, 7.0)
    healthy, fault = bank.key(dp, "healthy", 0.0, 0.0), bank.key(dp, "eccentric_wg", 0.1, 0.0)
    bank.want([healthy, fault])
    bank.release()
    assert bank.wanted() == {healthy}
    bank.release(healthy=True)
    assert bank.wanted() == set()


@pytest.mark.slow
def test_the_monitor_and_both_baselines_live_a_benchmark_family_end_to_end():
    """About 40 s: four instances of the tiny bench (two trained, two held out), the
    warm-up family (two nodes, a Coulomb law of its own, the friction in the dynamics),
    one design life and one scored life with its eccentric-WG lives."""
    cfg = bm.BenchmarkConfig(population=4, held_out=2, design_instances=1,
                             families=["warm_up"], healthy_hours=8.0, seeds=[300],
                             design_seeds=[200], study=TINY)
    cfg.check()
    p = bm.population_plan(P.plan(dataset_preset("tiny_bench")), cfg)
    train, held = bm.instances(cfg)
    banks = {g: record_bank(p, g) for g in train + held}
    models = {"monitor": train_model(p, banks, train, TINY),
              bm.ABLATION: train_model(p, banks, train, bm.ablated(TINY))}
    thr, design = bm.design_thresholds(p, banks, models["monitor"], cfg, "tiny_bench")
    assert set(thr) == set(bm.BASELINES) and design["lives"] == 1
    assert design["hours"] == pytest.approx(5.0)
    part = bm.benchmark_part(p, banks, models, held[0], "warm_up", cfg, thr, "tiny_bench")
    rows, fa = pd.DataFrame(part["rows"]), pd.DataFrame(part["false_alarms"])
    detectors = {"monitor", bm.ABLATION, *bm.BASELINES}
    assert set(rows.detector) == detectors
    assert len(rows) == 4  # one growing life (fault_lives=1), four detectors
    assert set(rows.onset) == {"growing"}
    assert set(fa.detector) == detectors and set(fa.healthy_hours) == {5.0}
    assert (rows.family == "warm_up").all() and rows.detected.dtype == bool
    # a fault life's windows before its onset are its healthy life's: the baselines read
    # those instead of simulating them again, with the same statistic
    study = cfg.study_of("warm_up")
    healthy, faults = bm.lives_of(p, banks, held[0], study, 300, "family:warm_up")
    sim, fo, _ = faults[0]
    k0 = int(np.searchsorted(sim.schedule.hour, fo.onset_h, side="left"))
    w = bm._Windows.of(healthy)
    charts = bm._charts(w, 180, cfg)
    reused = bm._statistics(charts, w.then(k0, bm._Windows.of(sim, k0)), 180)[0]
    whole = bm._statistics(charts, bm._Windows.of(sim), 180)[0]
    for b in bm.BASELINES:
        np.testing.assert_array_equal(reused[b], whole[b])


def test_the_lives_features_are_computed_once_and_read_alike():
    """Inside shared_features, windows asked for again, in other runs of windows, are
    read from those computed before, equal to computing them anew."""
    from swgmon.evaluation.training import features_of, shared_features

    cfg = bm.BenchmarkConfig(families=["warm_up"], healthy_hours=8.0, study=TINY)
    p = bm.population_plan(P.plan(dataset_preset("tiny_bench")), cfg)
    g = bm.instances(cfg)[1][0]
    study = cfg.study_of("warm_up", seeds=[300], faults=["eccentric_wg"])
    _, faults = bm.lives_of(p, {g: record_bank(p, g)}, g, study, 300, "family:warm_up")
    sim = faults[0][0]
    n = len(sim)
    whole = features_of(sim, 0, n)
    with shared_features():
        features_of(sim, n // 3, n // 2)
        again = features_of(sim, 0, n)
    np.testing.assert_array_equal(again[0], whole[0])
    np.testing.assert_array_equal(again[1], whole[1])
    for k, v in whole[2].items():
        np.testing.assert_array_equal(again[2][k], v)
        assert again[2][k].dtype == v.dtype


BENCH_TINY = ["benchmark.run_on=[tiny]", "+dataset@benchmark.datasets.tiny=tiny_bench",
              "benchmark.study.population=4", "benchmark.study.held_out=2",
              "benchmark.study.design_instances=1", "benchmark.study.families=[warm_up]",
              "benchmark.study.healthy_hours=8", "benchmark.study.seeds=[300]",
              "benchmark.study.design_seeds=[200]", "benchmark.study.study.commissioning_h=3",
              "benchmark.study.study.train_healthy_h=2", "benchmark.study.study.train_variants=2",
              "benchmark.study.study.faults=[eccentric_wg]", "benchmark.study.study.fault_life_h=2",
              "benchmark.study.study.onset_window_h=[0.5,1.0]",
              "benchmark.study.study.family_growth_h=2", "benchmark.progress=false"]


def _run(out, *extra):
    from swgcli import compose_app
    from swgcli.tasks import run_train

    return run_train(compose_app("train", ["experiment=benchmark", "~logger",
                                           f"benchmark.report_dir={out}", *BENCH_TINY,
                                           *extra]))


@pytest.mark.slow
def test_the_benchmark_experiment_runs_resumes_and_a_scored_run_enters_the_ledger(
        tmp_path, monkeypatch):
    """swgsim-train experiment=benchmark on the tiny bench (two held-out instances, one
    family): its parts, tables and files; a rerun resumes every part; a scored seed is
    refused unless the run is declared scored, and a scored run appends one ledger row."""
    from learn.tracking import ledger

    out = tmp_path / "bench"
    first = _run(out)
    assert first["parts"] == 2 and first["resumed"] == 0 and "ledger" not in first
    tab = pd.read_csv(out / "table.csv")
    assert set(tab.detector) == {"monitor", bm.ABLATION, *bm.BASELINES}
    assert {"any_alarm_high", "cadd_h", "worst_life_per_1000h"} <= set(tab.columns)
    assert _run(out)["resumed"] == 2 + 1  # the lives' parts and the design part
    with pytest.raises(ValueError, match=r"seeds \[1000\] are scored seeds"):
        _run(tmp_path / "refused", "benchmark.study.seeds=[1000]")
    book = tmp_path / "ledger.csv"
    monkeypatch.setattr(ledger, "LEDGER", str(book))
    monkeypatch.setattr(ledger, "repo_root", lambda: Path("/"))
    scored = _run(tmp_path / "scored", "benchmark.study.seeds=[1000]",
                  "benchmark.study.scored_run=true")
    assert scored["ledger"]["seeds"] == "1000" and len(ledger.read_ledger(book)) == 1


@pytest.mark.slow
def test_the_benchmark_runs_as_arrays_the_design_first(tmp_path):
    """benchmark.group: a lives group before its design part is refused in one line naming
    the group to run first; the design group, then the lives groups, write the parts the
    whole command then finds done."""
    out = tmp_path / "bench"
    with pytest.raises(ValueError) as e:
        _run(out, "benchmark.group=1")
    assert "needs its design part first: run benchmark.group=0 before" in str(e.value)
    assert "\n" not in str(e.value)
    with pytest.raises(ValueError, match=r"benchmark.group must lie in \[0, 2\]"):
        _run(out, "benchmark.group=3")
    assert _run(out, "benchmark.group=0")["group"] == 0
    for g in (1, 2):
        assert len(_run(out, f"benchmark.group={g}")["parts"]) == 1
    assert _run(out)["resumed"] == 3


def _synthetic(alarms_monitor: list[int], detected_monitor: list[bool]):
    """results.csv and false_alarms.csv of a benchmark of one data set and family, four
    lives per detector."""
    from swgmon.evaluation.benchmark_task import benchmark_targets

    rows, fa = [], []
    for det in ("monitor", bm.ABLATION, *bm.BASELINES):
        for i in range(4):
            mon = det == "monitor"
            hit = detected_monitor[i] if mon else i < 2
            rows.append({"dataset": "bench", "family": "warm_up", "detector": det,
                         "held_out_gear": 9 + i, "fault": "eccentric_wg", "detected": hit,
                         "time_to_detect_h": (5.0 if mon else 30.0) if hit else np.nan,
                         "fault_at_alarm": "eccentric_wg" if mon else np.nan,
                         "fault_after_1h": "eccentric_wg" if mon else np.nan})
            fa.append({"dataset": "bench", "family": "warm_up", "detector": det,
                       "held_out_gear": 9 + i, "healthy_hours": 176.0,
                       "gear_fault_alarms": alarms_monitor[i] if mon else 3})
    return benchmark_targets(pd.DataFrame(rows), pd.DataFrame(fa), 0.95).set_index("target")


def test_the_protocols_targets_are_judged_from_the_runs_rows():
    met = _synthetic([0, 0, 0, 0], [True] * 4)
    assert met.loc[[1, 2, 3, 4, 5, 6], "met"].all()
    assert met.loc[7, "met"].all() and bool(met.loc[8, "met"])
    bad = _synthetic([0, 2, 0, 1], [True, True, True, False])
    assert not bad.loc[1, "met"]  # 3 alarms in 704 h: 4.3 per 1000 h
    assert not bad.loc[2, "met"] and bad.loc[2, "value"] == 2  # a life with two
    assert not bad.loc[3, "met"] and bad.loc[3, "value"] == 0.5
    assert not bad.loc[4, "met"] and bad.loc[5, "met"] and bad.loc[6, "met"]


def test_the_second_protocols_targets_are_judged_from_the_runs_rows():
    """Targets A-F (docs/results/protocol.md, the second protocol) on rows written by hand:
    each met where it should be and missed where one life breaks it."""
    from swgmon.evaluation.benchmark_task import second_targets

    rows, fa = [], []
    faults = ("eccentric_wg", "root_tooth_crack", "reduced_stiffness")
    for det in ("monitor", *bm.BASELINES):
        mon = det == "monitor"
        for fam in ("warm_up", "sensor_stuck"):
            for g in (9, 10):
                for seed in range(5):
                    alarms = int(mon and fam == "sensor_stuck" and g == 10 and seed == 0)
                    fa.append({"dataset": "bench", "family": fam, "detector": det,
                               "held_out_gear": g, "seed": seed, "healthy_hours": 176.0,
                               "gear_fault_alarms": alarms if mon else 2})
                for i, fault in enumerate(faults):
                    t = (41.5 if fault == "root_tooth_crack" else 12.0) if mon else 30.0
                    hit = mon or i == 0
                    named = "tip_tooth_crack" if fault == "reduced_stiffness" else fault
                    rows.append({"dataset": "bench", "family": fam, "detector": det,
                                 "held_out_gear": g, "fault": fault, "detected": hit,
                                 "time_to_detect_h": t if hit else np.nan,
                                 "fault_at_alarm": named if mon else np.nan})
    t = second_targets(pd.DataFrame(rows), pd.DataFrame(fa), 40.0, 0.95)
    a = t[t.target == "A"].set_index("cell")
    assert a.loc["warm_up, 9", "met"] and a.loc["warm_up, 9", "n"] == 5
    assert not a.loc["sensor_stuck, 10", "met"] and a.loc["sensor_stuck, 10", "value"] == 0.2
    assert a.loc["sensor_stuck, 10", "high"] > 0.2  # Clopper-Pearson's upper bound
    assert not a.loc["sensor_stuck, all", "judged"]
    assert a.loc["sensor_stuck, all", "value"] == 0.1 and a.loc["sensor_stuck, all", "n"] == 10
    c = t[t.target == "C"].set_index("cell")
    assert c.loc["eccentric_wg", "value"] == 0.0 and c.loc["eccentric_wg", "met"]
    assert c.loc["root_tooth_crack", "value"] == 1.5 and not c.loc["root_tooth_crack", "met"]
    d = t[t.target == "D"].set_index("cell")
    assert d.loc["eccentric_wg", "met"] and not d.loc["reduced_stiffness", "judged"]
    assert d.loc["reduced_stiffness", "value"] == 0.0
    b = t[t.target == "B"].set_index("cell")
    assert b.loc["root_tooth_crack", "value"] == 1.0 and b.loc["root_tooth_crack", "n"] == 4
    e = t[t.target == "E"].iloc[0]
    assert e.value == 1 and e.n == 10 and not e.met
    f = t[t.target == "F"].set_index("cell")
    assert set(f.index) == set(bm.BASELINES) and f.met.all()  # all found, sooner on average
