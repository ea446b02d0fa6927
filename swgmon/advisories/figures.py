"""The monitor's figures of a stream: ``health.png`` (:func:`health_figure`) and
``prognosis.png`` (:func:`prognosis_figure`), each written atomically
(:func:`swgsim.files.ownership.write_owned`) by :func:`.report.write_outputs`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from swgmon.assessment.gear_monitor import Trace
from swgmon.prognosis.stream import StreamPrognoses
from swgsim.files.ownership import save_figure

__all__ = ["EVENT_MARKS", "crossings", "health_figure", "prognosis_figure"]


def _pyplot():
    """matplotlib's pyplot on the Agg backend (no display)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


#: How each kind of event is marked on ``health.png``: (colour, line style).
EVENT_MARKS = {"gear_fault": ("r", "-"), "sensor_fault": ("tab:purple", "-"),
               "unexplained_change": ("tab:brown", "-"), "advisory": ("tab:orange", "-."),
               "recommissioned": ("tab:green", ":")}


def crossings(s: np.ndarray, threshold: float) -> np.ndarray:
    """Indices of the windows where the CUSUM ``s`` (shape (n,)) reaches ``threshold``
    from below (the first window counts when it starts there), shape (k,)."""
    above = np.asarray(s, float) >= threshold
    return np.flatnonzero(above & ~np.concatenate([[False], above[:-1]]))


def health_figure(trace: Trace, threshold: float, events: list[dict], onset_h: float | None,
                  true_fault: str | None, path: Path) -> None:
    """``health.png`` at ``path``: the windows' −log10 p-values and the CUSUM against the
    rule's threshold, every crossing of it (triangles), every event by its kind (alarms,
    advisories, recommissioned points: :data:`EVENT_MARKS`) and the stream's true onset
    (dotted black) where it records one; the legend outside the data; written
    atomically.

    Parameters
    ----------
    trace : Trace
        The monitored windows' p-values ``p`` and CUSUM ``s`` by ``hour`` [h].
    threshold : float
        h, the rule's alarm threshold.
    events : list of dict
        :meth:`.report.StreamResult.events`: ``kind`` and ``hour`` [h] each.
    onset_h : float or None
        The true onset [h] (a simulated stream), else None.
    true_fault : str or None
    path : Path
    """
    plt = _pyplot()
    tr, h = trace, threshold
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8.5, 4.5), sharex=True)
    a1.plot(tr.hour, -np.log10(tr.p), ".", ms=1.5, color="0.4")
    a1.set_ylabel("−log10 p")
    a2.plot(tr.hour, tr.s, lw=0.8, label="CUSUM")
    a2.axhline(h, color="r", lw=0.8, ls="--", label=f"threshold h = {h:.1f}")
    up = crossings(tr.s, h)
    a2.plot(np.asarray(tr.hour)[up], np.full(up.size, h), "v", color="r", ms=5,
            label=f"crossings ({up.size})")
    for ax in (a1, a2):
        if onset_h is not None:
            ax.axvline(onset_h, color="k", lw=0.8, ls=":",
                       label=f"true onset ({true_fault})" if ax is a2 else None)
        seen = set()
        for e in events:
            colour, style = EVENT_MARKS[e["kind"]]
            first = ax is a2 and e["kind"] not in seen
            seen.add(e["kind"])
            ax.axvline(e["hour"], color=colour, lw=0.8, ls=style,
                       label=e["kind"].replace("_", " ") if first else None)
    a2.set_ylabel("CUSUM")
    a2.set_xlabel("operating hours")
    a2.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    a1.set_title("health indicators", fontsize=9)
    fig.tight_layout()
    save_figure(fig, path, 130)


def prognosis_figure(prog: StreamPrognoses, path: Path) -> None:
    """``prognosis.png`` at ``path``: per alarm followed, the severity estimates with their
    90 % intervals, the failure threshold, and the last valid prognosis's predicted
    crossing (median) with its 5-95 % band; written atomically."""
    plt = _pyplot()
    n = max(len(prog.tracks), 1)
    fig, axes = plt.subplots(n, 1, figsize=(7, 2.8 * n), squeeze=False)
    for ax, t in zip(axes[:len(prog.tracks), 0], prog.tracks, strict=True):
        h, y = np.array(t["hours"]), np.array(t["severity"])
        ax.errorbar(h, y, yerr=[y - np.array(t["lo"]), np.array(t["hi"]) - y], fmt=".",
                    ms=3, lw=0.6, color="0.3", label="severity estimate (90 %)")
        ev = [e for e in prog.of_track(t) if e["valid"]]
        thr = ev[-1]["threshold"] if ev else None
        if thr is not None:
            ax.axhline(thr, color="r", lw=0.8, ls="--", label=f"failure at {thr:.3g}")
            last = ev[-1]
            if last["failure_h"] is not None:
                hi = last["failure_h_q95"] if last["failure_h_q95"] is not None else h[-1]
                ax.axvspan(last["failure_h_q05"], hi, color="C1", alpha=0.25,
                           label=f"crossing 5-95 % (at {last['hour']:.1f} h)")
                ax.axvline(last["failure_h"], color="C1", lw=1.0, label="crossing, median")
        ax.axvline(t["alarm_h"], color="r", lw=0.8, label="alarm")
        ax.set_ylabel(f"{t['fault']} severity")
        ax.legend(fontsize=7, loc="upper left")
    axes[-1, 0].set_xlabel("operating hours")
    fig.tight_layout()
    save_figure(fig, path, 130)
