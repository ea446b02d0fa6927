"""The design of the monitor's evaluation (``monitor.study``), declared before it runs, and
its checks.

The training lives (:mod:`learn.monitor.training`) and the held-out lives
(:mod:`learn.monitor.evaluate`) both read this design; nothing of it is chosen on the
held-out gear.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from swgsim.base.typed import check_finite, check_range, check_tree
from swgsim.datasets.conditions import ConditionsConfig, RunInConfig, check_conditions
from swgsim.gear.faults import FAULTS
from swgsim.gear.thermal import JointThermal
from swgsim.sensing.bridge_drift import BridgeDrift, TemperatureSensor

from .detectors import DETECTORS
from .families import NuisanceFamily, draw_conditions
from .normal import NormalConfig
from .rule import RuleConfig


def _nuisances() -> dict[str, ConditionsConfig]:
    """The benign changes of a real day the evaluation lives through, each alone and all
    together (magnitudes: :mod:`swgsim.datasets.conditions` and its sources). Commissioning
    (the first 24 h) sees two daily warm-ups; the hall warms by 10 K over the third and
    fourth day (wall-clock hours 48-96); the payload grows by 10 % at 36 h."""
    hall = [[0.0, 0.0], [48.0, 0.0], [96.0, 10.0]]

    def day(**kw) -> ConditionsConfig:  # a joint with its thermal day and its sensors
        return ConditionsConfig(**{"thermal": JointThermal(), "bridge_drift": BridgeDrift(),
                                   "temperature_sensor": TemperatureSensor(), **kw})

    still = {"thermal": None, "viscosity": False, "bridge_drift": None}
    return {"warm_up": day(),
            "hall": day(thermal=JointThermal(ambient_points=hall)),
            "run_in": day(run_in=RunInConfig(), **still),
            "payload": day(payload=[[36.0, 1.1]], **still),
            "all": day(thermal=JointThermal(ambient_points=hall), run_in=RunInConfig(),
                       payload=[[36.0, 1.1]])}


@dataclass
class MonitorStudyConfig:
    """The evaluation's design, declared before it runs.

    Attributes
    ----------
    seeds : list of int
        Life seeds per held-out gear.
    healthy_hours : float
        Operating hours of each held-out gear's healthy life, commissioning included.
    commissioning_h : float
        Commissioning period of every life [h].
    interval_min : float
        Minutes between windows.
    horizon_h : float
        Hours a fault life runs after its onset.
    onset_window_h : list of float
        The onset is drawn uniformly this many hours after commissioning, [lo, hi].
    growth_h : float
        Hours of a growing fault's linear growth to its largest severity.
    train_fault_h : float
        Hours of each training life after its fault's onset.
    train_variants : int
        Training lives per gear fault and severity: the fault at as many positions around
        the flexspline (at (j + 1/2) 360° / count, not the held-out lives' random ones); a
        sensor fault has one life on each of the five bridges. 15 (v3; 5 before): chosen
        on the training gears alone (``scripts/naming_study.py``: trained on one training
        gear, judged on the other, both ways, the root and tip cracks were named right in
        0.83-0.92 and 0.67 of lives with 5 positions, in 1.00 with 15).
    sensor_train_levels : int
        Training severities of a sensor fault: this many, geometrically spaced from its mild
        to its severe severity (:data:`swgsim.sensing.sensor_faults.SEVERITIES`; 2: those two).
    train_healthy_h : float
        Hours of each training gear's healthy life after commissioning.
    faults : list of str
        Classes evaluated; empty: every gear fault of the data set and every sensor fault.
    fault_severities : dict of str to list of float
        Training severities of a gear fault in place of its Table V ones
        (:func:`learn.monitor.training.train_severities`): increasing, inside the fault's
        severity range; empty: Table V's for every fault. A severity regressor estimates
        only what it was trained on (a tree ensemble neither extrapolates nor interpolates
        well between far levels), so the prognosis's study trains its growing faults on
        the levels their lives pass through (:mod:`learn.monitor.prognosis_evaluation`).
    gears : list of int
        Held-out gears; empty: every gear of the data set.
    detectors : list of str
        Per-window detectors evaluated beside the monitor (keys of
        :data:`learn.monitor.detectors.DETECTORS`); one that cannot run on a data set is
        reported in the table, not run.
    detector_hours : float
        Hours of each healthy life, after commissioning, over which the detectors' false
        alarms are counted (a rate of thousands per 1000 h needs no more).
    nuisances : dict of str to ConditionsConfig
        Benign changes, each lived by a healthy life of ``nuisance_hours`` per seed and by
        every gear fault at its mildest and largest Table V severity (default: the five
        of a real day); empty: none.
    nuisance_hours : float
        Operating hours of each nuisance's healthy life, commissioning included.
    families : dict of str to NuisanceFamily
        Benign changes drawn from a family per seed (:mod:`learn.monitor.families`),
        lived as ``family:<key>`` (:func:`life_conditions`) by a healthy life of
        ``nuisance_hours`` per seed and by every gear fault at its mildest and largest
        Table V severity, and at its mildest growing over ``family_growth_h``; default
        none: the families live where asked for (:func:`learn.monitor.evaluate.
        run_held_out`'s ``lives``; ``scripts/monitor_families.py`` lives
        :func:`~learn.monitor.families.default_families`), and each draw is checked
        against the study's lives only then (a study of 3-h lives is not refused for
        families it does not live).
    design_seeds : list of int
        Seeds of the family draws (and of their lives) the monitor's settings may be
        chosen on: its settings (``rule``, ``normal``, the naming rule) are chosen on
        design draws only, never on scored ones. Those in force were set before the
        families existed (the friction law's rate on nine hand-picked laws of
        tiny_real_day, issue 44), on no family draw.
    scored_seeds : list of int
        Seeds of the family draws the monitor is scored on; disjoint from
        ``design_seeds`` (:func:`check_study`).
    family_growth_h : float
        Hours over which a fault of a family life grows linearly from 0 to its mildest
        Table V severity (40: slowly, under daily warm-ups).
    rule : RuleConfig
    normal : NormalConfig
        How the gear's normal behaviour follows the conditions (:mod:`learn.monitor.normal`).
    """

    seeds: list[int] = field(default_factory=lambda: [0, 1, 2, 3, 4])
    healthy_hours: float = 1000.0
    commissioning_h: float = 24.0
    interval_min: float = 1.0
    horizon_h: float = 24.0
    onset_window_h: list[float] = field(default_factory=lambda: [1.0, 100.0])
    growth_h: float = 10.0
    train_fault_h: float = 0.5
    train_variants: int = 15
    sensor_train_levels: int = 2
    train_healthy_h: float = 10.0
    faults: list[str] = field(default_factory=list)
    fault_severities: dict[str, list[float]] = field(default_factory=dict)
    gears: list[int] = field(default_factory=list)
    detectors: list[str] = field(default_factory=lambda: list(DETECTORS))
    detector_hours: float = 100.0
    nuisances: dict[str, ConditionsConfig] = field(default_factory=_nuisances)
    nuisance_hours: float = 224.0
    families: dict[str, NuisanceFamily] = field(default_factory=dict)
    design_seeds: list[int] = field(default_factory=lambda: [100, 101, 102, 103, 104])
    scored_seeds: list[int] = field(default_factory=lambda: [0, 1, 2, 3, 4])
    family_growth_h: float = 40.0
    rule: RuleConfig = field(default_factory=RuleConfig)
    normal: NormalConfig = field(default_factory=NormalConfig)


#: Prefix of a family's lives among the nuisances (``family:warm_up``): the fixed
#: nuisances and the families share keys.
FAMILY_PREFIX = "family:"


def family_of(life: str) -> str | None:
    """The family key of a life's name (``family:warm_up`` -> ``warm_up``), None for
    ``none`` or a fixed nuisance."""
    return life[len(FAMILY_PREFIX):] if life.startswith(FAMILY_PREFIX) else None


def life_conditions(cfg: MonitorStudyConfig, life: str, seed: int) -> ConditionsConfig | None:
    """The conditions a life of the evaluation lives for a seed.

    Parameters
    ----------
    cfg : MonitorStudyConfig
    life : str
        ``none``, a key of ``cfg.nuisances`` (its fixed conditions, the same object for
        every seed) or ``family:<key>`` of ``cfg.families`` (drawn from it by the seed,
        :func:`learn.monitor.families.draw_conditions`).
    seed : int
        The life's seed, in [0, 2**32 - 1].

    Returns
    -------
    ConditionsConfig or None
        None for ``none``.

    Raises
    ------
    KeyError
        ``life`` names no nuisance or family (the allowed names listed).
    """
    fam = family_of(life)
    if fam is not None and fam in cfg.families:
        return draw_conditions(cfg.families[fam], int(seed))
    if life == "none" or life in cfg.nuisances:
        return None if life == "none" else cfg.nuisances[life]
    raise KeyError(f"nuisance {life!r}: allowed none, {', '.join(cfg.nuisances)}, "
                   + ", ".join(FAMILY_PREFIX + k for k in cfg.families))


def _check_families(sc: MonitorStudyConfig, key: str) -> None:
    """The families, their draws for every design and scored seed (a payload step inside
    the shortest fault life, commissioning_h + onset_window_h[0] + horizon_h), the seeds
    (disjoint) and the growth."""
    for name, seeds in (("design_seeds", sc.design_seeds), ("scored_seeds", sc.scored_seeds)):
        _req(len(seeds) >= 1, f"{key}.{name} must list at least one seed")
        for i, s in enumerate(seeds):
            check_range(s, 0, 2**32 - 1, f"{key}.{name}[{i}]")
    both = sorted(set(sc.design_seeds) & set(sc.scored_seeds))
    _req(not both, f"{key}.scored_seeds must be disjoint from design_seeds, both hold {both}")
    check_range(sc.family_growth_h, 0.0, 1e5, f"{key}.family_growth_h", "h", lo_open=True)
    shortest = sc.commissioning_h + sc.onset_window_h[0] + sc.horizon_h
    for name, fam in sc.families.items():
        _req(":" not in name, f"{key}.families: a key must not hold ':', got {name!r}")
        fam.check(f"{key}.families.{name}")
        for k in ("sensor_fault_h", "regrease_h"):
            _req(getattr(fam, k)[0] > sc.commissioning_h,
                 f"{key}.families.{name}.{k} must lie after commissioning (> "
                 f"{sc.commissioning_h:g} h), got {getattr(fam, k)}")
        for s in sc.design_seeds + sc.scored_seeds:
            check_conditions(draw_conditions(fam, int(s)), min(shortest, sc.nuisance_hours),
                             f"{key}.families.{name}[seed={s}]")


def _req(cond: bool, msg: str) -> None:
    if not cond:
        raise ValueError(msg)


def check_study(sc: MonitorStudyConfig, key: str = "monitor.study") -> None:
    """Refuse a study design outside its ranges, in one line naming the key, before any
    work.

    Parameters
    ----------
    sc : MonitorStudyConfig
    key : str
        Full name of ``sc`` for messages.

    Raises
    ------
    ValueError
        NaN or infinity anywhere, or a value outside its range (named with the range).
    """
    check_finite(sc, key)
    _req(len(sc.seeds) >= 1, f"{key}.seeds must list at least one seed")
    for i, s in enumerate(sc.seeds):
        check_range(s, 0, 2**32 - 1, f"{key}.seeds[{i}]")
    check_range(sc.healthy_hours, 0.0, 1e6, f"{key}.healthy_hours", "h", lo_open=True)
    check_range(sc.commissioning_h, 0.0, sc.healthy_hours, f"{key}.commissioning_h", "h",
                lo_open=True, hi_open=True, why="inside the healthy life")
    check_range(sc.interval_min, 0.0, 1440.0, f"{key}.interval_min", "min", lo_open=True)
    _req(len(sc.onset_window_h) == 2, f"{key}.onset_window_h must be [lo, hi], got "
                                      f"{sc.onset_window_h}")
    lo, hi = sc.onset_window_h
    _req(0 <= lo <= hi, f"{key}.onset_window_h must be [lo, hi] with 0 <= lo <= hi, got "
                        f"{sc.onset_window_h}")
    _req(sc.commissioning_h + hi <= sc.healthy_hours, f"{key}.onset_window_h: the latest "
         f"onset, commissioning_h + {hi:g} h, must lie within the healthy life (healthy_hours="
         f"{sc.healthy_hours:g} h), whose monitor state a fault life starts from")
    for k in ("horizon_h", "growth_h", "train_fault_h", "train_healthy_h"):
        check_range(getattr(sc, k), 0.0, 1e5, f"{key}.{k}", "h", lo_open=True)
    check_range(sc.train_variants, 1, 1000, f"{key}.train_variants")
    check_range(sc.sensor_train_levels, 2, 100, f"{key}.sensor_train_levels",
                why="mild and severe at least")
    for f, sevs in sc.fault_severities.items():
        _req(f in FAULTS, f"{key}.fault_severities: {f!r} is no gear fault; allowed: "
                          f"{', '.join(sorted(FAULTS))}")
        top = FAULTS[f].severity_range[1]
        _req(len(sevs) >= 1 and all(np.diff([0.0, *sevs]) > 0)
             and sevs[-1] <= top, f"{key}.fault_severities.{f} must be increasing in (0, "
             f"{top:g}] ({f}'s severity range), got {sevs}")
    check_tree(sc.rule, f"{key}.rule")
    sc.normal.check(f"{key}.normal")
    check_range(sc.nuisance_hours, sc.commissioning_h, 1e6, f"{key}.nuisance_hours", "h",
                lo_open=True, why="longer than commissioning")
    for name, c in sc.nuisances.items():
        check_conditions(c, sc.nuisance_hours, f"{key}.nuisances.{name}")
    _check_families(sc, key)
    bad = sorted(set(sc.detectors) - set(DETECTORS))
    _req(not bad, f"{key}.detectors: unknown {bad}; allowed: {sorted(DETECTORS)}")
    check_range(sc.detector_hours, 0.0, sc.healthy_hours - sc.commissioning_h,
                f"{key}.detector_hours", "h", lo_open=True,
                why="within each healthy life after commissioning")


__all__ = ["FAMILY_PREFIX", "MonitorStudyConfig", "check_study", "family_of",
           "life_conditions"]
