"""The benchmark of issue 83: the monitor and two baselines scored on lives whose physics
they were not built on, over gear instances they never saw, at one false-alarm rate.

A preset's gears become a production lot (:func:`population_plan`,
:func:`swgsim.datasets.config.gear_population`); the diagnosis model trains on its first
instances, the last ``held_out`` are scored. Each family of
:func:`.families.benchmark_families` (the joint in two nodes, a Coulomb law of
its own, the friction in the dynamics, plus the family's change) is lived per held-out
instance and seed by a healthy life of ``healthy_hours`` and ``fault_lives`` fault lives:
gear faults growing from 0 to their mildest Table V severity, taken in turn over the
instances and seeds (:func:`life_faults`), the monitor's rows from
:func:`.evaluate.evaluate_gear`. A part keeps the healthy records of its
family and one fault life's at a time (:func:`part_memory`, checked before any work). The baselines
(:mod:`.baselines`) are commissioned on each life's first ``commissioning_h``
as the monitor is, their thresholds set on design lives of training instances to the
monitor's own false-alarm rate there (:func:`design_thresholds`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from learn.tracking.ledger import check_seeds
from swgmon.assessment.model import DiagnosisModel
from swgmon.evaluation.baselines import BaselineConfig, PCAChart, RegressionMEWMA
from swgmon.evaluation.evaluate import (
    evaluate_gear,
    fault_life_configs,
    healthy_life,
    lives_of,
    monitor_healthy,
)
from swgmon.evaluation.families import benchmark_families
from swgmon.evaluation.statistics import matched_threshold, upcrossings
from swgmon.evaluation.study import FAMILY_PREFIX, MonitorStudyConfig
from swgmon.evaluation.training import classes, features_of, shared_features
from swgsim.base.typed import allowed
from swgsim.datasets.config import gear_population
from swgsim.datasets.life import LifeSimulator
from swgsim.datasets.plan import DatasetPlan, plan
from swgsim.datasets.records import RecordBank, record_bank
from swgsim.datasets.resources import BYTES_PER_RECORD_SAMPLE, RESERVE_BYTES
from swgsim.files.inputs import available_memory
from swgsim.sensing.sensor_faults import SENSOR_FAULTS

__all__ = ["ABLATION", "BASELINES", "BenchmarkConfig", "Lot", "ablated", "baseline_rows",
           "benchmark_part", "check_memory", "design_thresholds", "instances", "life_faults",
           "part_memory", "population_plan"]

#: The baselines, by the name their rows carry.
BASELINES = {"regression_mewma": RegressionMEWMA, "pca": PCAChart}
#: The monitor's ablation: its laws replaced by a generic regression
#: (:class:`~swgmon.detection.normal.NormalConfig` ``laws``), its own model.
ABLATION = "monitor_generic"


@dataclass
class BenchmarkConfig:
    """The benchmark's design (module docstring).

    Attributes
    ----------
    population : int
        Gear instances drawn per preset, in [3, 999] (12).
    population_seed : int
        The lot's seed (:func:`~swgsim.datasets.config.gear_population`).
    held_out : int
        Instances scored (the last ones), never trained on, in [1, population - 2] (4).
    design_instances : int
        Training instances whose design lives set the baselines' thresholds (2).
    families : list of str
        Keys of :func:`~.families.benchmark_families` lived (default all).
    healthy_hours : float
        Operating hours of each healthy life, commissioning included (200).
    fault_lives : int
        Fault lives per held-out instance and seed, each a gear fault growing from 0 to
        its mildest Table V severity over ``study.family_growth_h``, the faults taken in
        turn (:func:`life_faults`); at most the data set's gear faults (1: with 4
        instances and 5 seeds, 20 fault lives per family and data set, each of five
        faults 4 times).
    seeds : list of int
        The scored lives' seeds, per held-out instance: scored seeds (from
        :data:`~learn.tracking.ledger.SCORED_SEED_MIN`) in a scored run, design seeds
        otherwise (:func:`~learn.tracking.ledger.check_seeds`).
    design_seeds : list of int
        Seeds of the design lives (below the scored seeds' range).
    study : MonitorStudyConfig
        The monitor's evaluation settings (commissioning, windows, fault lives, rule, normal
        behaviour, the training lives); its seeds and families are the benchmark's
        (:meth:`study_of`), not read.
    baselines : BaselineConfig
    scored_run : bool
        A declared scored run (:mod:`learn.tracking.ledger`): ``seeds`` must be scored
        seeds, and the run enters the ledger.
    ablation : bool
        Also score the monitor with a generic regression in place of its laws
        (:data:`ABLATION`, :meth:`ablated`), trained and run as the monitor is.
    level : float
        Two-sided confidence level of every interval the tables give (the healthy lives'
        Clopper-Pearson interval, the delay's bootstrap), in (0, 1) (0.95: the protocol's,
        docs/results/protocol.md).
    """

    population: int = field(default=12, metadata=allowed(3, 999))
    population_seed: int = field(default=0, metadata=allowed(0, 2**22 - 1))
    held_out: int = field(default=4, metadata=allowed(1, 997))
    design_instances: int = field(default=2, metadata=allowed(1, 996))
    families: list[str] = field(default_factory=lambda: list(benchmark_families()))
    healthy_hours: float = field(default=200.0, metadata=allowed(0.0, 1e5, lo_open=True,
                                                                 unit="h"))
    fault_lives: int = field(default=1, metadata=allowed(1, 99))
    seeds: list[int] = field(default_factory=lambda: [300, 301, 302, 303, 304])
    design_seeds: list[int] = field(default_factory=lambda: [200, 201])
    study: MonitorStudyConfig = field(default_factory=MonitorStudyConfig)
    baselines: BaselineConfig = field(default_factory=BaselineConfig)
    scored_run: bool = False
    ablation: bool = True
    level: float = field(default=0.95, metadata=allowed(0.0, 1.0, lo_open=True, hi_open=True))

    def check(self, where: str = "benchmark") -> None:
        """Refuse instances, families or seeds that do not fit, in one line naming the key.

        Raises
        ------
        ValueError
            ``held_out`` leaving fewer than two training instances, ``design_instances``
            beyond them, an unknown family, scored and design seeds mixed
            (:func:`~learn.tracking.ledger.check_seeds`), design seeds among the scored.
        """
        if self.held_out > self.population - 2:
            raise ValueError(f"{where}.held_out must leave at least two training instances "
                             f"of population={self.population}, got {self.held_out}")
        if self.design_instances > self.population - self.held_out:
            raise ValueError(f"{where}.design_instances must lie within the "
                             f"{self.population - self.held_out} training instances, got "
                             f"{self.design_instances}")
        known = benchmark_families()
        bad = [f for f in self.families if f not in known]
        if bad or not self.families:
            raise ValueError(f"{where}.families: {bad or 'empty'}; allowed: "
                             f"{', '.join(known)}")
        check_seeds(self.seeds, self.scored_run, f"{where}.scored_run")
        check_seeds(self.design_seeds, False, f"{where}.design_seeds")
        both = sorted(set(self.design_seeds) & (set(self.seeds) | set(self.study.design_seeds)))
        if both:
            raise ValueError(f"{where}.design_seeds must differ from seeds and "
                             f"study.design_seeds, both hold {both}")
        if self.healthy_hours <= self.study.commissioning_h:
            raise ValueError(f"{where}.healthy_hours must exceed study.commissioning_h "
                             f"({self.study.commissioning_h:g} h), got {self.healthy_hours:g}")

    def study_of(self, family: str, design: bool = False, seeds: list[int] | None = None,
                 faults: list[str] | None = None) -> MonitorStudyConfig:
        """The monitor's study for one family's lives, checked: the scored lives
        (``seeds``, or those given), or the design lives (``design_seeds``, never a
        scored run's); growing faults only, ``faults`` (default the study's)."""
        seeds = list(self.design_seeds if design else self.seeds) if seeds is None else seeds
        study = dataclasses.replace(
            self.study, families={family: benchmark_families()[family]}, nuisances={},
            nuisance_hours=self.healthy_hours, seeds=seeds, family_seeds=seeds,
            scored_run=self.scored_run and not design, family_steps=False,
            faults=self.study.faults if faults is None else faults)
        study.check("benchmark.study")
        return study


def ablated(study: MonitorStudyConfig) -> MonitorStudyConfig:
    """The study with the monitor's laws replaced by a generic regression
    (:data:`ABLATION`)."""
    return dataclasses.replace(study, normal=dataclasses.replace(study.normal,
                                                                 laws="generic"))


class Lot(Protocol):
    """A design over a production lot: :class:`BenchmarkConfig`, the prognosis's
    :class:`~.prognosis_evaluation.PrognosisStudyConfig`."""

    population: int
    population_seed: int
    held_out: int


def population_plan(base: DatasetPlan, cfg: Lot) -> DatasetPlan:
    """A preset's plan with its gears replaced by the design's lot (checked)."""
    return plan(dataclasses.replace(base.config, gears=gear_population(
        cfg.population, cfg.population_seed)))


def instances(cfg: Lot) -> tuple[list[int], list[int]]:
    """The training instances and the held-out ones (ids, the last ``held_out``)."""
    ids = list(range(1, cfg.population + 1))
    return ids[:-cfg.held_out], ids[-cfg.held_out:]


def gear_faults(plan: DatasetPlan, cfg: BenchmarkConfig) -> list[str]:
    """The gear faults the benchmark's lives grow (the study's, sensor faults aside)."""
    return [c for c in classes(plan, cfg.study)[1:] if c not in SENSOR_FAULTS]


def life_faults(plan: DatasetPlan, cfg: BenchmarkConfig, g: int, seed: int) -> list[str]:
    """The gear faults held-out instance ``g`` lives for a seed: ``fault_lives`` of
    them in turn, starting at (instance index + seed index × ``fault_lives``) modulo
    their number, so the instances and seeds spread over every fault evenly.

    Raises
    ------
    ValueError
        ``fault_lives`` above the data set's gear faults.
    """
    faults = gear_faults(plan, cfg)
    if cfg.fault_lives > len(faults):
        raise ValueError(f"benchmark.study.fault_lives must be at most the "
                         f"{len(faults)} gear faults of {plan.config.name}, got "
                         f"{cfg.fault_lives}")
    i, j = instances(cfg)[1].index(g), list(cfg.seeds).index(seed)
    start = i + j * cfg.fault_lives
    return [faults[(start + m) % len(faults)] for m in range(cfg.fault_lives)]


def part_memory(plan: DatasetPlan, cfg: BenchmarkConfig) -> int:
    """Records a lives part holds at its peak [bytes], every life of every part planned on
    the way (its conditions drawn, its records keyed; nothing simulated): per held-out
    instance and family, the healthy records of its seeds' healthy lives plus those of its
    largest fault life (:meth:`RecordBank.release
    <swgsim.datasets.records.RecordBank.release>` drops a fault life's after its seed).

    Raises
    ------
    ValueError
        A life that cannot be planned (e.g. a friction factor beyond the simulated ones),
        or ``fault_lives`` beyond the data set's gear faults, before any work.
    """
    most = 0
    for g in instances(cfg)[1]:
        for family in cfg.families:
            bank, healthy, worst = record_bank(plan, g), set(), 0
            for seed in cfg.seeds:
                study = cfg.study_of(family, seeds=[seed],
                                     faults=life_faults(plan, cfg, g, seed))
                life = f"{FAMILY_PREFIX}{family}"
                base = healthy_life(plan, bank, g, study, seed, life).life
                healthy |= bank.wanted()
                for fl, _, _ in fault_life_configs(plan, study, seed, life, base):
                    one = record_bank(plan, g)
                    LifeSimulator(plan, g, fl, one)
                    worst = max(worst, len(one.wanted() - healthy))
            per = max(bank.record_samples(k) for k in healthy) * BYTES_PER_RECORD_SAMPLE
            most = max(most, (len(healthy) + worst) * per)
    return most


def check_memory(plans: dict[str, DatasetPlan], cfg: BenchmarkConfig, n_jobs: int,
                 available: int | None = None) -> None:
    """Refuse a benchmark whose lives cannot be planned or whose lives parts, ``n_jobs`` at
    once, cannot hold their records in memory (:func:`part_memory`), before any work.

    Raises
    ------
    ValueError
        One line naming the data set, the estimate, the memory available and the keys
        that lower it.
    """
    avail = available_memory() if available is None else available
    if avail is None:
        return
    for name, p in plans.items():
        need = part_memory(p, cfg) * n_jobs + RESERVE_BYTES
        if need > avail:
            raise ValueError(
                f"not enough memory: benchmark.datasets.{name}'s lives parts hold about "
                f"{need / 2**30:.3g} GiB with benchmark.n_jobs={n_jobs} at once; "
                f"{avail / 2**30:.3g} GiB available. Lower benchmark.n_jobs or "
                "benchmark.study.fault_lives")


@dataclass(frozen=True)
class _Windows:
    """A life's windows as the charts read them: features (W, F), duty labels (W,),
    temperature readings (W,) or None, hours (W,)."""

    x: np.ndarray
    duty: np.ndarray
    temp: np.ndarray | None
    hour: np.ndarray

    @classmethod
    def of(cls, sim: LifeSimulator, start: int = 0) -> _Windows:
        f, p, meta = features_of(sim, start, len(sim))
        return cls(f, p[:, 0] * 1e4 + p[:, 1], meta.get("temperature_c"), meta["hour"])

    def part(self, rows: slice) -> tuple:
        return self.x[rows], self.duty[rows], None if self.temp is None else self.temp[rows]

    def then(self, k0: int, after: _Windows) -> _Windows:
        """These windows up to ``k0``, then ``after``'s (a fault life: the healthy one's
        windows before its onset are its own)."""
        temp = None if self.temp is None else np.concatenate([self.temp[:k0], after.temp])
        return _Windows(np.concatenate([self.x[:k0], after.x]),
                        np.concatenate([self.duty[:k0], after.duty]), temp,
                        np.concatenate([self.hour[:k0], after.hour]))


def _charts(w: _Windows, n_comm: int, cfg: BenchmarkConfig) -> dict:
    """Each baseline commissioned on the life's first ``n_comm`` windows."""
    return {name: chart(cfg.baselines).fit(*w.part(slice(None, n_comm)))
            for name, chart in BASELINES.items()}


def _statistics(charts: dict, w: _Windows, n_comm: int) -> tuple[dict[str, np.ndarray],
                                                                  np.ndarray]:
    """Each baseline's statistic over the windows after commissioning, and their hours."""
    after = slice(n_comm, None)
    return {b: c.statistic(*w.part(after)) for b, c in charts.items()}, w.hour[after]


def design_thresholds(plan: DatasetPlan, banks: dict[int, RecordBank],
                      model: DiagnosisModel, cfg: BenchmarkConfig, dataset: str
                      ) -> tuple[dict[str, float], dict]:
    """Each baseline's threshold at the monitor's false-alarm rate, both measured on the
    healthy design lives of the first ``design_instances`` training instances (every
    family, every design seed): the monitor's gear-fault alarms there, at least one, over
    those lives' hours (matched ARL0;
    :func:`~.statistics.matched_threshold`).

    Returns
    -------
    thresholds : dict of str to float
        Per baseline of :data:`BASELINES`.
    design : dict
        ``lives``, ``hours`` and the monitor's ``alarms`` and ``per_1000h`` there.
    """
    train, _ = instances(cfg)
    stats: dict[str, list[np.ndarray]] = {b: [] for b in BASELINES}
    hours, alarms = [], 0
    for family in cfg.families:
        study = cfg.study_of(family, design=True)
        life = f"{FAMILY_PREFIX}{family}"
        n_comm = int(round(study.commissioning_h * 60 / study.interval_min))
        for g in train[:cfg.design_instances]:
            for seed in study.seeds:
                healthy = healthy_life(plan, banks[g], g, study, seed, life)
                with shared_features():
                    named = monitor_healthy(model, study, healthy, seed, life)[3]
                    w = _Windows.of(healthy)
                alarms += sum(a.kind == "gear_fault" for a in named)
                s, _ = _statistics(_charts(w, n_comm, cfg), w, n_comm)
                for b in BASELINES:
                    stats[b].append(s[b])
                hours.append(float(healthy.life.hours - study.commissioning_h))
        for bank in banks.values():  # a family's records serve no other
            bank.release(healthy=True)
    total = float(sum(hours))
    rate = 1000.0 * max(alarms, 1) / total
    thresholds = {b: matched_threshold(stats[b], hours, rate)
                  for b in BASELINES}
    return thresholds, {"lives": len(hours), "hours": total, "alarms": alarms,
                        "per_1000h": rate}


def baseline_rows(plan: DatasetPlan, banks: dict[int, RecordBank], g: int,
                  study: MonitorStudyConfig, cfg: BenchmarkConfig, family: str,
                  thresholds: dict[str, float], dataset: str
                  ) -> tuple[list[dict], list[dict]]:
    """The baselines on one held-out instance's lives of one family: per seed, the healthy
    life's alarms (upcrossings of the threshold) and each fault life's first alarm after
    its onset.

    Returns
    -------
    rows : list of dict
        One per fault life and baseline: ``detected``, ``time_to_detect_h`` (NaN when
        not), ``alarm_before_onset``.
    fa_rows : list of dict
        One per healthy life and baseline: ``healthy_hours``, ``gear_fault_alarms``.
    """
    nuisance = f"{FAMILY_PREFIX}{family}"
    n_comm = int(round(study.commissioning_h * 60 / study.interval_min))
    rows, fa_rows = [], []
    for seed in study.seeds:
        healthy, faults = lives_of(plan, banks, g, study, seed, nuisance)
        key = {"dataset": dataset, "held_out_gear": g, "seed": seed, "nuisance": nuisance}
        w = _Windows.of(healthy)
        charts = _charts(w, n_comm, cfg)
        s, _ = _statistics(charts, w, n_comm)
        hours = float(healthy.life.hours - study.commissioning_h)  # as the monitor's rows
        for b in BASELINES:
            fa_rows.append({**key, "detector": b, "healthy_hours": hours,
                            "gear_fault_alarms": upcrossings(s[b], thresholds[b])})
        for sim, fo, kind in faults:  # the healthy life's windows up to the onset
            k0 = int(np.searchsorted(sim.schedule.hour, fo.onset_h, side="left"))
            s, h = _statistics(charts, w.then(k0, _Windows.of(sim, k0)), n_comm)
            for b in BASELINES:
                above = np.nan_to_num(s[b], nan=-np.inf) > thresholds[b]
                after = np.flatnonzero(above & (h >= fo.onset_h))
                rows.append({**key, "detector": b, "fault": fo.fault,
                             "severity": fo.severity, "onset": kind, "onset_h": fo.onset_h,
                             "detected": bool(after.size),
                             "time_to_detect_h": float(h[after[0]] - fo.onset_h)
                             if after.size else np.nan,
                             "alarm_before_onset": bool(np.any(above & (h < fo.onset_h)))})
    return rows, fa_rows


def benchmark_part(plan: DatasetPlan, banks: dict[int, RecordBank],
                   models: dict[str, DiagnosisModel], g: int, family: str,
                   cfg: BenchmarkConfig, thresholds: dict[str, float], dataset: str) -> dict:
    """One held-out instance's lives of one family: the monitor's rows (``models``
    ``monitor``; and with ``cfg.ablation``, :data:`ABLATION`'s, its model under that
    key), and the baselines', every detector reading the same lives' features once
    (:func:`~.training.shared_features`).

    Returns
    -------
    dict
        ``rows`` (fault lives), ``false_alarms`` (healthy lives), each with a
        ``detector`` column (``monitor``, :data:`ABLATION` or a key of
        :data:`BASELINES`) and ``family``.
    """
    rows, fa = [], []
    for seed in cfg.seeds:  # a seed's own fault lives (life_faults)
        study = cfg.study_of(family, seeds=[seed], faults=life_faults(plan, cfg, g, seed))
        monitors = {"monitor": study, **({ABLATION: ablated(study)} if cfg.ablation else {})}
        with shared_features():
            for name, s in monitors.items():
                r, f, _ = evaluate_gear(plan, banks, g, models[name], s, dataset,
                                        f"{FAMILY_PREFIX}{family}", [seed])
                rows += [{**x, "detector": name} for x in r if x["detector"] == "monitor"]
                fa += [{**x, "detector": name} for x in f if x["detector"] == "monitor"]
            b_rows, b_fa = baseline_rows(plan, banks, g, study, cfg, family, thresholds,
                                         dataset)
        rows, fa = rows + b_rows, fa + b_fa
        banks[g].release()  # the seed's fault records: the healthy ones serve the next
    banks[g].release(healthy=True)
    return {"rows": [{**r, "family": family} for r in rows],
            "false_alarms": [{**r, "family": family} for r in fa]}
