"""Python reference of the embedded per-window stage: the C's arithmetic, op for op.

Per sample the monitor's basis (:mod:`learn.inputs.health`) at the input angle φ, and
per bridge the single-bin DFTs b = Bᵀy and the energy yᵀy of y = x − x₀, summed in float32
over blocks of :data:`BLOCK` samples into Kahan-compensated totals; at the window's end
c = G⁻¹ b with the operating point's stored normal equations, the features (offset,
amplitudes, log10 residual RMS from yᵀy − 2 cᵀb + cᵀGc, efficiency), their z-scores and
the classifier's int16 inputs (:func:`quantize`). Sines and cosines come from
:func:`sincos32`, log10 from :func:`log10_32`: IEEE float32 in a fixed order, so that the
C compiled with ``-ffp-contract=off`` gives the same bits. Method and measured error
against the monitor's float64 least squares: ``docs/EXPORT.md``, "Method".
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from learn.inputs.health import N_HARMONICS, NUISANCE_ORDERS, RATIO

F32 = np.float32
#: Samples per float32 partial sum (pairwise summation, module docstring).
BLOCK = 64
#: Scale of the classifier's int16 z-score inputs: 1/Z_SCALE z per step, ±32767 / Z_SCALE
#: z at most (larger z-scores are clipped; a tree learns on the clipped values).
Z_SCALE = 64.0
#: The nuisance orders' least common denominator: each is a multiple of 1/NUISANCE_DEN of
#: the input angle (1/4, 1/3, 1/2 of :data:`learn.inputs.health.NUISANCE_ORDERS`: 12).
NUISANCE_DEN = math.lcm(*(Fraction(o).limit_denominator(1000).denominator
                          for o in NUISANCE_ORDERS))

# float32 constants of the C (each printed by swgmon.export.cgen from these values)
TWO_OVER_PI = F32(2 / np.pi)
PIO2_HI = F32(1608 / 1024)  # π/2 to 11 bits: q · PIO2_HI exact for |q| < 2^13
PIO2_LO = F32(np.pi / 2 - 1608 / 1024)
SIN_C = tuple(F32(v) for v in (-1 / 6, 1 / 120, -1 / 5040, 1 / 362880))
COS_C = tuple(F32(v) for v in (-1 / 2, 1 / 24, -1 / 720, 1 / 40320, -1 / 3628800))
LN2 = F32(np.log(2.0))
INV_LN10 = F32(1 / np.log(10.0))
SQRT_HALF = F32(np.sqrt(0.5))
LOG_C = tuple(F32(v) for v in (2.0, 2 / 3, 2 / 5, 2 / 7, 2 / 9))
REST_FLOOR = F32(1e-9)  # as learn.inputs.health: log10(rms + 1e-9)
WG_ORDER = F32(1.0 + 1.0 / RATIO)
NUIS_BASE = F32(1.0 / NUISANCE_DEN)


@functools.lru_cache(maxsize=1)
def nuisance_multiples() -> tuple[int, ...]:
    """The nuisance orders as multiples m of φ / :data:`NUISANCE_DEN` (3, 4, 6).

    Raises
    ------
    ValueError
        If an order of :data:`learn.inputs.health.NUISANCE_ORDERS` is no ratio of small
        integers (denominator at most 1000), so no such multiple.
    """
    out = []
    for o in NUISANCE_ORDERS:
        m = Fraction(o).limit_denominator(1000) * NUISANCE_DEN
        if not np.isclose(float(m) / NUISANCE_DEN, o, rtol=0.0, atol=1e-12):
            raise ValueError(f"nuisance order {o:g} is not a multiple of 1/{NUISANCE_DEN}")
        out.append(int(m))
    return tuple(out)


def n_basis(n_harmonics: int = N_HARMONICS) -> int:
    """Columns P of the basis: 1 + 2 (H + nuisance orders) (31 for H = 12)."""
    return 1 + 2 * (n_harmonics + len(NUISANCE_ORDERS))


def sincos32(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """cos a, sin a in float32 as the C computes them (quadrant reduction to ``|r| ≤ π/4``,
    Taylor polynomials to r⁸ / r⁹: error below 3e-8 on the reduced angle, plus the
    rounding of a itself).

    Parameters
    ----------
    a : ndarray of float32
        Angles [rad], ``|a| < 2^13 π / 2``.

    Returns
    -------
    (ndarray, ndarray)
        cos a, sin a, float32, shape of ``a``.
    """
    a = np.asarray(a, F32)
    q = np.floor(a * TWO_OVER_PI + F32(0.5))
    r = (a - q * PIO2_HI) - q * PIO2_LO
    r2 = r * r
    s1, s2, s3, s4 = SIN_C
    c1, c2, c3, c4, c5 = COS_C
    s = r + r * r2 * (s1 + r2 * (s2 + r2 * (s3 + r2 * s4)))
    c = F32(1.0) + r2 * (c1 + r2 * (c2 + r2 * (c3 + r2 * (c4 + r2 * c5))))
    quad = q.astype(np.int32) & 3
    cos = np.select([quad == 0, quad == 1, quad == 2], [c, -s, -c], s)
    sin = np.select([quad == 0, quad == 1, quad == 2], [s, c, -s], -c)
    return cos.astype(F32), sin.astype(F32)


def log10_32(y: np.ndarray) -> np.ndarray:
    """log10 y in float32 as the C computes it (frexp, then 2 atanh((m − 1) / (m + 1))
    by its series to the 9th power; error about 1e-7), y > 0."""
    y = np.asarray(y, F32)
    m, e = np.frexp(y)  # y = m 2^e, m in [0.5, 1)
    m, e = m.astype(F32), e.astype(np.int32)
    low = m < SQRT_HALF
    m = np.where(low, m * F32(2.0), m).astype(F32)
    e = np.where(low, e - 1, e)
    s = (m - F32(1.0)) / (m + F32(1.0))
    s2 = s * s
    l0, l1, l2, l3, l4 = LOG_C
    series = s * (l0 + s2 * (l1 + s2 * (l2 + s2 * (l3 + s2 * l4))))
    return ((e.astype(F32) * LN2 + series) * INV_LN10).astype(F32)


def basis32(phi: np.ndarray, n_harmonics: int = N_HARMONICS) -> np.ndarray:
    """The basis at input angles φ as the C builds it, float32.

    Parameters
    ----------
    phi : ndarray of float32, shape (...)
        Input angle since the window's first sample [rad].
    n_harmonics : int
        H.

    Returns
    -------
    ndarray, float32, shape (..., P)
        [1, cos of the orders, sin of the orders], orders h (1 + 1/N) for h = 1..H then
        the nuisance orders (:func:`n_basis` columns; as learn.inputs.health).
    """
    phi = np.asarray(phi, F32)
    c1, s1 = sincos32(phi * WG_ORDER)
    cos, sin = [c1], [s1]
    for _ in range(1, n_harmonics):
        c, s = cos[-1], sin[-1]
        cos.append(c * c1 - s * s1)
        sin.append(s * c1 + c * s1)
    cb, sb = sincos32(phi * NUIS_BASE)
    pc, ps = [cb], [sb]
    for _ in range(1, max(nuisance_multiples())):
        c, s = pc[-1], ps[-1]
        pc.append(c * cb - s * sb)
        ps.append(s * cb + c * sb)
    for m in nuisance_multiples():
        cos.append(pc[m - 1])
        sin.append(ps[m - 1])
    return np.stack([np.ones_like(phi), *cos, *sin], axis=-1).astype(F32)


def accumulate32(x: np.ndarray, phi: np.ndarray, n_harmonics: int = N_HARMONICS
                 ) -> np.ndarray:
    """The DFTs and energies the C accumulates over a window (module docstring).

    Parameters
    ----------
    x : ndarray, shape (n, 5, n_t)
        Bridge outputs [mV/V] (cast to float32).
    phi : ndarray, shape (n, n_t)
        Input angle since each window's first sample [rad] (cast to float32).
    n_harmonics : int

    Returns
    -------
    acc : ndarray, float32, shape (n, 5, P + 1)
        Per bridge b = Bᵀy (P values) and yᵀy of y = x − x₀, as the C's totals
        (Kahan-compensated sums of :data:`BLOCK`-sample partial sums).
    x0 : ndarray, float32, shape (n, 5)
        The first sample of each window and bridge (subtracted: the fit is invariant to
        it, and the energy to cancel shrinks by the offset's) [mV/V].
    """
    x = np.asarray(x, F32)
    phi = np.asarray(phi, F32)
    n, c, n_t = x.shape
    p = n_basis(n_harmonics)
    x0 = x[:, :, 0].copy()  # (n, 5)
    y = x - x0[..., None]  # (n, 5, n_t)
    m = -(-n_t // BLOCK)  # blocks; the last one padded with zero products (s + 0 = s)
    prod = np.zeros((n, c, m * BLOCK, p + 1), F32)
    prod[:, :, :n_t, :p] = y[..., None] * basis32(phi, n_harmonics)[:, None]
    prod[:, :, :n_t, p] = y * y
    prod = prod.reshape(n, c, m, BLOCK, p + 1)
    blk = np.add.accumulate(prod, axis=3, dtype=F32)[:, :, :, -1]  # sequential in t
    tot = np.zeros((n, c, p + 1), F32)
    comp = np.zeros_like(tot)  # Kahan compensation of the totals
    for j in range(m):
        d = blk[:, :, j] - comp
        u = tot + d
        comp = (u - tot) - d
        tot = u
    return tot, x0


@dataclass(frozen=True)
class StageTables:
    """The stage's constant tables (what the C holds in flash).

    Attributes
    ----------
    n_t : int
        Samples per window.
    fs_hz : float
        Sample rate [Hz].
    n_harmonics : int
    speeds_rpm : ndarray, shape (S,)
        Nominal input speeds with normal equations [rpm].
    g_inv, gram : ndarray, float32, shape (S, P, P)
        (BᵀB)⁻¹ and BᵀB of each speed's nominal basis (symmetric: the C stores the
        upper triangles).
    points : ndarray, shape (K, 2)
        Operating points (n_in_rpm, t_out_nm) of the normal behaviour.
    speed_index : ndarray of int, shape (K,)
        Row of ``g_inv`` of each operating point.
    mean, inv_std : ndarray, float32, shape (K, F)
        The gear's normal behaviour (swgmon.detection.normal.NormalBehaviour): mean and
        1 / std per point.
    point_inputs : ndarray of int16, shape (K, 2)
        The classifier's operating-point inputs: speed [rpm] and torque [0.1 N m].
    """

    n_t: int
    fs_hz: float
    n_harmonics: int
    speeds_rpm: np.ndarray
    g_inv: np.ndarray
    gram: np.ndarray
    points: np.ndarray
    speed_index: np.ndarray
    mean: np.ndarray
    inv_std: np.ndarray
    point_inputs: np.ndarray

    @property
    def n_features(self) -> int:
        """Health features F = 5 (H + 2) + 1."""
        return 5 * (self.n_harmonics + 2) + 1


def nominal_angle(n_in_rpm: float, fs_hz: float, n_t: int) -> np.ndarray:
    """φ = 2π n t / 60 at the desired speed, float32, shape (n_t,) [rad] (the monitor's
    steady-window basis, learn.inputs.health)."""
    return (2 * np.pi * n_in_rpm / 60.0 * np.arange(n_t) / fs_hz).astype(F32)


def normal_equations(n_in_rpm: float, fs_hz: float, n_t: int,
                     n_harmonics: int = N_HARMONICS) -> tuple[np.ndarray, np.ndarray]:
    """(BᵀB)⁻¹ and BᵀB of the nominal basis of a speed (float64, then rounded to float32;
    symmetrised), each shape (P, P).

    Raises
    ------
    ValueError
        If the basis is ill-conditioned (the window too short for its orders) or its
        highest order reaches the Nyquist frequency.
    """
    if n_in_rpm / 60.0 * n_harmonics * float(WG_ORDER) >= fs_hz / 2:
        raise ValueError(f"harmonic {n_harmonics} of {n_in_rpm:g} rpm reaches the Nyquist "
                         f"frequency of {fs_hz:g} Hz")
    phi = 2 * np.pi * n_in_rpm / 60.0 * np.arange(n_t) / fs_hz
    orders = np.concatenate([(1 + 1 / RATIO) * np.arange(1, n_harmonics + 1),
                             NUISANCE_ORDERS])
    ang = phi[:, None] * orders[None, :]
    b = np.concatenate([np.ones((n_t, 1)), np.cos(ang), np.sin(ang)], axis=1)
    g = b.T @ b
    cond = np.linalg.cond(g)
    if not np.isfinite(cond) or cond > 1e6:
        raise ValueError(f"window of {n_t} samples at {n_in_rpm:g} rpm is too short for the "
                         f"basis (condition number of BᵀB {cond:.3g} > 1e6)")
    gi = np.linalg.inv(g)
    return ((gi + gi.T) / 2).astype(F32), ((g + g.T) / 2).astype(F32)


def features32(acc: np.ndarray, x0: np.ndarray, g_inv: np.ndarray, gram: np.ndarray,
               efficiency: np.ndarray, n_t: int, n_harmonics: int = N_HARMONICS
               ) -> np.ndarray:
    """Health features from the accumulated DFTs, as the C's window end.

    Parameters
    ----------
    acc : ndarray, float32, shape (n, 5, P + 1)
        :func:`accumulate32`'s totals.
    x0 : ndarray, float32, shape (n, 5)
        Each window's first sample, subtracted before accumulating [mV/V].
    g_inv : ndarray, float32, shape (n, P, P)
        Each window's normal-equation inverse (its speed's).
    gram : ndarray, float32, shape (n, P, P)
        Each window's BᵀB (its speed's): the residual energy is taken as
        yᵀy − 2 cᵀb + cᵀ(BᵀB)c, stationary in c, so that c's float32 rounding enters
        to second order only (cᵀb alone lost 4 % of the residual energy in float32).
    efficiency : ndarray, shape (n,)
        Mean P_out / mean P_in of each window [-].
    n_t : int
    n_harmonics : int

    Returns
    -------
    ndarray, float32, shape (n, 5 (H + 2) + 1)
        Columns as :func:`learn.inputs.health.feature_names`.
    """
    n, nb, p1 = acc.shape
    p, h, k = p1 - 1, n_harmonics, len(NUISANCE_ORDERS)
    b = acc[..., :p]
    c = np.zeros((n, nb, p), F32)
    for j in range(p):  # c_i = Σ_j G⁻¹_ij b_j, in the C's order
        c += g_inv[:, None, :, j] * b[..., j, None]
    cb = np.zeros((n, nb), F32)
    cgc = np.zeros((n, nb), F32)
    for i in range(p):
        cb += c[..., i] * b[..., i]
        gc = np.zeros((n, nb), F32)
        for j in range(p):
            gc += gram[:, None, i, j] * c[..., j]
        cgc += c[..., i] * gc
    ms = ((acc[..., p] - F32(2.0) * cb) + cgc) / F32(n_t)
    ms = np.maximum(ms, F32(0.0))
    out = np.empty((n, nb, h + 2), F32)
    out[..., 0] = c[..., 0] + x0
    cc, ss = c[..., 1:h + 1], c[..., 1 + h + k:1 + 2 * h + k]
    out[..., 1:h + 1] = np.sqrt(cc * cc + ss * ss)
    out[..., -1] = log10_32(np.sqrt(ms) + REST_FLOOR)
    return np.concatenate([out.reshape(n, -1), np.asarray(efficiency, F32)[:, None]], axis=1)


def quantize(z: np.ndarray) -> np.ndarray:
    """The classifier's int16 inputs of z-scores: ⌊z · Z_SCALE + 1/2⌋ clipped to ±32767
    (float32 arithmetic, as the C), shape of ``z``."""
    q = np.floor(np.asarray(z, F32) * F32(Z_SCALE) + F32(0.5))
    top = np.iinfo(np.int16).max
    return np.clip(q, -top, top).astype(np.int16)


def z32(feats: np.ndarray, tables: StageTables, op: np.ndarray) -> np.ndarray:
    """z-scores (f − mean) / std in float32, as the C: ``op`` (n,) rows of the tables."""
    return ((np.asarray(feats, F32) - tables.mean[op]) * tables.inv_std[op]).astype(F32)


def design_rows(feats: np.ndarray, tables: StageTables, op: np.ndarray) -> np.ndarray:
    """The classifier's int16 input rows: quantized z-scores, then the operating point's
    speed and torque inputs; shape (n, F + 2)."""
    return np.concatenate([quantize(z32(feats, tables, op)), tables.point_inputs[op]], axis=1)


def stage_features(x: np.ndarray, phi: np.ndarray, efficiency: np.ndarray, op: np.ndarray,
                   tables: StageTables, chunk: int = 32) -> np.ndarray:
    """Health features of windows as the embedded stage computes them.

    Parameters
    ----------
    x : ndarray, shape (n, 5, n_t)
        Bridge outputs [mV/V].
    phi : ndarray, shape (n, n_t)
        Input angle since each window's first sample [rad].
    efficiency : ndarray, shape (n,)
    op : ndarray of int, shape (n,)
        Operating-point row of each window (:attr:`StageTables.points`).
    tables : StageTables
    chunk : int
        Windows per vectorised pass (bounds memory).

    Returns
    -------
    ndarray, float32, shape (n, F)
    """
    out = []
    for a in range(0, len(x), chunk):
        acc, x0 = accumulate32(x[a:a + chunk], phi[a:a + chunk], tables.n_harmonics)
        si = tables.speed_index[op[a:a + chunk]]
        out.append(features32(acc, x0, tables.g_inv[si], tables.gram[si],
                              efficiency[a:a + chunk], tables.n_t, tables.n_harmonics))
    return np.concatenate(out) if out else np.empty((0, tables.n_features), F32)
