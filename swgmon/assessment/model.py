"""The diagnosis model trained on simulated gears.

A window is described by its z-scores against its own gear's normal behaviour
(:mod:`swgmon.detection.normal`), so that a model trained on other gears sees deviations from
healthy, not the gear's individual signature (the leave-one-gear-out study measured that one
commissioning window is too few: its error is as large as a mild fault's shift).

**Diagnosis model.** A histogram gradient-boosting classifier (scikit-learn) on the
z-scores and the operating point, trained on simulated gears' lives: healthy windows and
windows of every gear and sensor fault at every severity. Its evidence against healthy,
``ln(1 − P(healthy)) − ln P(healthy)``, is the window's score; after an alarm its
log-probabilities summed over the windows since the rise name the fault (windows taken as
independent given the class). Per fault, a gradient-boosting regressor estimates the
severity; the estimate after an alarm is the median over the windows, read through the
training gears' reading curve (:func:`reading_curve`: a regressor fitted on other gears reads
a crack's severity shrunk toward the middle), and its interval comes from the training
gears themselves: fitted on the others, the aggregated estimate's error on each gives the
5 % and 95 % quantiles (a split-conformal interval across gears).
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field

import numpy as np
from threadpoolctl import ThreadpoolController

from swgmon.assessment.trees import CompiledTrees

HEALTHY = "healthy"


def design_matrix(z: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The diagnosis model's inputs: z-scores and the operating point (speed, torque)."""
    return np.concatenate([z, np.asarray(points, float)], axis=1)


@dataclass
class DiagnosisModel:
    """Classifier and severity regressors trained on simulated gears (module docstring).

    Attributes
    ----------
    classes : list of str
        Healthy first.
    classifier : sklearn classifier
    severity : dict of str to (regressor, (q05, q95))
        Per fault: the regressor and the 5 % / 95 % quantiles of the aggregated estimate's
        error across training gears.
    points_range : ndarray, shape (2, 2)
        Lowest and highest (speed, torque) of the training windows.
    n_features : int
        Health features per window.
    sample_rate_hz : float
        Of the training windows.
    window_s : float
        Length of the training windows [s].
    reading : dict of str to (ndarray, ndarray)
        Per fault, the reading curve (:func:`reading_curve`): severity levels and what
        regressors fitted without each level's gear read there, both shape (L,),
        increasing; a fault without one is read as the regressor says (a model saved
        before the curve).
    severity_without, reading_without : dict of int to dict of str
        Per training gear, the severity regressors fitted without it (without its fold,
        :func:`gear_folds`: those that calibrate the intervals across gears;
        :meth:`without`) and the reading curves of the other folds; saved with the model
        only where asked (:func:`.model_io.save_model`'s ``without``).
    """

    classes: list[str]
    classifier: object
    severity: dict[str, tuple[object, tuple[float, float]]] = field(default_factory=dict)
    points_range: np.ndarray | None = None
    n_features: int = 0
    sample_rate_hz: float = 0.0
    window_s: float = 0.0
    reading: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    severity_without: dict[int, dict[str, object]] = field(default_factory=dict, repr=False)
    reading_without: dict[int, dict[str, tuple]] = field(default_factory=dict, repr=False)

    def check(self, where: str = "diagnosis_model") -> DiagnosisModel:
        """Refuse a model whose parts are not those :func:`fit_diagnosis` makes, in one
        line naming ``where`` and the part; return self.

        The file's types are checked when it is loaded (:mod:`.model_io`), but a card-
        matched file can hold another estimator, a number, classes in another order or a
        fault without its severity regressor, which failed only after the whole stream.

        Raises
        ------
        ValueError
            ``classes`` not distinct names with healthy first; a classifier that is not a
            fitted gradient-boosting classifier of one class per name; a class other than
            healthy without a fitted gradient-boosting severity regressor, or a regressor
            of a class the model lacks; inputs of another width than ``n_features`` + 2;
            quantiles not finite with q05 <= q95; a reading curve of a class without a
            regressor or not two finite increasing (L,) arrays, L >= 1; a sample rate,
            window or feature count not positive; ``points_range`` not finite (2, 2).
        """
        from sklearn.ensemble import HistGradientBoostingClassifier as Clf
        from sklearn.ensemble import HistGradientBoostingRegressor as Reg

        missing = [f.name for f in dataclasses.fields(self) if not hasattr(self, f.name)]
        if missing:  # an object made without its fields (a pickle of another make)
            raise ValueError(f"{where}: not a diagnosis model (no {', '.join(missing)})")
        c = self.classes
        if (not isinstance(c, list) or not c or not all(isinstance(x, str) for x in c)
                or len(set(c)) != len(c) or c[0] != HEALTHY):
            raise ValueError(f"{where}: classes must be distinct names, {HEALTHY} first; "
                             f"got {c!r}")
        for name, v in (("n_features", self.n_features), ("sample_rate_hz",
                        self.sample_rate_hz), ("window_s", self.window_s)):
            if not isinstance(v, (int, float)) or not np.isfinite(v) or v <= 0:
                raise ValueError(f"{where}: {name} must be positive, got {v!r}")
        width = int(self.n_features) + 2  # the z-scores and the operating point
        clf = self.classifier
        if (not isinstance(clf, Clf) or not hasattr(clf, "classes_")
                or list(clf.classes_) != list(range(len(c)))
                or getattr(clf, "n_features_in_", None) != width):
            raise ValueError(f"{where}: the classifier must be a fitted "
                             f"HistGradientBoostingClassifier of {len(c)} classes on {width} "
                             f"inputs, got {type(clf).__name__}")
        if set(self.severity) != set(c[1:]):
            raise ValueError(f"{where}: a severity regressor for every class but {HEALTHY}: "
                             f"missing {sorted(set(c[1:]) - set(self.severity))}, extra "
                             f"{sorted(set(self.severity) - set(c[1:]))}")
        for f, (reg, q) in self.severity.items():
            if not isinstance(reg, Reg) or getattr(reg, "n_features_in_", None) != width:
                raise ValueError(f"{where}: the severity regressor of {f} must be a fitted "
                                 f"HistGradientBoostingRegressor on {width} inputs, got "
                                 f"{type(reg).__name__}")
            if not (np.all(np.isfinite(q)) and len(q) == 2 and q[0] <= q[1]):
                raise ValueError(f"{where}: the severity interval of {f} must be finite "
                                 f"(q05, q95) with q05 <= q95, got {q!r}")
        for g, regs in self.severity_without.items():
            if set(regs) != set(self.severity) or not all(
                    isinstance(r, Reg) and getattr(r, "n_features_in_", None) == width
                    for r in regs.values()):
                raise ValueError(f"{where}: the severity regressors without gear {g} must "
                                 f"be fitted HistGradientBoostingRegressors on {width} "
                                 f"inputs, one for each of {sorted(self.severity)}")
        for f, (lv, rd) in [*self.reading.items(), *((f, c) for r in
                                                     self.reading_without.values()
                                                     for f, c in r.items())]:
            a = np.asarray([lv, rd], float) if np.shape(lv) == np.shape(rd) else None
            if f not in self.severity or a is None or a.ndim != 2 or a.shape[1] < 1 \
                    or not np.all(np.isfinite(a)) or np.any(np.diff(a, axis=1) <= 0):
                raise ValueError(f"{where}: the reading curve of {f} must be two finite "
                                 "increasing arrays of one length >= 1 for a class with a "
                                 "severity regressor")
        pr = self.points_range
        if pr is not None and (np.shape(pr) != (2, 2) or not np.all(np.isfinite(pr))):
            raise ValueError(f"{where}: points_range must be finite (2, 2), got {pr!r}")
        return self

    def log_proba(self, x: np.ndarray) -> np.ndarray:
        """ln P(class | window), shape (n, n_classes), columns in ``classes`` order: the
        classifier's probabilities through the compiled walk of its trees
        (:class:`.trees.CompiledTrees`, the same numbers)."""
        if getattr(self, "_trees", None) is None:
            self._trees = CompiledTrees(self.classifier)
        return np.log(np.clip(self._trees.predict_proba(x), 1e-12, 1.0))

    def score(self, log_p: np.ndarray) -> np.ndarray:
        """Evidence against healthy, ln(1 − P(healthy)) − ln P(healthy), shape (n,)."""
        lh = log_p[:, 0]
        return np.log(-np.expm1(np.minimum(lh, -1e-12))) - lh

    def name(self, log_p: np.ndarray) -> str:
        """The fault with the largest summed log-probability over windows (healthy
        excluded: an alarm has been raised)."""
        tot = log_p.sum(axis=0)
        return self.classes[1 + int(np.argmax(tot[1:]))]

    def read(self, fault: str, pred: np.ndarray) -> np.ndarray:
        """Severities of a regressor's predictions through the fault's reading curve
        (:func:`read_through`); unchanged without a curve. Shape of ``pred`` [-]."""
        return read_through(self.reading[fault], pred) if fault in self.reading else pred

    def without(self, gear: int) -> DiagnosisModel:
        """This model with the severity regressors fitted without training gear ``gear``
        (without its fold, :func:`gear_folds`) and read through the other folds' curves
        (the classifier and the intervals unchanged): its estimates on that gear's windows
        are out of sample, as on a held-out gear's (the prognosis calibrates its intervals
        on training gears' lives so, :func:`swgmon.evaluation.prognosis_evaluation.calibrate`).

        Raises
        ------
        ValueError
            ``gear`` is not a training gear of this model, or the model was loaded from a
            file saved without them (:func:`.model_io.save_model`'s ``without``).
        """
        if gear not in self.severity_without:
            raise ValueError(f"no severity regressors fitted without gear {gear}: the "
                             f"model's are for {sorted(self.severity_without)} (a model "
                             "loaded from a file saved without them has none)")
        out = dataclasses.replace(self, severity={
            c: (self.severity_without[gear][c], q) for c, (_, q) in self.severity.items()},
            reading=self.reading_without.get(gear, {}))
        out._trees = getattr(self, "_trees", None)  # the same classifier, compiled once
        return out

    def estimate(self, fault: str, x: np.ndarray, n_boot: int = 200
                 ) -> tuple[float, float, float]:
        """Severity estimate and its 90 % interval from windows ``x`` of one fault.

        The estimate is the median of the windows' estimates (:meth:`reads`). Its
        interval has two parts, added: the median's own spread over these windows (the
        5 % and 95 % quantiles of the medians of ``n_boot`` bootstrap resamples of the
        windows, Efron and Tibshirani 1993, ch. 13; a fixed seed), and the calibration
        error across training gears (``q05``, ``q95``): ``[b05 - q95, b95 - q05]``. The
        first keeps the interval open where the training gears agree to the digit (a
        sensor fault is the same on every gear); the windows are taken as independent, so
        it is a lower bound on that part.

        Parameters
        ----------
        fault : str
            A class of the model other than healthy.
        x : ndarray, shape (n, n_features + 2), or (n,)
            :func:`design_matrix` rows of the windows since the alarm's rise, or their
            estimates already read (:meth:`reads`: the prognosis reads a track's windows
            at once and estimates block by block).
        n_boot : int

        Returns
        -------
        (float, float, float)
            Estimate, low and high, in the fault's severity units.
        """
        pred = self.reads(fault, x) if np.ndim(x) == 2 else np.asarray(x, float)
        _, (q05, q95) = self.severity[fault]
        boot = np.median(pred[np.random.default_rng(0).integers(
            0, pred.size, (n_boot, pred.size))], axis=1)
        b05, b95 = np.quantile(boot, [0.05, 0.95])
        return float(np.median(pred)), float(b05 - q95), float(b95 - q05)

    def reads(self, fault: str, x: np.ndarray) -> np.ndarray:
        """Each window's severity estimate: the fault's regressor on :func:`design_matrix`
        rows ``x`` (n, n_features + 2), read through its curve (:meth:`read`), shape (n,)."""
        reg, _ = self.severity[fault]
        with one_thread():
            return self.read(fault, reg.predict(x))


def read_through(curve: tuple[np.ndarray, np.ndarray], pred: np.ndarray) -> np.ndarray:
    """Severities of predictions ``pred`` through a reading curve (levels, reads) of
    :func:`reading_curve`: inverted by linear interpolation; beyond its ends a reading
    moves the severity one for one [choice: the curve says nothing there, and a flat end
    segment must not amplify]. Shape of ``pred`` [-]."""
    lv, rd = (np.asarray(a, float) for a in curve)
    pred = np.asarray(pred, float)
    out = np.interp(pred, rd, lv)
    return out + np.minimum(pred - rd[0], 0.0) + np.maximum(pred - rd[-1], 0.0)


def reading_curve(pred: np.ndarray, true: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """What a severity regressor reads at each trained severity, on gears it was not
    fitted on: the median of the windows' out-of-sample predictions per level, made
    non-decreasing (the running maximum); levels that read alike become one point, at
    their mean.

    A regressor trained on a few gears reads a fault whose signature scatters from gear
    to gear shrunk toward the middle of its levels (the bench lot's tip crack: 0.38 at
    0.25, 0.90 at 1.0). A prognosis fits the track's growth, so an estimate must be right
    on average at each true severity: inverting the curve (:func:`read_through`) is the
    classical calibration of a measurement (Osborne, Int. Stat. Rev. 59 (1991) 309-336
    [unverified: recalled]), not the regression of severity on the reading, which
    shrinks again.

    Parameters
    ----------
    pred, true : ndarray, shape (n,)
        Out-of-sample predictions and the true severities [-].

    Returns
    -------
    levels, reads : ndarray, shape (L,)
        Each increasing (L = 1 where every level reads alike).
    """
    levels = np.unique(true)
    reads = np.maximum.accumulate([np.median(pred[true == v]) for v in levels])
    r, group = np.unique(reads, return_inverse=True)
    return np.bincount(group, levels) / np.bincount(group), r


@functools.cache
def _controller() -> ThreadpoolController:
    from sklearn import ensemble  # noqa: F401  (its OpenMP runtime, for the controller to see)

    return ThreadpoolController()


def one_thread():
    """A context in which scikit-learn's gradient boosting runs on one OpenMP thread.

    The fitted trees and their predictions are the same with any number of threads (the
    bench's diagnosis model trained with one and with two: identical probabilities and
    severities); but on a machine with other work running, OpenMP's waiting threads made
    the bench model's training 13 times slower (1254 s against 94 s, two cores) and the
    stream's predictions of small blocks 16 times slower (docs/monitor/prognosis.md,
    "Prognosis").
    Work runs in parallel as processes instead (the evaluation's parts, ``n_jobs``).
    The controller is made once (``threadpoolctl``: 0.05 ms a call, against 12 ms for a
    fresh ``threadpool_limits``)."""
    return _controller().limit(limits=1, user_api="openmp")


def _classifier(seed: int):
    from sklearn.ensemble import HistGradientBoostingClassifier

    return HistGradientBoostingClassifier(max_iter=200, learning_rate=0.1,
                                          early_stopping=False, random_state=seed)


def _regressor(seed: int):
    from sklearn.ensemble import HistGradientBoostingRegressor

    return HistGradientBoostingRegressor(max_iter=100, early_stopping=False,
                                         random_state=seed)


def fit_diagnosis(x: np.ndarray, fault: np.ndarray, severity: np.ndarray, gear: np.ndarray,
                  classes: list[str], seed: int = 0, n_agg: int = 60, folds: int = 0
                  ) -> DiagnosisModel:
    """Train the diagnosis model on training gears' windows.

    Parameters
    ----------
    x : ndarray, shape (n, F + 2)
        :func:`design_matrix` rows.
    fault : ndarray of str, shape (n,)
    severity : ndarray, shape (n,)
    gear : ndarray of int, shape (n,)
        Training gear of each window (the severity intervals are calibrated across them).
    classes : list of str
        Healthy first; every class must have windows.
    seed : int
    n_agg : int
        Windows per aggregated severity estimate in the interval's calibration.
    folds : int
        Groups of training gears the severity regressors are fitted without, each gear's
        windows read by the regressors of the group without it (:func:`gear_folds`): 0
        (or the number of gears and more), one gear a group (the jackknife's); fewer,
        cross-validation's folds (CV+, Barber et al., Ann. Statist. 49 (2021) 486-507:
        as many regressors, each fitted on fewer gears).

    Returns
    -------
    DiagnosisModel

    Raises
    ------
    ValueError
        If a class has no windows, fewer than two training gears are given, or ``folds``
        is 1 or negative.
    """
    missing = [c for c in classes if not (fault == c).any()]
    if missing or classes[0] != HEALTHY:
        raise ValueError(f"training windows lack classes {missing} (healthy must come first)")
    gears = np.unique(gear)
    if gears.size < 2:
        raise ValueError(f"the severity intervals need two training gears, got {gears.tolist()}")
    if folds < 0 or folds == 1:
        raise ValueError(f"folds must be 0 (one gear a fold) or at least 2, got {folds}")
    y = np.array([classes.index(f) for f in fault])
    clf = _classifier(seed)
    with one_thread():
        model = DiagnosisModel(list(classes), clf.fit(x, y))
        return _severity_regressors(model, x, fault, severity, gear, seed, n_agg, folds)


def gear_folds(gears: list[int] | np.ndarray, folds: int = 0) -> list[list[int]]:
    """The training gears in ``folds`` groups, in order, as even as can be
    (:func:`numpy.array_split` of the sorted ids); 0 or as many as the gears: one each.

    Parameters
    ----------
    gears : list of int
        Training gear ids.
    folds : int
        Groups, 0 or >= 2.

    Returns
    -------
    list of list of int
        The groups, each non-empty.
    """
    ids = sorted(int(g) for g in gears)
    k = len(ids) if folds == 0 or folds >= len(ids) else folds
    return [[int(g) for g in a] for a in np.array_split(np.array(ids), k)]


def _severity_regressors(model: DiagnosisModel, x, fault, severity, gear, seed, n_agg,
                         folds) -> DiagnosisModel:
    """:func:`fit_diagnosis`'s severity regressors and their intervals across gears."""
    gears = np.unique(gear)
    groups = gear_folds(gears, folds)
    rng = np.random.default_rng(seed)
    for c in model.classes[1:]:
        m = fault == c
        oof = np.full(x.shape[0], np.nan)  # each window read by a regressor without its fold
        for fold in groups:
            inside = np.isin(gear, fold)
            reg = _regressor(seed).fit(x[m & ~inside], severity[m & ~inside])
            for g in fold:
                model.severity_without.setdefault(g, {})[c] = reg
            oof[m & inside] = reg.predict(x[m & inside])
        for g, o in ((None, m), *((g, m & ~np.isin(gear, fold)) for fold in groups
                                  for g in fold)):
            curve = reading_curve(oof[o], severity[o])
            if curve[0].size >= 2:  # one level read: nothing to calibrate, read as said
                (model.reading if g is None else
                 model.reading_without.setdefault(int(g), {}))[c] = curve
        masks = m & (gear == gears[:, None])  # each training gear's windows of c
        q = _error_quantiles(oof, severity, masks, rng, n_agg, {
            k: model.reading_without.get(int(g), {}).get(c) for k, g in enumerate(gears)})
        if q[0] == q[1]:  # read, the training gears agree to the digit: the raw errors
            q = _error_quantiles(oof, severity, masks, rng, n_agg, {})
        model.severity[c] = (_regressor(seed).fit(x[m], severity[m]), q)
    return model


def _error_quantiles(oof: np.ndarray, severity: np.ndarray, masks: np.ndarray,
                     rng: np.random.Generator, n_agg: int, curves: dict) -> tuple[float, float]:
    """The 5 % and 95 % quantiles of the aggregated estimate's error on each training gear
    (``masks``, shape (G, n)), each read through its curve in ``curves`` (by the gear's
    index; none: as the regressor said): 20 medians of ``n_agg`` windows per level."""
    errs = []
    for k, te in enumerate(masks):
        curve = curves.get(k)
        pred = oof[te] if curve is None else read_through(curve, oof[te])
        true = severity[te]
        for s in np.unique(true):
            ps = pred[true == s]
            for _ in range(20):
                errs.append(np.median(rng.choice(ps, min(n_agg, ps.size))) - s)
    return float(np.quantile(errs, 0.05)), float(np.quantile(errs, 0.95))


__all__ = ["DiagnosisModel", "design_matrix", "fit_diagnosis", "gear_folds", "one_thread",
           "read_through", "reading_curve", "HEALTHY"]
