"""Held-out splits that cannot leak.

Samples of one recording are strongly autocorrelated, so a random split would put
near-copies of test samples into the fit. Two splits are offered:

* :func:`time_block_split` cuts a recording into contiguous blocks in time; every block
  has one role (fit, validation, test) and a guard interval around each boundary between
  roles is dropped, so slow states (hysteresis, drift, lags) and coloured noise cannot
  carry information across. The default roles hold out the last block for the test, so
  a drift term must extrapolate: the honest check for drift.
* :func:`group_split` holds out whole groups (recordings, operating points, windows of a
  strain data set) by label.

Validation samples choose the effects (model selection); test samples are touched only
once, for the errors reported before and after.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["HeldOutSplit", "PAUSE_STEPS", "group_split", "recorded_time", "time_block_split"]


@dataclass(frozen=True)
class HeldOutSplit:
    """Indices of the fit, validation and test samples (disjoint, sorted).

    Attributes
    ----------
    fit, validation, test : ndarray of int
    description : dict
        JSON-serialisable account of how the held-out data were chosen.
    """

    fit: np.ndarray
    validation: np.ndarray
    test: np.ndarray
    description: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for a, b in ((self.fit, self.validation), (self.fit, self.test),
                     (self.validation, self.test)):
            if np.intersect1d(a, b).size:
                raise ValueError("split sets overlap")
        for name in ("fit", "validation", "test"):
            if getattr(self, name).size == 0:
                raise ValueError(f"split has no {name} samples; change the block roles")

    @property
    def fit_validation(self) -> np.ndarray:
        """Fit and validation samples together (the final refit)."""
        return np.union1d(self.fit, self.validation)


#: A step of the time stamps over this many median sample intervals is a pause between
#: sessions, not a logger's hiccup [choice: the six real friction recordings' largest
#: step is 6.5 median intervals].
PAUSE_STEPS = 50.0


def recorded_time(t: np.ndarray) -> np.ndarray:
    """Time with every pause (a step over :data:`PAUSE_STEPS` median intervals) shortened
    to one median interval: the time over which something was recorded.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Time stamps [s], increasing.

    Returns
    -------
    ndarray, shape (n,)
        ``t`` itself where there is no pause; otherwise from ``t[0]`` on, pauses shortened [s].
    """
    t = np.asarray(t, float)
    if t.size < 3:
        return t
    d = np.diff(t)
    m = float(np.median(d))
    pause = d > PAUSE_STEPS * m
    if not pause.any():
        return t
    return t[0] + np.concatenate([[0.0], np.cumsum(np.where(pause, m, d))])


def time_block_split(
    t: np.ndarray,
    n_blocks: int = 10,
    validation_blocks: Sequence[int] = (3, 7),
    test_blocks: Sequence[int] = (5, 9),
    guard_frac: float = 0.05,
) -> HeldOutSplit:
    """Split one time series into contiguous blocks with roles and guard gaps.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Time [s], increasing.
    n_blocks : int, default 10
        Blocks of equal recorded duration (pauses between sessions shortened,
        :func:`recorded_time`).
    validation_blocks, test_blocks : sequence of int
        Block indices (0-based; negative counts from the end) for validation and test;
        the others are fit blocks.
    guard_frac : float, default 0.05
        At every boundary between blocks of different roles, samples closer than
        ``guard_frac`` block durations to the boundary are dropped from all sets.

    Raises
    ------
    ValueError
        ``n_blocks`` < 3, a block index outside [−n_blocks, n_blocks), a block in both
        role lists, ``guard_frac`` outside [0, 0.45], or a role left without samples.
    """
    t = np.asarray(t, float)
    if n_blocks < 3:
        raise ValueError(f"n_blocks must be >= 3, got {n_blocks}")
    if not 0 <= guard_frac <= 0.45:
        raise ValueError(f"guard_frac must be in [0, 0.45], got {guard_frac}")

    def norm(blocks: Sequence[int], what: str) -> list[int]:
        out = []
        for b in blocks:
            if not -n_blocks <= int(b) < n_blocks:
                raise ValueError(f"{what} block {b} outside [-{n_blocks}, {n_blocks})")
            out.append(int(b) % n_blocks)
        return sorted(set(out))

    val = norm(validation_blocks, "validation")
    test = norm(test_blocks, "test")
    if set(val) & set(test):
        raise ValueError(f"blocks {sorted(set(val) & set(test))} are both validation and test")
    role = np.zeros(n_blocks, int)  # 0 fit, 1 validation, 2 test
    role[val] = 1
    role[test] = 2
    t = recorded_time(t)
    t0, t1 = float(t[0]), float(t[-1])
    edges = np.linspace(t0, t1, n_blocks + 1)
    blk = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, n_blocks - 1)
    guard = guard_frac * (t1 - t0) / n_blocks
    keep = np.ones(t.size, bool)
    for i in range(1, n_blocks):
        if role[i] != role[i - 1]:
            keep &= np.abs(t - edges[i]) >= guard
    r = role[blk]
    names = ("fit", "validation", "test")
    desc = {
        "method": "contiguous time blocks with guard gaps (over the recorded time: "
                  "pauses between sessions shortened)",
        "n_blocks": n_blocks,
        "validation_blocks": val,
        "test_blocks": test,
        "guard_s": guard,
        "block_s": (t1 - t0) / n_blocks,
        "time_ranges_s": {
            names[k]: [[float(edges[i]), float(edges[i + 1])] for i in range(n_blocks)
                       if role[i] == k] for k in range(3)},
        "n_samples": {names[k]: int(np.sum(keep & (r == k))) for k in range(3)},
        "n_dropped_guard": int(np.sum(~keep)),
        "note": ("validation blocks choose the effects, test blocks are used only for the "
                 "errors before/after; the final models are refitted on fit + validation"),
    }
    return HeldOutSplit(np.flatnonzero(keep & (r == 0)), np.flatnonzero(keep & (r == 1)),
                        np.flatnonzero(keep & (r == 2)), desc)


def group_split(
    groups: np.ndarray,
    validation_groups: Sequence[Any],
    test_groups: Sequence[Any],
) -> HeldOutSplit:
    """Hold out whole groups (recordings, operating points) by label.

    Parameters
    ----------
    groups : ndarray, shape (n,)
        Group label of every sample.
    validation_groups, test_groups : sequence
        Labels held out for validation and for the test.

    Raises
    ------
    ValueError
        A label that does not occur, or a label in both lists.
    """
    groups = np.asarray(groups)
    present = set(np.unique(groups).tolist())
    for what, gs in (("validation", validation_groups), ("test", test_groups)):
        unknown = [g for g in gs if g not in present]
        if unknown:
            raise ValueError(f"{what} groups {unknown} not in the data ({sorted(present)})")
    both = set(validation_groups) & set(test_groups)
    if both:
        raise ValueError(f"groups {sorted(both)} are both validation and test")
    v = np.isin(groups, list(validation_groups))
    te = np.isin(groups, list(test_groups))
    desc = {"method": "whole groups held out", "validation_groups": list(validation_groups),
            "test_groups": list(test_groups),
            "n_samples": {"fit": int(np.sum(~v & ~te)), "validation": int(v.sum()),
                          "test": int(te.sum())}}
    return HeldOutSplit(np.flatnonzero(~v & ~te), np.flatnonzero(v), np.flatnonzero(te), desc)
