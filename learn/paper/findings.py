"""The paper's qualitative findings of Sec. IV, each as a check on our scores.

Every statement the paper makes about Tables VII-X (Sec. IV-A to IV-D) is one
:class:`Finding`: its words (paraphrased), and a check that reads our scores and returns
whether it holds and the numbers it looked at. "About X %" in the paper is read as
within ±5 points of X (:data:`ABOUT`); "below / above X %" literally.

    >>> from learn.paper.findings import check_findings
    >>> rows = check_findings(cells)  # cells: learn.paper.results.our_cells(results)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from learn.inputs.features import SELECTIONS
from learn.learners.models import model_label
from learn.paper.results import GEAR_SPLITS
from learn.paper.tables import M5
from swgsim.base.lazy import lazy_module

pd = lazy_module("pandas")

#: Tolerance of "about X %" in the paper's text [points].
ABOUT = 5.0
_SEL = SELECTIONS
_NAMES = {m: model_label(m) for m in M5}  # the paper's models, in its order


class Scores:
    """Our scores [%] by table, selection, model and split
    (:func:`learn.paper.results.our_cells`).

    Parameters
    ----------
    cells : pandas.DataFrame
        Columns ``table``, ``selection``, ``model``, ``split``, ``ours``.
    """

    def __init__(self, cells: pd.DataFrame):
        self._s = {(r.table, r.selection, r.model, r.split): float(r.ours)
                   for r in cells.itertuples()}

    def cv(self, table: str, sel: int, model: str) -> float:
        """Mean test score of a CV table (VII or VIII); NaN if absent."""
        return self._s.get((table, _SEL[sel], model, "mean"), float("nan"))

    def ood(self, table: str, sel: int, model: str) -> np.ndarray:
        """Scores of the three held-out gears (order 3, 1, 2) of Table IX or X, shape (3,)."""
        return np.array([self._s.get((table, _SEL[sel], model, g), float("nan"))
                         for g in GEAR_SPLITS])

    def has(self, table: str) -> bool:
        """Whether any score of ``table`` is present."""
        return any(k[0] == table for k in self._s)


@dataclass(frozen=True)
class Finding:
    """A qualitative statement of the paper and its check.

    Attributes
    ----------
    key : str
        Short id, e.g. "VII-1".
    table : str
        The table it is about ("VII".."X").
    text : str
        The paper's statement (paraphrased from Sec. IV).
    check : callable
        ``check(scores) -> (holds, measured)``: bool and the numbers behind it.
    """

    key: str
    table: str
    text: str
    check: Callable[[Scores], tuple[bool, str]]


def _about(x: float, target: float) -> bool:
    return bool(abs(x - target) <= ABOUT)


def _fmt(x) -> str:
    x = np.atleast_1d(np.asarray(x, float))
    return "/".join(f"{v:.1f}" for v in x)


def _vii_1(s):
    rf = [s.cv("VII", k, "rf") for k in (1, 2)]
    kn = [s.cv("VII", k, "knn") for k in (1, 2)]
    ok = (abs(rf[0] - rf[1]) <= ABOUT and min(rf) >= 100 - ABOUT
          and abs(kn[0] - kn[1]) <= ABOUT and all(_about(v, 97) for v in kn))
    return ok, f"RF Sel.1/2 {_fmt(rf)}, KNN Sel.1/2 {_fmt(kn)}"


def _vii_2(s):
    rf = [s.cv("VII", k, "rf") for k in (1, 2, 3)]
    kn = [s.cv("VII", k, "knn") for k in (1, 2, 3)]
    ok = rf[2] < min(rf[:2]) and kn[2] < min(kn[:2])
    return ok, f"RF Sel.1/2/3 {_fmt(rf)}, KNN {_fmt(kn)}"


def _vii_3(s):
    m = [s.cv("VII", k, "mlp") for k in (1, 2, 3)]
    ok = m[2] > max(m[:2]) and max(m[:2]) < 84 and _about(m[2], 98)
    return ok, f"MLP Sel.1/2/3 {_fmt(m)}"


def _vii_4(s):
    nb = [s.cv("VII", k, "nb") for k in (1, 2, 3)]
    ok = _about(nb[0], 93) and max(nb[1:]) < 80
    return ok, f"NB Sel.1/2/3 {_fmt(nb)}"


def _vii_5(s):
    last = all(s.cv("VII", k, "svm") < min(s.cv("VII", k, m) for m in ("mlp", "rf", "knn", "nb"))
               for k in (1, 2, 3))
    sv = [s.cv("VII", k, "svm") for k in (1, 2, 3)]
    ok = last and int(np.nanargmax(sv)) == 2 and _about(sv[2], 66)
    return ok, f"SVM Sel.1/2/3 {_fmt(sv)}; last on every selection: {last}"


def _best_model(s, table, models=("mlp", "svm", "rf", "knn", "nb"), sels=(1, 2, 3)):
    if table in ("VII", "VIII"):
        means = {m: np.nanmean([s.cv(table, k, m) for k in sels]) for m in models}
    else:
        means = {m: np.nanmean([s.ood(table, k, m) for k in sels]) for m in models}
    return max(means, key=means.get), means


def _vii_6(s):
    best, means = _best_model(s, "VII")
    return best == "rf", "mean over selections: " + ", ".join(
        f"{_NAMES[m]} {v:.1f}" for m, v in means.items())


def _vii_7(s):
    bad = [m for m in ("mlp", "svm", "rf", "knn", "nb")
           if s.cv("VII", 2, m) > max(s.cv("VII", 1, m), s.cv("VII", 3, m))]
    return not bad, ("Sel.2 best for " + ", ".join(_NAMES[m] for m in bad)) if bad else \
        "Sel.1 or Sel.3 best for every classifier"


def _drop(s, sel, m):
    return s.cv("VII", sel, m) - s.cv("VIII", sel, m)


def _viii_1(s):
    a = np.nanmean([s.cv("VII", k, m) for k in (1, 2, 3) for m in _NAMES])
    b = np.nanmean([s.cv("VIII", k, m) for k in (1, 2, 3) for m in _NAMES])
    return bool(b < a), f"mean test score VII {a:.1f}, VIII {b:.1f}"


def _viii_2(s):
    d = [_drop(s, 3, m) for m in ("mlp", "rf")]
    return bool(max(d) <= ABOUT), f"drop VII -> VIII on Sel.3: MLP {d[0]:.1f}, RF {d[1]:.1f}"


def _viii_3(s):
    d = [_drop(s, k, "rf") for k in (1, 2)]
    ok = _about(d[0], 7) and _about(d[1], 9)
    return ok, f"RF drop on Sel.1/2 {_fmt(d)} (paper about 7 and 9)"


def _viii_4(s):
    cmp = [(_drop(s, k, "knn") > _drop(s, k, "rf")) and (_drop(s, k, "nb") > _drop(s, k, "rf"))
           for k in (1, 2, 3)]
    txt = "; ".join(f"Sel.{k}: RF {_drop(s, k, 'rf'):.1f}, KNN {_drop(s, k, 'knn'):.1f}, "
                    f"NB {_drop(s, k, 'nb'):.1f}" for k in (1, 2, 3))
    return all(cmp), "drops " + txt


def _viii_5(s):
    kn = [s.cv("VIII", k, "knn") for k in (1, 2, 3)]
    nb = [s.cv("VIII", k, "nb") for k in (1, 2, 3)]
    ok = (int(np.nanargmax(kn)) == 0 and _about(kn[0], 80) and int(np.nanargmax(nb)) == 0
          and _about(nb[0], 73.72))
    return ok, f"KNN Sel.1/2/3 {_fmt(kn)}, NB {_fmt(nb)}"


def _viii_6(s):
    sv = [s.cv("VIII", k, "svm") for k in (1, 2, 3)]
    last = all(s.cv("VIII", k, "svm") <= min(s.cv("VIII", k, m) for m in ("mlp", "rf", "knn",
                                                                          "nb"))
               for k in (1, 2, 3))
    return last and max(sv) <= 47 + ABOUT, f"SVM Sel.1/2/3 {_fmt(sv)}; last everywhere: {last}"


def _viii_7(s):
    cells = {(m, k): s.cv("VIII", k, m) for m in _NAMES for k in (1, 2, 3)}
    best = max(cells, key=cells.get)
    return best in (("mlp", 3), ("rf", 3)), \
        f"best cell {_NAMES[best[0]]} Sel.{best[1]} {cells[best]:.1f}"


def _ix_1(s):
    rf = s.ood("IX", 1, "rf")
    best, means = _best_model(s, "IX", sels=(1,))
    return bool(rf.min() > 92 and best == "rf"), \
        f"RF Sel.1 {_fmt(rf)}; best on Sel.1: {_NAMES[best]}"


def _ix_2(s):
    nb, kn = s.ood("IX", 1, "nb"), s.ood("IX", 1, "knn")
    ok = (nb.min() >= 86 - ABOUT and nb.max() <= 93 + ABOUT and kn.min() >= 86 - ABOUT
          and kn.max() <= 90 + ABOUT)
    return bool(ok), f"NB Sel.1 {_fmt(nb)}, KNN Sel.1 {_fmt(kn)}"


def _ix_3(s):
    by = {k: s.ood("IX", k, "mlp") for k in (1, 2, 3)}
    best = max(by, key=lambda k: np.nanmax(by[k]))
    top = float(np.nanmax(by[best]))
    return bool(best == 3 and _about(top, 82)), \
        f"MLP best on Sel.{best}, {top:.1f}; Sel.1/2/3 max " + \
        _fmt([np.nanmax(by[k]) for k in (1, 2, 3)])


def _ix_4(s):
    sv = np.concatenate([s.ood("IX", k, "svm") for k in (1, 2, 3)])
    best, means = _best_model(s, "IX")
    worst = min(means, key=means.get)
    return bool(worst == "svm" and np.nanmax(sv) <= 49 + ABOUT), \
        f"SVM best {np.nanmax(sv):.1f}; weakest on average: {_NAMES[worst]}"


def _ix_5(s):
    _, means = _best_model(s, "IX", sels=(1,))
    top2 = sorted(means, key=means.get, reverse=True)[:2]
    return set(top2) == {"rf", "nb"}, "Sel.1 means: " + ", ".join(
        f"{_NAMES[m]} {v:.1f}" for m, v in means.items())


def _x_1(s):
    rf = s.ood("X", 3, "rf")
    best, _ = _best_model(s, "X", models=("mlp", "rf", "knn", "nb"), sels=(3,))
    ok = best == "rf" and rf.min() >= 86 - ABOUT and rf.max() <= 93 + ABOUT
    return bool(ok), f"RF Sel.3 {_fmt(rf)}; best on Sel.3: {_NAMES[best]}"


def _x_2(s):
    rf = s.ood("X", 1, "rf")
    return bool(rf.min() >= 79 - ABOUT and rf.max() <= 88 + ABOUT), f"RF Sel.1 {_fmt(rf)}"


def _x_3(s):
    m = np.nanmax(np.vstack([s.ood("X", 1, "mlp"), s.ood("X", 3, "mlp")]), axis=0)
    return bool(m.min() >= 72 - ABOUT and m.max() <= 83 + ABOUT), \
        f"MLP best selection per split {_fmt(m)}"


def _x_4(s):
    v = np.concatenate([s.ood("X", k, m) for k in (1, 3) for m in ("knn", "nb")])
    return bool(np.nanmax(v) < 75), f"KNN/NB highest {np.nanmax(v):.1f}"


def _x_5(s):
    rf = np.nanmax(np.vstack([s.ood("X", 1, "rf"), s.ood("X", 3, "rf")]), axis=0)
    others = max(np.nanmax(s.ood("X", k, m)) for k in (1, 3) for m in ("mlp", "knn", "nb"))
    return bool(rf.min() >= 86.2 - ABOUT and rf.min() >= others), \
        f"RF worst split {rf.min():.1f} (best selection per split); others' best {others:.1f}"


#: The findings of Sec. IV-A (Table VII) to IV-D (Table X), in the paper's order.
FINDINGS: tuple[Finding, ...] = (
    Finding("VII-1", "VII", "RF and KNN score alike on Selections 1 and 2, almost 100 % and "
            "about 97 %", _vii_1),
    Finding("VII-2", "VII", "RF and KNN have their lowest scores on Selection 3", _vii_2),
    Finding("VII-3", "VII", "MLP scores highest on Selection 3 (about 98 %), below 84 % on the "
            "others", _vii_3),
    Finding("VII-4", "VII", "NB reaches about 93 % on Selection 1 and stays below 80 % on the "
            "others", _vii_4),
    Finding("VII-5", "VII", "SVM comes last; its best is about 66 % on Selection 3", _vii_5),
    Finding("VII-6", "VII", "RF is the most promising classifier", _vii_6),
    Finding("VII-7", "VII", "Every classifier scores highest on Selection 1 or 3: the DFT of "
            "single signals (Selection 2) does not help", _vii_7),
    Finding("VIII-1", "VIII", "Scores on disturbed data are lower than on clean data", _viii_1),
    Finding("VIII-2", "VIII", "MLP and RF on Selection 3 lose only slightly", _viii_2),
    Finding("VIII-3", "VIII", "RF loses about 7 and 9 points on Selections 1 and 2", _viii_3),
    Finding("VIII-4", "VIII", "KNN and NB lose more than RF in every case", _viii_4),
    Finding("VIII-5", "VIII", "KNN's best is about 80 % and NB's best 73.72 %, both on "
            "Selection 1", _viii_5),
    Finding("VIII-6", "VIII", "SVM is lowest, at most about 47 %", _viii_6),
    Finding("VIII-7", "VIII", "MLP and RF on Selection 3 are the most robust to "
            "disturbances", _viii_7),
    Finding("IX-1", "IX", "RF is best, above 92 % on Selection 1 for every held-out gear",
            _ix_1),
    Finding("IX-2", "IX", "On Selection 1 NB reaches 86-93 % and KNN 86-90 %", _ix_2),
    Finding("IX-3", "IX", "MLP's highest score is about 82 %, on Selection 3", _ix_3),
    Finding("IX-4", "IX", "SVM is weakest (best about 48-49 %)", _ix_4),
    Finding("IX-5", "IX", "RF and NB are the best classifiers on Selection 1", _ix_5),
    Finding("X-1", "X", "RF is best on Selection 3 with 86-93 %", _x_1),
    Finding("X-2", "X", "RF reaches 79-88 % on Selection 1", _x_2),
    Finding("X-3", "X", "MLP reaches 72-83 % in its best case", _x_3),
    Finding("X-4", "X", "KNN and NB stay below 75 %", _x_4),
    Finding("X-5", "X", "RF is the most robust, at least 86.2 % for every held-out gear",
            _x_5),
)


def check_findings(cells: pd.DataFrame) -> pd.DataFrame:
    """Check every finding of :data:`FINDINGS` against our scores.

    Parameters
    ----------
    cells : pandas.DataFrame
        :func:`learn.paper.results.our_cells` of one study (columns ``table``,
        ``selection``, ``model``, ``split``, ``ours``).

    Returns
    -------
    pandas.DataFrame
        One row per finding: ``key``, ``table``, ``text``, ``reproduced`` (bool, or None
        where a table it needs was not run) and ``measured`` (the numbers checked).
    """
    s = Scores(cells)
    rows = []
    for f in FINDINGS:
        needs = {f.table, "VII"} if f.table == "VIII" else {f.table}
        if not all(s.has(t) for t in needs):
            rows.append((f.key, f.table, f.text, None, "table not run"))
            continue
        with np.errstate(all="ignore"):
            ok, measured = f.check(s)
        rows.append((f.key, f.table, f.text, bool(ok), measured))
    return pd.DataFrame(rows, columns=["key", "table", "text", "reproduced", "measured"])
