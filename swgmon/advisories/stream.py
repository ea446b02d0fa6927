"""One gear's recorded stream through the monitor: input checks and the run.

A stream is a schema-v1 data set (:mod:`swgsim.datasets.schema`) of one gear's windows with the
per-sample variables ``hour`` (operating hours, increasing) and ``commissioning`` (the
first windows, known healthy), e.g. a life written by ``swgsim-generate`` with
``dataset.life`` set (:mod:`swgsim.datasets.life`). :func:`check_stream` refuses, before any work
and in one line, a stream without commissioning, with hours out of order, or one that
disagrees with the model (bridges, sample rate, operating points outside the training
range), or one with no window after commissioning. :func:`monitor_stream` runs
:class:`~swgmon.assessment.gear_monitor.GearMonitor` over it, with its maintenance log,
and goes on without the temperature sensor where it fails or from a change it names
(:func:`run_stream`); what it made of the stream, :class:`~.report.StreamResult`, is
reported by :mod:`.report`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from learn.inputs.health import feature_names, health_features
from swgmon.advisories.report import (
    StreamResult,
    advisories,
    declared,
    recommissionings,
    unmonitored,
)
from swgmon.assessment.gear_monitor import RECOMMISSIONS, GearMonitor, MaintenanceEvent, Trace
from swgmon.assessment.hypotheses import Finding, ReadingCheck, Stream
from swgmon.assessment.model import DiagnosisModel
from swgmon.assessment.naming import diagnose, name
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

#: Alarms after which the monitor's state changes (:func:`run_stream`): the temperature
#: sensor's fault (the monitor goes on without it) and an unexplained change (the friction
#: factor takes the fitted change, the monitor watches for what comes on top of it).
CHANGES_STATE = (TEMPERATURE_SENSOR, UNEXPLAINED_CHANGE)


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
        named.append(diagnose(mon, tr, a, feats, points, cond, named[-1] if named else None))
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
    named again (:func:`~swgmon.assessment.naming.name`) with the friction as it was before it, the
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
    fault, _ = name(mon, ev, feats[w], points[w], cond[w], trace.friction[w] / taken[w],
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


__all__ = ["CHANGES_STATE", "OWN_JOINT_COMMAND", "adopt_change", "check_stream",
           "monitor_stream", "read_without", "reading_lost", "run_stream", "select_gear",
           "stream_features", "without_temperature"]
