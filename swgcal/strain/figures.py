"""Figures of a strain calibration: residual order spectrum, offsets along the sequence,
channel differences, order-2 amplitude and phase with speed and load, overlay of a test
window (base model and final model)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from swgsim.files.ownership import save_figure

from ..loop import CalibrationResult
from .report import order2_components
from .signals import SENSORS, StrainSignals

__all__ = ["make_figures"]


def make_figures(result: CalibrationResult, out_dir: str | Path,
                 fmt: str = "png") -> dict[str, str]:
    """Diagnosis figures of a strain calibration.

    Parameters
    ----------
    out_dir : path-like
        Report folder; figures go to ``out_dir/figures/`` (created).

    Returns
    -------
    dict of str to str
        Figure key -> path relative to ``out_dir``, for the report.
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    out = Path(out_dir) / "figures"
    out.mkdir(parents=True, exist_ok=True)
    v = _Views.of(result, plt.rcParams["axes.prop_cycle"].by_key()["color"])
    figs: dict[str, str] = {}
    for key, draw in (("order_spectrum", _order_spectrum), ("offsets", _offsets),
                      ("channel_differences", _channel_differences),
                      ("speed_load", _speed_load), ("overlay", _overlay)):
        fig = draw(plt, v)
        name = f"{key}.{fmt}"
        save_figure(fig, out / name, 110, bbox_inches="tight")
        figs[key] = f"{out.name}/{name}"
    return figs


@dataclass(frozen=True)
class _Views:
    """What the figures show: measured windows, predictions and residuals (base model and
    final), each (n_windows, 5, n_t), the role of each window (0 fit, 1 validation,
    2 test) and the test window shown."""

    sig: StrainSignals
    y: np.ndarray
    pb: np.ndarray
    pa: np.ndarray
    role: np.ndarray
    test_w: int
    colors: list[str]

    @classmethod
    def of(cls, result: CalibrationResult, colors: list[str]) -> _Views:
        sig: StrainSignals = result.problem.signals
        n_w, n_t = sig.n_windows, sig.n_t
        y = result.problem.y.reshape(n_w, 5, n_t)
        pb, pa = (x.reshape(n_w, 5, n_t) for x in result.predictions())
        sp = result.problem.split
        role = np.zeros(n_w, int)
        role[np.unique(sig.window[sp.validation])] = 1
        role[np.unique(sig.window[sp.test])] = 2
        test_w = int(np.flatnonzero(role == 2)[0]) if (role == 2).any() else 0
        return cls(sig, y, pb, pa, role, test_w, colors)

    @property
    def rb(self) -> np.ndarray:
        return self.y - self.pb

    @property
    def ra(self) -> np.ndarray:
        return self.y - self.pa

    @property
    def t_ms(self) -> np.ndarray:
        return np.arange(self.sig.n_t) / self.sig.fs * 1e3


def _order_spectrum(plt: Any, v: _Views) -> Any:
    """Residual amplitude spectrum against the order of the input rotation."""
    sig, colors = v.sig, v.colors
    n_w, n_t = sig.n_windows, sig.n_t
    rb, ra = v.rb, v.ra
    fig, axes = plt.subplots(5, 1, figsize=(8, 9), sharex=True)
    win = np.hanning(n_t)
    freqs = np.fft.rfftfreq(n_t, 1 / sig.fs)
    f_in = sig.n_in_rpm / 60.0
    grid = np.arange(0, 30.01, 0.05)
    for c in range(5):
        for r, col, lab in ((rb, "0.6", "base_model"), (ra, colors[c % len(colors)], "final")):
            spec = np.abs(np.fft.rfft(r[:, c] * win, axis=-1)) * 2 / win.sum()  # (n_w, n_f)
            amp = np.mean([np.interp(grid, freqs / f_in[w], spec[w]) for w in range(n_w)],
                          axis=0)
            axes[c].plot(grid, amp, color=col, lw=1, label=lab)
        axes[c].set_ylabel(f"{SENSORS[c]} [mV/V]")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("order relative to the input rotation")
    fig.suptitle("Residual amplitude spectrum (Hann), mean over windows")
    return fig


def _offsets(plt: Any, v: _Views) -> Any:
    """Mean residual per window and channel along the sequence (offsets, drift)."""
    sig, colors, role = v.sig, v.colors, v.role
    t_start = sig.t_seq_s.reshape(sig.n_windows, 5, sig.n_t)[:, 0, 0]
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6), sharey=True)
    for ax, r, title in ((axes[0], v.rb, "base model residual"),
                         (axes[1], v.ra, "final residual")):
        mean = r.mean(-1)
        for c in range(5):
            ax.plot(t_start, mean[:, c], "o-", ms=4, lw=0.8, color=colors[c % len(colors)],
                    label=SENSORS[c])
        for w in np.flatnonzero(role > 0):
            ax.axvline(t_start[w], color="r" if role[w] == 2 else "orange", lw=0.6, alpha=0.5)
        ax.set_title(title)
        ax.set_xlabel("time since the first window [s] (red: test, orange: validation)")
    axes[0].set_ylabel("mean residual [mV/V]")
    axes[1].legend(fontsize=8)
    return fig


def _channel_differences(plt: Any, v: _Views) -> Any:
    """s1−s3 and s2−s4 of the test window: measured, models, residuals."""
    y, pb, pa, rb, ra, w = v.y, v.pb, v.pa, v.rb, v.ra, v.test_w
    t_ms, col = v.t_ms, v.colors[0]
    fig, axes = plt.subplots(2, 2, figsize=(10, 5.5), sharex=True)
    for j, (a, b) in enumerate(((1, 3), (2, 4))):
        lab = f"s{a}−s{b}"
        axes[0, j].plot(t_ms, y[w, a] - y[w, b], color="k", lw=0.8, label="measured")
        axes[0, j].plot(t_ms, pb[w, a] - pb[w, b], color="0.6", lw=1, label="base_model")
        axes[0, j].plot(t_ms, pa[w, a] - pa[w, b], color=col, lw=1, label="final")
        axes[0, j].set_title(lab)
        axes[1, j].plot(t_ms, rb[w, a] - rb[w, b], color="0.6", lw=0.8)
        axes[1, j].plot(t_ms, ra[w, a] - ra[w, b], color=col, lw=0.8)
        axes[1, j].set_xlabel("time in the window [ms]")
    axes[0, 0].set_ylabel("[mV/V]")
    axes[1, 0].set_ylabel("residual [mV/V]")
    axes[0, 0].legend(fontsize=8)
    return fig


def _speed_load(plt: Any, v: _Views) -> Any:
    """Order-2 amplitude and phase per window against speed and load."""
    sig, n_w = v.sig, v.sig.n_windows
    m, b, a = (order2_components(sig, x.reshape(-1)) for x in (v.y, v.pb, v.pa))
    fig, axes = plt.subplots(2, 5, figsize=(13, 5))
    x_op = np.array([f"{sig.n_in_rpm[w]:.0f}/{sig.t_out_nm[w]:.0f}" for w in range(n_w)])
    order = np.lexsort((sig.t_out_nm, sig.n_in_rpm))
    for c in range(5):
        for z, mk, lab in ((m, "o", "measured"), (b, "x", "base_model"), (a, "+", "final")):
            axes[0, c].plot(x_op[order], z[order, c, 0], mk, label=lab, ms=6)
            axes[1, c].plot(x_op[order], z[order, c, 1], mk, ms=6)
        axes[0, c].set_title(SENSORS[c])
        axes[1, c].set_xlabel("n_in [rpm] / T_out [N m]")
        for ax in axes[:, c]:
            ax.tick_params(axis="x", labelrotation=60, labelsize=7)
    axes[0, 0].set_ylabel("order-2 amplitude [mV/V]")
    axes[1, 0].set_ylabel("order-2 phase [deg]")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return fig


def _overlay(plt: Any, v: _Views) -> Any:
    """Measured signals of the test window with the base model and final predictions."""
    t_ms, w = v.t_ms, v.test_w
    fig, axes = plt.subplots(5, 1, figsize=(8, 9), sharex=True)
    for c in range(5):
        axes[c].plot(t_ms, v.y[w, c], color="k", lw=0.7, label="measured")
        axes[c].plot(t_ms, v.pb[w, c], color="0.6", lw=1, label="base_model")
        axes[c].plot(t_ms, v.pa[w, c], color=v.colors[0], lw=1, label="final")
        axes[c].set_ylabel(f"{SENSORS[c]} [mV/V]")
    axes[0].legend(fontsize=8, loc="upper right")
    axes[-1].set_xlabel("time in the window [ms]")
    return fig
