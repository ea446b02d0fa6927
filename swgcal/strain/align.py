"""How well a window's input angle is known from its own data.

The torque ripple's dominant order 2 repeats every half revolution, so a window's input
angle φ_in is known modulo 180° unless the odd orders rise above the noise.
:func:`input_angle_evidence` gives per window (and for the global flip an odd
kinematic-error harmonic brings, :func:`flipped_ke`) the log-likelihood ratio of the chosen
alignment against the one half a revolution away; above ``min_evidence`` (10) φ_in is
reported modulo 360° (:class:`InputAngle`). Derivation and measurements:
docs/calibration.md, "How well a window's input angle is known".
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["InputAngle", "input_angle_evidence", "flipped_ke"]


def flipped_ke(ke: Sequence[tuple[int, float, float]]) -> tuple[tuple[int, float, float], ...]:
    """Extra kinematic-error harmonics seen from an input angle shifted by 180°:
    ``(k, a_sin, a_cos) -> (k, (−1)^k a_sin, (−1)^k a_cos)``."""
    return tuple((int(k), float(a) * (-1) ** int(k), float(b) * (-1) ** int(k))
                 for k, a, b in ke)


@dataclass(frozen=True)
class InputAngle:
    """How well each window's input angle is known.

    Attributes
    ----------
    flip_evidence : ndarray, shape (n_w,)
        2 ln Λ of the chosen torque shift against the best one half an input revolution
        away [-].
    period_deg : ndarray, shape (n_w,)
        360 where the evidence exceeds the threshold, else 180: φ_in is known modulo this.
    se_deg : ndarray, shape (n_w,)
        Standard error of φ_in from the objective's curvature [deg].
    global_evidence : float
        2 ln Λ against flipping every window together with the odd extra harmonics
        (NaN when not scored: no odd extra harmonic).
    """

    flip_evidence: np.ndarray
    period_deg: np.ndarray
    se_deg: np.ndarray
    global_evidence: float = float("nan")

    def reported(self, phi_deg: np.ndarray) -> np.ndarray:
        """φ_in modulo the period it is known to [deg], shape (n_w,)."""
        return np.mod(np.asarray(phi_deg, float), self.period_deg)


def input_angle_evidence(objectives: Sequence[np.ndarray], fs: float,
                         n_in_rpm: np.ndarray, sigma2: float, min_evidence: float = 10.0,
                         flipped: Sequence[np.ndarray] | None = None) -> InputAngle:
    """Evidence that each window's input angle is known modulo 360°, not only 180°.

    Parameters
    ----------
    objectives : sequence of ndarray
        Per window, the torque-alignment objective J over shifts of 0, 1, ... samples
        covering at least one input revolution [(mV/V)²] (``Realigner.objectives`` of
        :mod:`.model`).
    fs : float
        Sample rate [Hz].
    n_in_rpm : ndarray, shape (n_w,)
        Input speed of each window [rpm].
    sigma2 : float
        Residual variance per sample [(mV/V)²], times the integrated autocorrelation
        time where the residual is coloured.
    min_evidence : float, default 10
        2 ln Λ above which the chosen peak is taken as decided.
    flipped : sequence of ndarray, optional
        The objectives with the odd extra kinematic-error harmonics flipped
        (:func:`flipped_ke`), to score the global flip.

    Raises
    ------
    ValueError
        ``sigma2`` not positive, or an objective shorter than one input revolution.
    """
    if not sigma2 > 0:
        raise ValueError(f"sigma2 must be > 0 [(mV/V)^2], got {sigma2}")
    n_in = np.asarray(n_in_rpm, float)
    ev = np.empty(len(objectives))
    se = np.empty(len(objectives))
    glob = 0.0
    for w, obj in enumerate(objectives):
        obj = np.asarray(obj, float)
        period = 60.0 / n_in[w] * fs  # samples per input revolution
        if obj.size < period:
            raise ValueError(f"objective of window {w} covers {obj.size} samples, less than "
                             f"one input revolution ({period:.1f})")
        j = int(np.argmax(obj))
        d = np.abs(np.arange(obj.size) - j) % period
        d = np.minimum(d, period - d)
        ev[w] = (obj[j] - obj[d > period / 4].max()) / sigma2
        if flipped is not None:
            glob += (obj[j] - np.asarray(flipped[w], float)[:obj.size][d > period / 4].max()
                     ) / sigma2
        # curvature at the peak, or at the same phase one revolution on (edge of the range)
        jc = next((k for k in (j, j + round(period), j - round(period))
                   if 0 < k < obj.size - 1), j)
        curv = (obj[jc - 1] - 2 * obj[jc] + obj[jc + 1]) if 0 < jc < obj.size - 1 else 0.0
        se_j = np.sqrt(2 * sigma2 / -curv) if curv < 0 else np.inf
        se[w] = se_j / period * 360.0
    known = ev > min_evidence
    if flipped is not None:
        known &= glob > min_evidence
    return InputAngle(flip_evidence=ev, period_deg=np.where(known, 360.0, 180.0), se_deg=se,
                      global_evidence=glob if flipped is not None else float("nan"))
