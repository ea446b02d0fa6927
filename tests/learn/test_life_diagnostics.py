"""scripts/life_diagnostics.py: one held-out gear's life through the monitor, the same
windows as the evaluation's (swgmon.evaluation.evaluate.healthy_life), its events and per-point
z-scores; bad input in one line, exit 2."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from swgmon.assessment.model_io import save_model
from swgmon.evaluation.evaluate import healthy_life, lives_of
from swgmon.evaluation.families import default_families
from swgmon.evaluation.study import MonitorStudyConfig
from swgmon.evaluation.training import train_model

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))
import life_diagnostics  # noqa: E402


@pytest.fixture(scope="module")
def tiny_model(tmp_path_factory, tiny_bench):
    """A diagnosis model of the tiny bench trained on gears 1 and 2, saved with its card
    (the bench's records shared with the worker's other tests: tests/conftest.py)."""
    p, banks = tiny_bench
    design = MonitorStudyConfig(commissioning_h=4.0, train_healthy_h=2.0, train_variants=1,
                                faults=["eccentric_wg"], nuisances={})
    model = train_model(p, banks, [1, 2], design)
    return save_model(model, tmp_path_factory.mktemp("model") / "tiny_bench_without_gear3",
                      [{"name": "tiny_bench", "config_hash": p.config_hash}])


def test_healthy_life_is_the_evaluations(tiny_bench):
    p, banks = tiny_bench
    cfg = MonitorStudyConfig(healthy_hours=30.0, nuisance_hours=30.0,
                             families=default_families())
    for nuisance in ("none", "warm_up", "family:warm_up"):
        ours = healthy_life(p, banks[3], 3, cfg, 4, nuisance)
        theirs, _ = lives_of(p, banks, 3, cfg, 4, nuisance)
        assert ours.life == theirs.life
        a, b = ours.windows(1500, 1510)[0], theirs.windows(1500, 1510)[0]
        np.testing.assert_array_equal(a, b)
    with pytest.raises(KeyError, match="allowed none, warm_up"):
        healthy_life(p, banks[3], 3, cfg, 4, "summer")


def test_life_diagnostics_lists_events_and_points(tiny_model, tmp_path, capsys):
    out = tmp_path / "z.csv"
    rc = life_diagnostics.main([str(tiny_model), "--dataset", "tiny_bench", "--gear", "3",
                                "--nuisance", "warm_up", "--hours", "30", "--csv", str(out)])
    assert rc == 0
    text = capsys.readouterr().out
    assert "tiny_bench gear 3, seed 0, nuisance warm_up: 360 windows after commissioning" \
        in text
    assert "mean z, furthest" in text
    assert re.search(r"(s\d_\w+|efficiency) [+-]\d\.\d\d", text)
    table = pd.read_csv(out)
    assert len(table) == 360
    assert {"hour", "p", "novelty", "z_efficiency", "temperature_c"} <= set(table.columns)
    assert table["hour"].is_monotonic_increasing
    assert table["p"].between(0, 1).all()


def test_a_family_draw_is_looked_at_like_a_nuisance(tiny_model, capsys):
    rc = life_diagnostics.main([str(tiny_model), "--dataset", "tiny_bench", "--gear", "3",
                                "--seed", "7", "--nuisance", "family:drift", "--hours", "30"])
    assert rc == 0
    assert "tiny_bench gear 3, seed 7, nuisance family:drift: 360 windows" \
        in capsys.readouterr().out


@pytest.mark.parametrize("args, says", [
    (["--nuisance", "summer"], "--nuisance 'summer': allowed none, warm_up"),
    (["--nuisance", "family:summer"], "family:<key> with key one of friction_law, warm_up"),
    (["--gear", "7"], "--gear 7: tiny_bench has gears [1, 2, 3]"),
    (["--hours", "3"], "--hours 3: must lie in (24, 1e5]"),
    (["--set", "chain.window_s=0.2"], "was trained on tiny_bench, not on --dataset tiny_bench"),
    (["--benchmark", "--nuisance", "family:drift"],
     "with --benchmark, family:<key> with key one of warm_up, hall"),
    (["--benchmark", "--nuisance", "family:all", "--seed", "1000"],
     "seeds [1000] are scored seeds"),
    (["--benchmark", "--nuisance", "family:all", "--seed", "300"],
     "was trained on tiny_bench, not on --dataset tiny_bench"),  # not the benchmark's lot
])
def test_bad_input_is_one_line(tiny_model, capsys, args, says):
    rc = life_diagnostics.main([str(tiny_model), "--dataset", "tiny_bench", *args])
    err = capsys.readouterr().err
    assert rc == 2 and says in err and err.count("\n") == 1


def test_missing_model_is_one_line(tmp_path, capsys):
    rc = life_diagnostics.main([str(tmp_path / "none.skops"), "--dataset", "tiny_bench"])
    err = capsys.readouterr().err
    assert rc == 2 and "no diagnosis model" in err and err.count("\n") == 1
