"""What the monitor tells of a stream (ISO 13374's advisory generation): its events in
time order, one line each, the advisories where a condition left what commissioning
saw, the recommissioning entries of the maintenance log, and the outputs.

:class:`StreamResult` is what :func:`swgmon.advisories.stream.monitor_stream` made of a
stream; :meth:`StreamResult.events` its alarms, advisories and recommissionings, each
printed by :func:`event_line` (the report and ``swgsim-monitor``); :func:`write_outputs`
writes ``summary.json``, ``report.md`` and ``health.png``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from swgmon.advisories.figures import health_figure, prognosis_figure
from swgmon.assessment.gear_monitor import GearMonitor, MaintenanceEvent, Trace
from swgmon.detection.normal import Outside
from swgmon.detection.rule import TEMPERATURE_SENSOR, Alarm
from swgmon.prognosis.stream import StreamPrognoses
from swgsim.files.ownership import atomic_write_bytes, atomic_write_json

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


__all__ = ["CONDITIONS", "EVENT_KINDS", "StreamResult", "advisories", "declared",
           "event_line", "recommissionings", "unmonitored", "write_outputs"]
