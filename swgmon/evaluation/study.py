"""The design of the monitor's evaluation (``monitor.study``), declared before it runs, and
its checks.

The training lives (:mod:`.training`) and the held-out lives
(:mod:`.evaluate`) both read this design; nothing of it is chosen on the
held-out gear.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from learn.tracking.ledger import SCORED_SEED_MIN, check_seeds
from swgmon.assessment.hypotheses import registered
from swgmon.assessment.sensor_check import NamingConfig
from swgmon.detection.normal import NormalConfig
from swgmon.detection.rule import RuleConfig
from swgmon.evaluation.detectors import DETECTORS
from swgmon.evaluation.families import NuisanceFamily, draw_conditions
from swgsim.base.typed import allowed, check_range, check_tree
from swgsim.datasets.conditions import ConditionsConfig, RunInConfig
from swgsim.datasets.schedule import MAX_WINDOWS
from swgsim.gear.faults import FAULTS
from swgsim.gear.thermal import JointThermal
from swgsim.sensing.bridge_drift import BridgeDrift, TemperatureSensor


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


def _req(cond: bool, msg: str) -> None:
    if not cond:
        raise ValueError(msg)


#: Range of a duration of the study, (0, 1e5] h.
_HOURS = allowed(0.0, 1e5, lo_open=True, unit="h")


@dataclass
class MonitorStudyConfig:
    """The evaluation's design, declared before it runs; it checks itself (its fields'
    ranges and :meth:`check`, run by :func:`swgsim.base.typed.check_tree`).

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
    fault_life_h : float
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
        (:func:`.training.train_severities`): increasing, inside the fault's
        severity range; empty: Table V's for every fault. A severity regressor estimates
        only what it was trained on (a tree ensemble neither extrapolates nor interpolates
        well between far levels), so the prognosis's study trains its growing faults on
        the levels their lives pass through (:mod:`.prognosis_evaluation`).
    gears : list of int
        Held-out gears; empty: every gear of the data set.
    detectors : list of str
        Per-window detectors evaluated beside the monitor (keys of
        :data:`.detectors.DETECTORS`); one that cannot run on a data set is
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
        Benign changes drawn from a family per seed (:mod:`.families`),
        lived as ``family:<key>`` (:func:`life_conditions`) by a healthy life of
        ``nuisance_hours`` per seed and by every gear fault at its mildest and largest
        Table V severity, and at its mildest growing over ``family_growth_h``; default
        none: the families live where asked for (:func:`.evaluate.
        run_held_out`'s ``lives``; ``scripts/monitor_families.py`` lives
        :func:`~.families.default_families`), and each draw is checked
        against the study's lives only then (a study of 3-h lives is not refused for
        families it does not live).
    design_seeds : list of int
        Seeds of the family draws (and of their lives) the monitor's settings may be
        chosen on: its settings (``rule``, ``normal``, the naming rule) are chosen on
        design draws only, never on scored ones. Those in force were set before the
        families existed (the friction law's rate on nine hand-picked laws of
        tiny_real_day, issue 44), on no family draw.
    family_seeds : list of int
        Seeds of the family draws the evaluation judges the monitor on (design seeds
        unless ``scored_run``: :mod:`learn.tracking.ledger`); disjoint from
        ``design_seeds`` (:meth:`check`).
    family_growth_h : float
        Hours over which a fault of a family life grows linearly from 0 to its mildest
        Table V severity (40: slowly, under daily warm-ups).
    family_steps : bool
        A family's seed also lives every gear fault as a step at its mildest and largest
        Table V severity (False: the growing faults only, as the benchmark does).
    rule : RuleConfig
    normal : NormalConfig
        How the gear's normal behaviour follows the conditions (:mod:`swgmon.detection.normal`).
    naming : NamingConfig
        The numbers the naming of an alarm was tuned with
        (:class:`swgmon.assessment.sensor_check.NamingConfig`), logged with the run.
    scored_run : bool
        A declared scored run (:mod:`learn.tracking.ledger`): its ``seeds`` and
        ``family_seeds`` must be scored seeds (from
        :data:`~learn.tracking.ledger.SCORED_SEED_MIN` up) and the run appends itself to
        the ledger; False (the default): every seed a design seed, below it.
    curve_hours : list of float
        Design rates of the trade-off curve (one false alarm per this many hours), each a
        threshold of the same rule on the same p-values; those up to
        ``rule.design_hours`` are drawn; increasing, each in (0, 10^6] [h] (1, 3, 10, 30,
        100, 300, 1000 [choice: two a decade]).
    severity_folds : int
        Groups of training gears the severity regressors are also fitted without
        (:func:`~swgmon.assessment.model.gear_folds`), 0 or in [2, 999]: 0, one gear a
        group (the jackknife's); the prognosis's cross-validation reads a held-out
        gear's lives with each group's (:mod:`.prognosis_evaluation`).
    windows_at_once : int
        Windows of a fault life simulated at once, in [1, 10^4] (120 [choice]: a life stops
        after the chunk that holds its confirmation); no result changes
        (tests/learn/test_monitor.py).
    """

    seeds: list[int] = field(default_factory=lambda: [0, 1, 2, 3, 4])
    healthy_hours: float = field(default=1000.0, metadata=allowed(0.0, 1e6, lo_open=True,
                                                                  unit="h"))
    commissioning_h: float = 24.0
    interval_min: float = field(default=1.0, metadata=allowed(0.0, 1440.0, lo_open=True,
                                                              unit="min"))
    fault_life_h: float = field(default=24.0, metadata=_HOURS)
    onset_window_h: list[float] = field(default_factory=lambda: [1.0, 100.0])
    growth_h: float = field(default=10.0, metadata=_HOURS)
    train_fault_h: float = field(default=0.5, metadata=_HOURS)
    train_variants: int = field(default=15, metadata=allowed(1, 1000))
    sensor_train_levels: int = field(default=2, metadata=allowed(
        2, 100, "mild and severe at least"))
    train_healthy_h: float = field(default=10.0, metadata=_HOURS)
    faults: list[str] = field(default_factory=list)
    fault_severities: dict[str, list[float]] = field(default_factory=dict)
    gears: list[int] = field(default_factory=list)
    detectors: list[str] = field(default_factory=lambda: list(DETECTORS))
    detector_hours: float = 100.0
    nuisances: dict[str, ConditionsConfig] = field(default_factory=_nuisances)
    nuisance_hours: float = 224.0
    families: dict[str, NuisanceFamily] = field(default_factory=dict)
    design_seeds: list[int] = field(default_factory=lambda: [100, 101, 102, 103, 104])
    family_seeds: list[int] = field(default_factory=lambda: [0, 1, 2, 3, 4])
    family_growth_h: float = field(default=40.0, metadata=_HOURS)
    family_steps: bool = True
    rule: RuleConfig = field(default_factory=RuleConfig)
    normal: NormalConfig = field(default_factory=NormalConfig)
    naming: NamingConfig = field(default_factory=NamingConfig)
    scored_run: bool = False
    curve_hours: list[float] = field(
        default_factory=lambda: [1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0])
    severity_folds: int = field(default=0, metadata=allowed(0, 999))
    windows_at_once: int = field(default=120, metadata=allowed(1, 10**4))

    def check(self, where: str) -> None:
        """Refuse a design whose rules across fields fail, in one line naming the key,
        before any work (the fields' ranges are their metadata; the rule, the normal
        behaviour and each family check themselves, before, in the same pass).

        Parameters
        ----------
        where : str
            Full name of the study for messages, e.g. ``monitor.study``.

        Raises
        ------
        ValueError
            No seed or one outside [0, 2**32 - 1]; ``commissioning_h`` outside the healthy
            life; ``onset_window_h`` not ``[lo, hi]`` with 0 <= lo <= hi and the latest
            onset inside the healthy life; training severities not increasing inside the
            fault's range; ``nuisance_hours`` not longer than commissioning; a life of more
            windows than :data:`swgsim.datasets.schedule.MAX_WINDOWS` at ``interval_min``
            (each life the study lives, :meth:`_lives`: the hours option that makes it
            longest named, with the hours it may have); a nuisance's
            conditions out of range; the families' seeds, keys and draws
            (:meth:`_check_families`); an unknown detector; ``detector_hours`` outside each
            healthy life after commissioning; ``severity_folds`` 1.
        """
        _req(self.severity_folds != 1, f"{where}.severity_folds must be 0 (one gear a fold) "
                                       "or in [2, 999], got 1")
        _req(len(self.seeds) >= 1, f"{where}.seeds must list at least one seed")
        for i, s in enumerate(self.seeds):
            check_range(s, 0, 2**32 - 1, f"{where}.seeds[{i}]")
        check_range(self.commissioning_h, 0.0, self.healthy_hours, f"{where}.commissioning_h",
                    "h", lo_open=True, hi_open=True, why="inside the healthy life")
        _req(len(self.onset_window_h) == 2, f"{where}.onset_window_h must be [lo, hi], got "
                                            f"{self.onset_window_h}")
        lo, hi = self.onset_window_h
        _req(0 <= lo <= hi, f"{where}.onset_window_h must be [lo, hi] with 0 <= lo <= hi, "
                            f"got {self.onset_window_h}")
        _req(self.commissioning_h + hi <= self.healthy_hours, f"{where}.onset_window_h: the "
             f"latest onset, commissioning_h + {hi:g} h, must lie within the healthy life "
             f"(healthy_hours={self.healthy_hours:g} h), whose monitor state a fault life "
             "starts from")
        for f, sevs in self.fault_severities.items():
            _req(f in FAULTS, f"{where}.fault_severities: {f!r} is no gear fault; allowed: "
                              f"{', '.join(sorted(FAULTS))}")
            top = FAULTS[f].severity_range[1]
            _req(len(sevs) >= 1 and all(np.diff([0.0, *sevs]) > 0)
                 and sevs[-1] <= top, f"{where}.fault_severities.{f} must be increasing in "
                 f"(0, {top:g}] ({f}'s severity range), got {sevs}")
        check_range(self.nuisance_hours, self.commissioning_h, 1e6, f"{where}.nuisance_hours",
                    "h", lo_open=True, why="longer than commissioning")
        most_h = MAX_WINDOWS * self.interval_min / 60.0  # the hours a life may hold
        for fixed, keys in self._lives():  # a life's windows, before any work
            life = fixed + sum(getattr(self, k) for k in keys)
            n = life * 60.0 / self.interval_min
            key = max(keys, key=lambda k: getattr(self, k))  # the option that makes it long
            hours = getattr(self, key)
            _req(n <= MAX_WINDOWS, f"{where}.{key}={hours:g} h at interval_min="
                 f"{self.interval_min:g} min is {n:.3g} windows a life; allowed: at most "
                 f"{MAX_WINDOWS:.0e} (up to {max(most_h - (life - hours), 0.0):.3g} h)")
        for name, c in self.nuisances.items():  # their own rules: checked as parts, before
            c.check_inside(self.nuisance_hours, f"{where}.nuisances.{name}")
        self._check_families(where)
        bad = sorted(set(self.detectors) - set(DETECTORS))
        _req(not bad, f"{where}.detectors: unknown {bad}; allowed: {sorted(DETECTORS)}")
        check_range(self.detector_hours, 0.0, self.healthy_hours - self.commissioning_h,
                    f"{where}.detector_hours", "h", lo_open=True,
                    why="within each healthy life after commissioning")
        registered(self.naming)  # each hypothesis named imports, before any work
        _req(len(self.curve_hours) >= 1 and all(np.diff(self.curve_hours) > 0)
             and 0 < self.curve_hours[0] and self.curve_hours[-1] <= 1e6,
             f"{where}.curve_hours must be increasing in (0, 1e6] h, got {self.curve_hours}")

    def _lives(self) -> list[tuple[float, tuple[str, ...]]]:
        """The longest life of each kind the study lives, as (its hours set by no hours
        option, the hours options that add up to the rest): the held-out gear's healthy
        and nuisance lives, a fault life (the latest onset, then ``fault_life_h``; with
        families, their growing faults' ``family_growth_h`` before it:
        :func:`.evaluate.nuisance_fault_lives`) and the training lives
        (:func:`.training.training_lives`). ``growth_h`` makes no life
        longer: the growing faults of :func:`.evaluate.fault_lives` end
        ``fault_life_h`` after their onset."""
        onset = self.commissioning_h + self.onset_window_h[1]
        lives = [(0.0, ("healthy_hours",)), (0.0, ("nuisance_hours",)),
                 (onset, ("fault_life_h",)), (0.0, ("commissioning_h", "train_healthy_h")),
                 (self.interval_min / 60.0, ("train_fault_h",))]
        if self.families:
            lives.append((onset, ("family_growth_h", "fault_life_h")))
        return lives

    def _check_families(self, where: str) -> None:
        """The design and scored seeds (disjoint), and each family against the study: its
        sensor fault and re-greasing after commissioning, its draws for every seed (a
        payload step inside the shortest fault life, commissioning_h + onset_window_h[0] +
        fault_life_h). Each family's own ranges: :meth:`NuisanceFamily.check
        <swgmon.evaluation.families.NuisanceFamily.check>`, before, in the same pass."""
        for name in ("design_seeds", "family_seeds"):
            seeds = getattr(self, name)
            _req(len(seeds) >= 1, f"{where}.{name} must list at least one seed")
            for i, s in enumerate(seeds):
                check_range(s, 0, 2**32 - 1, f"{where}.{name}[{i}]")
        high = [s for s in self.design_seeds if s >= SCORED_SEED_MIN]
        _req(not high, f"{where}.design_seeds must lie below {SCORED_SEED_MIN} (the scored "
                       f"seeds' range), got {high}")
        check_seeds([*self.seeds, *self.family_seeds], self.scored_run, f"{where}.scored_run")
        both = sorted(set(self.design_seeds) & set(self.family_seeds))
        _req(not both, f"{where}.family_seeds must be disjoint from design_seeds, both hold "
                       f"{both}")
        shortest = self.commissioning_h + self.onset_window_h[0] + self.fault_life_h
        for name, fam in self.families.items():
            _req(":" not in name, f"{where}.families: a key must not hold ':', got {name!r}")
            for k in ("sensor_fault_h", "regrease_h"):
                _req(getattr(fam, k)[0] > self.commissioning_h,
                     f"{where}.families.{name}.{k} must lie after commissioning (> "
                     f"{self.commissioning_h:g} h), got {getattr(fam, k)}")
            for s in self.design_seeds + self.family_seeds:
                draw, key = draw_conditions(fam, int(s)), f"{where}.families.{name}[seed={s}]"
                check_tree(draw, key)
                draw.check_inside(min(shortest, self.nuisance_hours), key)


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
        :func:`.families.draw_conditions`).
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


__all__ = ["FAMILY_PREFIX", "MonitorStudyConfig", "family_of",
           "life_conditions"]
