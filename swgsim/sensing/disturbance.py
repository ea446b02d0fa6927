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
    arguments as :func:`disturb`."""
    a0, aj, alpha = draws
    f_in = np.asarray(n_in_rpm, float) / 60.0  # rev/s
    j = np.arange(1, 5)
    # (n_w, 4, n_t)
    if phi_in is None:
        wt = 2 * np.pi * (f_in[:, None] / j[None, :])[:, :, None] * time_s[None, None, :]
    else:
        wt = np.asarray(phi_in, float)[:, None, :] / j[None, :, None]
    # a sin(wt + alpha) = a cos(alpha) sin(wt) + a sin(alpha) cos(wt)
    cs = (aj * np.cos(alpha))[..., 0]  # (n_w, n_s, 4)
    sn = (aj * np.sin(alpha))[..., 0]
    harm = np.einsum("wsj,wjt->wst", cs, np.sin(wt)) + np.einsum("wsj,wjt->wst", sn, np.cos(wt))
    return signals + a0 + harm
