"""Model inputs built from a schema-v1 data set: raw signals, differenced signals, features.

The transfer study's learners (``learn.transfer.study``) take them from :func:`build_input`:
``raw``/``diff`` (the bridges normalised by the gear's healthy reference window; the
redundant gauges' differences, paper eq. 8), ``sel3``/``sel1`` (Table III) and
``raw_res``/``diff_res``/``res_spec``, the synchronous residual against the reference
rotated to the window's phase (:func:`harmonic_coefficients`, :func:`reference_residual`).
Design (the normalisation's form and why, the residual, the auxiliary scalars, shapes):
docs/learners_transfer.md, "Reference normalisation and the synchronous residual".
"""

from __future__ import annotations

import functools
import logging
from dataclasses import dataclass, field

import numba
import numpy as np

from learn.inputs.features import extract_features, meta_table, reference_index
from swgsim.base.lazy import lazy_module

pd = lazy_module("pandas")

log = logging.getLogger(__name__)

INPUTS = ("raw", "diff", "sel1", "sel3", "raw_res", "diff_res", "res_spec")
SIGNAL_INPUTS = ("raw", "diff", "raw_res", "diff_res")
RESIDUAL_INPUTS = ("raw_res", "diff_res", "res_spec")
#: Largest condition number of a window's angle-domain basis [-] [choice]: the
#: desired-speed basis of a 0.12 s window at 10 kHz (H = 12, orders 1/4, 1/3, 1/2) has
#: 1.1e4 at 1000 rpm, 4.2e5 at 750 rpm, 6.7e10 at 500 rpm (nuisance orders no longer
#: separable from the offset and ψ harmonics); an angle-domain basis above it is refused.
MAX_CONDITION = 1e6


@dataclass
class ResidualSettings:
    """Settings of the synchronous residual inputs
    (docs/learners_transfer.md, "Reference normalisation and the synchronous residual")."""

    ratio: float = 100.0        # gear ratio N: the WG turns at 1 + 1/N per input revolution
    n_harmonics: int = 48       # harmonics of the WG angle fitted per window
    nuisance_orders: list[float] = field(  # eq. (10) sub-harmonics, fitted and dropped
        default_factory=lambda: [0.25, 1 / 3, 0.5, 1.0])
    min_harmonic: int = 2       # synthesised from (0: offset; 1: order-1 disturbance out)
    n_points: int = 192         # samples of one WG revolution
    compress: float | None = 1e-4  # asinh(x / compress), 0 or None: none; residuals span 4 decades


AUX = ("eta2_rel", "eta_rel")
_META = ("gear", "fault", "variant", "severity", "n_in_rpm", "t_out_nm", "disturbed")


@dataclass(frozen=True)
class InputSet:
    """Model input for the non-reference windows of a data set.

    Attributes
    ----------
    X : ndarray, float32
        (n, C, T) for signal inputs (the last ``n_aux`` channels constant along time) or
        (n, F) for feature inputs.
    y : ndarray of str, shape (n,)
        Fault class of each window.
    meta : pandas.DataFrame, n rows
        gear, fault, variant, severity, n_in_rpm, t_out_nm, disturbed and ``sample`` (the
        window's index in the data set).
    n_aux : int
        Number of trailing auxiliary channels of a signal input (0 for features).
    kind : str
        One of :data:`INPUTS`.
    """

    X: np.ndarray
    y: np.ndarray
    meta: pd.DataFrame
    n_aux: int
    kind: str


def window_meta(ds, disturbed: bool | None = None) -> tuple[pd.DataFrame, np.ndarray]:
    """Metadata of the non-reference windows of ``ds`` and their reference windows.

    Parameters
    ----------
    ds : xarray.Dataset
        Schema v1 with one reference window per gear, operating point and disturbed flag.
    disturbed : bool, optional
        Keep only the clean (False) or disturbed (True) windows; default all.

    Returns
    -------
    meta : pandas.DataFrame
        One row per window, in data-set order: ``sample`` and gear, fault, variant,
        severity, n_in_rpm, t_out_nm, disturbed.
    refs : ndarray of int, shape (n,)
        Sample index of each window's reference window.

    Raises
    ------
    ValueError
        From :func:`learn.inputs.features.reference_index` (no or ambiguous reference window).
    """
    samples, refs = reference_index(ds)
    if disturbed is not None:
        keep = ds["disturbed"].values[samples].astype(bool) == bool(disturbed)
        samples, refs = samples[keep], refs[keep]
    return meta_table(ds, samples, _META), refs


def normalise_signals(ds, samples: np.ndarray, refs: np.ndarray) -> np.ndarray:
    """Reference-normalised bridge outputs.

    Parameters
    ----------
    ds : xarray.Dataset
        Schema v1.
    samples, refs : ndarray of int, shape (n,)
        Windows to normalise and the reference window of each (:func:`window_meta`).

    Returns
    -------
    ndarray, float32, shape (n, 5, T)
        (s - m_ref) / r_ref per channel, dimensionless
        (docs/learners_transfer.md, "Reference normalisation and the synchronous residual").
    """
    sig = ds["strain_signal"].values  # (N, 5, T) [mV/V]
    uref, inv = np.unique(refs, return_inverse=True)
    rs = np.asarray(sig[uref], dtype=np.float64)  # (R, 5, T)
    m = rs.mean(axis=2)  # (R, 5)
    rms = np.sqrt(((rs - m[:, :, None]) ** 2).mean(axis=2))  # (R, 5)
    rms = np.where(rms > 1e-12, rms, 1.0)
    x = np.asarray(sig[samples], dtype=np.float32)  # (n, 5, T)
    x -= m[inv][:, :, None].astype(np.float32)
    x /= rms[inv][:, :, None].astype(np.float32)
    return x


def efficiency_features(ds, samples: np.ndarray, refs: np.ndarray) -> np.ndarray:
    """η2_rel (paper eq. 9) and η_rel - 1 (eq. 7) of the windows ``samples``.

    Returns
    -------
    ndarray, float64, shape (n, 2)
        Columns: ``|1 - η/η_ref|^(1/4)``, ``η/η_ref - 1`` [-].
    """
    eta = np.asarray(ds["efficiency"].values, dtype=np.float64)
    rel = eta[samples] / eta[refs]
    return np.stack([np.abs(1.0 - rel) ** 0.25, rel - 1.0], axis=1)


def pinv(basis: np.ndarray) -> np.ndarray:
    """Pseudo-inverse of a least-squares basis (T, P) -> (P, T).

    :func:`numpy.linalg.pinv`, except where LAPACK's divide-and-conquer SVD (``gesdd``;
    OpenBLAS 0.3.30) reports no convergence although the basis is well conditioned (found
    for a Fourier basis at f0 = 66.66625 Hz, 10 kHz, 1200 samples, 48 ψ-harmonics and eq.
    (10)'s orders: condition number 15): there the QR-iteration SVD (``gesvd``) takes
    over, with NumPy's cut-off of small singular values (1e-15 of the largest)."""
    try:
        return np.linalg.pinv(basis)
    except np.linalg.LinAlgError:
        import scipy.linalg

        u, s, vt = scipy.linalg.svd(basis, full_matrices=False, lapack_driver="gesvd")
        keep = s > 1e-15 * s.max()
        return (vt[keep].T / s[keep]) @ u[:, keep].T


@functools.lru_cache(maxsize=32)
def _basis_pinv(f0_hz: float, t0_s: float, dt_s: float, n_t: int,
                orders: tuple[float, ...]) -> np.ndarray:
    """Pseudo-inverse (:func:`pinv`) of the Fourier basis [1, cos, sin](2π o f0 t), shape
    (P, T), cached: a stream of windows at one speed reuses it."""
    time_s = t0_s + dt_s * np.arange(n_t)
    ang = 2 * np.pi * f0_hz * time_s[:, None] * np.asarray(orders)[None, :]  # (T, K)
    basis = np.concatenate([np.ones((n_t, 1)), np.cos(ang), np.sin(ang)], axis=1)
    out = pinv(basis)
    out.setflags(write=False)
    return out


def harmonic_coefficients(x: np.ndarray, time_s: np.ndarray, f_in_hz: np.ndarray,
                          psi_order: float, n_harmonics: int,
                          nuisance_orders=(0.25, 1 / 3, 0.5, 1.0),
                          psi: np.ndarray | None = None) -> np.ndarray:
    """Least-squares Fourier series in the WG angle ψ of each window.

    Model: x(t) = c0 + sum_h Re(c_h e^{i h ψ(t)}) + sum_o (a_o cos + b_o sin)(o φ_in(t)),
    h = 1..H; without ``psi``, ψ(t) = 2π psi_order f_in t and φ_in(t) = 2π f_in t (one
    steady speed per window); with ``psi``, each window's own ψ(t) and φ_in = ψ / psi_order
    (computed order tracking, :func:`angle_coefficients`).

    Parameters
    ----------
    x : ndarray, shape (n, C, T)
        Signals [any unit].
    time_s : ndarray, shape (T,)
        Time since window start [s].
    f_in_hz : ndarray, shape (n,)
        Input rotation frequency of each window [Hz]. Windows are grouped by the value
        rounded to 1e-3 Hz and share the group's median (one pseudo-inverse per group).
    psi_order : float
        ψ rate per input revolution, 1 + 1/N [-].
    n_harmonics : int
        H.
    nuisance_orders : sequence of float
        Further orders of the input rotation fitted and discarded.
    psi : ndarray, shape (n, T), optional
        WG angle ψ = φ_in − φ_out of each sample [rad] (measured or estimated, e.g.
        ``SimResult.psi``): fit each window in its own angle, which holds at varying speed
        (``time_s`` and ``f_in_hz`` are then unused). None: the steady-speed basis above.

    Returns
    -------
    ndarray, complex128, shape (n, C, H + 1)
        c0 (real) at index 0, c_h at index h.

    Raises
    ------
    ValueError
        If the highest harmonic reaches the Nyquist frequency (with ``psi``: of ψ's fastest
        step), the window has fewer samples than the series has coefficients, or (with
        ``psi``) shapes disagree or a window's ψ covers too little angle.
    """
    x = np.asarray(x, dtype=np.float64)
    if psi is not None:
        return angle_coefficients(x, psi, psi_order, n_harmonics, nuisance_orders)
    n, n_ch, n_t = x.shape
    time_s = np.asarray(time_s, dtype=np.float64)
    h = np.arange(1, n_harmonics + 1)
    orders = np.concatenate([psi_order * h, np.asarray(nuisance_orders, dtype=np.float64)])
    fs = 1.0 / float(time_s[1] - time_s[0])
    f_top = float(np.max(f_in_hz)) * float(orders.max())
    if f_top >= fs / 2 or 1 + 2 * orders.size > n_t:
        raise ValueError(
            f"{n_harmonics} harmonics need {1 + 2 * orders.size} samples below Nyquist: the "
            f"highest lies at {f_top:.0f} Hz for a sample rate of {fs:.0f} Hz and windows of "
            f"{n_t} samples; lower n_harmonics")
    out = np.empty((n, n_ch, n_harmonics + 1), dtype=np.complex128)
    key = np.round(np.asarray(f_in_hz, dtype=np.float64), 3)
    dt = float(time_s[1] - time_s[0])
    for k in np.unique(key):
        idx = np.flatnonzero(key == k)
        f0 = float(np.median(np.asarray(f_in_hz)[idx]))
        pinv = _basis_pinv(f0, float(time_s[0]), dt, n_t, tuple(orders.tolist()))  # (P, T)
        coef = np.einsum("pt,nct->ncp", pinv, x[idx])  # (m, C, P)
        k_all = orders.size
        out[idx, :, 0] = coef[:, :, 0]
        out[idx, :, 1:] = coef[:, :, 1:1 + n_harmonics] - 1j * coef[:, :, 1 + k_all:
                                                                     1 + k_all + n_harmonics]
    return out


@numba.njit(cache=True)
def _angle_basis(psi, psi_order, h, orders, bt):
    """Transposed angle-domain basis of windows ``psi`` (n, T) into ``bt`` (n, P, T),
    P = 1 + 2 (H + K): rows [1, cos hψ (h = 1..H), cos o φ_in, sin hψ, sin o φ_in],
    φ_in = ψ / psi_order, the column order of :func:`_basis_pinv`; cos, sin of hψ by angle
    addition from (h − 1)ψ (error ~ h eps). Compiled, sample by sample: the same
    operations in the same order as its array form (the reference, in
    tests/learn/test_angle_features.py) without their temporaries; :func:`angle_fit` of
    32 windows of 1,200 samples, H = 12, three orders: 12 against 15 ms, the basis 3.7
    against 6.6 ms (one core of this project's 2-core machine, 2026-11-28)."""
    k = orders.size
    for i in range(psi.shape[0]):
        for t in range(psi.shape[1]):
            p = psi[i, t]
            bt[i, 0, t] = 1.0
            if h:
                c1, s1 = np.cos(p), np.sin(p)
                bt[i, 1, t], bt[i, 1 + h + k, t] = c1, s1
                c, s = c1, s1
                for j in range(2, h + 1):
                    c, s = c * c1 - s * s1, s * c1 + c * s1
                    bt[i, j, t], bt[i, h + k + j, t] = c, s
            phi_in = p / psi_order
            for j in range(k):
                a = orders[j] * phi_in
                bt[i, 1 + h + j, t], bt[i, 1 + 2 * h + k + j, t] = np.cos(a), np.sin(a)


def angle_coefficients(x: np.ndarray, psi: np.ndarray, psi_order: float, n_harmonics: int,
                       nuisance_orders=(0.25, 1 / 3, 0.5, 1.0), chunk: int = 32
                       ) -> np.ndarray:
    """:func:`harmonic_coefficients` in each window's own WG angle ψ(t).

    Computed order tracking by least squares on the samples as they are (no resampling to
    uniform ψ; a reversal keeps each sample's angle), solved by the normal equations with
    the condition-number refusal :data:`MAX_CONDITION` (:func:`angle_fit`, also the
    solver of ``learn.inputs.health``). Nuisance
    orders are multiples of φ_in = ψ / psi_order = ψ N / (N + 1) (rigid gear; the elastic
    twist shifts it by the output-side twist angle [not measured]; they are dropped).

    Parameters
    ----------
    x : ndarray, shape (n, C, T)
        Signals [any unit].
    psi : ndarray, shape (n, T)
        WG angle of each sample [rad].
    psi_order, n_harmonics, nuisance_orders
        As :func:`harmonic_coefficients`.
    chunk : int
        Windows per batched solve (the bases stay in cache).

    Returns
    -------
    ndarray, complex128, shape (n, C, H + 1)
        c0 (real) at index 0, c_h at index h (phase relative to ψ = 0).

    Raises
    ------
    ValueError
        On a shape mismatch, a non-finite ψ, harmonic H of ψ's fastest step at or above
        the Nyquist frequency, or a window whose basis condition exceeds
        :data:`MAX_CONDITION` (named by its index).
    """
    x = np.asarray(x, dtype=np.float64)
    ang = np.asarray(psi, dtype=np.float64)
    n, n_ch, n_t = x.shape
    nuis = tuple(float(o) for o in nuisance_orders)
    h, k = int(n_harmonics), len(nuis)
    if ang.shape != (n, n_t) or not np.all(np.isfinite(ang)):
        raise ValueError(f"psi must be finite with shape (n, T) = {(n, n_t)}, got {ang.shape}")
    top = max([h, *(o / psi_order for o in nuis)])  # highest order, in ψ harmonics
    step = float(np.abs(np.diff(ang, axis=1)).max()) if n and n_t > 1 else 0.0
    if step * top >= np.pi or 1 + 2 * (h + k) > n_t:
        raise ValueError(f"{h} harmonics need {1 + 2 * (h + k)} samples and psi steps below "
                         f"pi / {top:g} rad: windows have {n_t} samples and psi's fastest "
                         f"step is {step:.3g} rad; lower n_harmonics")
    out = np.empty((n, n_ch, h + 1), dtype=np.complex128)
    for i in range(0, n, chunk):
        coef = angle_fit(x[i:i + chunk], ang[i:i + chunk], psi_order, h, nuis, first=i)[0]
        out[i:i + chunk, :, 0] = coef[:, :, 0]
        out[i:i + chunk, :, 1:] = coef[:, :, 1:1 + h] - 1j * coef[:, :, 1 + h + k:1 + 2 * h + k]
    return out


def angle_fit(x: np.ndarray, psi: np.ndarray, psi_order: float, n_harmonics: int,
              nuisance_orders: tuple[float, ...], first: int = 0
              ) -> tuple[np.ndarray, np.ndarray]:
    """Least squares of windows on their own angle-domain basis (:func:`_angle_basis`),
    by the normal equations; the one solver of :func:`angle_coefficients` and
    ``learn.inputs.health.window_features``.

    Parameters
    ----------
    x : ndarray, shape (m, C, T)
        Signals [any unit].
    psi : ndarray, shape (m, T)
        WG angle of each sample [rad].
    psi_order, n_harmonics, nuisance_orders
        As :func:`harmonic_coefficients`.
    first : int
        Index of the first window, for the message.

    Returns
    -------
    coef : ndarray, shape (m, C, P)
        Real coefficients in the rows' order of :func:`_angle_basis`.
    rest : ndarray, shape (m, C, T)
        What the series leaves.

    Raises
    ------
    ValueError
        A window whose basis has a condition number above :data:`MAX_CONDITION`, named by
        its index ``first + i``.
    """
    bt = np.empty((psi.shape[0], 1 + 2 * (n_harmonics + len(nuisance_orders)), psi.shape[1]))
    _angle_basis(np.ascontiguousarray(psi, dtype=np.float64), float(psi_order),
                 int(n_harmonics), np.asarray(nuisance_orders, dtype=np.float64), bt)
    gram = bt @ np.swapaxes(bt, 1, 2)  # cond(G) = cond(B)^2 <= MAX_CONDITION^2
    lam = np.linalg.eigvalsh(gram)
    cond = np.sqrt(lam[:, -1] / np.maximum(lam[:, 0], 1e-300))
    bad = np.flatnonzero(~(cond <= MAX_CONDITION))
    if bad.size:
        w = int(bad[0])
        raise ValueError(
            f"window {first + w}: psi spans {np.ptp(psi[w]) / (2 * np.pi):.3g} WG "
            f"revolutions, too little for harmonics 1..{n_harmonics} and orders "
            f"{tuple(nuisance_orders)} (basis condition {cond[w]:.3g} > {MAX_CONDITION:g})")
    coef = np.swapaxes(np.linalg.solve(gram, bt @ np.swapaxes(x, 1, 2)), 1, 2)  # (m, C, P)
    return coef, x - coef @ bt


def align_phase(cw: np.ndarray, cr: np.ndarray, channels=(1, 2, 3, 4),
                n_newton: int = 6) -> np.ndarray:
    """ψ-shift δ of each window against its reference.

    Minimises ``sum_{c, h >= 1} |cw[c, h] - cr[c, h] e^{i h δ}|^2`` over ``channels``.

    Parameters
    ----------
    cw, cr : ndarray, complex, shape (n, C, H + 1)
        Coefficients of the windows and of their references (:func:`harmonic_coefficients`).

    Returns
    -------
    ndarray, shape (n,)
        δ [rad].
    """
    ch = list(channels)
    h = np.arange(1, cw.shape[2])
    a, b = cw[:, ch, 1:], cr[:, ch, 1:]
    z = np.sum(a[:, :, 1] * np.conj(b[:, :, 1]), axis=1)  # 2nd harmonic
    best = err_best = None
    for start in (np.angle(z) / 2, np.angle(z) / 2 + np.pi):
        d = start.copy()
        for _ in range(n_newton):  # maximise Re sum a conj(b) e^{-ihd}
            q = a * np.conj(b) * np.exp(-1j * h * d[:, None, None])
            grad = np.sum(np.imag(q) * h, axis=(1, 2))
            curv = np.sum(np.real(q) * h * h, axis=(1, 2))
            with np.errstate(divide="ignore", invalid="ignore"):
                step = np.where(curv > 0, grad / curv, 0.0)
            d = d + np.clip(np.nan_to_num(step), -0.2, 0.2)  # Newton, damped
        err = np.sum(np.abs(a - b * np.exp(1j * h * d[:, None, None])) ** 2, axis=(1, 2))
        if best is None:
            best, err_best = d, err
        else:
            better = err < err_best
            best, err_best = np.where(better, d, best), np.where(better, err, err_best)
    return best


def reference_residual(ds, samples: np.ndarray, refs: np.ndarray,
                       settings: ResidualSettings | None = None,
                       psi: np.ndarray | None = None) -> np.ndarray:
    """Harmonics of each window minus those of its phase-aligned reference window.

    Parameters
    ----------
    ds : xarray.Dataset
        Schema v1 (uses ``strain_signal``, ``time``, ``n_in_mean_rpm``/``n_in_rpm``).
    samples, refs : ndarray of int, shape (n,)
        Windows and their reference windows (:func:`window_meta`).
    settings : ResidualSettings, optional
        Uses ``ratio`` (the gear ratio N: catalogue, 100 for the paper's gears;
        docs/PHYSICS.md sec. 2), ``n_harmonics`` and ``nuisance_orders``; default
        :class:`ResidualSettings`.
    psi : ndarray, shape (N, T), optional
        WG angle ψ of every sample of every window of ``ds`` [rad] (row i: window i; the
        data set does not carry it): windows and references are fitted in their own angle
        (:func:`angle_coefficients`), which holds at varying speed. None: the basis of
        each window's mean speed (steady speed).

    Returns
    -------
    ndarray, complex128, shape (n, 5, H + 1)
        Residual coefficients divided by the reference's RMS per channel [-]; index 0 is
        the change of the mean, index h the h-th harmonic of ψ.
    """
    sig = ds["strain_signal"].values
    t = np.asarray(ds["time"].values, dtype=np.float64)
    n_act = np.asarray(ds["n_in_mean_rpm"].values, dtype=np.float64)
    n_des = np.asarray(ds["n_in_rpm"].values, dtype=np.float64)
    f_in = np.where(np.isfinite(n_act), n_act, n_des) / 60.0
    rs = settings or ResidualSettings()
    n_harmonics = int(rs.n_harmonics)
    psi_order = 1.0 + 1.0 / float(rs.ratio)
    kw = {"psi_order": psi_order, "n_harmonics": n_harmonics,
          "nuisance_orders": tuple(rs.nuisance_orders)}
    if psi is not None and np.shape(psi) != (sig.shape[0], t.size):
        raise ValueError(f"psi must have shape (windows, T) = {(sig.shape[0], t.size)}, got "
                         f"{np.shape(psi)}")
    uref, inv = np.unique(refs, return_inverse=True)
    cr = harmonic_coefficients(sig[uref], t, f_in[uref], **kw,
                               psi=None if psi is None else psi[uref])[inv]  # (n, 5, H+1)
    cw = np.empty_like(cr)
    for start in range(0, len(samples), 1024):  # bound the float64 copy of the signals
        sl = slice(start, start + 1024)
        cw[sl] = harmonic_coefficients(sig[samples[sl]], t, f_in[samples[sl]], **kw,
                                       psi=None if psi is None else psi[samples[sl]])
    delta = align_phase(cw, cr)
    h = np.arange(1, n_harmonics + 1)
    res = cw.copy()
    res[:, :, 1:] -= cr[:, :, 1:] * np.exp(1j * h * delta[:, None, None])
    res[:, :, 0] -= cr[:, :, 0]
    rms = np.sqrt(0.5 * np.sum(np.abs(cr[:, :, 1:]) ** 2, axis=2))  # (n, 5)
    return res / np.where(rms > 1e-12, rms, 1.0)[:, :, None]


def synthesise(res: np.ndarray, n_points: int = 192, min_harmonic: int = 2) -> np.ndarray:
    """Residual waveform over one ψ revolution from harmonics ``min_harmonic``..H.

    Parameters
    ----------
    res : ndarray, complex, shape (n, C, H + 1)
    n_points : int
        M samples of ψ in [0, 2π).

    Returns
    -------
    ndarray, float64, shape (n, C, M)
    """
    n_h = res.shape[2] - 1
    h = np.arange(min_harmonic, n_h + 1)
    psi = 2 * np.pi * np.arange(n_points) / n_points
    e = np.exp(1j * h[:, None] * psi[None, :])  # (h, M)
    return np.real(np.einsum("nch,hm->ncm", res[:, :, min_harmonic:], e))


def _append_aux(x: np.ndarray, aux: np.ndarray) -> np.ndarray:
    """Append per-window scalars as channels constant along time: (n, C, T) -> (n, C+A, T)."""
    if aux.shape[1] == 0:
        return x
    a = np.broadcast_to(aux[:, :, None], (x.shape[0], aux.shape[1], x.shape[2]))
    return np.concatenate([x, a.astype(x.dtype)], axis=1)


def build_input(ds, kind: str, aux: tuple[str, ...] | list[str] = AUX,
                disturbed: bool | None = None, feature_kwargs: dict | None = None,
                residual: ResidualSettings | None = None,
                psi: np.ndarray | None = None, cache: dict | None = None) -> InputSet:
    """Model input of kind ``kind`` for the non-reference windows of ``ds``.

    Parameters
    ----------
    ds : xarray.Dataset
        Schema v1 with reference windows.
    kind : {"raw", "diff", "sel1", "sel3", "raw_res", "diff_res", "res_spec"}
        See docs/learners_transfer.md, "Reference normalisation and the synchronous residual".
    aux : sequence of {"eta2_rel", "eta_rel"}
        Per-window scalars appended as constant channels to a signal input, or as
        columns to ``res_spec`` (ignored for sel1/sel3, which carry their own efficiency
        term).
    disturbed : bool, optional
        Keep only the clean (False) or disturbed (True) windows; default all.
    feature_kwargs : dict, optional
        ``orders``, ``floor_rel`` of :func:`learn.inputs.features.extract_features`.
    residual : ResidualSettings, optional
        Settings of the residual inputs; default :class:`ResidualSettings`.
    psi : ndarray, shape (N, T), optional
        WG angle of every window of ``ds`` [rad], for the residual inputs
        (:func:`reference_residual`); refused for the other kinds.
    cache : dict, optional
        Shared by the calls for several kinds on the same ``ds``: the reference residual
        that ``raw_res``, ``diff_res`` and ``res_spec`` share is computed once (without
        ``psi``).

    Returns
    -------
    InputSet
        Rows in data-set order, so :func:`learn.studies.protocols.protocol_splits` on
        ``meta`` indexes ``X``.

    Raises
    ------
    ValueError
        On an unknown ``kind`` or ``aux`` name, or a window without reference.
    """
    if kind not in INPUTS:
        raise ValueError(f"unknown input {kind!r}; choose one of {INPUTS}")
    if psi is not None and kind not in RESIDUAL_INPUTS:
        raise ValueError(f"psi is used by the residual inputs {RESIDUAL_INPUTS} only, not "
                         f"{kind!r}")
    bad = set(aux) - set(AUX)
    if bad:
        raise ValueError(f"unknown auxiliary scalars {sorted(bad)}; choose from {AUX}")
    meta, refs = window_meta(ds, disturbed)
    samples = meta["sample"].to_numpy()
    y = meta["fault"].to_numpy()
    if kind in ("sel1", "sel3"):  # the paper's features (Table III)
        feats = extract_features(ds, int(kind[-1]), **dict(feature_kwargs or {}))
        fs = feats.meta["sample"].to_numpy()
        pos = np.searchsorted(fs, samples)
        if not np.array_equal(fs[np.minimum(pos, fs.size - 1)], samples):
            raise ValueError("features and windows disagree on the non-reference windows")
        return InputSet(np.asarray(feats.X[pos], dtype=np.float32), y, meta, 0, kind)
    eff = efficiency_features(ds, samples, refs)[:, [AUX.index(a) for a in aux]]  # (n, A)
    if kind in RESIDUAL_INPUTS:
        rs = residual or ResidualSettings()
        key = ("residual", disturbed, repr(rs))
        x = None if psi is not None or cache is None else cache.get(key)
        if x is None:
            x = reference_residual(ds, samples, refs, rs, psi)  # (n, 5, H+1)
            if psi is None and cache is not None:
                cache[key] = x
        if kind == "res_spec":
            amp = np.log10(np.abs(x[:, :, int(rs.min_harmonic):]) + 1e-7)  # (n, 5, H')
            x = np.concatenate([amp.reshape(len(amp), -1), eff], axis=1)
            return InputSet(x.astype(np.float32), y, meta, 0, kind)
    else:
        x = normalise_signals(ds, samples, refs)  # (n, 5, T)
    if kind in ("diff", "diff_res"):  # s0 and the redundant gauges' differences (eq. 8)
        x = np.stack([x[:, 0], x[:, 1] - x[:, 3], x[:, 2] - x[:, 4]], axis=1)  # (n, 3, .)
    if kind in RESIDUAL_INPUTS:
        x = synthesise(x, int(rs.n_points), int(rs.min_harmonic))  # (n, C, M)
        if rs.compress:
            x = np.arcsinh(x / float(rs.compress))
        x = x.astype(np.float32)
    x = _append_aux(x, eff)
    return InputSet(np.ascontiguousarray(x, dtype=np.float32), y, meta, eff.shape[1], kind)
