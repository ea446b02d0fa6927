"""A hypothesis and a check of one's own, written outside the package as a user would
(docs/ARCHITECTURE.md, "To add a hypothesis"; not a test module): the bridges' common
excitation supply stepped, which moves every bridge's zero by one δ [mV/V]; and a
temperature reading that jumps faster than a joint's grease can warm.
"""

from __future__ import annotations

import numpy as np

from swgmon.assessment.hypotheses import Candidate, Finding, Stream, Windows
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


class ReadingJump:
    """A check of one's own (docs/ARCHITECTURE.md, "To add a hypothesis"): the reading
    jumps between two windows by more than a joint's grease can move in that time (a
    converter's glitch, a loose contact), a rate-of-change test; found at the window after
    the jump. It explains no alarm's windows by itself (no candidates)."""

    name = "reading_jump"
    max_k_per_h = 60.0  # [K/h]: a joint warms by a few K per hour at most

    def candidates(self, w: Windows) -> list[Candidate]:
        return []

    def found(self, s: Stream) -> Finding | None:
        t = s.cond.temperature_c
        if t is None or len(t) < 2 or not s.read:
            return None
        rate = np.abs(np.diff(t)) / np.maximum(np.diff(s.hours), 1e-9)
        jump = np.flatnonzero(rate > self.max_k_per_h)
        return Finding(self.name, int(jump[0]) + 1, int(jump[0]) + 1) if jump.size else None
