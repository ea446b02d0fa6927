"""Signal-processing primitives of the measurement chain: fractional delays by cubic
B-splines, spline evaluation at arbitrary positions, a first-order Tustin low-pass.

Used by the sensor effects (:mod:`swgsim.sensing.effects`) and by the calibration's effect
models (:mod:`swgcal.strain.effects`).
"""

from __future__ import annotations

import numpy as np

from swgsim.base.lazy import lazy_module

ndimage = lazy_module("scipy.ndimage")
signal = lazy_module("scipy.signal")


def _mirror(j: np.ndarray, n: int) -> np.ndarray:
    """Indices reflected about the first and last sample (ndimage's ``mirror`` mode)."""
    if n == 1:
        return np.zeros_like(j)
    period = 2 * (n - 1)
    j = np.mod(np.abs(j), period)
    return np.where(j > n - 1, period - j, j)


def fractional_delay(x: np.ndarray, delay_samples: np.ndarray) -> np.ndarray:
    """Delay rows of ``x`` by a fractional number of samples, y[k] = x(k − d).

    Cubic B-spline interpolation along the last axis only (interpolating at the samples,
    so a zero delay returns ``x`` exactly; Unser, IEEE Signal Proc. Mag. 16(6), 1999);
    samples beyond the ends are mirrored.

    Parameters
    ----------
    x : ndarray, shape (..., n)
    delay_samples : ndarray, broadcastable to x.shape[:-1]
        Delay of each row [samples] (negative: advance).

    Returns
    -------
    ndarray, shape of ``x``
    """
    x = np.asarray(x, float)
    d = np.broadcast_to(np.asarray(delay_samples, float), x.shape[:-1])
    if not np.any(d):
        return x.copy()
    n = x.shape[-1]
    rows = x.reshape(-1, n)
    pos = np.arange(n)[None, :] - d.reshape(-1)[:, None]  # (rows, n)
    return spline_at(rows, pos).reshape(x.shape)


def spline_at(rows: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """Cubic B-spline interpolant of each row of ``rows`` at fractional sample positions.

    The interpolation of :func:`fractional_delay` (which calls it with pos = k − d) at any
    positions: exact at integer positions, samples beyond the ends mirrored.

    Parameters
    ----------
    rows : ndarray, shape (m, n)
        Uniformly sampled signals.
    pos : ndarray, shape (m, n_out)
        Positions [samples] at which to evaluate row i, 0 the first sample.

    Returns
    -------
    ndarray, shape (m, n_out)
    """
    n = rows.shape[-1]
    coef = ndimage.spline_filter1d(rows, order=3, axis=-1, mode="mirror")
    i = np.floor(pos).astype(np.int64)
    f = pos - i
    g = 1.0 - f
    weights = (g ** 3 / 6.0, 2.0 / 3.0 - f ** 2 + 0.5 * f ** 3,
               2.0 / 3.0 - g ** 2 + 0.5 * g ** 3, f ** 3 / 6.0)  # B-spline at i-1 .. i+2
    out = np.zeros_like(pos)
    for m, w in zip((-1, 0, 1, 2), weights, strict=True):
        out += np.take_along_axis(coef, _mirror(i + m, n), axis=1) * w
    return out


def lowpass_coefficients(f_c_hz: float, fs_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """(b, a) of a first-order low-pass, bilinear transform pre-warped at f_c.

    H(s) = 1 / (1 + s / ω_c) with s → (2 fs) (z − 1) / (z + 1) and ω_c pre-warped, so the
    discrete response equals the analog one at f_c (−3 dB, −45°).

    Raises
    ------
    ValueError
        f_c not in (0, fs / 2).
    """
    if not 0.0 < f_c_hz < 0.5 * fs_hz:
        raise ValueError(f"f_c_hz must lie in (0, {0.5 * fs_hz:g}) Hz (Nyquist of the "
                         f"{fs_hz:g} Hz sampling), got {f_c_hz}")
    k = np.tan(np.pi * f_c_hz / fs_hz)
    b = np.array([k, k]) / (1 + k)
    a = np.array([1.0, (k - 1) / (k + 1)])
    return b, a


def lowpass(x: np.ndarray, f_c_hz: float, fs_hz: float) -> np.ndarray:
    """First-order low-pass along the last axis, started in the steady state of x[..., 0].

    Parameters
    ----------
    x : ndarray, shape (..., n)
    f_c_hz : float
        Cut-off [Hz], in (0, fs / 2); ``inf`` returns x unchanged.
    fs_hz : float
        Sample rate [Hz].

    Returns
    -------
    ndarray, shape of ``x``
    """
    x = np.asarray(x, float)
    if np.isinf(f_c_hz):
        return x.copy()
    b, a = lowpass_coefficients(f_c_hz, fs_hz)
    zi = signal.lfilter_zi(b, a)[0] * x[..., :1]
    y, _ = signal.lfilter(b, a, x, axis=-1, zi=zi)
    return y


__all__ = ["fractional_delay", "lowpass", "lowpass_coefficients", "spline_at"]
