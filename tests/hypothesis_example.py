"""A hypothesis of one's own, written outside the package as a user would
(docs/ARCHITECTURE.md, "To add a hypothesis"; not a test module): the bridges' common
excitation supply stepped, which moves every bridge's zero by one δ [mV/V].
"""

from __future__ import annotations

import numpy as np

from swgmon.assessment.hypotheses import Candidate, Windows
from swgmon.detection.laws import BLOCK


class SupplyStep:
    """One δ on the five bridges' offsets, by weighted least squares on the windows'
    z-scores (z_c = (offset_c − mean_c) / σ_c, so δ moves z_c by δ / σ_c); plausible
    where it lowers Σ z² by the χ²₁ quantile of ``naming.fit_level``."""

    name = "supply_step"

    def candidates(self, w: Windows) -> list[Candidate]:
        cols = [c * BLOCK for c in range(5)]
        inv = 1.0 / w.spread[:, cols]
        delta = float(np.sum(w.z[:, cols] * inv) / np.sum(inv ** 2))
        z = w.z.copy()
        z[:, cols] -= delta * inv
        if np.sum(w.z ** 2) - np.sum(z ** 2) < w.naming.least_reduction(1):
            return []
        return [Candidate(self.name, "supply_step", None, z)]
