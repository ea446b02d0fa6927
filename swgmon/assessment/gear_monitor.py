"""One gear's monitor: commissioning, scoring and the sequential alarm.

:class:`GearMonitor` takes a trained :class:`~.model.DiagnosisModel` and a
gear's windows in time order. :meth:`GearMonitor.commission` builds the normal behaviour from
the commissioning windows, alternately per operating point: even ones fit the normal behaviour,
odd ones calibrate the rule (:mod:`swgmon.detection.rule`). :meth:`GearMonitor.run` scores every
later window by the diagnosis model's evidence relative to the gear's own healthy
calibration windows (:meth:`GearMonitor.evidence`) and the novelty, updates the CUSUM and
raises an alarm when it crosses h; :func:`.naming.diagnose` names it. The alarm
latches: one alarm per stream until the gear is commissioned again; an evaluation of false
alarms restarts the CUSUM after each (``latch=False``). Where an operating point's acting
load stays beyond what commissioning saw there (a heavier tool), the monitor gathers the
point's windows and recommissions it (:meth:`GearMonitor._learn`: its load range grows
where commissioning's laws hold there, else the windows become its normal;
:class:`~swgmon.detection.normal.NormalConfig` ``recommission_load``).
:meth:`GearMonitor.step` is the same monitor for one window at a time, as a live joint
delivers them: the same numbers as :meth:`~GearMonitor.run` (tested), with the CUSUMs
kept in the monitor, at a fraction of the block path's overhead for a single window.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field

import numpy as np

from swgmon.assessment.hypotheses import registered
from swgmon.assessment.model import DiagnosisModel, design_matrix
from swgmon.assessment.sensor_check import NamingConfig, virtual_temperature
from swgmon.detection.normal import (
    Conditions,
    NormalBehaviour,
    NormalConfig,
    Outside,
)
from swgmon.detection.rule import (
    RuleConfig,
    check_commissioning,
    conformal_p,
    judged_bets,
    log_bets,
    normal_scores,
    run_cusums,
    threshold,
)
from swgsim.base.typed import check_range

#: What the maintenance log may declare (:class:`MaintenanceEvent`).
MAINTENANCE_KINDS = ("regrease", "tool_change", "repair")
#: Declared events after which the monitor commissions anew: a new tool changes the load
#: at every point, a repair the gear itself.
RECOMMISSIONS = ("tool_change", "repair")


@dataclass
class MaintenanceEvent:
    """One entry of the joint's maintenance log, an input of the monitor: what was done
    and when. A declared event recommissions what it affects: a re-greasing the friction
    (:class:`~swgmon.detection.normal.NormalConfig` ``regrease_settle_h``); a tool change or a
    repair (:data:`RECOMMISSIONS`) the whole monitor, on as many windows after it as
    commissioning had (:func:`swgmon.advisories.stream.monitor_stream`).

    Attributes
    ----------
    hour : float
        Operating hours when it was done [h], >= 0.
    kind : str
        One of :data:`MAINTENANCE_KINDS`.
    """

    hour: float = 0.0
    kind: str = "regrease"

    def check(self, key: str = "maintenance") -> None:
        """Refuse an hour or kind out of range in one line naming ``<key>.<field>``.

        Raises
        ------
        ValueError
        """
        check_range(self.hour, 0.0, 1e7, f"{key}.hour", "h", why="operating hours")
        if self.kind not in MAINTENANCE_KINDS:
            raise ValueError(f"{key}.kind: {self.kind!r} is not one of "
                             f"{list(MAINTENANCE_KINDS)}")


@dataclass
class Trace:
    """Per-window output of a run.

    Attributes
    ----------
    hour : ndarray, shape (n,)
    score : ndarray, shape (n, 2)
        The diagnosis model's evidence against healthy and the novelty.
    p : ndarray, shape (n,)
        Combined conformal p-value.
    cusums : ndarray, shape (n, k)
        Every CUSUM of the rule (:func:`swgmon.detection.rule.log_bets`); NaN after a
        latched alarm.
    alarms : list of int
        Windows that raised an alarm.
    log_proba : ndarray, shape (n, n_classes)
        The diagnosis model's ln P(class | window).
    op_index : ndarray of int, shape (n,)
        Each window's operating point in the normal behaviour.
    friction : ndarray, shape (n,)
        The friction factor in force at each window (:meth:`GearMonitor.track_friction`).
    outside : ndarray of int, shape (n,)
        The conditions commissioning did not see at each window
        (:meth:`swgmon.detection.normal.NormalBehaviour.outside`: 1 temperature, 2 load,
        4 friction; 8 not judged: p-value 1, the CUSUMs hold,
        :func:`~swgmon.detection.rule.judged_bets`).
    recommissioned : list of (int, int, bool)
        (window, operating point's row, relearnt) where a point was recommissioned at its
        new load after that window (:meth:`GearMonitor.run`): relearnt True where the
        windows became its new normal, False where its load range grew (the laws hold).
    """

    hour: np.ndarray
    score: np.ndarray
    p: np.ndarray
    cusums: np.ndarray
    alarms: list[int]
    log_proba: np.ndarray
    op_index: np.ndarray
    friction: np.ndarray
    outside: np.ndarray
    recommissioned: list[tuple[int, int, bool]] = field(default_factory=list)

    def head(self, n: int) -> Trace:
        """The trace of its first ``n`` windows."""
        cut = {k: getattr(self, k)[:n] for k in ("hour", "score", "p", "cusums", "log_proba",
                                                  "op_index", "friction", "outside")}
        return Trace(alarms=[a for a in self.alarms if a < n],
                     recommissioned=[r for r in self.recommissioned if r[0] < n], **cut)

    @classmethod
    def concat(cls, traces: list[Trace]) -> Trace:
        """Traces of consecutive windows as one (alarm indices shifted)."""
        off = np.cumsum([0] + [len(t.hour) for t in traces[:-1]])
        cat = {k: np.concatenate([getattr(t, k) for t in traces])
               for k in ("hour", "score", "p", "cusums", "log_proba", "op_index", "friction",
                         "outside")}
        return cls(alarms=[int(a + o) for t, o in zip(traces, off, strict=True)
                           for a in t.alarms],
                   recommissioned=[(int(a + o), k, r) for t, o in zip(traces, off, strict=True)
                                   for a, k, r in t.recommissioned], **cat)

    def state(self, i: int) -> tuple[float, float]:
        """The friction-tracking start of a run that continues after window ``i``: the
        factor in force at window ``i + 1`` (window ``i``'s update included) and window
        ``i``'s hour (:meth:`GearMonitor.run`'s ``friction_start``)."""
        return float(self.friction[min(i + 1, len(self.friction) - 1)]), float(self.hour[i])

    @property
    def s(self) -> np.ndarray:
        """The largest CUSUM of each window, shape (n,)."""
        return np.max(self.cusums, axis=1)


def normal_windows(points: np.ndarray) -> np.ndarray:
    """Which commissioning windows fit the normal behaviour: every other one of each operating
    point, from its first (the rest calibrate the rule). Boolean mask, shape (n,)."""
    _, inv = np.unique(points, axis=0, return_inverse=True)
    rank = np.zeros(len(points), int)
    for k in np.unique(inv):
        idx = np.flatnonzero(inv == k)
        rank[idx] = np.arange(idx.size)
    return rank % 2 == 0


class GearMonitor:
    """Monitor of one gear (module docstring).

    Parameters
    ----------
    model : DiagnosisModel
    rule : RuleConfig
    interval_min : float
        Operating minutes between windows.
    seed : int
        Of the p-values' smoothing draws.
    confirm_h : float
        Hours after an alarm whose windows name the fault (default 1 h).
    normal : NormalConfig, optional
        How the normal behaviour follows the conditions (:mod:`swgmon.detection.normal`).
    naming : NamingConfig, optional
        The numbers the naming of an alarm was tuned with (:mod:`.sensor_check`).
    """

    def __init__(self, model: DiagnosisModel, rule: RuleConfig, interval_min: float,
                 seed: int = 0, confirm_h: float = 1.0,
                 normal: NormalConfig | None = None,
                 naming: NamingConfig | None = None) -> None:
        self.model, self.rule = model, rule
        self.interval_min = float(interval_min)
        self.h = threshold(rule, interval_min)
        self.seed = int(seed)
        self.rng = np.random.default_rng(seed)
        self.confirm_h = float(confirm_h)
        self.normal_config = normal or NormalConfig()
        self.naming = naming or NamingConfig()
        self.hypotheses = registered(self.naming)
        self.normal: NormalBehaviour | None = None
        self.calibration: dict[int, np.ndarray] = {}
        self.cusum = np.zeros(0)
        self.friction, self.last_hour = 1.0, None
        self.learning: dict[int, list[tuple[np.ndarray, float]]] = {}
        # an alarm not explained away since commissioning: the gear is not known healthy,
        # so no point is relearnt at a new load (_learn; the stream clears it, run_stream)
        self.fault_suspected = False
        self.commissioned_on: tuple[np.ndarray, np.ndarray, Conditions] | None = None
        self._virtual: dict[str, tuple] = {}
        self.regreased: list[float] = []
        # the readings are the laws' virtual temperature (the sensor failed): no sensor
        # left to name (swgmon.advisories.stream.reading_lost)
        self.reading_virtual = False

    def declare(self, events: list[MaintenanceEvent]) -> None:
        """Take the maintenance log: after a declared re-greasing the friction factor
        follows the windows one by one for ``regrease_settle_h`` (:meth:`track_friction`).

        Raises
        ------
        ValueError
            An event out of range (:meth:`MaintenanceEvent.check`).
        """
        for i, e in enumerate(events):
            e.check(f"maintenance[{i}]")
        self.regreased = sorted(float(e.hour) for e in events if e.kind == "regrease")

    def commission(self, feats: np.ndarray, points: np.ndarray,
                   cond: Conditions | None = None) -> None:
        """Normal behaviour and calibration from commissioning windows (module docstring).

        Parameters
        ----------
        feats : ndarray, shape (n, F)
            Health features (:func:`learn.inputs.health.window_features`).
        points : ndarray, shape (n, 2)
            (n_in_rpm, t_out_nm) of each window's duty point.
        cond : Conditions, optional
            The windows' acting load and temperature (:class:`swgmon.detection.normal.Conditions`);
            default: the commanded load, no temperature.
        """
        check_commissioning(points, self.rule, self.interval_min)
        cond = cond if cond is not None else Conditions(np.asarray(points[:, 1], float))
        fit = normal_windows(points)
        cal = ~fit
        self.normal = NormalBehaviour.fit(feats[fit], points[fit], cond[fit],
                                          self.normal_config)
        fr = self._commissioning_friction(feats, points, cond)
        if self.normal_config.friction_track_h > 0:  # the efficiency's spread about it
            self.normal = NormalBehaviour.fit(feats[fit], points[fit], cond[fit],
                                              self.normal_config, fr[fit])
        self.normal.friction_range = np.array([min(fr.min(), self.friction),
                                               max(fr.max(), self.friction)])
        self.calibration, self.bias = self._calibrated(feats[cal], points[cal], cond[cal],
                                                       fr[cal])
        self._rows = {(float(a), float(b)): k for k, (a, b) in enumerate(self.normal.points)}
        self.cusum = np.zeros(log_bets(np.ones(1), self.rule).shape[1])
        self.last_hour = None  # the friction factor stays commissioning's last
        self.learning = {}
        self.fault_suspected = False
        self.commissioned_on = (feats, points, cond)
        self._virtual: dict[str, tuple] = {}  # read_virtually's, shared by the forks

    def _calibrated(self, feats: np.ndarray, points: np.ndarray, cond: Conditions,
                    fr: np.ndarray) -> tuple[dict[int, np.ndarray], np.ndarray]:
        """The rule's calibration (each point's sorted scores) and the evidence's bias
        (each point's mean ``ln P(c|x) − ln P(healthy|x)``) of calibration windows."""
        opi = self.normal.index(points)
        scores, lp = self.scores(feats, points, cond, fr, opi)
        n_p = len(self.normal.points)
        llr = lp - lp[:, :1]
        return ({k: np.sort(scores[opi == k], axis=0) for k in range(n_p)},
                np.stack([llr[opi == k].mean(axis=0) for k in range(n_p)]))

    def read_virtually(self) -> None:
        """Go on with the temperature the laws say (the temperature sensor failed,
        :func:`swgmon.advisories.stream.reading_lost`): no sensor is left to name, and the
        rule's calibration and the evidence's bias are taken anew from commissioning's
        calibration windows read the same way, their temperature the
        :func:`~.sensor_check.virtual_temperature` of commissioning's windows by its laws.
        Calibrated as it scores: the virtual temperature errs by a few tenths of a kelvin
        (a running median), which on the efficiency, steep in the temperature, is up to
        one spread, without the second harmonics' share that a true change of
        temperature brings - the pattern of reduced damping. Scored against the reading's
        calibration, healthy windows read so gave that class's evidence a 99th
        percentile of 23 against 2.6 with the true temperature, and gear-fault alarms
        (bench gear 3, family ``sensor_stuck``, scored seed 1: docs/monitor/assessment.md, "The
        monitor checks its temperature sensor").

        Raises
        ------
        ValueError
            If the monitor is not commissioned or its normal behaviour has no temperature
            law.
        """
        if self.normal is None or not self.normal.temperature_law:
            raise ValueError("read_virtually: the monitor is not commissioned with a "
                             "temperature law (GearMonitor.commission with readings)")
        if "calibration" not in self._virtual:
            feats, points, cond = self.commissioned_on
            fresh = GearMonitor(self.model, self.rule, self.interval_min, self.seed,
                                self.confirm_h, self.normal_config, self.naming)
            fresh.commission(feats, points, cond)  # commissioning's normal behaviour
            fr = fresh._commissioning_friction(feats, points, cond)
            virtual = Conditions(cond.torque_nm, virtual_temperature(
                fresh.normal, feats, points, cond.torque_nm, fr, fresh.normal.index(points),
                self.naming))
            cal = ~normal_windows(points)
            self._virtual["calibration"] = fresh._calibrated(feats[cal], points[cal],
                                                             virtual[cal], fr[cal])
        self.reading_virtual = True
        self.calibration, self.bias = self._virtual["calibration"]

    def _commissioning_friction(self, feats: np.ndarray, points: np.ndarray,
                                cond: Conditions) -> np.ndarray:
        """The friction factor tracked over commissioning's windows (consecutive, one per
        ``interval_min``) as the run tracks it (:meth:`track_friction`, from 1: the loss
        law's mean), in force at each window, shape (n,); the monitor's own factor is then
        the one after them. Why:
        a gear that runs in during commissioning (its friction 10 % down in the first
        day) would otherwise leave the drift in the efficiency's spread, there 5-10
        times commissioning's noise, and hide the friction change of reduced damping
        (robot_joint gear 3, seed 1: the efficiency 1-1.7 spreads up at its onset, 6-17
        on a gear that does not run in)."""
        self.friction, self.last_hour = 1.0, None
        hours = np.arange(len(feats)) * self.interval_min / 60.0
        return self.track_friction(feats, points, hours, cond, self.normal.index(points))

    def fork(self, fresh_draws: bool = False) -> GearMonitor:
        """A copy whose state (normal behaviour, recommissioning, CUSUMs, friction
        factor) is its own, and so are its p-value draws: a stream spawned from the
        monitor's (``Generator.spawn``), so that what one fork draws moves no other's, nor
        the monitor's own. ``fresh_draws``: its draws start again from the seed (a replay
        of the windows since commissioning then gives the same numbers)."""
        out = copy.copy(self)
        out.normal = copy.deepcopy(self.normal)
        out.learning = {k: list(v) for k, v in self.learning.items()}
        out.cusum = self.cusum.copy()
        out.rng = np.random.default_rng(self.seed) if fresh_draws else self.rng.spawn(1)[0]
        return out

    def evidence(self, lp: np.ndarray, opi: np.ndarray) -> np.ndarray:
        """Per window and class, the evidence against healthy relative to this gear's
        healthy windows: ``ln P(c|x) − ln P(healthy|x)`` minus its mean over the
        calibration windows of the operating point (a class the model gives this gear's
        healthy windows anyway, e.g. one it cannot tell from healthy, gains nothing)."""
        return lp - lp[:, :1] - self.bias[opi]

    def inputs(self, feats: np.ndarray, points: np.ndarray, cond: Conditions | None = None,
               friction: np.ndarray | float = 1.0) -> np.ndarray:
        """The severity regressors' inputs of windows (z-scores and operating point): the
        z-scores in commissioning's spread, the laws extrapolated where the load or
        temperature lies beyond commissioning's range
        (:meth:`~swgmon.detection.normal.NormalBehaviour.unwidened`). The widened spread
        of :meth:`scores` keeps the detection from alarming on an extrapolation; read by
        the regressors it shrinks a fault's signature: on the bench lot (instance 10,
        design seed 1, a payload of 0.85) a root crack at 0.39 read 0.34 in it and 0.39 in
        commissioning's spread (docs/monitor/prognosis.md, "The severity track")."""
        return design_matrix(self.normal.unwidened().z(feats, points, cond, friction),
                             points)

    def scores(self, feats: np.ndarray, points: np.ndarray, cond: Conditions | None = None,
               friction: np.ndarray | float = 1.0, index: np.ndarray | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
        """Scores (n, 2) and log-probabilities (n, n_classes) of windows (``index``: their
        operating points' rows in the normal behaviour, when known).

        Two scores per window: the diagnosis model's evidence against healthy, and the
        novelty ``Σ z²`` of its health features (a change the model was not trained on,
        e.g. a bridge it never saw faulty, moves the latter).
        """
        score, lp, _ = self._scores(feats, points, cond, friction, index)
        return score, lp

    def _scores(self, feats, points, cond, friction, index):
        """:meth:`scores` and the windows' features at the reference condition."""
        z, spread = self.normal.z_and_spread(feats, points, cond, friction, index)
        score, lp = self.scores_of(z, points)
        i = self.normal.index(points) if index is None else index
        return score, lp, z * spread + self.normal.mean[i]

    def scores_of(self, z: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`scores` (n, 2) and log-probabilities (n, n_classes) of windows' z-scores
        (n, F) at their points (n, 2)."""
        lp = self.model.log_proba(design_matrix(z, points))
        return np.stack([self.model.score(lp), np.sum(z ** 2, axis=1)], axis=1), lp

    def p_values(self, score: np.ndarray, opi: np.ndarray, u: np.ndarray | None = None,
                 outside: np.ndarray | None = None) -> np.ndarray:
        """Conformal p-values of windows against the calibration of their operating point
        (``opi``: its row in the normal behaviour), the two scores' combined by Bonferroni,
        ``min(1, 2 min(p1, p2))`` (still super-uniform, so the CUSUM's bound holds).
        ``u``: the smoothing draws, shape as ``score`` (default: the monitor's own).

        ``outside`` (the windows' :meth:`NormalBehaviour.outside` bits): where a window's
        acting load lies beyond what commissioning saw at its point, its p-value is the
        novelty's alone. The spread widened by the extrapolation
        (:meth:`NormalBehaviour.z_and_spread`) bounds the z-scores' size, which the novelty
        ``Σ z²`` measures, not their direction, which the diagnosis model's evidence
        measures: behind a robot link a 10 % heavier tool left every bridge's residual
        0.7 spread above the extrapolation, a pattern the model took for a root crack
        (10 gear-fault alarms in 200 h, robot_joint gear 3, seed 0). A window not judged
        (:attr:`~swgmon.detection.normal.Outside.UNJUDGED`) has p-value 1."""
        pe = self.p_each(score, opi, u)
        p = np.minimum(1.0, score.shape[1] * pe.min(axis=1))
        if outside is not None:
            beyond = (np.asarray(outside) & Outside.LOAD) != 0
            p[beyond] = pe[beyond, 1]
            p[(np.asarray(outside) & Outside.UNJUDGED) != 0] = 1.0
        return p

    def p_each(self, score: np.ndarray, opi: np.ndarray, u: np.ndarray | None = None
               ) -> np.ndarray:
        """Each score's conformal p-value against the calibration of the windows' points,
        shape as ``score`` (uniform on healthy windows exchangeable with the calibration;
        ``u`` as :meth:`p_values`)."""
        u = self.rng.uniform(size=score.shape) if u is None else u
        p = np.empty(score.shape)
        for k in np.unique(opi):
            cal, m = self.calibration[int(k)], opi == k
            for j in range(score.shape[1]):
                p[m, j] = conformal_p(score[m, j], cal[:, j], u[m, j])
        return p

    def track_friction(self, feats: np.ndarray, points: np.ndarray, hours: np.ndarray,
                       cond: Conditions, opi: np.ndarray,
                       start: tuple[float, float | None] | None = None) -> np.ndarray:
        """The friction factor in force at each window (before it updates it) and the
        monitor's own factor after the last (:mod:`swgmon.detection.normal`: an exponential mean
        of the windows' loss ratios over ``friction_track_h`` operating hours; for
        ``regrease_settle_h`` after a declared re-greasing, :meth:`declare`, over one
        window's interval: the windows one by one), shape (n,). ``start``: (factor, hour
        of the window before), default the monitor's own. A window beyond commissioning's
        temperatures at its point (:meth:`swgmon.detection.normal.NormalBehaviour.outside`) leaves
        the factor as it is: its loss law is extrapolated there (docs/monitor/detection.md, "The
        normal
        behaviour's laws")."""
        tau = self.normal_config.friction_track_h
        r, last = (self.friction, self.last_hour) if start is None else start
        out = np.empty(len(hours))
        if tau <= 0:
            out[:] = 1.0
            return out
        ratio = self.normal.friction_ratio(feats, points, cond, opi)
        # beyond commissioning's temperatures the loss law is an extrapolation: no evidence
        hot = self.normal.outside(points, cond, 1.0, opi) & Outside.TEMPERATURE
        ratio[hot != 0] = np.nan
        default_dh = self.interval_min / 60.0
        settle = self.normal_config.regrease_settle_h
        for i, (h, q) in enumerate(zip(hours.tolist(), ratio.tolist(), strict=True)):
            out[i] = r
            dh = default_dh if last is None else h - last
            t = default_dh if any(0 <= h - g < settle for g in self.regreased) else tau
            if np.isfinite(q):
                r += (1.0 - np.exp(-max(dh, 0.0) / t)) * (q - r)
            last = h
        self.friction, self.last_hour = r, last
        return out

    def run(self, feats: np.ndarray, points: np.ndarray, hours: np.ndarray,
            cond: Conditions | None = None, latch: bool = True, start: float = 0.0,
            friction_start: tuple[float, float | None] | None = None) -> Trace:
        """Score windows after commissioning and run the CUSUM.

        Parameters
        ----------
        feats, points, cond
            As :meth:`commission`, of the windows after commissioning, in time order.
        hours : ndarray, shape (n,)
            Operating hours of each window, increasing.
        latch : bool
            Stop at the first alarm; else restart the CUSUM after each alarm and go on
            (the monitor keeps watching; counting false alarms).
        start : float or ndarray, shape (k,)
            CUSUM values before the first window (e.g. a trace's ``cusums`` row).
        friction_start : (float, float or None), optional
            The friction factor and the hour of the window before (e.g. from a trace);
            default the monitor's own.

        Returns
        -------
        Trace
        """
        cond = cond if cond is not None else Conditions(np.asarray(points[:, 1], float))
        hours = np.asarray(hours, float)
        opi = self.normal.index(points)
        fr = self.track_friction(feats, points, hours, cond, opi, friction_start)
        u = self.rng.uniform(size=(len(feats), 2))
        parts, i0, s, ev = [], 0, start, None
        score, lp, ref = self._scores(feats, points, cond, fr, opi)
        while True:  # one pass per recommissioned point (its windows after it change)
            w = slice(i0, None)
            if ev is not None:  # only the changed point's windows score anew
                score, lp, ref = self._rescore(score, lp, ref, ev[0] + 1, ev[1], feats[w],
                                               points[w], cond[w], fr[w], opi[w])
            out = self.normal.outside(points[w], cond[w], fr[w], opi[w])
            p = self.p_values(score, opi[w], u[w], out)
            cus, alarms = run_cusums(judged_bets(p, out, self.rule), self.h, s, latch)
            ev = self._learn(opi[w], out, ref, cond.torque_nm[w], alarms)
            n = len(p) if ev is None else ev[0] + 1
            parts.append(Trace(hours[w][:n], score[:n], p[:n], cus[:n],
                               [a for a in alarms if a < n], lp[:n], opi[w][:n], fr[w][:n],
                               out[:n], [] if ev is None else [ev]))
            i0, s = i0 + n, cus[n - 1]
            if ev is None or i0 == len(feats):
                return Trace.concat(parts)

    def _rescore(self, score, lp, ref, n: int, k: int, feats, points, cond, fr, opi):
        """The scores of the windows after the first ``n`` of a pass, where point ``k`` was
        recommissioned after window ``n − 1``: its windows scored anew, every other
        point's kept (a point's normal behaviour is its own row; the same numbers as
        scoring them all again). ``feats`` .. ``opi``: the windows after the first n."""
        score, lp, ref = score[n:].copy(), lp[n:].copy(), ref[n:].copy()
        m = np.flatnonzero(opi == k)
        if m.size:
            score[m], lp[m], ref[m] = self._scores(feats[m], points[m], cond[m], fr[m],
                                                   opi[m])
        return score, lp, ref

    def _learn(self, opi: np.ndarray, out: np.ndarray, ref: np.ndarray, torque: np.ndarray,
               alarms: list[int]) -> tuple[int, int, bool] | None:
        """Windows in time order through the recommissioning of points whose acting load
        left commissioning's range (:class:`~swgmon.detection.normal.NormalConfig`
        ``recommission_load``): a point's windows beyond its load range gather, in a row,
        until as many as commissioning gave its normal behaviour recommission it
        (:meth:`~swgmon.detection.normal.NormalBehaviour.recommission`); a window back inside
        the range clears its point's, an alarm every point's (the change may be a fault:
        from it on no point is recommissioned until the stream explains it away,
        :attr:`fault_suspected`; relearning a gear whose fault was named adopts the fault
        as its normal, docs/monitor/prognosis.md, "The severity track"); a window whose
        features could not be brought to the reference condition (NaN where its
        temperature reading dropped out) is neither gathered nor clears.
        Returns the window after which a point was recommissioned (the monitor's normal
        behaviour has changed from the next on), the point's row and whether it was
        relearnt (:meth:`_recommission`), or None. ``ref``: the windows' features at the
        reference condition, shape (n, F)."""
        loaded = (out & Outside.LOAD) != 0
        if not self.normal_config.recommission_load or self.fault_suspected \
                or not (loaded.any() or self.learning):
            self.fault_suspected |= bool(alarms)
            return None
        alarm = set(alarms)
        for i, k in enumerate(opi.tolist()):
            if i in alarm:
                self.learning, self.fault_suspected = {}, True
                return None
            elif not loaded[i]:
                self.learning.pop(k, None)
            elif np.isfinite(ref[i]).all():  # a lost reading's window is no evidence
                buf = self.learning.setdefault(k, [])
                buf.append((ref[i], float(torque[i])))
                if len(buf) >= self.normal.count[k]:
                    rows, tq = zip(*self.learning.pop(k), strict=True)
                    return i, k, self._recommission(k, np.array(rows), np.array(tq))
        return None

    def _recommission(self, k: int, ref: np.ndarray, torque: np.ndarray) -> bool:
        """Point ``k`` at a new load, from its gathered windows (:meth:`_learn`): where
        they agree with commissioning's normal behaviour carried there by its laws
        (each score's p-values in σ, not the widened spread, uniform: the mean of their
        normal scores Φ⁻¹(1 − p) within the one-sided bound of N(0, 1/m) at ``naming.law_level``
        shared by the two scores; not the combined p-value, 1 wherever both exceed 1/2: on
        tiny_bench its statistic lay at −9 to −17 for healthy windows and at −1.2 for a
        point one of whose features was 2.7 σ off its law), the laws
        hold and the point's load range grows to cover the new load; else the laws fail
        there and the windows become the point's new normal
        (:meth:`~swgmon.detection.normal.NormalBehaviour.recommission`). Returns whether the
        point was relearnt."""
        nb = self.normal
        z = nb.without_warm_ups((ref - nb.mean[k]) / nb.std[k], np.full(len(ref), k))
        score, _ = self.scores_of(z, np.broadcast_to(nb.points[k], (len(ref), 2)))
        p = self.p_each(score, np.full(len(ref), k), np.full(score.shape, 0.5))
        stat = np.sqrt(len(p)) * np.mean(normal_scores(p), axis=0)
        if (stat <= normal_scores(self.naming.law_level / score.shape[1])).all():
            nb.extend_load_range(k, torque)
            return False
        nb.recommission(k, ref, torque)
        return True

    def step(self, feat: np.ndarray, point: tuple[float, float], hour: float,
             torque_nm: float | None = None, temperature_c: float | None = None) -> Trace:
        """Score one window after commissioning and update the monitor's own CUSUMs,
        friction factor and recommissioning (:meth:`_learn`).

        Parameters
        ----------
        feat : ndarray, shape (F,)
            Health features of the window.
        point : (float, float)
            (n_in_rpm, t_out_nm) of its duty point.
        hour : float
            Its operating hours.
        torque_nm, temperature_c : float, optional
            Its acting load [N m] (default the commanded) and temperature reading [°C].

        Returns
        -------
        Trace
            Of this one window; ``alarms == [0]`` when it raised an alarm, after which the
            CUSUMs start again from zero.

        Raises
        ------
        ValueError
            If the monitor is not commissioned or the operating point was not seen at
            commissioning.
        """
        if self.normal is None:
            raise ValueError("the monitor is not commissioned (GearMonitor.commission)")
        k = self._rows.get((float(point[0]), float(point[1])))
        if k is None:
            raise ValueError(f"operating point {point[0]:g} rpm, {point[1]:g} N m was not seen "
                             f"at commissioning; the normal behaviour has {list(self._rows)}")
        f, pt = np.asarray(feat, float)[None, :], np.array([point], float)
        cond = Conditions(np.array([point[1] if torque_nm is None else torque_nm], float),
                          None if temperature_c is None else np.array([temperature_c], float))
        opi = np.array([k])
        fr = self.track_friction(f, pt, np.array([float(hour)]), cond, opi)
        score, lp, ref = self._scores(f, pt, cond, fr, opi)
        out = self.normal.outside(pt, cond, fr, opi)
        p = self.p_values(score, opi, self.rng.uniform(size=(1, 2)), out)
        cus = np.maximum(0.0, self.cusum + judged_bets(p, out, self.rule)[0])
        alarm = bool((cus >= self.h).any())
        self.cusum = np.zeros_like(cus) if alarm else cus
        ev = self._learn(opi, out, ref, cond.torque_nm, [0] if alarm else [])
        return Trace(np.array([float(hour)]), score, p, cus[None, :],
                     [0] if alarm else [], lp, opi, fr, out, [] if ev is None else [ev])

    def score_only(self, feats: np.ndarray, points: np.ndarray, hours: np.ndarray,
                   cond: Conditions | None = None,
                   friction_start: tuple[float, float | None] | None = None) -> Trace:
        """Windows after a latched alarm: scored for the naming, no CUSUM (NaN)."""
        cond = cond if cond is not None else Conditions(np.asarray(points[:, 1], float))
        opi = self.normal.index(points)
        fr = self.track_friction(feats, points, np.asarray(hours, float), cond, opi,
                                 friction_start)
        score, lp = self.scores(feats, points, cond, fr, opi)
        k = log_bets(np.ones(1), self.rule).shape[1]
        return Trace(np.asarray(hours, float), score, np.full(len(score), np.nan),
                     np.full((len(score), k), np.nan), [], lp, opi, fr,
                     self.normal.outside(points, cond, fr, opi))


__all__ = ["MAINTENANCE_KINDS", "RECOMMISSIONS", "GearMonitor", "MaintenanceEvent", "Trace",
           "normal_windows"]
