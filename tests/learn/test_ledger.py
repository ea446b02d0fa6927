"""Scored seeds and the ledger of scored runs (learn.tracking.ledger, issue 83): a scored
seed outside a declared scored run is refused in one line, a design seed inside one too,
and every scored run is one more row of the ledger, the same run twice twice."""

from __future__ import annotations

import dataclasses

import pytest

from learn.tracking import ledger as lg
from swgmon.evaluation.study import MonitorStudyConfig
from swgsim.base.typed import check_tree


def test_a_scored_seed_outside_a_scored_run_is_refused_in_one_line():
    with pytest.raises(ValueError, match=r"^seeds \[1000\] are scored seeds \(>= 1000\): they "
                                         r"run only in a declared scored run \(k=true\)"):
        lg.check_seeds([3, 1000], False, "k")
    with pytest.raises(ValueError, match=r"^k=true: a scored run draws scored seeds \(>= "
                                         r"1000\) only, got design seeds \[3\]$"):
        lg.check_seeds([3, 1000], True, "k")
    lg.check_seeds([0, 4, 100], False, "k")
    lg.check_seeds([1000, 1001], True, "k")


def test_the_monitor_study_refuses_scored_seeds_unless_declared_a_scored_run():
    study = dataclasses.replace(MonitorStudyConfig(), seeds=[1000, 1001])
    with pytest.raises(ValueError, match=r"monitor.study.scored_run=true"):
        check_tree(study, "monitor.study")
    scored = dataclasses.replace(study, scored_run=True, family_seeds=[1002])
    check_tree(scored, "monitor.study")
    with pytest.raises(ValueError, match=r"design_seeds must lie below 1000"):
        check_tree(dataclasses.replace(scored, design_seeds=[1003]), "monitor.study")


def test_every_scored_run_is_a_row_of_the_ledger_the_same_run_twice_twice(tmp_path):
    res = tmp_path / "results.csv"
    res.write_text("a,b\n1,2\n")
    book = tmp_path / "ledger.csv"
    first = lg.append_scored_run([1001, 1000], [res], "swgsim-train experiment=monitor",
                                 ledger=book)
    again = lg.append_scored_run([1000, 1001], [res], "swgsim-train experiment=monitor",
                                 ledger=book)
    rows = lg.read_ledger(book)
    assert len(rows) == 2 and rows[0]["seeds"] == rows[1]["seeds"] == "1000 1001"
    assert first["results_sha256"] == again["results_sha256"] == rows[1]["results_sha256"]
    assert rows[0]["tree"] in ("clean", "dirty", "unknown") and rows[0]["commit"]
    res.write_text("a,b\n1,3\n")  # other results: another digest
    assert lg.append_scored_run([1000], [res], "x", ledger=book)["results_sha256"] != \
        first["results_sha256"]
    assert len(lg.read_ledger(book)) == 3
