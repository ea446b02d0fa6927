"""Residual probes of the strain side of the calibration, one per residual signature.

Per-channel and per-window means, a trend along the sequence of windows, bins over the
WG angle ψ, and the best tone in orders of the input rotation or in frequency
(:func:`strain_probes`); scored out of sample by :mod:`swgcal.diagnose`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..diagnose import Probe
from .signals import SENSORS, StrainSignals

__all__ = ["GroupMeanProbe", "SequenceTrendProbe", "ToneProbe", "strain_probes"]


class GroupMeanProbe(Probe):
    """Residual mean per group label (fitted on one half, predicting the other)."""

    def __init__(self, name: str, label: str, key: Callable[[StrainSignals], np.ndarray],
                 describe_detail: Callable[[StrainSignals, np.ndarray, np.ndarray], dict]
                 | None = None) -> None:
        self.name, self.label, self.key, self._detail = name, label, key, describe_detail

    def fit_predict(self, sig, r, ia, ib):
        g = self.key(sig)
        n_g = int(g.max()) + 1
        cnt = np.bincount(g[ia], minlength=n_g)
        s = np.bincount(g[ia], weights=r[ia], minlength=n_g)
        mean = np.where(cnt > 0, s / np.maximum(cnt, 1), 0.0)
        detail = self._detail(sig, mean, cnt) if self._detail else {}
        return mean[g[ib]], detail

    def describe(self, detail, units):
        txt = self.label
        if "text" in detail:
            txt += " " + detail["text"].replace("{units}", units)
        return txt


def _channel_detail(sig, mean, cnt):
    parts = ", ".join(f"{s} {m:+.3g}" for s, m in zip(SENSORS, mean, strict=True))
    return {"means": [float(m) for m in mean], "text": f"(means {parts} {{units}})"}


def _psi_bins(n_bins: int) -> Callable[[StrainSignals], np.ndarray]:
    def key(sig):
        b = np.floor(np.mod(sig.psi_rad, 2 * np.pi) / (2 * np.pi) * n_bins).astype(int)
        return (sig.op * 5 + sig.channel) * n_bins + np.clip(b, 0, n_bins - 1)
    return key


def _pattern_detail(n_bins: int):
    def detail(sig, mean, cnt):
        centres = (np.arange(n_bins) + 0.5) * 2 * np.pi / n_bins
        m = mean.reshape(-1, 5, n_bins)  # (op, channel, bin)
        c2 = (m * np.cos(2 * centres)).sum(-1) * 2 / n_bins
        s2 = (m * np.sin(2 * centres)).sum(-1) * 2 / n_bins
        amp = np.hypot(c2, s2)  # (op, channel)
        o, c = np.unravel_index(int(np.argmax(amp)), amp.shape)
        pp = np.ptp(m, axis=-1)
        op = sig.ops[o] if o < len(sig.ops) else (float("nan"), float("nan"))
        return {"order2_amplitude": amp.tolist(), "peak_to_peak": pp.tolist(),
                "text": (f"(largest order-2 component {amp[o, c]:.3g} {{units}} on "
                         f"{SENSORS[c]} at {op[0]:g} rpm, {op[1]:g} N m; order-2 amplitude "
                         "per operating point and channel: "
                         + "; ".join(f"{sig.ops[i][0]:g} rpm/{sig.ops[i][1]:g} N m: "
                                     + ", ".join(f"{a:.2g}" for a in amp[i])
                                     for i in range(min(amp.shape[0], len(sig.ops))))
                         + ")")}
    return detail


class SequenceTrendProbe(Probe):
    """Per-channel linear trend of the residual over the sequence time (offsets removed)."""

    name = "sequence_drift"
    label = "drifts along the sequence of windows"

    def fit_predict(self, sig, r, ia, ib):
        slopes = np.zeros(5)
        pred = np.zeros(ib.size)
        for c in range(5):
            a = ia[sig.channel[ia] == c]
            b = sig.channel[ib] == c
            if a.size < 3 or np.ptp(sig.t_seq_s[a]) == 0:
                continue
            ta = sig.t_seq_s[a]
            tm = ta.mean()
            slopes[c] = float(np.sum((ta - tm) * (r[a] - r[a].mean())) / np.sum((ta - tm) ** 2))
            pred[b] = slopes[c] * (sig.t_seq_s[ib[b]] - tm)
        return pred, {"slopes": slopes.tolist()}

    def describe(self, detail, units):
        if "slopes" not in detail:
            return self.label
        slopes = ", ".join(f"{s} {v:+.3g}"
                           for s, v in zip(SENSORS, detail["slopes"], strict=True))
        return f"{self.label} (slopes {slopes} {units}/s)"


class ToneProbe(Probe):
    """Best sinusoid on a grid of orders (of the input rotation) or frequencies, with
    its own amplitude and phase per window and channel: the residual's line spectrum.

    Per-window phases keep tones whose phase the aligned model cannot know (half orders,
    interference at a fixed frequency) predictable from one set of time slices of a
    window to the other; the grid value is common to all windows.

    Parameters
    ----------
    coord : callable sig -> ndarray (n,)
        Phase coordinate per sample: φ_in [rad] for orders, 2π t [rad·Hz⁻¹] for
        frequencies.
    grid : ndarray
        Uniform grid of orders [-] or frequencies [Hz].
    unit : str
        "order" or "Hz" (text).
    """

    def __init__(self, name: str, label: str, coord: Callable[[StrainSignals], np.ndarray],
                 grid: np.ndarray, unit: str) -> None:
        self.name, self.label, self.coord, self.unit = name, label, coord, unit
        self.grid = np.asarray(grid, float)
        if self.grid.size > 1 and not np.allclose(np.diff(self.grid), self.grid[1] - self.grid[0]):
            raise ValueError("the grid must be uniform")

    @staticmethod
    def _groups(sig: StrainSignals, idx: np.ndarray) -> tuple[np.ndarray, int]:
        return sig.window[idx] * 5 + sig.channel[idx], sig.n_windows * 5

    def spectrum(self, sig: StrainSignals, r: np.ndarray, idx: np.ndarray) -> np.ndarray:
        """Power per grid value, summed over windows and channels, shape (n_grid,)
        [(data units)²]: per group ``4 |mean r e^{−i k x}|²`` (x the phase coordinate).

        ``idx`` must be sorted (groups are then contiguous runs); e^{−i k x} on the
        uniform grid by recurrence e^{−i (k + Δ) x} = e^{−i k x} e^{−i Δ x}."""
        idx = np.sort(np.asarray(idx))
        g, n_g = self._groups(sig, idx)
        starts = np.flatnonzero(np.r_[True, g[1:] != g[:-1]])
        cnt = np.diff(np.r_[starts, g.size])
        x = self.coord(sig)[idx]
        rr = np.asarray(r, float)[idx]
        ks = self.grid
        e = np.exp(-1j * ks[0] * x) * rr
        step = np.exp(-1j * (ks[1] - ks[0]) * x) if ks.size > 1 else None
        p = np.empty(ks.size)
        for i in range(ks.size):
            sums = np.add.reduceat(e, starts)
            p[i] = 4.0 * np.sum(np.abs(sums / cnt) ** 2)
            if step is not None:
                e = e * step
        return p

    def _fit(self, sig, r, idx, k):
        """Per-group least squares on [cos k x, sin k x]: coefficients (n_g, 2)."""
        g, n_g = self._groups(sig, idx)
        ph = k * self.coord(sig)[idx]
        c, s_ = np.cos(ph), np.sin(ph)
        ri = np.asarray(r, float)[idx]

        def bc(w):
            return np.bincount(g, weights=w, minlength=n_g)

        cc, ss, cs, cr, sr = bc(c * c), bc(s_ * s_), bc(c * s_), bc(c * ri), bc(s_ * ri)
        det = cc * ss - cs * cs
        ok = det > 1e-9 * np.maximum(cc * ss, 1e-300)
        a = np.where(ok, (ss * cr - cs * sr) / np.where(ok, det, 1.0), 0.0)
        b = np.where(ok, (cc * sr - cs * cr) / np.where(ok, det, 1.0), 0.0)
        return np.column_stack([a, b])

    def fit_predict(self, sig, r, ia, ib):
        p = self.spectrum(sig, r, ia)
        k = float(self.grid[int(np.argmax(p))])
        coef = self._fit(sig, r, ia, k)
        gb, _ = self._groups(sig, ib)
        ph = k * self.coord(sig)[ib]
        pred = coef[gb, 0] * np.cos(ph) + coef[gb, 1] * np.sin(ph)
        amp = np.hypot(coef[:, 0], coef[:, 1]).reshape(-1, 5)  # (n_w, 5)
        return pred, {"value": k, "unit": self.unit,
                      "amplitude_rms": np.sqrt((amp ** 2).mean(axis=0)).tolist()}

    def describe(self, detail, units):
        if "value" not in detail:
            return self.label
        at = (f"order {detail['value']:.2f} of the input rotation" if self.unit == "order"
              else f"{detail['value']:.4g} Hz")
        return (f"{self.label} at {at} (amplitude per channel, RMS over windows: "
                + ", ".join(f"{s} {v:.2g}" for s, v in zip(SENSORS, detail["amplitude_rms"],
                                                            strict=True))
                + f" {units})")


def strain_probes(psi_bins: int = 36, max_order: float = 20.0, d_order: float = 0.05,
                  f_range_hz: tuple[float, float] = (20.0, 2000.0), d_f_hz: float = 5.0
                  ) -> list[Probe]:
    """Residual probes of the strain side, one per residual signature.

    The diagnosis halves are interleaved time slices of every window (``Problem.t`` is
    the time within the window), so per-window models predict across them.

    Returns
    -------
    list of Probe
        channel_offset (mean per channel), window_offset (mean per window and channel:
        offsets that jump between windows), sequence_drift (per-channel trend over the
        sequence time), wg_pattern (bins over the WG angle ψ per operating point and
        channel: gain, misplacement, nonlinearity, low-pass), input_order (best order of
        the input rotation, per window and channel: order spectrum), time_tone (best
        frequency, per window and channel: interference, glitch trains).
    """
    return [
        GroupMeanProbe("channel_offset", "constant offset per channel", lambda s: s.channel,
                       _channel_detail),
        GroupMeanProbe("window_offset", "offset per window and channel",
                       lambda s: s.window * 5 + s.channel),
        SequenceTrendProbe(),
        GroupMeanProbe("wg_pattern", "periodic in the WG angle ψ, per channel and operating "
                       "point", _psi_bins(psi_bins), _pattern_detail(psi_bins)),
        ToneProbe("input_order", "a tone locked to the input rotation",
                  lambda s: s.phi_in_rad, np.arange(0.25, max_order + 1e-9, d_order), "order"),
        ToneProbe("time_tone", "a tone at a fixed frequency", lambda s: 2 * np.pi * s.t_s,
                  np.arange(f_range_hz[0], f_range_hz[1] + 1e-9, d_f_hz), "Hz"),
    ]
