"""Disturbances of measured-looking data, paper eq. (10).

    s_i^d = s_i + a_0 + Σ_{j=1}^{4} a_j sin(2π n_in t / j + α_j),

an offset and sub-harmonics of the input speed n_in (orders 1, 1/2, 1/3, 1/4), with
amplitudes and phases drawn at random per window and per sensor signal. The paper gives
no ranges (docs/PHYSICS.md sec. 7): a_0 ~ U(−A_0, A_0), a_j ~ U(0, A_h), α_j ~ U(0, 2π), with
A_0 and A_h in mV/V (defaults 0.01 mV/V each, a few per cent of the signals' range,
which are 0.05-0.3 mV/V).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from swgsim.base.typed import check_range


@dataclass
class DisturbanceSpec:
    """Amplitude ranges of eq. (10).

    Attributes
    ----------
    offset_mvv : float
        A_0, half-range of the uniform offset a_0 [mV/V], >= 0.
    harmonic_mvv : float
        A_h, upper bound of the uniform sub-harmonic amplitudes a_1..a_4 [mV/V], >= 0.
    """

    offset_mvv: float = 0.01
    harmonic_mvv: float = 0.01

    def check(self, where: str = "disturbance") -> None:
        """Refuse an amplitude outside [0, 1] mV/V, naming ``<where>.<key>``.

        Raises
        ------
        ValueError
            ``<where>.offset_mvv must lie in [0, 1] mV/V, got ...``.
        """
        for key in ("offset_mvv", "harmonic_mvv"):
            check_range(getattr(self, key), 0.0, 1.0, f"{where}.{key}", "mV/V")


def disturb(signals: np.ndarray, time_s: np.ndarray, n_in_rpm: np.ndarray,
            spec: DisturbanceSpec, rng: np.random.Generator,
            phi_in: np.ndarray | None = None) -> np.ndarray:
    """Apply eq. (10) to a batch of windows.

    At a steady speed the sub-harmonics' phase is 2π n_in t / j; at a varying speed (a
    window of an operating profile) eq. (10)'s orders of the input rotation are taken in
    the input angle itself, φ_in(t) / j (equal at a steady speed up to the constant phase,
    which α_j draws anyway).

    Parameters
    ----------
    signals : ndarray, shape (n_windows, n_sensors, n_t)
        Clean signals [mV/V].
    time_s : ndarray, shape (n_t,)
        Time since window start [s].
    n_in_rpm : ndarray, shape (n_windows,)
        Input speed of each window [rpm].
    spec : DisturbanceSpec
    rng : numpy.random.Generator
    phi_in : ndarray, shape (n_windows, n_t), optional
        Input angle of each sample [rad]: the sub-harmonics in the angle domain; None: at
        the steady speed ``n_in_rpm`` (then bit-identical to before).

    Returns
    -------
    ndarray, same shape as ``signals``
    """
    return apply_disturbance(signals, time_s, n_in_rpm,
                             draw_disturbance(spec, rng, signals.shape[:2]), phi_in)


def draw_disturbance(spec: DisturbanceSpec, rng: np.random.Generator,
                     shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """eq. (10)'s random draws for ``shape`` = (n_windows, n_sensors) windows: the offsets
    a0 (n_w, n_s, 1), the sub-harmonics' amplitudes a_j and phases α_j (n_w, n_s, 4, 1),
    in this order from ``rng`` [mV/V, rad]."""
    n_w, n_s = shape
    a0 = rng.uniform(-spec.offset_mvv, spec.offset_mvv, size=(n_w, n_s, 1))
    aj = rng.uniform(0.0, spec.harmonic_mvv, size=(n_w, n_s, 4, 1))
    alpha = rng.uniform(0.0, 2 * np.pi, size=(n_w, n_s, 4, 1))
    return a0, aj, alpha


def apply_disturbance(signals: np.ndarray, time_s: np.ndarray, n_in_rpm: np.ndarray,
                      draws: tuple[np.ndarray, np.ndarray, np.ndarray],
                      phi_in: np.ndarray | None = None) -> np.ndarray:
    """eq. (10) with given draws (:func:`draw_disturbance`) on windows (n_w, n_s, n_t);
    arguments as :func:`disturb`.

    Compiled (:func:`_add_harmonics`): per window the four sub-harmonics' sines and
    cosines once, a sin(wt + α) = a cos α sin wt + a sin α cos wt summed over j in order
    for each sensor; the same numbers as the array form in tests/swgsim/test_life_profile.py.
    """
    a0, aj, alpha = draws
    f_in = np.asarray(n_in_rpm, float) / 60.0  # rev/s
    sig = np.ascontiguousarray(signals, dtype=float)
    n_w, n_s, _ = sig.shape
    out = np.empty_like(sig)
    use_phi = phi_in is not None
    phi = np.ascontiguousarray(phi_in, dtype=float) if use_phi else np.empty((1, 1))
    _add_harmonics(sig, np.ascontiguousarray(time_s, dtype=float),
                   np.ascontiguousarray(np.broadcast_to(f_in, (n_w,)), dtype=float),
                   np.ascontiguousarray(np.broadcast_to(a0, (n_w, n_s, 1)), dtype=float),
                   np.ascontiguousarray(np.broadcast_to(aj, (n_w, n_s, 4, 1)), dtype=float),
                   np.ascontiguousarray(np.broadcast_to(alpha, (n_w, n_s, 4, 1)), dtype=float),
                   phi, use_phi, out)
    return out


@numba.njit(cache=True)
def _add_harmonics(signals, time_s, f_in, a0, aj, alpha, phi_in, use_phi, out):
    """out = signals + a0 + Σ_j (a_j cos α_j sin w_j t + a_j sin α_j cos w_j t), window by
    window (w_j t = 2π f_in t / j, or φ_in / j along a measured angle)."""
    n_w, n_s, n_t = signals.shape
    sw, cw = np.empty((4, n_t)), np.empty((4, n_t))
    cs, sn = np.empty((n_s, 4)), np.empty((n_s, 4))
    for w in range(n_w):
        for j in range(4):
            c = 2 * np.pi * (f_in[w] / (j + 1.0))
            for t in range(n_t):
                x = phi_in[w, t] / (j + 1.0) if use_phi else c * time_s[t]
                sw[j, t], cw[j, t] = np.sin(x), np.cos(x)
        for s in range(n_s):
            for j in range(4):
                cs[s, j] = aj[w, s, j, 0] * np.cos(alpha[w, s, j, 0])
                sn[s, j] = aj[w, s, j, 0] * np.sin(alpha[w, s, j, 0])
        for s in range(n_s):
            for t in range(n_t):
                h1 = (cs[s, 0] * sw[0, t] + cs[s, 1] * sw[1, t] + cs[s, 2] * sw[2, t]
                      + cs[s, 3] * sw[3, t])
                h2 = (sn[s, 0] * cw[0, t] + sn[s, 1] * cw[1, t] + sn[s, 2] * cw[2, t]
                      + sn[s, 3] * cw[3, t])
                out[w, s, t] = (signals[w, s, t] + a0[w, s, 0]) + (h1 + h2)
