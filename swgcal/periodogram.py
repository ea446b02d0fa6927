"""Strongest periods of a residual over an irregular coordinate (joint angle or time).

Used by the diagnosis probes (:mod:`swgcal.diagnose`), the ripple starts of the friction
library (:mod:`swgcal.friction.library`), discovery and figures; the simulator does not
need it.
"""

from __future__ import annotations

import numpy as np

__all__ = ["periodogram_peaks"]


def periodogram_peaks(x: np.ndarray, r: np.ndarray, p_min: float, p_max: float,
                      n_peaks: int = 3, oversample: float = 5.0) -> list[tuple[float, float]]:
    """Strongest periods of ``r`` over the irregular coordinate ``x``.

    Fast Schuster periodogram: ``r`` is accumulated onto a uniform grid of spacing
    p_min / 8 (nearest-cell extirpolation, the idea of Press & Rybicki 1989, order 0)
    and Fourier transformed with ``oversample``-fold zero padding. The power is
    normalised so that a pure sinusoid sampled evenly gives 1 (≈ the fraction of the
    variance a sinusoid at that period explains). Local maxima, strongest first.

    Parameters
    ----------
    x, r : ndarray, shape (n,)
        Coordinate (q [rad] or t [s]) and signal.
    p_min, p_max : float
        Period range [units of x], 0 < p_min < p_max.

    Returns
    -------
    list of (period, normalised power)
        Period [units of x], power [-].
    """
    x = np.asarray(x, float)
    r = np.asarray(r, float)
    span = float(np.ptp(x)) if x.size else 0.0
    if span <= 0 or not 0 < p_min < p_max or not np.any(r):
        return []
    rc = r - r.mean()
    h = p_min / 8.0
    cells = np.floor((x - x.min()) / h).astype(np.int64)
    m = int(cells.max()) + 1
    s = np.bincount(cells, weights=rc, minlength=m)
    nfft = 1 << int(np.ceil(np.log2(max(oversample * m, 16))))
    f = np.arange(nfft // 2 + 1) / (nfft * h)
    pw = np.abs(np.fft.rfft(s, nfft)) ** 2 * 2.0 / (x.size * float(np.sum(rc * rc)))
    band = (f >= 1.0 / p_max) & (f <= 1.0 / p_min)
    pb = np.where(band, pw, 0.0)
    loc = np.flatnonzero((pb[1:-1] > pb[:-2]) & (pb[1:-1] >= pb[2:])) + 1
    loc = loc[np.argsort(pb[loc])[::-1]][:n_peaks]
    return [(float(1.0 / f[i]), float(pb[i])) for i in loc if pb[i] > 0]
