"""The k-shot split of a held-out gear: labelled pool and evaluation windows.

For the held-out gear of a leave-one-gear-out split, a seeded draw picks, per class,
whole fault *variants* until they hold at least ``max(k_shots)`` windows: the *pool*.
The k labelled windows of a class are the first k of a seeded permutation of its pool
windows (so the k = 1 windows are among the k = 5 ones). Every model, k = 0 included, is
evaluated on the same remaining windows of the gear (other variants), so accuracies are
comparable across k; the pool's windows (labels dropped) are also the unlabelled target
data of the unsupervised adaptations (:mod:`learn.learners.adapt`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd


@dataclass(frozen=True)
class KShotSplit:
    """Labelled pool and evaluation windows of a held-out gear.

    Attributes
    ----------
    pool : ndarray of int
        Positions (rows of the input) of the windows set aside for fine-tuning.
    evaluation : ndarray of int
        Positions of the windows every model is scored on: the gear's other windows.
    order : dict of str to ndarray of int
        Per class, the pool positions in draw order.
    pool_groups : set of (str, int)
        (fault, variant) of the pool.
    """

    pool: np.ndarray
    evaluation: np.ndarray
    order: dict[str, np.ndarray]
    pool_groups: frozenset

    def shots(self, k: int) -> np.ndarray:
        """Positions of the k labelled windows per class (nested in k)."""
        if k <= 0:
            return np.array([], dtype=np.int64)
        short = [c for c, o in self.order.items() if len(o) < k]
        if short:
            raise ValueError(f"the pool holds fewer than k={k} windows of classes {short}")
        return np.sort(np.concatenate([o[:k] for o in self.order.values()]))


def kshot_split(meta: pd.DataFrame, target: np.ndarray, k_max: int, seed: int) -> KShotSplit:
    """Split the windows of a held-out gear into a labelled pool and evaluation windows.

    Parameters
    ----------
    meta : pandas.DataFrame
        Per-window metadata (columns ``fault``, ``variant``), rows = input positions.
    target : ndarray of int
        Positions of the held-out gear's windows (a leave-one-gear-out test split).
    k_max : int
        Largest k; the pool holds at least k_max windows of every class.
    seed : int
        Seed of the variant draw and of the window order.

    Returns
    -------
    KShotSplit

    Raises
    ------
    ValueError
        If a class has too few windows for ``k_max`` while leaving one variant for
        evaluation.
    """
    target = np.asarray(target, dtype=np.int64)
    sub = meta.iloc[target]
    rng = np.random.default_rng([int(seed), int(sub["gear"].iloc[0]) if "gear" in sub else 0])
    pool, order, groups = [], {}, set()
    faults = sub["fault"].astype(str).to_numpy()
    variants = sub["variant"].to_numpy()
    for c in sorted(set(faults)):
        in_c = faults == c
        vs = rng.permutation(np.unique(variants[in_c]))
        chosen, n = [], 0
        for v in vs:
            if n >= k_max:
                break
            chosen.append(v)
            n += int(np.sum(in_c & (variants == v)))
        if k_max > 0 and (n < k_max or len(chosen) == len(vs)):
            raise ValueError(
                f"class {c!r} of the held-out gear has too few windows for k={k_max} with "
                f"variants left for evaluation ({len(vs)} variants, {int(in_c.sum())} windows)")
        pos = target[in_c & np.isin(variants, chosen)]
        order[c] = rng.permutation(pos)
        pool.append(pos)
        groups.update((c, int(v)) for v in chosen)
    pool_arr = np.sort(np.concatenate(pool)) if pool else np.array([], dtype=np.int64)
    evaluation = np.setdiff1d(target, pool_arr)
    return KShotSplit(pool_arr, evaluation, order, frozenset(groups))


def check_no_leak(meta: pd.DataFrame, train: np.ndarray, kshot: KShotSplit) -> None:
    """Raise if evaluation windows meet the training or pool windows, a variant of the
    pool is evaluated, or the held-out gear is in training.

    Raises
    ------
    ValueError
        Naming the leak.
    """
    ev = kshot.evaluation
    if np.intersect1d(ev, train).size or np.intersect1d(ev, kshot.pool).size:
        raise ValueError("k-shot split leaks: evaluation windows in training or pool")
    groups = set(zip(meta["fault"].astype(str).to_numpy()[ev],
                     meta["variant"].to_numpy()[ev].astype(int).tolist(), strict=True))
    if groups & set(kshot.pool_groups):
        raise ValueError("k-shot split leaks: a pool variant is also evaluated")
    if set(meta["gear"].to_numpy()[train]) & set(meta["gear"].to_numpy()[ev]):
        raise ValueError("leave-one-gear-out split leaks: the target gear is in training")
