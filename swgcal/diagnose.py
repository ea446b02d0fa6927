"""Residual diagnosis: is the residual structured, and along what?

Each *probe* is a small nonparametric model of the residual along one signature
variable (velocity, position, time, acceleration, ...). It is fitted on half of the
samples and scored on the other half, the halves being made of contiguous blocks in time
(so autocorrelated noise cannot fake structure; blocks assigned by a fixed random
permutation so that periodic structure is not aliased), then the other way round. The
score is the out-of-sample fraction of the residual's mean square the probe explains:
about −(bins / samples) for noise, clearly positive for structure. A residual is called
*structured* when any probe scores above a threshold (default 0.03), or when it fails
the whiteness test against its noise floor (:func:`whiteness`: RMS above
:data:`WHITENESS_RATIO` times the noise floor) even if no probe explains it; the
signature text names the probes that fire, with their detail (period, amplitude,
direction symmetry), and the test's figure.

The noise floor is estimated by the difference-based estimator of Gasser, Sroka &
Jennen-Steinmetz (1986) on irregular samples: σ² from pseudo-residuals of linear
interpolation between neighbours. It removes smooth structure but not coloured noise,
which it underestimates (AR(1) with coefficient ρ: by a factor about sqrt(1 − 4ρ/3)).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .core import integrated_autocorr_time
from .periodogram import periodogram_peaks
from .split import recorded_time

log = logging.getLogger(__name__)

__all__ = [
    "WHITENESS_RATIO",
    "whiteness",
    "acf_and_periodogram",
    "Probe",
    "BinnedProbe",
    "PeriodicProbe",
    "TrendProbe",
    "ProbeResult",
    "Diagnosis",
    "diagnose",
    "noise_floor",
]


# ---------------------------------------------------------------------------------------
# probes


class Probe:
    """A nonparametric residual model along one variable. Subclasses implement
    :meth:`fit_predict`.

    Attributes
    ----------
    name : str
        Key (``"velocity"``).
    label : str
        Human description of the variable, used in the signature text.
    """

    name = "probe"
    label = ""

    def fit_predict(self, sig: Any, r: np.ndarray, ia: np.ndarray,
                    ib: np.ndarray) -> tuple[np.ndarray, dict[str, Any]]:
        """Fit on samples ``ia``, predict the residual on ``ib``.

        Returns
        -------
        pred : ndarray, shape (len(ib),)
        detail : dict
            Fitted summary (period, amplitude, ...), from the fit on ``ia``.
        """
        raise NotImplementedError

    def describe(self, detail: dict[str, Any], units: str) -> str:
        return self.label


def _sign_of(sig: Any) -> np.ndarray:
    return np.sign(getattr(sig, "v_eff", getattr(sig, "dq_rad_s", None)))


class BinnedProbe(Probe):
    """Bin means of the residual over a variable (quantile bins from the fit half).

    Parameters
    ----------
    key : callable sig -> ndarray (n,)
        The variable.
    odd : bool
        Model r = sgn(q̇) g(x) (odd in the direction of motion) instead of r = g(x).
    split_by : callable sig -> ndarray (n,) of int, optional
        A second, categorical key (e.g. sign of q̈): separate bins per category.
    """

    def __init__(self, name: str, label: str, key: Callable[[Any], np.ndarray],
                 n_bins: int = 30, odd: bool = False,
                 split_by: Callable[[Any], np.ndarray] | None = None) -> None:
        self.name, self.label, self.key = name, label, key
        self.n_bins, self.odd, self.split_by = n_bins, odd, split_by

    def fit_predict(self, sig, r, ia, ib):
        x = self.key(sig)
        s = _sign_of(sig) if self.odd else np.ones_like(r)
        cat = self.split_by(sig) if self.split_by is not None else np.zeros(r.size, int)
        edges = np.unique(np.quantile(x[ia], np.linspace(0, 1, self.n_bins + 1)))
        if edges.size < 2:
            return np.zeros(ib.size), {}
        nb = edges.size - 1
        cats = np.unique(cat[ia])
        ba = np.clip(np.searchsorted(edges, x[ia], side="right") - 1, 0, nb - 1)
        bb = np.clip(np.searchsorted(edges, x[ib], side="right") - 1, 0, nb - 1)
        means = np.zeros((cats.size, nb))
        counts = np.zeros((cats.size, nb))
        ra = r[ia] * s[ia]
        for ci, c in enumerate(cats):
            m = cat[ia] == c
            counts[ci] = np.bincount(ba[m], minlength=nb)
            sums = np.bincount(ba[m], weights=ra[m], minlength=nb)
            means[ci] = np.where(counts[ci] > 0, sums / np.maximum(counts[ci], 1), 0.0)
        ci_b = np.searchsorted(cats, cat[ib]).clip(0, cats.size - 1)
        known = cats[ci_b] == cat[ib]
        pred = np.where(known, means[ci_b, bb], 0.0) * s[ib]
        centres = 0.5 * (edges[:-1] + edges[1:])
        w = counts.sum(axis=0)
        g = (means * counts).sum(axis=0) / np.maximum(w, 1)
        j = int(np.argmax(np.abs(g)))
        detail = {"peak_value": float(g[j]), "peak_at": float(centres[j]),
                  "range": float(np.ptp(g))}
        if cats.size == 2:
            detail["loop_gap"] = float(np.mean(np.abs(means[1] - means[0])))
        if not self.odd and getattr(sig, "v_eff", None) is not None:
            sv = _sign_of(sig)[ia]
            pos, neg = r[ia][sv > 0], r[ia][sv < 0]
            if pos.size and neg.size:
                detail["mean_pos_dir"] = float(pos.mean())
                detail["mean_neg_dir"] = float(neg.mean())
        return pred, detail

    def describe(self, detail, units):
        txt = self.label
        if "peak_value" in detail:
            txt += (f" (largest bin mean {detail['peak_value']:+.3g} {units} at "
                    f"{detail['peak_at']:.3g})")
        if "loop_gap" in detail:
            txt += f", mean gap between the branches {detail['loop_gap']:.3g} {units}"
        if "mean_pos_dir" in detail:
            p, m = detail["mean_pos_dir"], detail["mean_neg_dir"]
            txt += (f"; mean {p:+.3g} {units} moving +, {m:+.3g} {units} moving −")
        return txt


class PeriodicProbe(Probe):
    """Best sinusoid over a coordinate (period from a Lomb-Scargle periodogram of the
    fit half), optionally odd in the direction of motion.

    Parameters
    ----------
    coord : callable sig -> ndarray (n,)
    period_range : callable sig -> (p_min, p_max)
    unit : str
        Unit of the coordinate (for the text).
    wg_order : bool, default False
        The coordinate is the output angle [rad]: with the signals' ``gear_ratio`` N the
        period is also given as the wave-generator order k = 2π / (period · N).
    """

    def __init__(self, name: str, label: str, coord: Callable[[Any], np.ndarray],
                 period_range: Callable[[Any], tuple[float, float]], odd: bool = False,
                 unit: str = "", wg_order: bool = False) -> None:
        self.name, self.label, self.coord = name, label, coord
        self.period_range, self.odd, self.unit = period_range, odd, unit
        self.wg_order = wg_order

    def fit_predict(self, sig, r, ia, ib):
        x = self.coord(sig)
        s = _sign_of(sig) if self.odd else np.ones_like(r)
        lo, hi = self.period_range(sig)
        peaks = periodogram_peaks(x[ia], r[ia] * s[ia], lo, hi, n_peaks=1)
        if not peaks:
            return np.zeros(ib.size), {}
        p = peaks[0][0]
        w = 2 * np.pi / p

        def cols(i):
            return np.column_stack([s[i] * np.sin(w * x[i]), s[i] * np.cos(w * x[i]), s[i]])

        c, *_ = np.linalg.lstsq(cols(ia), r[ia], rcond=None)
        detail = {"period": float(p), "amplitude": float(np.hypot(c[0], c[1]))}
        n_ratio = getattr(sig, "gear_ratio", None) if self.wg_order else None
        if n_ratio:
            detail["order"] = float(2 * np.pi / (p * n_ratio))
        return cols(ib) @ c, detail

    def describe(self, detail, units):
        if not detail:
            return self.label
        order = (f" (wave-generator order {detail['order']:.3g})" if "order" in detail
                 else "")
        return (f"{self.label}: period {detail['period']:.4g} {self.unit}{order}, amplitude "
                f"{detail['amplitude']:.3g} {units}")


class TrendProbe(Probe):
    """Smooth trend over a coordinate: polynomial of degree ``degree`` in the coordinate
    scaled to [−1, 1] (interpolates across the held-out blocks)."""

    def __init__(self, name: str, label: str, coord: Callable[[Any], np.ndarray],
                 degree: int = 3, odd: bool = False) -> None:
        self.name, self.label, self.coord = name, label, coord
        self.degree, self.odd = degree, odd

    def fit_predict(self, sig, r, ia, ib):
        x = self.coord(sig)
        s = _sign_of(sig) if self.odd else np.ones_like(r)
        lo, hi = float(np.min(x)), float(np.max(x))
        z = 2 * (x - lo) / max(hi - lo, 1e-300) - 1

        def cols(i):
            return s[i][:, None] * np.polynomial.legendre.legvander(z[i], self.degree)

        c, *_ = np.linalg.lstsq(cols(ia), r[ia], rcond=None)
        grid = np.polynomial.legendre.legval(np.array([-1.0, 1.0]), c)
        return cols(ib) @ c, {"change": float(grid[1] - grid[0])}

    def describe(self, detail, units):
        if "change" in detail:
            return f"{self.label} (change {detail['change']:+.3g} {units} end to end)"
        return self.label


# ---------------------------------------------------------------------------------------
# diagnosis


@dataclass(frozen=True)
class ProbeResult:
    """Score and detail of one probe.

    Attributes
    ----------
    score : float
        Out-of-sample fraction of the residual mean square explained (two-fold, mean).
    """

    name: str
    score: float
    detail: dict[str, Any]
    text: str

    def as_dict(self) -> dict[str, Any]:
        return {"score": self.score, "detail": self.detail, "text": self.text}


@dataclass
class Diagnosis:
    """Diagnosis of one residual.

    Attributes
    ----------
    rmse : float
        RMS of the residual on the diagnosed samples [data units].
    noise_floor : float
        Difference-based noise estimate [data units].
    tau_int : float
        Integrated autocorrelation time [samples].
    structured : bool
        Some probe explains at least ``threshold`` of the residual out of sample.
    signature : str
        Plain-text description of the structure (or of its absence).
    """

    rmse: float
    noise_floor: float
    tau_int: float
    probes: dict[str, ProbeResult] = field(default_factory=dict)
    structured: bool = False
    threshold: float = 0.03
    signature: str = ""

    def ranked(self) -> list[ProbeResult]:
        return sorted(self.probes.values(), key=lambda p: -p.score)

    def as_dict(self) -> dict[str, Any]:
        return {"rmse": self.rmse, "noise_floor": self.noise_floor, "tau_int": self.tau_int,
                "structured": self.structured, "threshold": self.threshold,
                "signature": self.signature,
                "probes": {k: v.as_dict() for k, v in self.probes.items()}}


def noise_floor(t: np.ndarray, r: np.ndarray) -> float:
    """Difference-based noise standard deviation (Gasser, Sroka & Jennen-Steinmetz 1986).

    Parameters
    ----------
    t : ndarray, shape (n,)
        Sample coordinate (time), increasing; gaps are handled by using only triples of
        consecutive samples.
    r : ndarray, shape (n,)

    Returns
    -------
    float
        σ estimate [units of r].
    """
    t = np.asarray(t, float)
    r = np.asarray(r, float)
    if t.size < 3:
        return float("nan")
    h1 = t[1:-1] - t[:-2]
    h2 = t[2:] - t[1:-1]
    a = h2 / (h1 + h2)
    b = h1 / (h1 + h2)
    e = a * r[:-2] + b * r[2:] - r[1:-1]
    c2 = 1.0 / (a * a + b * b + 1.0)
    return float(np.sqrt(np.mean(c2 * e * e)))


#: The whiteness test's limit on RMS / noise floor [-]: white noise gives 1, AR(1) noise
#: of coefficient ρ about 1 / sqrt(1 − 4ρ/3 + ρ²/3) (1.26 at ρ = 0.3, 1.55 at 0.5, 2 at
#: 0.66) [derived from the estimator's pseudo-residuals]; above 2 the residual holds more
#: slow content than mildly coloured measurement noise [choice].
WHITENESS_RATIO = 2.0


def whiteness(t: np.ndarray, r: np.ndarray, idx: np.ndarray) -> tuple[float, float, float]:
    """The whiteness test against the noise floor: RMS of ``r[idx]``, its
    difference-based noise floor (:func:`noise_floor` on runs of consecutive samples) and
    their ratio.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Time [s].
    r : ndarray, shape (n,)
        Residual [data units].
    idx : ndarray of int
        Samples tested (e.g. the held-out ones).

    Returns
    -------
    rms, floor, ratio : float
        [data units, data units, -]; the test fails where ratio > :data:`WHITENESS_RATIO`
        (NaN ratio: too few consecutive samples).
    """
    idx = np.asarray(idx)
    ra = r[idx]
    rms = float(np.sqrt(np.mean(ra * ra))) if ra.size else float("nan")
    runs = np.split(idx, np.flatnonzero(np.diff(idx) != 1) + 1)
    num, den = 0.0, 0
    for run in runs:
        if run.size >= 3:
            nf = noise_floor(t[run], r[run])
            num += nf * nf * (run.size - 2)
            den += run.size - 2
    nf = float(np.sqrt(num / den)) if den else float("nan")
    return rms, nf, rms / nf if nf > 0 else float("nan")


def acf_and_periodogram(t: np.ndarray, r: np.ndarray, idx: np.ndarray, max_lag: int = 200,
                        segment: int = 1024) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The whiteness test's views of ``r[idx]`` (docs/calibration.md, "The held-out
    whiteness test as a figure"), pooled over the runs of at least 8 consecutive samples:
    the normalised autocorrelation (a lag never crosses a run's end) and the averaged
    periodogram (Welch: segments of ``segment`` samples, or a shorter run whole).

    Parameters
    ----------
    t, r : ndarray, shape (n,)
        Time [s] and residual [data units].
    idx : ndarray of int
        Samples used, increasing.
    max_lag, segment : int
        Largest lag (at most the longest run less one), segment length [samples].

    Returns
    -------
    acf : ndarray, shape (k + 1,)
        ρ_0 = 1, ..., ρ_k of the mean-removed residual.
    freq, power : ndarray, shape (m,)
        Frequencies above 0 [Hz] (median sample spacing) and the mean of |X_f|² / L
        [(data units)²]: white noise of variance σ² gives σ² at every frequency.

    Raises
    ------
    ValueError
        No run of 8 consecutive samples.
    """
    idx = np.asarray(idx)
    runs = [u for u in np.split(idx, np.flatnonzero(np.diff(idx) != 1) + 1) if u.size >= 8]
    if not runs:
        raise ValueError("no run of 8 consecutive samples for the whiteness views")
    x = np.asarray(r, float) - float(np.mean(r[idx]))
    k = min(max_lag, max(u.size for u in runs) - 1)
    acf, segs = np.zeros(k + 1), []
    for u in runs:
        f = np.fft.rfft(x[u], 2 * u.size)
        m = min(u.size, k + 1)
        acf[:m] += np.fft.irfft(f * np.conj(f), 2 * u.size)[:m]
        segs += [u[s:s + segment] for s in range(0, u.size, segment)
                 if s == 0 or u.size - s >= segment]
    dt = float(np.median(np.concatenate([np.diff(t[u]) for u in runs])))
    freq = np.fft.rfftfreq(max(s.size for s in segs), dt)[1:]
    power = np.mean([np.interp(freq, np.fft.rfftfreq(s.size, dt)[1:], np.abs(
        np.fft.rfft(x[s] - x[s].mean())[1:]) ** 2 / s.size) for s in segs], axis=0)
    return acf / acf[0], freq, power


def _halves(t: np.ndarray, idx: np.ndarray, n_blocks: int) -> tuple[np.ndarray, np.ndarray]:
    """Two halves of ``idx`` made of contiguous time blocks assigned by a fixed random
    permutation (balanced), so that a structure periodic in time is not aliased by a
    regular alternation of blocks. Blocks cut the recorded time (pauses between sessions
    shortened, :func:`~swgcal.split.recorded_time`)."""
    tt = recorded_time(t)[idx]
    edges = np.linspace(tt.min(), tt.max(), n_blocks + 1)
    blk = np.clip(np.searchsorted(edges, tt, side="right") - 1, 0, n_blocks - 1)
    perm = np.random.default_rng(20240607).permutation(n_blocks)
    in_a = np.zeros(n_blocks, bool)
    in_a[perm[: n_blocks // 2]] = True
    return idx[in_a[blk]], idx[~in_a[blk]]


def diagnose(sig: Any, t: np.ndarray, r: np.ndarray, idx: np.ndarray,
             probes: Sequence[Probe], units: str = "", threshold: float = 0.03,
             n_blocks: int = 24) -> Diagnosis:
    """Diagnose the residual ``r`` on the samples ``idx``.

    Parameters
    ----------
    sig : object
        Signals (passed to the probes).
    t : ndarray, shape (n,)
        Time [s] (for the block halves and the noise floor).
    r : ndarray, shape (n,)
        Residual [data units]; only ``r[idx]`` is used.
    idx : ndarray of int
        Samples to diagnose.
    units : str
        Data units, for the text.
    threshold : float, default 0.03
        Score above which the residual counts as structured.
    n_blocks : int, default 24
        Contiguous time blocks, half of them (fixed random choice) form each half.

    Notes
    -----
    The residual also counts as structured when it fails the whiteness test against its
    noise floor (:func:`whiteness`, :data:`WHITENESS_RATIO`), whatever its integrated
    autocorrelation time: a ripple left in the residual oscillates, and its τ_int is small.
    """
    idx = np.asarray(idx)
    ra = r[idx]
    rmse, nf, ratio = whiteness(t, r, idx)
    ia, ib = _halves(t, idx, n_blocks)
    results = {}
    for p in probes:
        scores, detail = [], {}
        for a, b in ((ia, ib), (ib, ia)):
            try:
                pred, det = p.fit_predict(sig, r, a, b)
            except (ValueError, np.linalg.LinAlgError) as e:  # pragma: no cover
                log.debug("probe %s failed: %s", p.name, e)
                pred, det = np.zeros(b.size), {}
            ms = float(np.mean(r[b] ** 2))
            scores.append(1.0 - float(np.mean((r[b] - pred) ** 2)) / ms if ms > 0 else 0.0)
            if not detail:
                detail = det
        score = float(np.mean(scores))
        results[p.name] = ProbeResult(p.name, score, detail, p.describe(detail, units))
    diag = Diagnosis(rmse=rmse, noise_floor=nf, tau_int=integrated_autocorr_time(ra),
                     probes=results, threshold=threshold)
    top = [p for p in diag.ranked() if p.score >= threshold]
    # whiteness: a residual far above its noise floor is structured even when no probed
    # variable explains it (an oscillating residual may have a small τ_int)
    coloured = bool(ratio > WHITENESS_RATIO)
    diag.structured = bool(top) or coloured
    head = (f"RMS {rmse:.3g} {units}, {ratio:.2f}x the difference-based noise floor "
            f"{nf:.3g} {units}, τ_int {diag.tau_int:.3g} samples")
    if top:
        parts = [f"{p.text} [{100 * p.score:.0f} % of the residual mean square]"
                 for p in top[:4]]
        diag.signature = f"structured residual ({head}): " + "; ".join(parts)
        if coloured:
            diag.signature += (f"; besides, it fails the whiteness test (RMS {ratio:.2f}x "
                               f"its noise floor > {WHITENESS_RATIO:g})")
    elif coloured:
        diag.signature = (f"structured residual ({head}): it fails the whiteness test (RMS "
                          f"{ratio:.2f}x its noise floor > {WHITENESS_RATIO:g}) along none of "
                          "the probed variables: strongly coloured measurement noise, or an "
                          "effect of a variable the data do not carry")
    else:
        best = diag.ranked()[0] if results else None
        diag.signature = (f"no structure found ({head}; best probe "
                          + (f"{best.name} explains {100 * best.score:.1f} %)" if best else ")"))
    return diag
