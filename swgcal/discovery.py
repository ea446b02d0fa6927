"""Discovery: terms beyond the effect library, proposed by sparse regression.

When the calibration loop (:mod:`.loop`) ends with a structured residual, :func:`discover`
proposes terms from a generic basis of the data's context (SINDy's idea, Brunton, Proctor
& Kutz 2016): the final model and local nuisances projected off (:class:`Projector`),
groups screened by the lasso path with the effective-sample BIC, forward selection scored
on held-out rows, each :class:`Proposal` in words. Each data kind builds its :class:`Group`
basis (:mod:`swgcal.strain.discovery`, :mod:`swgcal.friction.discovery`). The four steps,
sources and limits: docs/calibration.md, "Discovery beyond the library".
"""

from __future__ import annotations

import logging
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from itertools import combinations
from typing import Any

import numpy as np

from swgsim.base.markdown import md_table

from .core import integrated_autocorr_time
from .loop import CalibrationResult

log = logging.getLogger(__name__)

__all__ = ["Proposal", "Group", "MIN_GAIN", "LOAD_SPEED_COLLINEAR", "discover",
           "model_design", "Projector", "line_spectrum", "spectral_peaks", "tone_group",
           "proposals_section"]

MIN_GAIN = 0.01
"""Default held-out gain a proposal must exceed: 1 % of the validation RMSE, half the
loop's ``min_rel_improvement``. On noise-only residuals the effective-BIC lasso selects
no column at all (tests/swgcal/test_calib_discovery.py); the planted effects gain 5-60 %."""

LOAD_SPEED_COLLINEAR = 0.99
"""|correlation| of load and speed over the windows above which their products are
reported as one (the data cannot tell them apart)."""


@dataclass(frozen=True)
class Proposal:
    """A proposed term: ``expression`` (words for a reader, e.g. ``"crosstalk: 8 % of s2
    in s1"``), ``parameters`` (fitted values; units in the key names or a ``"unit"``
    entry), ``heldout_gain`` (relative drop of the validation RMSE when the term is
    added, 1 − after / before) and ``kind`` (``"crosstalk"``, ``"order_tone"``,
    ``"fixed_tone"``, ``"gain_modulation"``, ``"offset_modulation"``, ``"trend"``)."""

    expression: str
    parameters: dict[str, Any]
    heldout_gain: float
    kind: str = ""

    def as_dict(self) -> dict[str, Any]:
        return {"expression": self.expression, "parameters": dict(self.parameters),
                "heldout_gain": float(self.heldout_gain), "kind": self.kind}


@dataclass
class Group:
    """The candidate columns of one phenomenon: ``key`` (unique name, e.g. ``"crosstalk
    s1->s3"``), ``kind``, ``columns`` (n_rows, m) on the basis rows (fit and validation),
    ``names`` (one per column; ``"x_load"`` etc. mark the products with a modulator) and
    ``describe(coef: dict name -> value) -> (expression, parameters)`` (unselected
    columns have coefficient 0)."""

    key: str
    kind: str
    columns: np.ndarray
    names: tuple[str, ...]
    describe: Callable[[dict[str, float]], tuple[str, dict[str, Any]]]


# ---------------------------------------------------------------------------------------
# the mechanism


class Projector:
    """Least squares on nuisance columns: local ones (a window's WG-angle shift) fitted
    on each block's own rows first, then global ones fitted on the fit rows.

    Parameters
    ----------
    nuisance : ndarray, shape (n_rows, k)
    fit : ndarray of int
        Fit rows (indices into the rows).
    local : ndarray, shape (n_rows, k_local), optional
    block : ndarray of int, shape (n_rows,), optional
        Block label of every row (with ``local``).
    """

    def __init__(self, nuisance: np.ndarray, fit: np.ndarray, local: np.ndarray | None = None,
                 block: np.ndarray | None = None) -> None:
        self.local = None if local is None else np.asarray(local, float).reshape(
            len(nuisance), -1)
        self.blocks = [] if local is None else [np.flatnonzero(block == b)
                                                for b in np.unique(block)]
        x = self._local(np.asarray(nuisance, float))
        self.fit = np.asarray(fit)
        scale = np.sqrt(np.sum(x[self.fit] ** 2, axis=0))
        scale[scale == 0] = 1.0
        self.x = x / scale
        self.pinv = np.linalg.pinv(self.x[self.fit], rcond=1e-10)  # (k, n_fit)

    def _local(self, v: np.ndarray) -> np.ndarray:
        if self.local is None:
            return v
        v = v.copy()
        for m in self.blocks:
            a = self.local[m]
            g = a.T @ a
            g += 1e-12 * np.trace(g) * np.eye(g.shape[0]) + 1e-300
            v[m] -= a @ np.linalg.solve(g, a.T @ v[m])
        return v

    def resid(self, v: np.ndarray) -> np.ndarray:
        """v minus its least-squares fit on the nuisance, on all rows; v of shape
        (n_rows,) or (n_rows, m)."""
        v = self._local(np.asarray(v, float))
        return v - self.x @ (self.pinv @ v[self.fit])


def _split_name(name: str) -> tuple[str, str]:
    """Column name -> (base, variant): ``"h1_0_cos_x_load"`` -> ("h1_0_cos", "load"),
    ``"plain"`` -> ("", "plain"), ``"p2"`` -> ("p2", "plain")."""
    if "x_" in name:
        base, var = name.rsplit("x_", 1)
        return base.rstrip("_"), var
    return ("" if name == "plain" else name), "plain"


def _standardised(target: np.ndarray, groups: Sequence[Group], fit: np.ndarray,
                  projector: Projector | None
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The target and all candidate columns with the nuisance projected off (step 1),
    the columns scaled to unit RMS on the fit rows; (target, columns, scales, usable:
    columns not numerically zero, the others set to 0)."""
    r = np.asarray(target, float)
    z = np.hstack([g.columns for g in groups])
    if projector is not None:
        r = projector.resid(r)
        z = projector.resid(z)
    sd = np.sqrt(np.mean(z[fit] ** 2, axis=0))
    ok = sd > 1e-9 * max(float(sd.max()), 1e-300)
    z /= np.where(ok, sd, 1.0)
    z[:, ~ok] = 0.0
    return r, z, sd, ok


@dataclass(frozen=True)
class _Gram:
    """Gram matrices of the standardised columns and the target on the fit rows (``gf``,
    ``bf``) and the validation rows (``gv``, ``bv``; target ``rv`` on ``n_v`` rows):
    least squares on the fit rows of any set of columns, scored on the validation
    rows."""

    gf: np.ndarray
    bf: np.ndarray
    gv: np.ndarray
    bv: np.ndarray
    rv: np.ndarray
    n_v: int

    def val_rmse(self, idx: np.ndarray) -> tuple[float, np.ndarray]:
        """Validation RMSE of the columns ``idx`` fitted on the fit rows, and their
        coefficients."""
        rv, n_v = self.rv, self.n_v
        if idx.size == 0:
            return float(np.sqrt(rv @ rv / n_v)), np.empty(0)
        c = np.linalg.lstsq(self.gf[np.ix_(idx, idx)], self.bf[idx], rcond=None)[0]
        sse = rv @ rv - 2 * c @ self.bv[idx] + c @ self.gv[np.ix_(idx, idx)] @ c
        return float(np.sqrt(max(sse, 0.0) / n_v)), c

    def gains(self, parts: dict[int, np.ndarray], order: Sequence[int]) -> list[float]:
        """Held-out gain of each group of ``order`` (its columns ``parts[i]``) added
        after the ones before it."""
        out, cur = [], self.val_rmse(np.empty(0, int))[0]
        for k in range(len(order)):
            v = self.val_rmse(_joint(parts, order[:k + 1]))[0]
            out.append(1.0 - v / cur if cur > 0 else 0.0)
            cur = v
        return out


def _joint(parts: dict[int, np.ndarray], order: Sequence[int]) -> np.ndarray:
    """The columns of the groups ``order``, concatenated."""
    return np.concatenate([parts[j] for j in order] or [np.empty(0, int)]).astype(int)


def _lasso_columns(zf: np.ndarray, rf: np.ndarray, gram: _Gram, ok: np.ndarray,
                   owner: np.ndarray, groups: Sequence[Group]) -> dict[int, np.ndarray]:
    """Screening (step 2): the lasso path on the fit rows, the point on it of least BIC
    with the effective number of samples; group -> the columns it keeps."""
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.linear_model import lars_path_gram

    gf, bf, n_f = gram.gf, gram.bf, rf.size
    with warnings.catch_warnings():  # collinear candidates: LARS drops them, says so
        warnings.simplefilter("ignore", ConvergenceWarning)
        _, _, path = lars_path_gram(Xy=bf, Gram=gf, n_samples=n_f, method="lasso",
                                    max_iter=min(500, 2 * zf.shape[1]))
    c_all = np.linalg.solve(gf + 1e-9 * n_f * np.eye(gf.shape[0]), bf)
    n_eff = n_f / integrated_autocorr_time(rf - zf @ c_all)
    rss = rf @ rf - 2 * path.T @ bf + np.einsum("ij,ij->j", path, gf @ path)
    df = np.count_nonzero(path, axis=0)
    bic = n_eff * np.log(np.maximum(rss, 1e-300) / n_f) + df * np.log(n_eff)
    sel = np.flatnonzero((path[:, int(np.argmin(bic))] != 0) & ok)
    cols = {int(i): sel[owner[sel] == i] for i in np.unique(owner[sel])}
    log.debug("discovery: lasso kept %d of %d columns in %s", sel.size, zf.shape[1],
              [groups[i].key for i in cols])
    return cols


def _forward_selection(gram: _Gram, cols: dict[int, np.ndarray], max_terms: int,
                       min_gain: float) -> list[int]:
    """Held-out scoring (step 3): the kept groups, best alone first, each added when it
    lowers the validation RMSE by more than ``min_gain``."""
    chosen: list[int] = []
    for i in sorted(cols, key=lambda i: gram.val_rmse(cols[i])[0]):
        if len(chosen) < max_terms and gram.gains(cols, chosen + [i])[-1] > min_gain:
            chosen.append(i)
    return chosen


def _fewest_variants(gram: _Gram, groups: Sequence[Group], cols: dict[int, np.ndarray],
                     chosen: Sequence[int], start: np.ndarray, min_gain: float) -> None:
    """Of each chosen group's variants (plain, × load, × speed) on its selected bases,
    the fewest that do (nearly) as well on the validation rows: ``cols`` updated."""
    for i in chosen:
        g = groups[i]
        split = [_split_name(nm) for nm in g.names]
        bases = {split[j - start[i]][0] for j in cols[i]}
        variants = sorted({v for _, v in split})
        cand = []
        for m in range(1, len(variants) + 1):
            for combo in combinations(variants, m):
                idx = np.array([start[i] + j for j, (b, v) in enumerate(split)
                                if b in bases and v in combo], int)
                others = _joint(cols, [k for k in chosen if k != i])
                cand.append((m, gram.val_rmse(np.concatenate([others, idx]))[0], idx))
        best = min(c[1] for c in cand)
        cols[i] = min((c for c in cand if c[1] <= best * (1 + 0.5 * min_gain)),
                      key=lambda c: (c[0], c[1]))[2]


def _proposals(gram: _Gram, groups: Sequence[Group], cols: dict[int, np.ndarray],
               kept: Sequence[int], start: np.ndarray, sd: np.ndarray) -> list[Proposal]:
    """Words (step 4): each kept group described from its coefficients in the joint fit
    of all kept groups (in the data's units), with its held-out gain."""
    final_gain = dict(zip(kept, gram.gains(cols, kept), strict=True))
    idx = _joint(cols, kept)
    coef = dict(zip(idx.tolist(), (gram.val_rmse(idx)[1] / sd[idx]).tolist(), strict=True))
    out = []
    for i in kept:
        g = groups[i]
        cg = {nm: coef.get(int(start[i]) + j, 0.0) for j, nm in enumerate(g.names)}
        expr, params = g.describe(cg)
        params = {**params, "selected_columns": [g.names[j - start[i]] for j in cols[i]]}
        out.append(Proposal(expr, params, final_gain[i], g.kind))
    return out


def discover(target: np.ndarray, groups: Sequence[Group], fit: np.ndarray,
             validation: np.ndarray, projector: Projector | None = None, *,
             max_terms: int = 5, min_gain: float = MIN_GAIN) -> list[Proposal]:
    """Select groups sparsely on the fit rows, score them on the validation rows (steps
    2-4 of docs/calibration.md, "Discovery beyond the library";
    ``sklearn.linear_model.lars_path_gram``; τ_int of the residual
    of all candidate columns fitted together, Sokal's window).

    Parameters
    ----------
    target : ndarray, shape (n_rows,)
        The data (with ``projector`` holding the final model) or the final residual.
    fit, validation : ndarray of int
        Row indices (disjoint).
    projector : Projector, optional
        Nuisance projected off the target and the columns, step 1 of
        docs/calibration.md, "Discovery beyond the library".
    max_terms : int, default 5
        At most this many proposals.
    min_gain : float, default :data:`MIN_GAIN`
        Held-out gain (relative RMSE drop) a proposal must exceed.

    Returns
    -------
    list of Proposal
        In the order they were added (largest gain first, then conditional gains).

    Raises
    ------
    ValueError
        ``max_terms`` < 0 or ``min_gain`` outside [0, 1).
    """
    if max_terms < 0:
        raise ValueError(f"max_terms must be >= 0, got {max_terms}")
    if not 0 <= min_gain < 1:
        raise ValueError(f"min_gain must lie in [0, 1), got {min_gain}")
    groups = [g for g in groups if g.columns.shape[1]]
    if not groups or max_terms == 0:
        return []
    r, z, sd, ok = _standardised(target, groups, fit, projector)
    owner = np.concatenate([np.full(g.columns.shape[1], i) for i, g in enumerate(groups)])
    start = np.searchsorted(owner, np.arange(len(groups)))
    zf, zv, rf, rv = z[fit], z[validation], r[fit], r[validation]
    gram = _Gram(zf.T @ zf, zf.T @ rf, zv.T @ zv, zv.T @ rv, rv, rv.size)
    cols = _lasso_columns(zf, rf, gram, ok, owner, groups)
    chosen = _forward_selection(gram, cols, max_terms, min_gain)
    _fewest_variants(gram, groups, cols, chosen, start, min_gain)
    kept = [i for i, gn in zip(chosen, gram.gains(cols, chosen), strict=True) if gn > min_gain]
    if not kept:
        return []
    return _proposals(gram, groups, cols, kept, start, sd)


def model_design(result: CalibrationResult) -> tuple[np.ndarray, Any]:
    """Linear design of the final model at its fitted nonlinear parameters, shape (n, k)
    on all samples, and the signals after its transforms (applied in order, as in
    :func:`~.core.fit_terms`)."""
    s = result.problem.signals
    cols = []
    for t, th in zip(result.final.terms, result.final.thetas, strict=True):
        th = np.asarray(th, float)
        if t.is_transform:
            s = t.transform(s, th)
            continue
        if t.n_linear:
            c = np.asarray(t.columns(s, th), float)
            cols.append(c[:, None] if c.ndim == 1 else c)
    n = result.problem.y.size
    return (np.hstack(cols) if cols else np.zeros((n, 0))), s


# ---------------------------------------------------------------------------------------
# generic column builders


def _block_fit(r: np.ndarray, phases: Sequence[np.ndarray], block: np.ndarray,
               n_blocks: int) -> tuple[np.ndarray, np.ndarray]:
    """Least squares of r on [1, cos φ_1, sin φ_1, ..., cos φ_H, sin φ_H] in every block.

    Returns the sum of squares the sinusoids explain beyond the block mean, shape
    (n_blocks,), and their complex amplitudes a_h − i b_h (r ≈ Σ_h a_h cos φ_h +
    b_h sin φ_h = Re Σ_h (a_h − i b_h) e^{iφ_h}), shape (n_blocks, H)."""
    x = [np.ones_like(r)] + [f(p) for p in phases for f in (np.cos, np.sin)]
    m = len(x)
    g, b = np.empty((n_blocks, m, m)), np.empty((n_blocks, m))
    for i in range(m):
        b[:, i] = np.bincount(block, weights=x[i] * r, minlength=n_blocks)
        for j in range(i, m):
            g[:, i, j] = g[:, j, i] = np.bincount(block, weights=x[i] * x[j],
                                                  minlength=n_blocks)
    sc = np.sqrt(np.maximum(np.einsum("bii->bi", g), 1e-300))
    gs = g / sc[:, :, None] / sc[:, None, :] + 1e-10 * np.eye(m)
    c = np.linalg.solve(gs, (b / sc)[..., None])[..., 0] / sc
    ess = np.einsum("bi,bi->b", c, b) - b[:, 0] ** 2 / np.maximum(g[:, 0, 0], 1.0)
    return ess, c[:, 1::2] - 1j * c[:, 2::2]


def line_spectrum(r: np.ndarray, coord: np.ndarray, block: np.ndarray,
                  grid: np.ndarray, harmonics: Sequence[int] = (1,)) -> np.ndarray:
    """P(k) = Σ_blocks sum of squares explained by least squares of r on [1, cos h k x,
    sin h k x for h in ``harmonics``], each block with its own phases and mean.

    x: phase coordinate per sample (input angle [rad] for orders k, 2π t for frequencies
    k [Hz]); block: e.g. window × 5 + channel; shapes (n,), grid (n_grid,) -> (n_grid,)
    [(data units)²]. Least squares, not a Fourier sum: in short blocks (40 ms holds two
    periods of 50 Hz) the sinusoids are not orthogonal and a Fourier peak is pulled off
    the line by the tone's own harmonics (measured: 49.5 Hz for 50 Hz with its third
    harmonic, noise free), hence harmonics fitted jointly when refining. One phase per
    block: a tone whose phase changes from block to block still peaks.
    """
    _, blk = np.unique(block, return_inverse=True)
    n_b = int(blk.max()) + 1
    r = np.asarray(r, float)
    return np.array([_block_fit(r, [h * k * coord for h in harmonics], blk, n_b)[0].sum()
                     for k in grid])


def spectral_peaks(r: np.ndarray, coord: np.ndarray, block: np.ndarray, lo: float,
                   hi: float, step: float, lobe: float, n_peaks: int = 2,
                   n_harmonics: int = 4) -> list[float]:
    """The ``n_peaks`` strongest lines of :func:`line_spectrum` [orders or Hz].

    Local maxima of the single-sinusoid spectrum on the grid ``lo:hi:step``, strongest
    first; one within ``lobe`` (half width of a line's main lobe, 1 / window length in
    cycles) of an earlier line or of its harmonics 2..``n_harmonics`` is skipped; each
    kept one is refined within ± lobe / 4 (two stages of 21 points, to lobe / 800) with
    harmonics 1..``n_harmonics`` fitted jointly.
    """
    grid = np.arange(lo, hi + 0.5 * step, step)
    p = line_spectrum(r, coord, block, grid)
    loc = np.flatnonzero((p >= np.r_[-np.inf, p[:-1]]) & (p >= np.r_[p[1:], -np.inf]))
    out: list[float] = []
    for i in loc[np.argsort(-p[loc])]:
        k = float(grid[i])
        near = any(abs(k - h * f) < lobe for f in out for h in range(1, n_harmonics + 1))
        if near:
            continue
        for half in (lobe / 4, lobe / 80):  # two stages of 21 points: lobe / 800 steps
            fine = np.linspace(k - half, k + half, 21)
            k = float(fine[int(np.argmax(line_spectrum(r, coord, block, fine,
                                                       range(1, n_harmonics + 1))))])
        out.append(k)
        if len(out) >= n_peaks:
            break
    return out


def tone_group(key: str, kind: str, value: float, coord: np.ndarray, r: np.ndarray,
               window: np.ndarray, channel: np.ndarray, n_channels: int,
               fit: np.ndarray, harmonics: Sequence[int],
               modulators: Mapping[str, np.ndarray],
               describe: Callable[[dict[str, float]], tuple[str, dict[str, Any]]]) -> Group:
    """Group of a tone at ``value`` (order [-] or frequency [Hz]; ``coord`` the phase
    coordinate per row) and its harmonics, one phase per window and harmonic.

    The residual's complex amplitudes z_wc (least squares per window w and channel c,
    harmonics jointly) are modelled as s_w u_c, u the channel pattern (principal
    singular vector over the fit windows), s_w = Σ_c conj(u_c) z_wc: a nuisance phase
    from the window's own residual. Columns on the rows of channel c: cos(h value x +
    arg s_w), sin(·) and their products with each of ``modulators`` (name -> per-row
    factor, e.g. the load [N m]), named ``"h{h}_{c}_{cos|sin}[_x_{modulator}]"``.
    """
    n_w = int(window.max()) + 1
    blk = window * n_channels + channel
    fit_w = np.unique(window[fit])
    cols, names = [], []
    amps = _block_fit(np.asarray(r, float), [h * value * coord for h in harmonics], blk,
                      n_w * n_channels)[1]
    for j, h in enumerate(harmonics):
        th = h * value * coord
        z = amps[:, j].reshape(n_w, n_channels)
        _, _, vh = np.linalg.svd(z[fit_w], full_matrices=False)
        phase = np.angle(z @ vh[0].conj())  # s_w = Σ_c conj(u_c) z_wc, u = vh[0]
        ph = th + phase[window]
        for c in range(n_channels):
            m = (channel == c).astype(float)
            for nm, f in (("cos", np.cos(ph)), ("sin", np.sin(ph))):
                cols.append(m * f)
                names.append(f"h{h}_{c}_{nm}")
                for mn, mv in modulators.items():
                    cols.append(m * f * mv)
                    names.append(f"h{h}_{c}_{nm}_x_{mn}")
    return Group(key, kind, np.column_stack(cols), tuple(names), describe)


# ---------------------------------------------------------------------------------------
# report


def proposals_section(summary: Mapping[str, Any]) -> list[str]:
    """Markdown lines of the report section "Proposed terms (not in the library)".

    Parameters
    ----------
    summary : mapping
        Its ``proposed``: :meth:`Proposal.as_dict` entries (none when absent).
    """
    proposed = summary.get("proposed", [])
    lines = ["## Proposed terms (not in the library)", "",
             "Not part of the fitted model. Candidate terms from a generic basis (strain: "
             "crosstalk between channels; friction: ripples over the joint angle and velocity "
             "laws; both: tones at a free order or a fixed frequency with harmonics, "
             "products with load and speed, slow trends), selected by a lasso on the fit "
             "data beside the final model and kept when they lower the validation RMSE "
             f"(held-out gain) by more than {100 * MIN_GAIN:g} % "
             "(swgcal.discovery).", ""]
    if not proposed:
        return lines + ["None.", ""]
    return lines + [md_table(["proposed term", "held-out gain"],
                             [[p["expression"].replace("|", "/"),
                               f"{100 * float(p['heldout_gain']):.1f} %"] for p in proposed]),
                    ""]
