"""One gear's recorded stream through the monitor: input checks, the run, its outputs.

A stream is a schema-v1 data set (:mod:`swgsim.datasets.schema`) of one gear's windows with the
per-sample variables ``hour`` (operating hours, increasing) and ``commissioning`` (the
first windows, known healthy), e.g. a life written by ``swgsim-generate`` with
``dataset.life`` set (:mod:`swgsim.datasets.life`). :func:`check_stream` refuses, before any work
and in one line, a stream without commissioning, with hours out of order, or one that
disagrees with the model (bridges, sample rate, operating points outside the training
range), or one with no window after commissioning. :func:`monitor_stream` runs
:class:`~swgmon.assessment.gear_monitor.GearMonitor` and :func:`write_outputs` writes
``summary.json``, ``report.md`` and ``health.png``; :func:`event_line` is the one line of
each event (:meth:`StreamResult.events`) that the report and ``swgsim-monitor`` print.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from learn.inputs.health import feature_names, health_features
from swgmon.advisories.figures import health_figure, prognosis_figure
from swgmon.assessment.gear_monitor import RECOMMISSIONS, GearMonitor, MaintenanceEvent, Trace
from swgmon.assessment.hypotheses import Finding, ReadingCheck, Stream
from swgmon.assessment.model import DiagnosisModel
from swgmon.assessment.sensor_check import NamingConfig, virtual_temperature
from swgmon.detection.normal import (
    Conditions,
    NormalConfig,
    Outside,
)
from swgmon.detection.rule import (
    TEMPERATURE_SENSOR,
    UNEXPLAINED_CHANGE,
    Alarm,
    RuleConfig,
    check_commissioning,
)
from swgmon.prognosis.stream import (
    StreamPrognoses,
    StreamPrognosis,
    stream_prognoses,
    trained_duty,
    window_interval_h,
)
from swgsim.datasets.schema import SENSORS, TEMPERATURE_RANGE_C

#: Bits of :meth:`swgmon.detection.normal.NormalBehaviour.outside` and what they mean.
CONDITIONS = {Outside.TEMPERATURE: "temperature", Outside.LOAD: "load",
              Outside.FRICTION: "friction"}


@dataclass
class StreamResult:
    """What the monitor made of a stream.

    Attributes
    ----------
    trace : Trace
        The monitored windows (after commissioning).
    alarms : list of Alarm
        Every alarm, named; the monitor keeps watching after each (consecutive alarms
        naming the same fault are one).
    advisories : list of dict
        Where the condition left what commissioning saw: ``hour``, ``index`` and
        ``condition`` (temperature, load, friction): recommission, not a gear fault.
    n_commissioning : int
    onset_h : float or None
        The stream's true fault onset, where it records one (a simulated life).
    true_fault : str or None
    threshold : float
        h, the alarm threshold the rule used (:func:`swgmon.detection.rule.threshold` at the
        stream's median window spacing, :func:`check_stream`); what the outputs report.
    recommissioned : list of dict
        Where the monitor recommissioned an operating point at a load that stayed beyond
        commissioning's (:func:`recommissionings`).
    prognosis : StreamPrognoses or None
        With the prognosis option on (:mod:`swgmon.prognosis.stream`), its tracks and prognoses.
    """

    trace: Trace
    alarms: list[Alarm]
    advisories: list[dict]
    n_commissioning: int
    onset_h: float | None
    true_fault: str | None
    threshold: float
    recommissioned: list[dict] = field(default_factory=list)
    prognosis: StreamPrognoses | None = None

    def events(self) -> list[dict]:
        """Alarms, advisories and recommissioned points in time order, each with its
        ``kind``: ``gear_fault``, ``sensor_fault`` (named with its bridge, or the
        temperature sensor), ``unexplained_change``, ``advisory`` or ``recommissioned``."""
        ev = [{"kind": a.kind, **a.as_dict()}
              for a in self.alarms]
        ev += [{"kind": "advisory", **a} for a in self.advisories]
        ev += [{"kind": "recommissioned", **a} for a in self.recommissioned]
        return sorted(ev, key=lambda e: e["hour"])


#: Alarms after which the monitor's state changes (:func:`run_stream`): the temperature
#: sensor's fault (the monitor goes on without it) and an unexplained change (the friction
#: factor takes the fitted change, the monitor watches for what comes on top of it).
CHANGES_STATE = (TEMPERATURE_SENSOR, UNEXPLAINED_CHANGE)
#: The kinds of event :meth:`StreamResult.events` gives, each printed by :func:`event_line`.
EVENT_KINDS = ("gear_fault", "sensor_fault", "unexplained_change", "advisory",
               "recommissioned")


def event_line(event: dict) -> str:
    """One line saying what an event of :meth:`StreamResult.events` is, by its kind.

    Parameters
    ----------
    event : dict
        ``kind`` (one of :data:`EVENT_KINDS`), ``hour`` and the kind's own entries: an
        alarm's (:meth:`~swgmon.detection.rule.Alarm.as_dict`), an advisory's
        ``advice`` (:func:`advisories`), a recommissioning's ``note``
        (:func:`recommissionings`).

    Returns
    -------
    str
        E.g. ``alarm at 6.20 h: eccentric_wg (at the alarm: eccentric_wg), severity 0.1
        [0.08, 0.12]``, ``advisory at 30.00 h: ...``, ``recommissioned at 37.10 h: ...``.

    Raises
    ------
    ValueError
        If ``kind`` is not one of :data:`EVENT_KINDS`.
    """
    kind, hour = event.get("kind"), float(event["hour"])
    moved = "".join(f"{'; moved: ' if i == 0 else ', '}{name} {z:+.1f} sigma"
                    for i, (name, z) in enumerate(event.get("moved") or []))
    moved += "".join(f"{'; weighed: ' if i == 0 else ', '}{h}"
                     f"{'' if bridge is None else f' s{bridge}'} log odds {o:+.1f}"
                     for i, (h, _, bridge, o) in enumerate(event.get("hypotheses") or []))
    if kind == "unexplained_change":  # its severity: the friction's change, always fitted
        lo, hi = event["severity_low"], event["severity_high"]
        ci = "" if lo is None or hi is None else f" [{100 * lo:+.1f}, {100 * hi:+.1f}] %"
        return (f"alarm at {hour:.2f} h: an unexplained change: the friction changed by "
                f"{100 * event['severity']:+.1f} %{ci} evenly over the operating points (no "
                "gear fault's signature; was the joint re-greased? the monitor goes on "
                f"from the new level){moved}")
    if kind in ("gear_fault", "sensor_fault"):
        where = ("" if kind != "sensor_fault" else
                 f" on bridge {event['bridge']} (check that gauge)" if event["bridge"] else
                 " (check the joint's temperature sensor; the monitor goes on without it)"
                 if event["fault"] == TEMPERATURE_SENSOR else
                 " (no one bridge explains it: check the gauges and their wiring)")
        sev, lo, hi = event["severity"], event["severity_low"], event["severity_high"]
        severity = ("no severity" if sev is None else f"severity {sev:.3g}" + (
            "" if lo is None or hi is None else f" [{_apart(lo, hi)}]"))
        return (f"alarm at {hour:.2f} h: {event['fault']}{where} (at the alarm: "
                f"{event['fault_at_alarm']}), {severity}{moved}")
    if kind == "advisory":
        return f"advisory at {hour:.2f} h: {event['advice']}"
    if kind == "recommissioned":
        return f"recommissioned at {hour:.2f} h: {event['note']}"
    raise ValueError(f"event kind: {kind!r} is not one of {list(EVENT_KINDS)}")


def _apart(lo: float, hi: float) -> str:
    """``lo, hi`` with the fewest significant digits (3 at least) that tell them apart."""
    digits = 3
    while f"{lo:.{digits}g}" == f"{hi:.{digits}g}" and lo != hi and digits < 12:
        digits += 1
    return f"{lo:.{digits}g}, {hi:.{digits}g}"


def select_gear(ds, gear: int | None):
    """The windows of one gear (the only one, or ``gear``).

    Raises
    ------
    ValueError
        If the stream holds several gears and none is named, or not the one named.
    """
    gears = sorted(set(int(g) for g in ds["gear"].values))
    if gear is None:
        if len(gears) != 1:
            raise ValueError(f"gear: the stream holds gears {gears}; name one (gear=<id>)")
        return ds
    if int(gear) not in gears:
        raise ValueError(f"gear: {gear} is not in the stream; it holds gears {gears}")
    return ds.isel(sample=np.flatnonzero(ds["gear"].values == int(gear)))


#: The command that makes a diagnosis model for a stream's acquisition
#: (:mod:`swgmon.evaluation.own_joint`), named by :func:`check_stream` when it refuses one.
OWN_JOINT_COMMAND = "swgsim-train experiment=own_joint own_joint.stream={stream}"


def check_stream(ds, model, rule: RuleConfig, source: str = "stream") -> float:
    """Refuse a stream the monitor cannot take (module docstring); return interval_min.

    Raises
    ------
    ValueError
        One line naming the stream and what is wrong, with the allowed values (also a
        stream that is all commissioning: nothing to monitor).
    """
    for v in ("hour", "commissioning"):
        if v not in ds:
            raise ValueError(f"{source}: no per-sample variable {v!r}; a stream is a gear's "
                             "life (swgsim-generate with dataset.life set)")
    hours = ds["hour"].values.astype(float)
    if hours.size and not (np.all(np.isfinite(hours)) and hours.min() >= 0):
        bad = int(np.flatnonzero(~(np.isfinite(hours) & (hours >= 0)))[0])
        raise ValueError(f"{source}: variable 'hour' must be finite and >= 0 (operating hours "
                         f"since commissioning began); window {bad} is at {hours[bad]:g} h")
    if hours.size < 2 or not np.all(np.diff(hours) > 0):
        bad = int(np.argmax(np.diff(hours) <= 0)) + 1 if hours.size >= 2 else 0
        raise ValueError(f"{source}: hours must increase from window to window; window {bad} "
                         f"is at {hours[bad] if hours.size else float('nan'):g} h")
    comm = ds["commissioning"].values.astype(bool)
    if not comm.any() or not comm[0] or np.any(np.diff(comm.astype(int)) > 0):
        raise ValueError(f"{source}: the commissioning windows must be the first ones and "
                         f"there must be some (found {int(comm.sum())})")
    if comm.all():
        raise ValueError(f"{source}: all {comm.size} windows are commissioning; the stream "
                         "has no windows after commissioning to monitor")
    sensors = [str(s) for s in ds["sensor"].values]
    if sensors != list(SENSORS):
        raise ValueError(f"{source}: bridges {sensors}; the model was trained on s0..s4")
    twist = "phi_out_meas" in ds
    make = ("; a model for it: " + (
        "swgsim-train experiment=monitor (robot_joint_motion's models)" if twist
        else OWN_JOINT_COMMAND.format(stream=source)))
    fs = float(ds.attrs.get("sample_rate_hz", np.nan))
    if not np.isclose(fs, model.sample_rate_hz):
        raise ValueError(f"{source}: sample rate {fs:g} Hz; the model was trained at "
                         f"{model.sample_rate_hz:g} Hz{make}")
    n_t = ds.sizes["time"]
    if not np.isclose(n_t / fs, model.window_s):
        raise ValueError(f"{source}: windows of {n_t / fs:g} s; the model was trained on "
                         f"windows of {model.window_s:g} s{make}")
    n_f = len(feature_names(twist=twist))
    if getattr(model, "n_features", 0) and n_f != model.n_features:
        raise ValueError(f"{source}: its windows give {n_f} health features "
                         f"({'with' if twist else 'without'} an output encoder's twist); the "
                         f"model was trained on {model.n_features}{make}")
    pts = np.stack([ds["n_in_rpm"].values, ds["t_out_nm"].values], axis=1)
    lo, hi = model.points_range
    out = ~np.all((pts >= lo - 1e-9) & (pts <= hi + 1e-9), axis=1)
    if out.any():
        o = pts[np.flatnonzero(out)[0]]
        raise ValueError(f"{source}: operating point {o[0]:g} rpm, {o[1]:g} N m outside the "
                         f"model's training range: speed [{lo[0]:g}, {hi[0]:g}] rpm, torque "
                         f"[{lo[1]:g}, {hi[1]:g}] N m{make}")
    if "temperature_c" in ds:
        t = ds["temperature_c"].values.astype(float)
        lo, hi = TEMPERATURE_RANGE_C
        bad = np.flatnonzero((t < lo) | (t > hi) | np.isinf(t))
        if bad.size:
            raise ValueError(f"{source}: temperature_c of window {int(bad[0])} is "
                             f"{t[bad[0]]:g} °C; allowed: in [{lo:g}, {hi:g}] °C, or NaN "
                             "(no reading: the monitor reports the temperature sensor and "
                             "goes on without it)")
    interval = float(np.median(np.diff(hours)) * 60.0)
    check_commissioning(pts[comm], rule, interval)
    return interval


def _input_sensor(ds):
    """The input angle sensor of a stream with angle channels, from its config."""
    import json

    from swgsim.sensing.angles import InputAngleSensor

    cfg = ds.attrs.get("config", "{}")
    cfg = json.loads(cfg) if isinstance(cfg, str) else cfg
    counts = ((cfg.get("profile") or {}).get("angles") or {}).get("input_counts_per_rev")
    return InputAngleSensor() if counts is None else InputAngleSensor(int(counts))


def stream_features(ds) -> np.ndarray:
    """Health features of a stream's windows, shape (n, F): in the angle domain when the
    stream carries angle channels (a life on a profile), with the twist features when it
    carries an output encoder's (:func:`learn.inputs.health.health_features`)."""
    meta = {k: ds[k].values for k in ("n_in_rpm", "efficiency", "phi_in_meas",
                                      "phi_out_meas") if k in ds}
    return health_features(ds["strain_signal"].values, meta, float(ds.attrs["sample_rate_hz"]),
                           _input_sensor(ds) if "phi_in_meas" in meta else None)


def monitor_stream(ds, model, rule: RuleConfig, seed: int = 0, confirm_h: float = 1.0,
                   source: str = "stream", normal: NormalConfig | None = None,
                   maintenance: list[MaintenanceEvent] | None = None,
                   prognosis: StreamPrognosis | None = None,
                   naming: NamingConfig | None = None,
                   readers: Sequence[DiagnosisModel] = ()) -> StreamResult:
    """Commission on the stream's commissioning windows and monitor the rest, with its
    conditions (acting load, temperature where the stream has it; :mod:`swgmon.detection.normal`)
    and its maintenance log (:meth:`GearMonitor.declare`: each declared event is listed
    among the recommissionings; after a declared tool change or repair,
    :data:`~swgmon.assessment.gear_monitor.RECOMMISSIONS`, the monitor commissions anew on as
    many windows as commissioning had, and monitors the rest); the monitor keeps
    watching after every alarm and advisory; with ``prognosis`` enabled, the prognoses
    after its gear-fault alarms (:func:`swgmon.prognosis.stream.stream_prognoses`; and
    by each of ``readers``, the model with other severity regressors: a cross-validation's,
    in ``prognosis.readers``).

    Raises
    ------
    ValueError
        A stream the monitor cannot take (:func:`check_stream`), a maintenance event out
        of range (a tool change or repair inside commissioning) or a prognosis option out
        of range (a planned duty outside the model's, prognoses more often than the
        stream's windows or more than ``prognosis.max_prognoses`` after an
        alarm), before any work.
    """
    log = sorted(maintenance or [], key=lambda e: e.hour)
    check_stream(ds, model, rule, source)
    hours = ds["hour"].values.astype(float)
    n_c = int(ds["commissioning"].values.astype(bool).sum())
    # at most a prognosis per window, and a bounded number over the hours an alarm may be
    # followed: from the first window monitored (the earliest alarm) to the last
    prognosis = (prognosis.check(trained=trained_duty(model),
                                 interval_h=window_interval_h(hours),
                                 span_h=float(hours[-1] - hours[n_c]))
                 if prognosis and prognosis.enabled else None)
    for i, e in enumerate(maintenance or []):
        e.check(f"maintenance[{i}]")
        if e.kind in RECOMMISSIONS and e.hour <= hours[n_c]:
            raise ValueError(f"maintenance[{i}].hour: a {e.kind} at {e.hour:g} h; allowed: "
                             f"after the first window monitored, at {hours[n_c]:g} h")
    again = [e for e in log if e.kind in RECOMMISSIONS]
    if not again:
        return _monitor_once(ds, model, rule, seed, confirm_h, source, normal, log, prognosis,
                             naming, readers)
    cut = int(np.searchsorted(hours, again[0].hour))
    before = [e for e in log if e.hour < again[0].hour]
    first = _monitor_once(ds.isel(sample=slice(0, cut)), model, rule, seed, confirm_h,
                          source, normal, before, prognosis, naming, readers)
    entry = declared([again[0]], None)
    if hours.size - cut <= n_c:  # too few windows after it to commission and monitor
        return dataclasses.replace(first, recommissioned=first.recommissioned + unmonitored(
            again[0], [e for e in log if e.hour >= again[0].hour and e is not again[0]],
            hours.size - cut, n_c, float(hours[-1])))
    rest = ds.isel(sample=slice(cut, None)).copy()
    rest["commissioning"] = rest["commissioning"].copy(data=np.arange(rest.sizes["sample"]) < n_c)
    later = monitor_stream(rest, model, rule, seed, confirm_h, source, normal,
                           [e for e in log if e.hour >= again[0].hour and e is not again[0]],
                           prognosis, naming, readers)
    return _joined(first, later, entry)


def _joined(first: StreamResult, later: StreamResult, entry: list[dict]) -> StreamResult:
    """The result of a stream monitored up to a declared recommissioning (``first``) and
    from it on (``later``, whose indices count after ``first``'s windows); the windows of
    the new commissioning are in neither trace."""
    off = len(first.trace.hour)
    shift = [dict(d, index=d["index"] + off) if "index" in d else d
             for d in later.advisories + later.recommissioned]
    alarms = [dataclasses.replace(a, index=a.index + off, rise_index=a.rise_index + off)
              for a in later.alarms]
    on = first.onset_h if first.onset_h is not None else later.onset_h
    fault = first.true_fault if first.onset_h is not None else later.true_fault
    return StreamResult(Trace.concat([first.trace, later.trace]), first.alarms + alarms,
                        first.advisories + shift[:len(later.advisories)],
                        first.n_commissioning, on, fault, first.threshold,
                        first.recommissioned + entry + shift[len(later.advisories):],
                        None if first.prognosis is None else _both(first.prognosis,
                                                                   later.prognosis))


def _both(first: StreamPrognoses, later: StreamPrognoses) -> StreamPrognoses:
    """The prognoses of a stream's two parts (:func:`_joined`), each reader's joined too."""
    return StreamPrognoses(first.events + later.events, first.tracks + later.tracks,
                           [_both(a, b) for a, b in zip(first.readers, later.readers,
                                                        strict=True)])


def _monitor_once(ds, model, rule: RuleConfig, seed: int = 0, confirm_h: float = 1.0,
                   source: str = "stream", normal: NormalConfig | None = None,
                   maintenance: list[MaintenanceEvent] | None = None,
                   prognosis: StreamPrognosis | None = None,
                   naming: NamingConfig | None = None,
                   readers: Sequence[DiagnosisModel] = ()) -> StreamResult:
    """:func:`monitor_stream` on a stream without a declared recommissioning after its
    commissioning."""
    log = list(maintenance or [])
    interval = check_stream(ds, model, rule, source)
    pts = np.stack([ds["n_in_rpm"].values, ds["t_out_nm"].values], axis=1)
    feats = stream_features(ds)
    cond = Conditions.of({k: ds[k].values for k in ("t_out_mean_nm", "temperature_c")
                          if k in ds})
    comm = ds["commissioning"].values.astype(bool)
    n_c = int(comm.sum())
    hours = ds["hour"].values.astype(float)
    mon = GearMonitor(model, rule, interval, seed=seed, confirm_h=confirm_h, normal=normal,
                      naming=naming)
    mon.declare(log)
    lost = _lost_reading(cond, n_c, hours)
    read = np.ones(n_c, bool) if lost is None else np.isfinite(cond.temperature_c[:n_c])
    if not read.any():  # no reading in commissioning: as a joint without the sensor
        cond, read = Conditions(cond.torque_nm), np.ones(n_c, bool)
    mon.commission(feats[:n_c][read], pts[:n_c][read], cond[:n_c][read])
    f, p, c = feats[n_c:], pts[n_c:], cond[n_c:]
    if lost is not None and c.temperature_c is not None:  # from the first window on
        c = Conditions(c.torque_nm, np.full(len(f), np.nan))  # without it
    tr, named, mon = run_stream(mon, f, p, hours[n_c:], c)
    alarms: list[Alarm] = [] if lost is None else [lost]
    for al in named:
        if not alarms or alarms[-1].fault != al.fault:  # the same fault again: one alarm
            alarms.append(al)
    fault = ds["fault"].values.astype(str)
    on = np.flatnonzero((fault != "healthy") & (fault != "unknown"))  # a recording: unknown
    return StreamResult(tr, alarms, advisories(tr, mon), n_c,
                        float(hours[on[0]]) if on.size else None,
                        str(fault[on[0]]) if on.size else None, mon.h,
                        recommissionings(tr, mon) + declared(log, mon),
                        None if prognosis is None else
                        stream_prognoses(tr, alarms, mon, f, p, c, prognosis, readers))


def _lost_reading(cond: Conditions, n_c: int, hours: np.ndarray) -> Alarm | None:
    """The temperature sensor's fault where commissioning has a window without a
    reading (the monitor is then commissioned on the windows with one and goes on without
    the sensor, :func:`run_stream`), else None."""
    t = cond.temperature_c
    bad = np.array([], int) if t is None else np.flatnonzero(~np.isfinite(t[:n_c]))
    return None if not bad.size else _no_reading(float(hours[bad[0]]), int(bad[0]) - n_c)


def _no_reading(hour: float, index: int) -> Alarm:
    """The temperature sensor's fault at a window without a reading."""
    return Alarm(hour, index, index, TEMPERATURE_SENSOR, TEMPERATURE_SENSOR, np.nan,
                 np.nan, np.nan)


def run_stream(mon: GearMonitor, feats: np.ndarray, points: np.ndarray, hours: np.ndarray,
               cond: Conditions) -> tuple[Trace, list[Alarm], GearMonitor]:
    """Monitor windows after commissioning, keep watching after every alarm, and go on
    without the temperature sensor where it fails: from the first window without a
    reading (missing, dropped out), from the first at which a check in force finds the
    reading failed without an alarm (:func:`_checked`; built in, a stuck reading,
    :class:`~swgmon.assessment.hypotheses.StuckReading`; an alarm raised from the failure's
    first window and within ``confirm_h`` of its finding is named the sensor's fault), or
    after an alarm named
    :data:`~swgmon.assessment.sensor_check.TEMPERATURE_SENSOR` (a stuck or drifting reading,
    :func:`~swgmon.assessment.sensor_check.fit_temperature`), the monitor goes on without the
    reading (:func:`reading_lost`, :func:`read_without`). After an alarm named an
    unexplained change (an even change of the friction,
    :func:`~swgmon.assessment.unexplained.fit_friction`) the friction factor takes the fitted
    change and the monitor goes on from there (:func:`adopt_change`).

    Parameters
    ----------
    mon : GearMonitor
        Commissioned.
    feats, points : ndarray, shapes (n, F), (n, 2)
    hours : ndarray, shape (n,)
        Operating hours, increasing.
    cond : Conditions
        Readings may be NaN (no reading).

    Returns
    -------
    (Trace, list of Alarm, GearMonitor)
        The trace of every window, every alarm named (indices into the windows; a
        missing reading's alarm has no severity), and the monitor in force at the end.
    """
    traces, alarms, i0, n, fstart = [], [], 0, len(feats), None
    while True:  # an alarm named a gear fault keeps the monitor from relearning a point
        mon.fault_suspected = any(a.kind == "gear_fault" for a in alarms)
        t = cond.temperature_c
        bad = np.array([], int) if t is None else np.flatnonzero(~np.isfinite(t[i0:]))
        stop = n if not bad.size else i0 + int(bad[0])
        stop, found = _checked(mon, feats, points, hours, cond, i0, stop, fstart)
        w = slice(i0, stop)
        tr = mon.run(feats[w], points[w], hours[w], cond[w], latch=False,
                     friction_start=fstart) if stop > i0 else None
        named, cut = _named(mon, tr, alarms, feats[w], points[w], cond[w], found,
                            float(hours[stop]) - mon.confirm_h if found is not None else np.inf)
        if cut:
            stop = i0 + named[-1].index + 1
            tr = tr.head(named[-1].index + 1)
        alarms += [dataclasses.replace(al, index=al.index + i0, rise_index=al.rise_index + i0)
                   for al in named]
        traces += [] if tr is None else [tr]
        if stop == n:
            return Trace.concat(traces), alarms, mon
        fstart = None if tr is None else tr.state(len(tr.hour) - 1)
        undo = None if not cut or named[-1].fault == TEMPERATURE_SENSOR else \
            _drifting(mon, Trace.concat(traces), alarms, feats, points, hours, cond)
        if undo is not None:  # a drifting reading, not the friction: the changes undone
            alarms[-1] = _sensor_named(alarms[-1])
            fstart = (fstart[0] / undo, fstart[1])
        elif cut and named[-1].fault not in CHANGES_STATE:  # a gear fault it stays
            i0 = stop
            continue
        if cut and named[-1].fault == UNEXPLAINED_CHANGE and undo is None:
            fstart = (adopt_change(mon, named[-1], fstart[0]), fstart[1])
        else:
            if not cut:
                alarms.append(_no_reading(float(hours[stop]), stop))
            mon = reading_lost(mon)
            rest = read_without(mon, feats[stop:], points[stop:], cond[stop:], hours[stop:],
                                (mon.friction, mon.last_hour) if fstart is None else fstart)
            cond = Conditions.concat([Conditions(cond.torque_nm[:stop], None if
                                                 rest.temperature_c is None else
                                                 np.full(stop, np.nan)), rest])
        i0 = stop


def _checked(mon: GearMonitor, feats: np.ndarray, points: np.ndarray, hours: np.ndarray,
             cond: Conditions, i0: int, stop: int, fstart: tuple | None
             ) -> tuple[int, Finding | None]:
    """Where the checks in force (:class:`~swgmon.assessment.hypotheses.ReadingCheck`,
    in ``naming.hypotheses``'s order) find the reading failed in windows ``i0:stop``: each
    asked on the windows before the last one's finding, at the friction factor in force
    (``fstart``'s, else the monitor's). Returns the window to stop at (``stop`` where none
    holds) and the last finding (indices from ``i0``), else None.

    Raises
    ------
    ValueError
        A finding outside the windows it was asked on, or found before its first window.
    """
    found = None
    for c in (h for h in mon.hypotheses if isinstance(h, ReadingCheck)):
        w = slice(i0, stop)
        f = c.found(Stream(mon.normal, feats[w], points[w], cond[w],
                           mon.friction if fstart is None else fstart[0], hours[w],
                           mon.naming, not mon.reading_virtual))
        if f is not None and not 0 <= f.first <= f.found < stop - i0:
            raise ValueError(f"check {c.name}: first {f.first} and found {f.found} must "
                             f"satisfy 0 <= first <= found < {stop - i0}, the windows asked")
        stop, found = (stop, found) if f is None else (i0 + f.found, f)
    return stop, found


def _named(mon: GearMonitor, tr: Trace | None, alarms: list[Alarm], feats: np.ndarray,
           points: np.ndarray, cond: Conditions, found: Finding | None, found_h: float
           ) -> tuple[list[Alarm], bool]:
    """The alarms of the run ``tr`` (:func:`run_stream`'s, on these windows) named, up to
    the first that changes the monitor's state (:data:`CHANGES_STATE`, or a gear fault
    soon after an unexplained change, :func:`_after_change`), and whether one did; one
    raised where a check found the reading failed (``found``, from its ``first`` window
    and ``found_h``: its finding's hour less ``confirm_h``) named the temperature
    sensor's (:func:`_sensor_named`)."""
    named = []
    for a in [] if tr is None else tr.alarms:
        named.append(mon.diagnose(tr, a, feats, points, cond, named[-1] if named else None))
        if found is not None and a >= found.first and tr.hour[a] >= found_h:
            named[-1] = _sensor_named(named[-1])
        if named[-1].fault in CHANGES_STATE or _after_change(mon, alarms, named[-1],
                                                             float(tr.hour[a]), cond):
            return named, True
    return named, False


def _drifting(mon: GearMonitor, trace: Trace, alarms: list[Alarm], feats: np.ndarray,
              points: np.ndarray, hours: np.ndarray, cond: Conditions) -> float | None:
    """Where the unexplained change or gear fault of ``alarms[-1]`` comes within
    ``naming.recur_h`` after an unexplained change while the reading is in use
    (:func:`_after_change`): the windows since the earlier change's rise
    named again (:meth:`GearMonitor.name`) with the friction as it was before it, the
    changes taken since undone. Where the reading's drift
    (:func:`~swgmon.assessment.sensor_check.fit_temperature_drift`) names them, the factor
    the friction was taken to have changed by since (to divide out), else None: under a
    steep friction law a drifting reading moves the efficiency before the bridges, and
    each change taken hid a part of it (docs/monitor/evaluation.md, "Scored under every family,
    every held-out gear")."""
    last = alarms[-1]
    earlier = [a for a in alarms[:-1] if a.fault == UNEXPLAINED_CHANGE
               and a.hour >= last.hour - mon.naming.recur_h]
    if mon.reading_virtual or cond.temperature_c is None or not earlier:
        return None
    w = slice(earlier[0].rise_index, last.index + 1)
    taken = np.ones(len(trace.hour))
    for a in earlier:  # each taken from the window after its alarm
        taken[a.index + 1:] *= 1.0 + a.severity
    ev = mon.evidence(trace.log_proba[w], trace.op_index[w])
    ev[(trace.outside[w] & Outside.UNJUDGED) != 0] = 0.0
    fault, _ = mon.name(ev, feats[w], points[w], cond[w], trace.friction[w] / taken[w],
                        hours[w])
    return float(taken[-1]) if fault == TEMPERATURE_SENSOR else None


def _after_change(mon: GearMonitor, alarms: list[Alarm], alarm: Alarm, hour: float,
                  cond: Conditions) -> bool:
    """Whether ``alarm``, named a gear fault at ``hour`` while the reading is in use,
    comes within ``naming.recur_h`` after an unexplained change (``alarms``, those before
    it): then :func:`_drifting` names its windows again with the changes taken undone, as
    for a recurring change (a drifting reading whose first effect was taken for the
    friction shows next as a change of the efficiency a gear fault also makes)."""
    return (alarm.kind == "gear_fault" and not mon.reading_virtual
            and cond.temperature_c is not None
            and any(a.fault == UNEXPLAINED_CHANGE and a.hour >= hour - mon.naming.recur_h
                    for a in alarms))


def _sensor_named(alarm: Alarm) -> Alarm:
    """``alarm`` named the temperature sensor's fault (no severity), unless a bridge's
    fault named it: raised while the reading was already stuck and found stuck within the
    hour its name is decided in (``confirm_h``), or a recurring unexplained change that
    the reading's drift explains (:func:`_drifting`)."""
    if alarm.sensor_fault and alarm.fault != TEMPERATURE_SENSOR:
        return alarm
    return dataclasses.replace(alarm, fault=TEMPERATURE_SENSOR, severity=np.nan,
                               severity_low=np.nan, severity_high=np.nan, bridge=None)


def adopt_change(mon: GearMonitor, alarm: Alarm, factor: float) -> float:
    """After ``alarm`` named an unexplained change: the friction factor's new level
    (``factor`` times one plus its severity). Where that level is a friction
    commissioning did not see (beyond its range by more than ``friction_margin``,
    :meth:`~swgmon.detection.normal.NormalBehaviour.beyond_friction`: fresh grease), ``mon``
    follows it from the alarm's hour as after a declared re-greasing, window by window
    (:meth:`GearMonitor.track_friction`); else at its usual pace, so that a change within
    what healthy operation moves the friction by does not blind the efficiency for
    ``regrease_settle_h``."""
    new = factor * (1.0 + alarm.severity)
    if mon.normal.beyond_friction(new):
        mon.regreased = sorted([*mon.regreased, alarm.hour])
    return new


def reading_lost(mon: GearMonitor) -> GearMonitor:
    """The monitor that goes on where the temperature sensor failed: ``mon`` where
    commissioning learnt the temperature's laws (its readings the laws' own from now on,
    so no alarm is named the temperature sensor again, and its calibration theirs:
    :meth:`GearMonitor.read_virtually`), else ``mon``
    commissioned again without temperature (:func:`without_temperature`)."""
    if not mon.normal.temperature_law:
        return without_temperature(mon)
    mon.read_virtually()
    return mon


def read_without(mon: GearMonitor, feats: np.ndarray, points: np.ndarray, cond: Conditions,
                 hours: np.ndarray, start: tuple[float, float | None]) -> Conditions:
    """Windows' conditions without the temperature reading (:func:`reading_lost`'s
    monitor): the temperature the laws say each window was at
    (:func:`~swgmon.assessment.sensor_check.virtual_temperature`), or none where
    commissioning learnt no law. Each window's at the friction factor the monitor tracks
    there (:meth:`GearMonitor.track_friction` from ``start``, the factor in force and the
    hour of the window before, over the last pass's temperatures; ``naming.virtual_passes``):
    at the factor in force at the loss for every later window, a friction still running in
    after it was read as a warmer joint (the efficiency up, the bridges saying otherwise)
    and every cold start as a pattern of the bridges' second harmonics (bench gear 1,
    family ``all``, scored seed 4: the factor tracked from 1.05 to 0.90 in the 32 h after
    the reading was lost, the virtual temperature 5 K warm at the cold start of 112 h and a
    root crack named there; docs/monitor/assessment.md,
    "The monitor checks its temperature sensor").
    """
    if not mon.normal.temperature_law:
        return Conditions(cond.torque_nm)
    opi = mon.normal.index(points)
    fr = np.full(len(feats), float(start[0]))
    passes = mon.naming.virtual_passes
    for k in range(passes + 1):
        temp = virtual_temperature(mon.normal, feats, points, cond.torque_nm, fr, opi,
                                   mon.naming)
        if k < passes:
            fr = mon.fork().track_friction(feats, points, hours,
                                           Conditions(cond.torque_nm, temp), opi, start)
    return Conditions(cond.torque_nm, temp)


def unmonitored(event: MaintenanceEvent, later: list[MaintenanceEvent], left: int,
                n_c: int, end_h: float) -> list[dict]:
    """The entries of a declared tool change or repair after which the stream holds too
    few windows to commission anew (``left`` of the ``n_c`` commissioning needs), and of
    the events declared after it: each listed, with the hours left unmonitored said."""
    what = event.kind.replace("_", " ")
    out = [{"hour": float(event.hour), "maintenance": event.kind, "declared": True,
            "monitored": False,
            "note": f"{what} declared: only {left} window(s) after it, fewer than the {n_c} "
                    f"commissioning needs; the monitor cannot commission anew, and the "
                    f"stream's windows from {event.hour:g} h to {end_h:.4g} h are not "
                    "monitored"}]
    out += [{"hour": float(e.hour), "maintenance": e.kind, "declared": True,
             "monitored": False,
             "note": f"{e.kind.replace('_', ' ')} declared at {e.hour:g} h: not monitored, "
                     f"after the {what} at {event.hour:g} h"} for e in later]
    return out


def declared(log: list[MaintenanceEvent], mon: GearMonitor | None) -> list[dict]:
    """The recommissioning entry of each declared maintenance event (``hour``,
    ``kind``, ``note``): what the monitor relearns after it (``mon``: the monitor of a
    re-greasing, for its settling time; None where the log holds none)."""
    notes = {"tool_change": "tool change declared: the monitor commissions anew after it "
                            "(the load at every point changed)",
             "repair": "repair declared: the monitor commissions anew after it (a repaired "
                       "gear is learnt as a new one)"}
    out = []
    for e in log:
        note = notes.get(e.kind) or (
            f"re-greasing declared: the friction is followed window by window for "
            f"{mon.normal_config.regrease_settle_h:g} h while the new grease runs in (the "
            "efficiency is not judged then)")
        out.append({"hour": float(e.hour), "maintenance": e.kind, "declared": True,
                    "note": note})
    return out


def without_temperature(mon: GearMonitor) -> GearMonitor:
    """The same monitor commissioned on the same windows without their temperature
    readings, as for a joint without a temperature sensor (its spreads hold
    commissioning's warm-ups), with the same maintenance log: where the temperature sensor
    fails and commissioning learnt no temperature law, the monitor goes on with it
    (:func:`run_stream`).

    Raises
    ------
    ValueError
        If the monitor is not commissioned.
    """
    if mon.normal is None:
        raise ValueError("the monitor is not commissioned (GearMonitor.commission)")
    feats, points, cond = mon.commissioned_on
    out = GearMonitor(mon.model, mon.rule, mon.interval_min, mon.seed, mon.confirm_h,
                      mon.normal_config, mon.naming)
    out.commission(feats, points, Conditions(cond.torque_nm, None))
    out.regreased = list(mon.regreased)
    return out


def recommissionings(tr: Trace, mon: GearMonitor) -> list[dict]:
    """Each point the monitor recommissioned at a new load (:attr:`Trace.recommissioned`):
    ``hour``, ``index``, ``operating_point``, ``relearnt`` (True: the windows at the new
    load became its normal; False: commissioning's laws held there and its load range
    grew) and the ``load_range_nm`` it now holds normal (the monitor's state at the end of
    the run; a point recommissioned twice shows its last range at both)."""
    out = []
    for i, k, relearnt in tr.recommissioned:
        o = mon.normal.points[k]
        lo, hi = mon.normal.torque_range[k]
        how = ("relearnt there (commissioning's laws did not hold)" if relearnt else
               "commissioning's laws held there; its load range grew")
        out.append({"hour": float(tr.hour[i]), "index": int(i),
                    "operating_point": [float(o[0]), float(o[1])],
                    "relearnt": bool(relearnt), "load_range_nm": [float(lo), float(hi)],
                    "note": f"the load at {o[0]:g} rpm, {o[1]:g} N m stayed beyond what "
                            f"commissioning saw: {how}, {lo:.4g}-{hi:.4g} N m"})
    return out


def advisories(tr: Trace, mon: GearMonitor, clear_h: float = 1.0) -> list[dict]:
    """An advisory where a condition leaves what commissioning saw (a bit of
    :attr:`Trace.outside` set), naming the condition and the point; the same condition
    is advised again only after it was back inside for ``clear_h`` hours (the duty
    cycle's points have ranges of their own)."""
    out = []
    raised: dict[int, float] = {}  # bit -> hour it was last seen outside, while raised
    for i, (bits, hour) in enumerate(zip(tr.outside.tolist(), tr.hour.tolist(), strict=True)):
        for b in [b for b, last in raised.items() if not bits & b and hour - last >= clear_h]:
            del raised[b]
        new = [b for b in CONDITIONS if bits & b and b not in raised]
        for b in CONDITIONS:
            if bits & b:
                raised[b] = hour
        if new:
            what = ", ".join(CONDITIONS[b] for b in new)
            o = mon.normal.points[tr.op_index[i]]
            out.append({"hour": float(hour), "index": i, "condition": what,
                        "operating_point": [float(o[0]), float(o[1])],
                        "friction_factor": float(tr.friction[i]),
                        "advice": f"the {what} left what commissioning saw at {o[0]:g} rpm, "
                                  f"{o[1]:g} N m: recommission the monitor if the gear is "
                                  f"known healthy; that relearns as normal the features "
                                  f"there as they read now and the friction at "
                                  f"{tr.friction[i]:.2f}x commissioning's"})
    return out


def write_outputs(res: StreamResult, out_dir: Path, source: str) -> dict[str, Path]:
    """``summary.json``, ``report.md`` and ``health.png`` (module docstring), each with
    the threshold the rule used (:attr:`StreamResult.threshold`); with the prognosis on,
    ``summary.json``'s ``prognosis``, a report line per valid one and, where an alarm was
    followed, ``prognosis.png``. ``summary.json`` is written last: a folder that holds it
    holds the run's every output (the app claims its folder ``fresh``, so none of an
    earlier run's is left beside them)."""
    from swgsim.files.ownership import atomic_write_bytes, atomic_write_json

    h = res.threshold
    out_dir.mkdir(parents=True, exist_ok=True)
    summary = {"stream": source, "alarms": [a.as_dict() for a in res.alarms],
               "events": res.events(), "threshold": h,
               "windows_monitored": int(res.trace.s.size),
               "commissioning_windows": res.n_commissioning}
    followed = res.prognosis is not None and bool(res.prognosis.tracks)
    if res.prognosis is not None:
        summary["prognosis"] = res.prognosis.events
    if followed:
        prognosis_figure(res.prognosis, out_dir / "prognosis.png")
    tr = res.trace
    health_figure(res.trace, res.threshold, res.events(), res.onset_h, res.true_fault,
                  out_dir / "health.png")
    lines = [f"# Monitor report: {source}", "",
             f"{res.n_commissioning} commissioning windows, {tr.s.size} monitored; alarm "
             f"threshold h = {h:.2f}.", ""]
    if not res.alarms:
        lines.append("- no alarm")
    lines += [f"- {event_line(e)}" for e in res.events()]
    lines += res.prognosis.report_lines() if res.prognosis is not None else []
    if res.onset_h is not None:
        lines += ["", f"Ground truth in the stream: {res.true_fault} from {res.onset_h:.2f} h."]
    lines += ["", "![health indicators](health.png)", ""]
    atomic_write_bytes(out_dir / "report.md", "\n".join(lines).encode())
    # the summary last: a folder holding it holds the whole run's outputs
    atomic_write_json(out_dir / "summary.json", summary)
    return {k: out_dir / v for k, v in (("summary", "summary.json"), ("report", "report.md"),
                                        ("figure", "health.png"), ("prognosis", "prognosis.png"))
            if k != "prognosis" or followed}


__all__ = ["CHANGES_STATE", "CONDITIONS", "EVENT_KINDS", "OWN_JOINT_COMMAND", "StreamResult",
           "advisories", "check_stream", "declared", "event_line", "monitor_stream",
           "recommissionings", "run_stream", "select_gear", "without_temperature", "write_outputs"]
