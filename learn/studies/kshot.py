"""The split of a held-out gear: labelled pool, unlabelled healthy windows and evaluation
windows.

Per class a seeded draw picks whole fault *variants* until they hold at least
``max(k_shots)`` windows: the *pool*; the k labelled windows of a class are the first k
of a seeded permutation of its pool (the k = 1 windows are among the k = 5 ones). A
second draw (its own generator: the pool is the same without it) picks whole healthy
variants outside the pool until they hold ``n_unlabelled`` windows, the unsupervised
adaptations' data (:mod:`learn.learners.adapt`). Every model and k is evaluated on the
same remaining windows. Why: ``docs/learners_transfer.md``, "What was chosen on what data".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swgsim.base.lazy import lazy_module

pd = lazy_module("pandas")

#: The class whose windows a gear offers without labels (its commissioning windows).
HEALTHY = "healthy"


@dataclass(frozen=True)
class KShotSplit:
    """Labelled pool, unlabelled healthy windows and evaluation windows of a held-out gear.

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
    unlabelled : ndarray of int
        Positions of the unlabelled healthy windows: the target windows of the
        unsupervised adaptations (empty when none was asked for).
    unlabelled_groups : set of (str, int)
        (fault, variant) of the unlabelled healthy windows.
    """

    pool: np.ndarray
    evaluation: np.ndarray
    order: dict[str, np.ndarray]
    pool_groups: frozenset
    unlabelled: np.ndarray
    unlabelled_groups: frozenset

    def shots(self, k: int) -> np.ndarray:
        """Positions of the k labelled windows per class (nested in k)."""
        if k <= 0:
            return np.array([], dtype=np.int64)
        short = [c for c, o in self.order.items() if len(o) < k]
        if short:
            raise ValueError(f"the pool holds fewer than k={k} windows of classes {short}")
        return np.sort(np.concatenate([o[:k] for o in self.order.values()]))


def kshot_split(meta: pd.DataFrame, target: np.ndarray, k_max: int, seed: int, *,
                n_unlabelled: int) -> KShotSplit:
    """Split the windows of a held-out gear into a labelled pool, unlabelled healthy windows and
    evaluation windows.

    Parameters
    ----------
    meta : pandas.DataFrame
        Per-window metadata (columns ``fault``, ``variant``), rows = input positions.
    target : ndarray of int
        Positions of the held-out gear's windows (a leave-one-gear-out test split).
    k_max : int
        Largest k; the pool holds at least k_max windows of every class.
    seed : int
        Seed of the variant draws and of the window order.
    n_unlabelled : int
        Least number of unlabelled healthy windows (whole healthy variants
        outside the pool); 0: none (``transfer.adapt_windows``).

    Returns
    -------
    KShotSplit

    Raises
    ------
    ValueError
        If a class has too few windows for ``k_max``, or the healthy class too few for
        ``n_unlabelled`` on top of the pool, while leaving one variant for evaluation.
    """
    target = np.asarray(target, dtype=np.int64)
    sub = meta.iloc[target]
    gear = int(sub["gear"].iloc[0]) if "gear" in sub else 0
    faults = sub["fault"].astype(str).to_numpy()
    variants = sub["variant"].to_numpy()
    rng = np.random.default_rng([int(seed), gear])
    pool, order, groups = [], {}, set()
    for c in sorted(set(faults)):
        in_c = faults == c
        chosen = _draw_variants(rng, variants[in_c], k_max, f"class {c!r}", f"k={k_max}")
        pos = target[in_c & np.isin(variants, chosen)]
        order[c] = rng.permutation(pos)
        pool.append(pos)
        groups.update((c, int(v)) for v in chosen)
    pool_arr = np.sort(np.concatenate(pool)) if pool else np.array([], dtype=np.int64)
    unlabelled, unlabelled_groups = _unlabelled(target, faults, variants, groups, n_unlabelled,
                                                np.random.default_rng([int(seed), gear, 1]))
    evaluation = np.setdiff1d(target, np.concatenate([pool_arr, unlabelled]))
    return KShotSplit(pool_arr, evaluation, order, frozenset(groups), unlabelled,
                      frozenset(unlabelled_groups))


def _draw_variants(rng: np.random.Generator, variants: np.ndarray, n_min: int, what: str,
                   need: str) -> list:
    """Whole variants in a seeded order until they hold ``n_min`` of the windows whose
    variants are ``variants``; at least one variant is left over."""
    vs = rng.permutation(np.unique(variants))
    chosen, n = [], 0
    for v in vs:
        if n >= n_min:
            break
        chosen.append(v)
        n += int(np.sum(variants == v))
    if n_min > 0 and (n < n_min or len(chosen) == len(vs)):
        raise ValueError(
            f"{what} of the held-out gear has too few windows for {need} with variants "
            f"left for evaluation ({len(vs)} variants, {len(variants)} windows)")
    return chosen


def _unlabelled(target: np.ndarray, faults: np.ndarray, variants: np.ndarray,
                pool_groups: set, n: int, rng: np.random.Generator) -> tuple[np.ndarray, set]:
    """Positions and (fault, variant) groups of the unlabelled healthy windows: whole healthy
    variants outside the pool, at least ``n`` windows."""
    if n <= 0:
        return np.array([], dtype=np.int64), set()
    free = (faults == HEALTHY) & ~np.isin(
        variants, [v for c, v in pool_groups if c == HEALTHY])
    chosen = _draw_variants(rng, variants[free], n, "the healthy class",
                            f"{n} unlabelled healthy windows outside the k-shot pool")
    return np.sort(target[free & np.isin(variants, chosen)]), {(HEALTHY, int(v))
                                                               for v in chosen}


def check_no_leak(meta: pd.DataFrame, train: np.ndarray, kshot: KShotSplit) -> None:
    """Raise if evaluation windows meet the training, pool or unlabelled windows, a
    variant of the pool or of the unlabelled windows is evaluated, these hold a window that is
    not healthy or one of training, or the held-out gear is in training.

    Raises
    ------
    ValueError
        Naming the leak.
    """
    ev, unlabelled = kshot.evaluation, kshot.unlabelled
    if np.intersect1d(ev, train).size or np.intersect1d(ev, kshot.pool).size:
        raise ValueError("k-shot split leaks: evaluation windows in training or pool")
    if np.intersect1d(ev, unlabelled).size or np.intersect1d(unlabelled, train).size:
        raise ValueError("unlabelled windows leak: they are evaluated or in training")
    if (meta["fault"].astype(str).to_numpy()[unlabelled] != HEALTHY).any():
        raise ValueError("unlabelled windows leak labels: they hold windows that are not "
                         "healthy")
    groups = set(zip(meta["fault"].astype(str).to_numpy()[ev],
                     meta["variant"].to_numpy()[ev].astype(int).tolist(), strict=True))
    if groups & set(kshot.pool_groups):
        raise ValueError("k-shot split leaks: a pool variant is also evaluated")
    if groups & set(kshot.unlabelled_groups):
        raise ValueError("unlabelled windows leak: an unlabelled variant is also evaluated")
    if set(meta["gear"].to_numpy()[train]) & set(meta["gear"].to_numpy()[ev]):
        raise ValueError("leave-one-gear-out split leaks: the target gear is in training")
