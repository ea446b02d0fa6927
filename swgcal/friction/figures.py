"""Figures of a friction calibration (matplotlib object API, no pyplot state).

One PNG per diagnosis view, each comparing the residual of the paper law (before) with
that of the final model (after) on the fit + validation samples, plus an overlay of the
predictions on the test blocks:

* ``velocity.png``: residual against q̇ (coloured by the sign of q̇·q̈) with bin means;
* ``position.png``: residual against q per direction of motion, and its spectrum over q;
* ``hysteresis.png``: residual near reversals against q̇, accelerating vs decelerating,
  and against q̈;
* ``time.png``: residual against time with the block roles, and its spectrum in time;
* ``overlay.png``: measured torque, paper law and final model on the test blocks.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from swgsim.files.ownership import save_figure

from ..loop import CalibrationResult
from ..periodogram import periodogram_peaks

log = logging.getLogger(__name__)

__all__ = ["make_figures"]

_MAX_POINTS = 15000
BEFORE, AFTER = "#1f77b4", "#d62728"


def _thin(idx: np.ndarray, n: int = _MAX_POINTS) -> np.ndarray:
    if idx.size <= n:
        return idx
    return idx[np.linspace(0, idx.size - 1, n).astype(int)]


def _bin_means(x: np.ndarray, y: np.ndarray, n_bins: int = 40) -> tuple[np.ndarray, np.ndarray]:
    edges = np.unique(np.quantile(x, np.linspace(0, 1, n_bins + 1)))
    b = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, edges.size - 2)
    cnt = np.bincount(b, minlength=edges.size - 1)
    m = np.bincount(b, weights=y, minlength=edges.size - 1) / np.maximum(cnt, 1)
    c = 0.5 * (edges[:-1] + edges[1:])
    ok = cnt > 0
    return c[ok], m[ok]


def _spectrum(x: np.ndarray, r: np.ndarray, p_min: float, p_max: float
              ) -> tuple[np.ndarray, np.ndarray]:
    """Normalised periodogram (as in periodogram_peaks) on a grid of periods."""
    x = np.asarray(x, float)
    rc = r - r.mean()
    h = p_min / 8.0
    cells = np.floor((x - x.min()) / h).astype(np.int64)
    s = np.bincount(cells, weights=rc)
    nfft = 1 << int(np.ceil(np.log2(max(4 * s.size, 16))))
    f = np.arange(nfft // 2 + 1) / (nfft * h)
    pw = np.abs(np.fft.rfft(s, nfft)) ** 2 * 2.0 / (x.size * float(np.sum(rc * rc)))
    band = (f >= 1.0 / p_max) & (f <= 1.0 / p_min)
    return 1.0 / f[band], pw[band]


def _log_smooth(f: np.ndarray, pw: np.ndarray, n_bins: int = 120
                ) -> tuple[np.ndarray, np.ndarray]:
    """Average a spectrum in logarithmically spaced frequency bins (readability)."""
    edges = np.geomspace(f.min(), f.max(), n_bins + 1)
    b = np.clip(np.searchsorted(edges, f, side="right") - 1, 0, n_bins - 1)
    cnt = np.bincount(b, minlength=n_bins)
    m = np.bincount(b, weights=pw, minlength=n_bins) / np.maximum(cnt, 1)
    c = np.sqrt(edges[:-1] * edges[1:])
    return c[cnt > 0], m[cnt > 0]


@dataclass(frozen=True)
class _FigureData:
    """What the figures of a friction calibration draw: the problem, its signals and split,
    predictions and residuals before/after, the thinned plotting samples."""

    p: Any
    sig: Any
    y: np.ndarray
    sp: Any
    pred_b: np.ndarray
    pred_a: np.ndarray
    rb: np.ndarray
    ra: np.ndarray
    idx: np.ndarray
    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    u: str
    title: str
    sc: Any
    acc_dec: np.ndarray
    roles: dict


def _figure_data(result: CalibrationResult) -> _FigureData:
    p = result.problem
    sig, y, sp = p.signals, p.y, p.split
    pred_b, pred_a = result.predictions()
    v, a = sig.dq_rad_s, sig.ddq_rad_s2
    return _FigureData(
        p=p, sig=sig, y=y, sp=sp, pred_b=pred_b, pred_a=pred_a, rb=y - pred_b, ra=y - pred_a,
        idx=_thin(sp.fit_validation), t=sig.t_s, q=sig.q_rad, v=v, a=a, u=p.units,
        title=f"{p.name}: paper law (before) vs final model (after)", sc=sig.scales,
        acc_dec=np.sign(v * a), roles=sp.description.get("time_ranges_s", {}))


def _fig_velocity(d: _FigureData) -> Any:
    """Residual before and after against q̇, coloured by accelerating/decelerating."""
    from matplotlib.figure import Figure

    v, idx, rb, ra, u, title, acc_dec = (d.v, d.idx, d.rb, d.ra, d.u, d.title, d.acc_dec)
    fig = Figure(figsize=(11, 4.2), layout="constrained")
    axs = fig.subplots(1, 2, sharey=True)
    for ax, r, lab in ((axs[0], rb, "before"), (axs[1], ra, "after")):
        ax.scatter(v[idx], r[idx], c=acc_dec[idx], cmap="coolwarm", s=2, vmin=-1, vmax=1,
                   rasterized=True)
        cx, cy = _bin_means(v[idx], r[idx])
        ax.plot(cx, cy, color="k", lw=1.5, label="bin mean")
        ax.axhline(0, color="0.5", lw=0.5)
        ax.set_xlabel("q̇ [rad/s]")
        ax.set_title(f"residual {lab} (RMS {np.sqrt(np.mean(r[idx] ** 2)):.3g} {u})",
                     fontsize=9)
        ax.legend(fontsize=8, loc="upper left")
    axs[0].set_ylabel(f"residual [{u}]")
    fig.suptitle(title + "; colour: red accelerating, blue decelerating", fontsize=10)
    return fig


def _fig_position(d: _FigureData) -> Any:
    """Residual over q per direction; spectra over q of its even and odd parts."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullFormatter

    q, v, idx, rb, ra, u, sc, sp, sig, title = (
        d.q, d.v, d.idx, d.rb, d.ra, d.u, d.sc, d.sp, d.sig, d.title)
    fig = Figure(figsize=(11, 7), layout="constrained")
    axs = fig.subplots(2, 2)
    for j, (r, lab) in enumerate(((rb, "before"), (ra, "after"))):
        ax = axs[0, j]
        for s_, col, name in ((1, "tab:red", "q̇ > 0"), (-1, "tab:blue", "q̇ < 0")):
            m = idx[np.sign(v[idx]) == s_]
            ax.scatter(q[m], r[m], s=2, color=col, alpha=0.5, label=name, rasterized=True)
        ax.axhline(0, color="0.5", lw=0.5)
        ax.set_xlabel("q [rad]")
        ax.set_ylabel(f"residual {lab} [{u}]")
        ax.legend(fontsize=8, markerscale=4)
    p_min, p_max = max(4 * sc.dq_med, sc.q_span / 2000), sc.q_span / 2
    ax = axs[1, 0]
    for r, lab, col in ((rb, "before", BEFORE), (ra, "after", AFTER)):
        per, pw = _spectrum(q[sp.fit_validation], r[sp.fit_validation], p_min, p_max)
        ax.semilogx(per, pw, color=col, lw=0.8, label=f"{lab}, even part")
        pk = periodogram_peaks(q[sp.fit_validation], r[sp.fit_validation], p_min, p_max, 1)
        if pk:
            n_ratio = getattr(sig, "gear_ratio", None)  # label the wave-generator order
            order = f" (order {2 * np.pi / (pk[0][0] * n_ratio):.3g})" if n_ratio else ""
            ax.annotate(f"{pk[0][0]:.4g} rad{order}", (pk[0][0], pk[0][1]), fontsize=7,
                        color=col)
    ax.set_xlabel("period over q [rad]")
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_ylabel("normalised power")
    ax.set_title("spectrum of the residual over q (same in both directions)", fontsize=9)
    ax.legend(fontsize=8)
    ax = axs[1, 1]
    for r, lab, col in ((rb, "before", BEFORE), (ra, "after", AFTER)):
        rr = r[sp.fit_validation] * np.sign(v[sp.fit_validation])
        per, pw = _spectrum(q[sp.fit_validation], rr, p_min, p_max)
        ax.semilogx(per, pw, color=col, lw=0.8, label=f"{lab}, odd part")
    ax.set_xlabel("period over q [rad]")
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_title("spectrum of residual · sgn(q̇) over q (flips with direction)", fontsize=9)
    ax.legend(fontsize=8)
    fig.suptitle(title, fontsize=10)
    return fig


def _fig_hysteresis(d: _FigureData) -> Any:
    """Residual near reversals (hysteresis) and against q̈."""
    from matplotlib.figure import Figure

    v, a, idx, rb, ra, u, sc, acc_dec, title = (
        d.v, d.a, d.idx, d.rb, d.ra, d.u, d.sc, d.acc_dec, d.title)
    fig = Figure(figsize=(11, 4.2), layout="constrained")
    axs = fig.subplots(1, 3)
    vlim = 0.1 * sc.v_ref
    near = idx[np.abs(v[idx]) < vlim]
    for ax, r, lab in ((axs[0], rb, "before"), (axs[1], ra, "after")):
        for s_, col, name in ((1, "tab:red", "accelerating"), (-1, "tab:blue", "decelerating")):
            m = near[acc_dec[near] == s_]
            ax.scatter(v[m], r[m], s=2, color=col, alpha=0.5, label=name, rasterized=True)
            if m.size > 20:
                cx, cy = _bin_means(v[m], r[m], 20)
                ax.plot(cx, cy, color=col, lw=1.5)
        ax.set_xlabel("q̇ [rad/s] (|q̇| < 10 % of max)")
        ax.set_title(f"residual {lab} near reversals", fontsize=9)
        ax.legend(fontsize=8, markerscale=4)
    axs[0].set_ylabel(f"residual [{u}]")
    ax = axs[2]
    for r, lab, col in ((rb, "before", BEFORE), (ra, "after", AFTER)):
        cx, cy = _bin_means(a[idx], r[idx], 30)
        ax.plot(cx, cy, color=col, lw=1.5, label=lab)
    ax.axhline(0, color="0.5", lw=0.5)
    ax.set_xlabel("q̈ [rad/s²]")
    ax.set_ylabel(f"bin mean of residual [{u}]")
    ax.set_title("residual against acceleration", fontsize=9)
    ax.legend(fontsize=8)
    fig.suptitle(title, fontsize=10)
    return fig


def _fig_time(d: _FigureData) -> Any:
    """Residual over time with the held-out blocks; its spectrum in time."""
    from matplotlib.figure import Figure

    t, rb, ra, u, sp, sc, roles, title = (d.t, d.rb, d.ra, d.u, d.sp, d.sc, d.roles, d.title)
    fig = Figure(figsize=(11, 6.5), layout="constrained")
    axs = fig.subplots(2, 1)
    ax = axs[0]
    for role, col in (("validation", "tab:orange"), ("test", "tab:green")):
        for i, (lo, hi) in enumerate(roles.get(role, [])):
            ax.axvspan(lo, hi, color=col, alpha=0.12, label=role if i == 0 else None)
    every = _thin(np.arange(t.size), 30000)
    ax.plot(t[every], rb[every], color=BEFORE, lw=0.4, label="before")
    ax.plot(t[every], ra[every], color=AFTER, lw=0.4, label="after")
    ax.set_xlabel("t [s]")
    ax.set_ylabel(f"residual [{u}]")
    ax.legend(fontsize=8, ncol=4)
    ax.set_title("residual over time (shaded: held-out blocks)", fontsize=9)
    ax = axs[1]
    for r, lab, col in ((rb, "before", BEFORE), (ra, "after", AFTER)):
        per, pw = _spectrum(t[sp.fit_validation], r[sp.fit_validation], 4 * sc.dt_med,
                            sc.t_span / 2)
        fq, pq = _log_smooth(1 / per, pw * np.mean(r[sp.fit_validation] ** 2))
        ax.loglog(fq, pq, color=col, lw=1.0, label=lab)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(f"power [({u})², log-binned]")
    ax.set_title("spectrum of the residual in time (share of the mean square per "
                 "frequency, log-binned)", fontsize=9)
    ax.legend(fontsize=8)
    fig.suptitle(title, fontsize=10)
    return fig


def _fig_overlay(d: _FigureData) -> Any:
    """Measured torque and both models on the held-out test blocks."""
    from matplotlib.figure import Figure

    t, y, sp, pred_b, pred_a, rb, ra, u, roles, p = (
        d.t, d.y, d.sp, d.pred_b, d.pred_a, d.rb, d.ra, d.u, d.roles, d.p)
    test_ranges = roles.get("test", [])
    fig = Figure(figsize=(11, 3.2 * max(len(test_ranges), 1)), layout="constrained")
    axs = np.atleast_1d(fig.subplots(max(len(test_ranges), 1), 1))
    for ax, (lo, hi) in zip(axs, test_ranges or [(t[0], t[-1])], strict=True):
        m = sp.test[(t[sp.test] >= lo) & (t[sp.test] <= hi)]
        ax.plot(t[m], y[m], color="0.3", lw=0.6, label="measured")
        ax.plot(t[m], pred_b[m], color=BEFORE, lw=1.0,
                label=f"paper law (RMS err {np.sqrt(np.mean(rb[m] ** 2)):.3g} {u})")
        ax.plot(t[m], pred_a[m], color=AFTER, lw=1.0,
                label=f"final model (RMS err {np.sqrt(np.mean(ra[m] ** 2)):.3g} {u})")
        ax.set_ylabel(f"τ [{u}]")
        ax.legend(fontsize=8, ncol=3, loc="upper right")
    axs[-1].set_xlabel("t [s]")
    fig.suptitle(f"{p.name}: held-out test blocks", fontsize=10)
    return fig


def make_figures(result: CalibrationResult, out_dir: str | Path, dpi: int = 110
                 ) -> dict[str, str]:
    """Write the diagnosis figures of a friction calibration.

    Parameters
    ----------
    result : CalibrationResult
        A friction calibration.
    out_dir : str or Path
        Directory; figures go to ``out_dir/figures/``.

    Returns
    -------
    dict of str to str
        Figure key to path relative to ``out_dir``.
    """
    out = Path(out_dir)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    d = _figure_data(result)
    files: dict[str, str] = {}
    for key, draw in (("velocity", _fig_velocity), ("position", _fig_position),
                      ("hysteresis", _fig_hysteresis), ("time", _fig_time),
                      ("overlay", _fig_overlay)):
        fig = draw(d)
        save_figure(fig, out / "figures" / f"{key}.png", dpi)
        files[key] = f"figures/{key}.png"
    log.info("figures written to %s", out / "figures")
    return files
