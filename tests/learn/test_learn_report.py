"""Paper study and its report (learn.paper.task.run_paper_study, learn.paper.report)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from learn.paper.report import write_report, write_tables
from learn.paper.results import PAPER_RESULTS
from learn.paper.tables import PAPER_TABLES, StudyOptions
from learn.paper.task import run_paper_study


def _fake_results() -> pd.DataFrame:
    rows = []
    for table, spec in PAPER_TABLES.items():
        splits = (["fold0", "fold1", "fold2", "fold3"] if spec.protocol.startswith("cv")
                  else ["gear3", "gear1", "gear2"])
        for s in spec.selections:
            for m in spec.models:
                for sp in splits:
                    rows.append({"table": table, "protocol": spec.protocol,
                                 "selection": f"selection{s}", "model": m, "split": sp,
                                 "train_accuracy": 0.5, "test_accuracy": 0.25})
    return pd.DataFrame(rows)


def _section(md: str, table: str) -> str:
    return md.split(f"## Table {table}:")[1].split("## ")[0]


def test_tables_have_paper_layout_and_numbers(tmp_path):
    md = write_tables(_fake_results(), tmp_path / "t.md").read_text()
    for table in ("VII", "VIII", "IX", "X"):
        assert f"## Table {table}:" in md
    vii = _section(md, "VII")
    assert "| | MLP | SVM | RF | KNN | NB |" in vii
    assert "| Avg. test score [%] | 25.00 (83.33) | 25.00 (49.60) | 25.00 (99.81)" in vii
    assert "| Avg. training score [%] | 50.00 (84.17)" in vii
    assert "gives no numbers" in _section(md, "VIII") and "(–)" in _section(md, "VIII")
    assert "| 2,3 → 1 | 25.00 (75.83) | 25.00 (48.15) | 25.00 (99.91)" in _section(md, "IX")
    x = _section(md, "X")
    assert "| | MLP | RF | KNN | NB |" in x and "Selection 2" not in x
    assert "| 1,3 → 2 | 25.00 (82.87) | 25.00 (92.31) | 25.00 (50.32) | 25.00 (74.26) |" in x
    assert PAPER_RESULTS["VIII"] is None


def test_missing_jobs_read_dash(tmp_path):
    res = _fake_results()
    res = res[~((res["table"] == "IX") & (res["model"] == "svm"))]
    md = write_tables(res, tmp_path / "t.md").read_text()
    assert "| 1,2 → 3 | 25.00 (70.74) | – (44.44) |" in _section(md, "IX")


def test_paper_study_small(tiny_dataset, tracking_uri, tmp_path):
    out = run_paper_study(tiny_dataset, tmp_path / "paper",
                          StudyOptions(tables=["VII", "X"], models=["nb", "knn"]),
                          tracking_uri=tracking_uri, progress=False)
    res = out["results"]
    assert set(res["table"]) == {"VII", "X"}
    assert len(res) == 3 * 2 * 4 + 2 * 2 * 3 and out["n_jobs_run"] == 6 + 4
    assert res["run_id"].notna().all() and res["run_id"].nunique() == 10
    assert set(out["timings_s"]) == {"features", "VII", "X"}
    nb1 = res[(res["table"] == "VII") & (res["model"] == "nb")
              & (res["selection"] == "selection1")]
    assert nb1["test_accuracy"].mean() > 0.5  # chance: 1/6
    files = out["files"]
    for kind in ("tables", "csv", "fig6", "fig7", "fig8", "confusion_VII", "confusion_X"):
        assert files[kind].is_file() and files[kind].stat().st_size > 0, kind
    md = files["tables"].read_text()
    assert "## Table VII:" in md and "## Table X:" in md and "## Run time" in md
    back = pd.read_csv(files["csv"])
    assert np.allclose(back["test_accuracy"], res["test_accuracy"])
    with pytest.raises(ValueError, match="tables must be among"):
        run_paper_study(tiny_dataset, tmp_path, StudyOptions(tables=["XI"]), track=False)


def test_write_report_without_dataset_has_no_figures(tmp_path):
    files = write_report(_fake_results(), tmp_path / "r")
    assert set(files) == {"tables", "csv"}
