"""Health assessment (ISO 13374) of an alarm: its fault named, its severity estimated.

After an alarm of a :class:`~.gear_monitor.GearMonitor` run, :func:`diagnose` names the
fault from the windows since the CUSUM's last rise from zero up to the alarm
(``fault_at_alarm``) and up to ``confirm_h`` after it (``fault``, with the severity and its
interval). :func:`name` weighs the hypotheses of ``naming.hypotheses``
(:mod:`.hypotheses`: a bridge's fault, a wrong or drifting temperature reading, an even
change of the friction, one's own): the candidate whose corrected windows look healthy
with the largest posterior odds, where they are above 1; else the gear fault with the
largest evidence. The severity is the fit's (a reading's error, the friction's change) or
the diagnosis model's regressor's (:meth:`~.model.DiagnosisModel.estimate`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from learn.inputs.health import feature_names
from swgmon.assessment.gear_monitor import GearMonitor, Trace
from swgmon.assessment.hypotheses import Candidate, Windows, log_odds
from swgmon.detection.normal import Conditions, Outside
from swgmon.detection.rule import TEMPERATURE_SENSOR, UNEXPLAINED_CHANGE, Alarm, moved_features


def diagnose(mon: GearMonitor, trace: Trace, a: int, feats: np.ndarray, points: np.ndarray,
             cond: Conditions | None = None, before: Alarm | None = None) -> Alarm:
    """Name the fault of the alarm at window ``a`` of ``trace`` and its severity.

    ``trace``, ``feats``, ``points`` and ``cond`` cover the same windows: those of the
    run, the ones after the alarm included as far as the stream goes (up to
    ``confirm_h``). ``before``: the alarm named before it in the same run (indices
    into the same windows), or None. Where that named a gear fault and this alarm's
    rise began at or before it, the two are one episode: the CUSUM has not gone back
    to zero since, so the windows named then are among those named now. The alarm is
    then that one again at its own hour (name, severity, what moved): the stream
    keeps an episode's first alarm only (:func:`swgmon.advisories.stream.run_stream`),
    and the severity's course is the prognosis's track. A growing crack alarms again
    some 10 times an hour; naming each cost 1.2 s, a 356-h life 397 s (issue 85).
    """
    j = int(np.argmax(trace.cusums[a]))  # the CUSUM that raised it
    zero = np.flatnonzero(trace.cusums[:a, j] <= 0)
    rise = int(zero[-1]) + 1 if zero.size else 0
    if before is not None and before.kind == "gear_fault" and rise <= before.index:
        return dataclasses.replace(before, hour=float(trace.hour[a]), index=int(a))
    end = int(np.searchsorted(trace.hour, trace.hour[a] + mon.confirm_h, side="right"))
    cond = cond if cond is not None else Conditions(np.asarray(points[:, 1], float))
    fr = trace.friction
    ev = mon.evidence(trace.log_proba, trace.op_index)
    ev[(trace.outside & Outside.UNJUDGED) != 0] = 0.0  # not judged: no evidence
    at_alarm = _weighed(mon, ev[rise:a + 1], feats[rise:a + 1], points[rise:a + 1],
                        cond[rise:a + 1], fr[rise:a + 1], trace.hour[rise:a + 1])[0]
    fault, bridge, fit, weighed = _weighed(mon, ev[rise:end], feats[rise:end],
                                           points[rise:end], cond[rise:end],
                                           fr[rise:end], trace.hour[rise:end])
    if fault == TEMPERATURE_SENSOR:  # its severity: the reading's error [K]
        err = fit.temperature_c - fit.reading_c
        est, lo, hi = fit.offset_k, *map(float, np.quantile(err, [0.05, 0.95]))
    elif fault == UNEXPLAINED_CHANGE:  # the friction's relative change [-]
        est, lo, hi = fit.factor - 1.0, fit.low - 1.0, fit.high - 1.0
    elif fault not in mon.model.classes:  # a hypothesis of one's own: no regressor
        est = lo = hi = float("nan")
    else:
        x = mon.inputs(feats[rise:end], points[rise:end], cond[rise:end], fr[rise:end])
        est, lo, hi = mon.model.estimate(fault, x)
    z = mon.normal.z(feats[rise:end], points[rise:end], cond[rise:end], fr[rise:end],
                      trace.op_index[rise:end])
    names = feature_names(twist=z.shape[1] > len(feature_names()))
    return Alarm(float(trace.hour[a]), int(a), rise, at_alarm, fault, est, lo, hi,
                 None if bridge is None else f"s{bridge}", moved_features(z, names),
                 weighed)


def name(mon: GearMonitor, ev: np.ndarray, feats: np.ndarray, points: np.ndarray,
         cond: Conditions | None = None, friction: np.ndarray | float = 1.0,
         hours: np.ndarray | None = None) -> tuple[str, int | None]:
    """Name the fault of windows since an alarm by the hypotheses of
    ``naming.hypotheses`` (:mod:`.hypotheses`: a bridge's offset step or gain drift, a
    wrong or drifting temperature reading, an even change of the friction, one's own):
    the candidate with the largest posterior odds that its corrected windows look
    healthy (:func:`~.hypotheses.log_odds` of their conformal p-values, priors
    :attr:`~.sensor_check.NamingConfig.prior_odds`,
    ``right_median_p`` and ``wrong_median_p``), where they are above 1, with its
    bridge (None but for a bridge's fault); else the fault with the largest summed
    evidence (:meth:`~.gear_monitor.GearMonitor.evidence` rows ``ev``) and None.
    ``hours``: the windows' hours, for the rates."""
    return _weighed(mon, ev, feats, points, cond, friction, hours)[:2]


def _weighed(mon: GearMonitor, ev, feats, points, cond, friction, hours=None):
    """:func:`name`, the fit of the candidate that named it (None where the gear
    fault did) and the candidates weighed, ``[hypothesis, fault, bridge, log
    posterior odds]`` each (docs/monitor/assessment.md, "The hypotheses")."""
    b = mon.normal
    opi = b.index(points)
    z, spread = b.z_and_spread(feats, points, cond, friction, opi)
    u = np.full((len(z), 2), 0.5)  # mid-p: the naming draws nothing from the monitor

    def odds(c: Candidate) -> float:
        p = mon.p_values(mon.scores_of(c.z, points)[0], opi, u)
        return log_odds(p, mon.naming.prior_odds, mon.naming.right_median_p,
                        mon.naming.wrong_median_p)

    w = Windows(b, feats, points, cond, np.broadcast_to(friction, (len(z),)), opi, z,
                spread, hours, mon.naming, tuple(mon.model.classes),
                cond is not None and not mon.reading_virtual)
    cands = [(odds(c), c) for h in mon.hypotheses for c in h.candidates(w)]
    weighed = [[c.hypothesis, c.fault, c.bridge, round(o, 3)] for o, c in cands]
    best = max(cands, key=lambda oc: oc[0], default=None)
    if best is not None and best[0] > 0.0:
        return best[1].fault, best[1].bridge, best[1].fit, weighed
    return mon.model.name(ev), None, None, weighed


__all__ = ["diagnose", "name"]
