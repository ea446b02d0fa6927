"""The paper's published scores (Tables VII-X) and the reproduction scorecard.

:data:`PAPER_RESULTS` holds the scores transcribed from the paper; :func:`paper_cells`
lists its *test cells* one per row (Table VII: the average test score of each selection
and model; Tables IX and X: the score on the held-out gear of each split, selection and
model; Table VIII has no numbers in the paper's text). :func:`our_cells` puts a study's
``results.csv`` into the same rows, and :func:`scorecard` counts how many cells of each
table lie within ±3, ±5 and ±10 points of the paper and their mean absolute deviation.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from learn.paper.tables import M4, M5, PAPER_TABLES
from swgsim.base.lazy import lazy_module

pd = lazy_module("pandas")

#: Held-out gear of the paper's out-of-distribution rows: 1,2 -> 3; 2,3 -> 1; 1,3 -> 2.
GEAR_SPLITS = ("gear3", "gear1", "gear2")
SPLIT_LABELS = {"gear3": "1,2 → 3", "gear1": "2,3 → 1", "gear2": "1,3 → 2"}
#: Tables with published test cells (Table VIII's numbers are missing from the text).
SCORED_TABLES = ("VII", "IX", "X")
#: Bands of the scorecard [points].
BANDS = (3.0, 5.0, 10.0)


def _cv(values: dict[str, tuple[float, float]]) -> dict[str, dict[str, float]]:
    return {m: {"train": tr, "test": te} for m, (tr, te) in values.items()}


def _ood(models: tuple[str, ...], rows: dict[str, tuple[float, ...]]) -> dict:
    return {split: dict(zip(models, vals, strict=True)) for split, vals in rows.items()}


#: Scores of the paper [%], transcribed from its tables.
#: Tables VII and VIII: avg. training and test score of 4-fold CV, per selection and model.
#: Tables IX and X: score on the held-out gear, per selection, split (held-out gear) and
#: model. Table VIII is ``None``: the paper's Table VIII has no numbers in our source
#: (its text quotes some: best KNN test score about 80 % and NB 73.72 % on Selection 1,
#: SVM at most about 47 %).
PAPER_RESULTS: dict[str, dict | None] = {
    # Table VII: score on training and test set for different selections (cv_clean)
    "VII": {
        "selection1": _cv({"mlp": (84.17, 83.33), "svm": (49.77, 49.60), "rf": (99.92, 99.81),
                           "knn": (98.91, 97.95), "nb": (92.64, 92.59)}),
        "selection2": _cv({"mlp": (82.47, 81.10), "svm": (35.60, 35.49), "rf": (99.56, 99.24),
                           "knn": (98.62, 97.21), "nb": (79.96, 79.89)}),
        "selection3": _cv({"mlp": (99.09, 98.30), "svm": (83.51, 66.10), "rf": (98.21, 96.96),
                           "knn": (97.92, 94.48), "nb": (79.49, 79.43)}),
    },
    # Table VIII: score on training and test set for disturbed data: numbers missing
    "VIII": None,
    # Table IX: avg. score in per cent on out-of-distribution classification (ood_clean)
    "IX": {
        "selection1": _ood(M5, {"gear3": (70.74, 44.44, 92.50, 90.14, 91.99),
                                "gear1": (75.83, 48.15, 99.91, 87.82, 92.69),
                                "gear2": (75.37, 43.84, 93.56, 86.30, 86.16)}),
        "selection2": _ood(M5, {"gear3": (61.16, 31.99, 59.54, 87.36, 76.30),
                                "gear1": (59.54, 30.32, 90.93, 80.88, 79.91),
                                "gear2": (58.98, 30.65, 61.76, 83.33, 67.92)}),
        "selection3": _ood(M5, {"gear3": (79.81, 40.93, 82.82, 77.08, 77.73),
                                "gear1": (81.62, 48.75, 77.82, 65.97, 60.28),
                                "gear2": (74.21, 47.92, 85.79, 83.15, 67.55)}),
    },
    # Table X: out-of-distribution classification on disturbed data (ood_disturbed)
    "X": {
        "selection1": _ood(M4, {"gear3": (51.25, 87.59, 70.93, 66.85),
                                "gear1": (53.70, 85.69, 71.67, 65.00),
                                "gear2": (61.30, 79.03, 65.65, 73.84)}),
        "selection3": _ood(M4, {"gear3": (72.08, 90.09, 56.99, 53.94),
                                "gear1": (82.92, 86.20, 47.31, 56.39),
                                "gear2": (82.87, 92.31, 50.32, 74.26)}),
    },
}


CELL_COLUMNS = ("table", "selection", "model", "split")


def score_text(v: float | None, digits: int) -> str:
    """A score [%] as a table cell shows it.

    Parameters
    ----------
    v : float or None
        The score; None or not finite where there is none.
    digits : int
        Decimals.

    Returns
    -------
    str
        ``v`` to ``digits`` decimals, or "–" where there is no score.
    """
    return "–" if v is None or not np.isfinite(v) else f"{v:.{digits}f}"


def paper_cells() -> pd.DataFrame:
    """The paper's test cells, one per row.

    Returns
    -------
    pandas.DataFrame
        Columns ``table`` ("VII", "IX", "X"), ``selection``, ``model``, ``split``
        ("mean" for the CV tables, else the held-out gear "gear1".."gear3") and
        ``paper`` [%]; 84 rows (15 + 45 + 24).
    """
    rows = []
    for table in SCORED_TABLES:
        for sel, by in PAPER_RESULTS[table].items():
            if table == "VII":
                rows += [(table, sel, m, "mean", v["test"]) for m, v in by.items()]
            else:
                rows += [(table, sel, m, split, v) for split, d in by.items()
                         for m, v in d.items()]
    return pd.DataFrame(rows, columns=[*CELL_COLUMNS, "paper"])


def our_cells(results: pd.DataFrame) -> pd.DataFrame:
    """Test scores of a study in the cells of :func:`paper_cells`.

    Parameters
    ----------
    results : pandas.DataFrame
        One row per (table, selection, model, split) with ``test_accuracy`` in [0, 1]
        (``results.csv`` of :func:`learn.paper.task.run_paper_study`).

    Returns
    -------
    pandas.DataFrame
        Columns :data:`CELL_COLUMNS` and ``ours`` [%]: the mean over folds for the CV
        tables (split "mean"), the held-out gear's score for the others; every table
        present in ``results`` (Table VIII too).
    """
    r = results.copy()
    cv = r["table"].isin(["VII", "VIII"])
    r.loc[cv, "split"] = "mean"
    out = (r.groupby(list(CELL_COLUMNS), sort=False)["test_accuracy"].mean() * 100.0)
    return out.rename("ours").reset_index()


def scorecard(cells: pd.DataFrame, column: str = "ours") -> pd.DataFrame:
    """Deviation of ``column`` from the paper per table.

    Parameters
    ----------
    cells : pandas.DataFrame
        :func:`paper_cells` merged with our scores (columns ``table``, ``paper``,
        ``column``); rows without a paper value are ignored; a missing score counts as
        outside every band.
    column : str
        Column of our scores [%].

    Returns
    -------
    pandas.DataFrame
        One row per table in :data:`SCORED_TABLES`: ``cells`` (number of paper cells),
        ``within_3``, ``within_5``, ``within_10`` (cells with ``|ours − paper| <= band``),
        ``mad`` (mean absolute deviation over the cells with a score [points]) and
        ``missing`` (cells without a score).
    """
    rows = []
    for table in SCORED_TABLES:
        c = cells[(cells["table"] == table) & cells["paper"].notna()]
        d = (c[column] - c["paper"]).abs()
        row = {"table": table, "cells": len(c)}
        for b in BANDS:
            row[f"within_{b:g}"] = int((d <= b).sum())
        row["mad"] = float(d.mean()) if d.notna().any() else float("nan")
        row["missing"] = int(d.isna().sum())
        rows.append(row)
    return pd.DataFrame(rows)


def side_by_side(results: Mapping[str, pd.DataFrame]) -> pd.DataFrame:
    """Every cell of Tables VII-X: the paper's score beside ours under each recording.

    Parameters
    ----------
    results : mapping of str to pandas.DataFrame
        Data-set name (e.g. "paper", "bench") -> that study's ``results.csv``.

    Returns
    -------
    pandas.DataFrame
        Columns :data:`CELL_COLUMNS`, ``paper`` [%] (NaN where the paper gives none, e.g.
        Table VIII) and one column ``ours_<name>`` [%] per data set; rows in the
        paper's order (table, selection, split, model).
    """
    frames = [our_cells(r).rename(columns={"ours": f"ours_{name}"})
              for name, r in results.items()]
    out = paper_cells()  # every paper cell stays, with or without our score
    for f in frames:
        out = out.merge(f, on=list(CELL_COLUMNS), how="outer")
    order = {t: i for i, t in enumerate(PAPER_TABLES)}
    split_order = {s: i for i, s in enumerate(("mean", *GEAR_SPLITS))}
    model_order = {m: i for i, m in enumerate(M5)}
    key = (out["table"].map(order) * 1e6 + out["selection"].str[-1].astype(int) * 1e4
           + out["split"].map(split_order) * 1e2 + out["model"].map(model_order).fillna(99))
    cols = [*CELL_COLUMNS, "paper", *(f"ours_{n}" for n in results)]
    return out.assign(_k=np.asarray(key)).sort_values("_k")[cols].reset_index(drop=True)
