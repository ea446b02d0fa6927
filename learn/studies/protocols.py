"""Evaluation protocols of the paper, Sec. IV.

=============  ===================  =========  ==========================================
name           scheme               disturbed  splits
=============  ===================  =========  ==========================================
cv_clean       ``group_kfold``      False      4-fold CV (Table VII)
cv_disturbed   ``group_kfold``      True       4-fold CV (Table VIII)
ood_clean      ``leave_one_gear``   False      1,2 -> 3; 2,3 -> 1; 1,3 -> 2 (Table IX)
ood_disturbed  ``leave_one_gear``   True       same, on disturbed data (Table X)
=============  ===================  =========  ==========================================

Splits come from metadata, never from shuffling windows. In the CV a group is one
``(gear, fault, variant)``: the windows of one fault variant at the six operating points
never straddle training and test (the paper does not say how it split; a split by window
would put near-copies of a test window into training). Folds are stratified by class
(:class:`~sklearn.model_selection.StratifiedGroupKFold`). In leave-one-gear-out the
held-out gear never appears in training; its features are still normalised by its own
reference windows (see :mod:`learn.inputs.features`).
"""

from __future__ import annotations

import dataclasses
import inspect
import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from swgsim.base.lazy import lazy_module
from swgsim.base.registry import travelling

pd = lazy_module("pandas")

log = logging.getLogger(__name__)

SCHEMES = ("group_kfold", "kfold", "leave_one_gear")
#: Training accuracy is read on at most this many of a split's training windows, evenly
#: spaced over them (a systematic sample: every class and gear in proportion; standard error
#: at most 0.011). Predicting every training window cost the RBF SVM twice its fit (6.7 s
#: against 3.5 s on 10 000 windows of the paper grid); the test windows are always all read.
TRAIN_ACCURACY_ROWS = 2000
GROUP_COLUMNS = ("gear", "fault", "variant")


@dataclass
class ProtocolConfig:
    """A protocol: a name and the arguments of :func:`make_splits` (``conf`` group
    ``protocol``). The paper's four are registered in :data:`PROTOCOLS`.

    Attributes
    ----------
    name : str
    scheme : str
        One of :data:`SCHEMES`.
    disturbed : bool
    n_splits : int
        Folds of the k-fold schemes.
    random_state : int or None
        Shuffling seed of the k-fold schemes (the apps set it to ``${seed}``).
    test_gears : list of int or None
        Held-out gears of ``leave_one_gear``, in order.
    """

    name: str = "cv_clean"
    scheme: str = "group_kfold"
    disturbed: bool = False
    n_splits: int = 4
    random_state: int | None = 0
    test_gears: list[int] | None = None

    @classmethod
    def paper(cls, name: str, **overrides) -> ProtocolConfig:
        """A copy of one of the paper's protocols (:data:`PROTOCOLS`), fields replaced by
        ``overrides``.

        Raises
        ------
        ValueError
            For a name not in :data:`PROTOCOLS`.
        """
        if name not in PROTOCOLS:
            raise ValueError(f"protocol must be one of {sorted(PROTOCOLS)}, got {name!r}")
        p = PROTOCOLS[name]
        return dataclasses.replace(p, test_gears=None if p.test_gears is None
                                   else list(p.test_gears), **overrides)

    @property
    def out_of_distribution(self) -> bool:
        """Whether the protocol holds a gear out of training (leave one gear out)."""
        return self.scheme == "leave_one_gear"

    @property
    def n_planned(self) -> int:
        """Number of splits it will give (the held-out gears, or the folds)."""
        return len(self.test_gears) if self.test_gears is not None else self.n_splits

    def spec(self) -> dict:
        """Scheme, data and splits (no name, no seed), e.g. for a run's parameters:
        ``{scheme, disturbed, n_splits}`` or ``{scheme, disturbed, test_gears}``."""
        out: dict = {"scheme": self.scheme, "disturbed": self.disturbed}
        if self.test_gears is None:
            out["n_splits"] = self.n_splits
        else:
            out["test_gears"] = list(self.test_gears)
        return out

    def splits(self, meta: pd.DataFrame) -> list[Split]:
        """:func:`make_splits` of this protocol on per-sample metadata."""
        return make_splits(meta, self.scheme, self.disturbed, n_splits=self.n_splits,
                           random_state=self.random_state, test_gears=self.test_gears)


#: The paper's protocols (Sec. IV), by name.
PROTOCOLS: dict[str, ProtocolConfig] = {
    p.name: p for p in (
        ProtocolConfig("cv_clean", "group_kfold", disturbed=False, n_splits=4),
        ProtocolConfig("cv_disturbed", "group_kfold", disturbed=True, n_splits=4),
        ProtocolConfig("ood_clean", "leave_one_gear", disturbed=False, test_gears=[3, 1, 2]),
        ProtocolConfig("ood_disturbed", "leave_one_gear", disturbed=True,
                       test_gears=[3, 1, 2]),
    )
}
#: Names of the paper's leave-one-gear-out protocols, and of all four.
OOD_PROTOCOLS: tuple[str, ...] = tuple(n for n, p in PROTOCOLS.items()
                                       if p.out_of_distribution)
ALL_PROTOCOLS: tuple[str, ...] = tuple(PROTOCOLS)


def window_groups(meta: pd.DataFrame) -> np.ndarray:
    """``gear:fault:variant`` of each window (:data:`GROUP_COLUMNS`), shape (n,): a fault
    variant's windows at every operating point, which the CV folds and the torch nets'
    early-stopping split keep together."""
    return (meta["gear"].astype(str) + ":" + meta["fault"].astype(str) + ":"
            + meta["variant"].astype(str)).to_numpy()


def class_labels(y: Sequence[str]) -> list[str]:
    """Classes present in ``y``: the registry's order (:func:`swgsim.gear.faults.fault_classes`)
    first, any others sorted after."""
    from swgsim.gear.faults import fault_classes

    known = fault_classes()
    present = {str(c) for c in np.unique(np.asarray(y).astype(str))}
    return [c for c in known if c in present] + sorted(present - set(known))


@dataclass(frozen=True)
class Split:
    """One train/test split.

    Attributes
    ----------
    name : str
        Short name usable as an MLflow key: ``fold0``.. or ``gear3``..
    label : str
        Human-readable name as in the paper: ``fold 1/4`` or ``1,2 -> 3``.
    train, test : ndarray of int
        Row positions into the metadata frame (and feature matrix) given to
        :func:`make_splits`.
    """

    name: str
    label: str
    train: np.ndarray
    test: np.ndarray


@dataclass
class ProtocolResult:
    """Accuracies of one model under one protocol, all splits.

    Attributes
    ----------
    splits : list of Split
    train_accuracy, test_accuracy : ndarray, shape (n_splits,)
        Accuracy on the training and test rows of each split [-], in 0..1.
    confusion : ndarray of int, shape (n_classes, n_classes)
        Test confusion matrix summed over splits (rows: true class, columns: predicted).
    labels : list of str
        Class names, order of ``confusion``.
    fit_time_s : ndarray, shape (n_splits,)
        Wall time of fit + predict per split [s].
    """

    splits: list[Split]
    train_accuracy: np.ndarray
    test_accuracy: np.ndarray
    confusion: np.ndarray
    labels: list[str]
    fit_time_s: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @classmethod
    def from_fits(cls, splits: Sequence[Split], fits: Sequence[tuple], labels: list[str]
                  ) -> ProtocolResult:
        """The result of :func:`fit_split`'s outputs ``fits``, one per split, in order."""
        return cls(splits=list(splits), train_accuracy=np.array([o[0] for o in fits]),
                   test_accuracy=np.array([o[1] for o in fits]),
                   confusion=np.sum([o[2] for o in fits], axis=0), labels=labels,
                   fit_time_s=np.array([o[3] for o in fits]))

    @property
    def mean_train_accuracy(self) -> float:
        """Mean training accuracy over splits [-]."""
        return float(np.mean(self.train_accuracy))

    @property
    def mean_test_accuracy(self) -> float:
        """Mean test accuracy over splits [-]."""
        return float(np.mean(self.test_accuracy))


def make_splits(
    meta: pd.DataFrame,
    scheme: str,
    disturbed: bool,
    n_splits: int = 4,
    random_state: int | None = 0,
    test_gears: Sequence[int] | None = None,
) -> list[Split]:
    """Train/test splits of a protocol from per-sample metadata.

    Parameters
    ----------
    meta : pandas.DataFrame
        Per-sample metadata with columns ``gear``, ``fault``, ``variant``, ``disturbed``
        (e.g. :attr:`learn.inputs.features.Features.meta`); no reference windows.
    scheme : {"group_kfold", "kfold", "leave_one_gear"}
        Stratified group k-fold with groups ``(gear, fault, variant)``, stratified k-fold
        over windows (a variant's operating points may straddle training and test), or
        leave one gear out.
    disturbed : bool
        Use only the disturbed (True) or only the clean (False) windows.
    n_splits : int, default 4
        Folds of ``group_kfold`` (paper: 4).
    random_state : int, optional
        Shuffling seed of ``group_kfold``; None: no shuffling.
    test_gears : sequence of int, optional
        Held-out gear of each ``leave_one_gear`` split, in order; default: every gear
        present, in the paper's order 3, 1, 2 where present.

    Returns
    -------
    list of Split
        Positions refer to rows of ``meta`` (``iloc``), so they index the feature matrix.

    Raises
    ------
    ValueError
        For an unknown scheme, missing columns, no windows with the requested
        ``disturbed`` flag, too few groups for ``n_splits``, or a test gear that is absent
        or is the only gear.
    """
    from sklearn.model_selection import StratifiedGroupKFold, StratifiedKFold

    missing = {*GROUP_COLUMNS, "disturbed"} - set(meta.columns)
    if missing:
        raise ValueError(f"meta lacks columns {sorted(missing)}")
    rows = np.flatnonzero(meta["disturbed"].to_numpy(bool) == bool(disturbed))
    if rows.size == 0:
        raise ValueError(f"no windows with disturbed={bool(disturbed)} in the data")
    sub = meta.iloc[rows]
    if scheme in ("group_kfold", "kfold"):
        kw = {"n_splits": n_splits, "shuffle": random_state is not None,
              "random_state": random_state}
        y = sub["fault"].astype(str).to_numpy()
        if scheme == "group_kfold":
            groups = sub.groupby(list(GROUP_COLUMNS), sort=True).ngroup().to_numpy()
            n_groups = int(groups.max()) + 1
            if n_groups < n_splits:
                raise ValueError(f"n_splits={n_splits} exceeds the number of groups "
                                 f"({n_groups})")
            folds = StratifiedGroupKFold(**kw).split(np.zeros(len(sub)), y, groups)
        else:
            folds = StratifiedKFold(**kw).split(np.zeros(len(sub)), y)
        return [Split(f"fold{i}", f"fold {i + 1}/{n_splits}", rows[tr], rows[te])
                for i, (tr, te) in enumerate(folds)]
    if scheme == "leave_one_gear":
        gear = sub["gear"].to_numpy()
        present = sorted(int(g) for g in np.unique(gear))
        if len(present) < 2:
            raise ValueError(f"leave_one_gear needs at least two gears, got {present}")
        if test_gears is None:
            order = [3, 1, 2]
            test_gears = [g for g in order if g in present] + [
                g for g in present if g not in order
            ]
        splits = []
        for g in test_gears:
            g = int(g)
            if g not in present:
                raise ValueError(f"test gear {g} is not in the data (gears: {present})")
            train_gears = [h for h in present if h != g]
            label = f"{','.join(map(str, train_gears))} -> {g}"
            splits.append(Split(f"gear{g}", label, rows[gear != g], rows[gear == g]))
        return splits
    raise ValueError(f"scheme must be one of {SCHEMES}, got {scheme!r}")


def protocol_splits(meta: pd.DataFrame, protocol: str, random_state: int | None = 0) -> list[Split]:
    """Splits of one of the paper's protocols (:data:`PROTOCOLS`).

    Parameters
    ----------
    meta : pandas.DataFrame
        See :func:`make_splits`.
    protocol : {"cv_clean", "cv_disturbed", "ood_clean", "ood_disturbed"}
    random_state : int, optional
        Seed of the CV shuffling.

    Raises
    ------
    ValueError
        For an unknown protocol (:meth:`ProtocolConfig.paper`).
    """
    return ProtocolConfig.paper(protocol, random_state=random_state).splits(meta)


def fit_with_groups(est, X, y, groups):
    """``est.fit``, passing ``groups`` (for a source-only early-stopping split) to an
    estimator (or a pipeline's final one) whose ``fit`` takes them; returns ``est``."""
    from sklearn.pipeline import Pipeline

    final = est[-1] if isinstance(est, Pipeline) else est
    if "groups" not in inspect.signature(final.fit).parameters:
        return est.fit(X, y)
    if isinstance(est, Pipeline):
        return est.fit(X, y, **{f"{est.steps[-1][0]}__groups": groups})
    return est.fit(X, y, groups=groups)


def fit_split(estimator, X: np.ndarray, y: np.ndarray, split: Split, labels: Sequence[str],
              warnings_out: list | None = None, return_model: bool = False,
              groups: np.ndarray | None = None):
    """Fit a fresh clone of ``estimator`` on one split's training rows and score it.

    Parameters
    ----------
    estimator : classifier
        Unfitted scikit-learn-compatible classifier (cloned, never modified).
    X : ndarray, shape (n_samples, n_features) or (n_samples, C, T)
        Features, or signals for a model that reads them (``learn.learners.nets``,
        ``learn.learners.rocket``).
    y : ndarray, shape (n_samples,)
        Class names.
    split : Split
    labels : sequence of str
        Class order of the confusion matrix.
    warnings_out : list, optional
        If given, the warnings raised by fit and predict are appended to it as
        ``(category name, first line of the message)`` instead of being shown (so that a
        caller, possibly in another process, can summarise them once).
    return_model : bool, default False
        Also return the fitted clone (e.g. to log it; it travels back from a worker
        process by pickling).
    groups : ndarray, shape (n_samples,), optional
        Group of each window (:data:`GROUP_COLUMNS`), handed to a model whose ``fit``
        takes groups (the torch nets' early-stopping split keeps groups of the training
        rows apart, :func:`fit_with_groups`); others ignore it.

    Returns
    -------
    train_acc : float
        On at most :data:`TRAIN_ACCURACY_ROWS` training windows (:func:`training_accuracy_rows`).
    test_acc : float
    confusion : ndarray of int, shape (n_classes, n_classes)
    seconds : float
        Wall time of fit + predict [s].
    model : estimator
        The fitted clone, only if ``return_model``.
    """
    import warnings

    from sklearn.base import clone
    from sklearn.metrics import confusion_matrix

    t0 = time.perf_counter()
    with warnings.catch_warnings(record=warnings_out is not None) as caught:
        if warnings_out is not None:
            warnings.simplefilter("always")
        est = clone(estimator)
        if groups is None:
            est.fit(X[split.train], y[split.train])
        else:
            fit_with_groups(est, X[split.train], y[split.train], groups[split.train])
        rows = training_accuracy_rows(split.train)
        pred_tr = est.predict(X[rows])
        pred_te = est.predict(X[split.test])
    if warnings_out is not None:
        warnings_out.extend((w.category.__name__, str(w.message).splitlines()[0])
                            for w in caught)
    train_acc = float(np.mean(pred_tr == y[rows]))
    test_acc = float(np.mean(pred_te == y[split.test]))
    cm = confusion_matrix(y[split.test], pred_te, labels=list(labels))
    out = (train_acc, test_acc, cm, time.perf_counter() - t0)
    return (*out, est) if return_model else out


def training_accuracy_rows(train: np.ndarray) -> np.ndarray:
    """The training rows a split's training accuracy is read on.

    Parameters
    ----------
    train : ndarray of int, shape (n_train,)
        A split's training rows.

    Returns
    -------
    ndarray of int, shape (min(n_train, TRAIN_ACCURACY_ROWS),)
        ``train`` itself when it has at most :data:`TRAIN_ACCURACY_ROWS` rows, else that many
        of them, evenly spaced (first and last included).
    """
    if len(train) <= TRAIN_ACCURACY_ROWS:
        return train
    return train[np.linspace(0, len(train) - 1, TRAIN_ACCURACY_ROWS).round().astype(int)]


def fit_split_quiet(estimator, X: np.ndarray, y: np.ndarray, split: Split,
                    labels: Sequence[str], return_model: bool = False):
    """:func:`fit_split` that returns its warnings instead of showing them.

    Returns
    -------
    tuple
        The four results of :func:`fit_split`, a list of ``(category, message)`` and, if
        ``return_model``, the fitted clone.
    """
    caught: list = []
    out = fit_split(estimator, X, y, split, labels, caught, return_model)
    return (*out[:4], caught, *out[4:])


def evaluate(
    estimator,
    X: np.ndarray,
    y: np.ndarray,
    splits: Sequence[Split],
    labels: Sequence[str] | None = None,
    n_jobs: int | None = 1,
    groups: np.ndarray | None = None,
) -> ProtocolResult:
    """Train and test accuracy of ``estimator`` on every split.

    Parameters
    ----------
    estimator : classifier
        Unfitted classifier; a clone is fitted per split.
    X : ndarray, shape (n_samples, n_features)
    y : ndarray, shape (n_samples,)
        Class names.
    splits : sequence of Split
    labels : sequence of str, optional
        Class order; default :func:`class_labels` of ``y``.
    n_jobs : int, optional
        Splits fitted in parallel (joblib); 1: sequential.
    groups : ndarray, shape (n_samples,), optional
        See :func:`fit_split`.

    Returns
    -------
    ProtocolResult
    """
    from joblib import Parallel, delayed

    y = np.asarray(y).astype(str)
    labels = class_labels(y) if labels is None else [str(c) for c in labels]
    if n_jobs == 1:
        out = [fit_split(estimator, X, y, s, labels, groups=groups) for s in splits]
    else:
        fit = travelling(fit_split)
        out = Parallel(n_jobs=n_jobs)(delayed(fit)(estimator, X, y, s, labels, groups=groups)
                                      for s in splits)
    return ProtocolResult.from_fits(splits, out, labels)
