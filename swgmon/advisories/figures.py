"""The monitor's figures of a stream: ``health.png`` (:func:`health_figure`) and
``prognosis.png`` (:func:`prognosis_figure`), each written atomically
(:func:`swgsim.files.ownership.write_owned`) by :func:`.stream.write_outputs`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from swgmon.assessment.gear_monitor import Trace
from swgmon.detection.rule import Alarm
from swgmon.prognosis.stream import StreamPrognoses
from swgsim.files.ownership import save_figure

__all__ = ["health_figure", "prognosis_figure"]


def _pyplot():
    """matplotlib's pyplot on the Agg backend (no display)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def health_figure(trace: Trace, threshold: float, alarms: list[Alarm], onset_h: float | None,
                  true_fault: str | None, path: Path) -> None:
    """``health.png`` at ``path``: the windows' −log10 p-values and the CUSUM against the
    rule's threshold, the alarms (red) and the stream's true onset (dotted) where it
    records one (the fields of a :class:`.stream.StreamResult`); written
    atomically.

    Parameters
    ----------
    trace : Trace
        The monitored windows' p-values ``p`` and CUSUM ``s`` by ``hour`` [h].
    threshold : float
        h, the rule's alarm threshold.
    alarms : list of Alarm
    onset_h : float or None
        The true onset [h] (a simulated stream), else None.
    true_fault : str or None
    path : Path
    """
    plt = _pyplot()
    tr, h = trace, threshold
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 4.5), sharex=True)
    a1.plot(tr.hour, -np.log10(tr.p), ".", ms=1.5, color="0.4")
    a1.set_ylabel("−log10 p")
    a2.plot(tr.hour, tr.s, lw=0.8)
    a2.axhline(h, color="r", lw=0.8, ls="--", label=f"threshold h = {h:.1f}")
    for ax in (a1, a2):
        if onset_h is not None:
            ax.axvline(onset_h, color="k", lw=0.8, ls=":")
        for al in alarms:
            ax.axvline(al.hour, color="r", lw=0.8)
    a2.set_ylabel("CUSUM")
    a2.set_xlabel("operating hours")
    a2.legend(fontsize=7)
    title = "health indicators" + (f"; true onset ({true_fault}) dotted"
                                   if onset_h is not None else "")
    a1.set_title(title, fontsize=9)
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
