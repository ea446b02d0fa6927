"""The torch nets on signals in the default transfer comparison: MLP and CNN, each on raw
and differenced signals, with the experiment's own model settings; the comparison's
progress line and its log line per job."""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np
import pytest
from data_sets import make_toy_dataset
from omegaconf import OmegaConf

from learn.studies.runs import JobProgress, RunRef
from learn.transfer.study import RUN_TIME_COLUMNS, planned_jobs, run_comparison
from swgcli import compose_app

pytestmark = pytest.mark.usefixtures("torch_one_thread")

SIGNAL_RUNS = [("mlp_torch", "raw"), ("mlp_torch", "diff"), ("cnn", "raw"), ("cnn", "diff")]


@pytest.fixture(scope="module")
def experiment():
    """The default comparison, typed (``swgsim-train experiment=transfer``)."""
    cfg = compose_app("train", ["experiment=transfer"])
    return OmegaConf.to_object(cfg.transfer)


@pytest.fixture(scope="module")
def toy():
    return make_toy_dataset(n_variants=4, n_time=256)


def test_default_comparison_holds_every_promised_run(experiment):
    """MLP and CNN on raw and differenced signals beside the paper's pipeline, the
    residual inputs and MiniRocket, fine-tuned on k shots; the declared primary stays."""
    runs = {(s.model, s.input): s for s in experiment.runs}
    assert set(SIGNAL_RUNS) <= set(runs)
    assert all(runs[r].finetune for r in SIGNAL_RUNS)
    assert ("rf", "sel1") in runs
    assert {"raw_res", "res_spec"} <= {s.input for s in experiment.runs}
    assert "minirocket" in {s.model for s in experiment.runs}
    assert experiment.primary == RunRef("minirocket", "raw_res")
    assert experiment.run_on == ["paper", "bench", "robot_joint"]
    assert experiment.protocols == ["ood_disturbed"] and len(experiment.seeds) == 5
    assert set(experiment.k_shots) == {0, 1, 5, 10}
    assert planned_jobs(experiment) == 3 * 5


@pytest.mark.parametrize(("model", "kind"), SIGNAL_RUNS,
                         ids=[f"{m}-{i}" for m, i in SIGNAL_RUNS])
def test_signal_run_trains_and_predicts_in_seconds(experiment, toy, model, kind):
    """Each of the four runs, as the default comparison configures it (epochs, early
    stopping, batch size, fine-tuning), on the toy data set: three held-out gears, k = 0
    and fine-tuned on k = 2; every row scored on the evaluation windows, in seconds."""
    spec = next(s for s in experiment.runs if (s.model, s.input) == (model, kind))
    tc = replace(experiment, runs=[spec], primary=None, seeds=[0], k_shots=[0, 2],
                 adapt_windows=4, n_jobs=1, latency=False, progress=False)
    out = run_comparison(toy, tc, dataset="toy")
    res, run_s = out["results"], out["run_s"]
    assert tuple(run_s.columns) == RUN_TIME_COLUMNS and len(run_s) == 3
    adapt = ["+adabn"] if spec.adapt == "adabn" else []
    assert set(res["model"]) == {model, *(model + a for a in adapt),
                                 f"{model}+ft_all", f"{model}+ft_last"}
    assert res["n_test"].gt(0).all() and res["accuracy"].between(0, 1).all()
    k0 = res[res["model"] == model]
    # chance 1/6; measured 0.44-0.71 (MLP, raw / diff) and 0.65-0.76 (CNN) mean over the
    # held-out gears: 0.3 leaves room, and a net that learned nothing fails it
    assert k0["accuracy"].mean() > 0.3
    # one thread; measured 0.2-2.5 s CPU per job on the toy's 288 windows of 256 samples
    assert run_s["cpu_s"].max() < 10.0


def test_progress_counts_jobs_and_logs_each(caplog):
    """One line over all data sets: done, left; a log line per finished job naming it."""
    from learn.studies.protocols import Split

    p = JobProgress(4, enabled=False)
    sp = Split("gear3", "1,2 -> 3", np.arange(2), np.arange(2, 4))
    rows = [{"model": "cnn", "input": "raw", "k_shot": 0, "accuracy": 0.5},
            {"model": "cnn+ft_all", "input": "raw", "k_shot": 5, "accuracy": 0.6}]
    with caplog.at_level(logging.INFO, logger="learn.studies.runs"):
        p.finished("bench", ("ood_disturbed", sp, 0), {"cnn/raw": (2.0, 1.5)}, rows)
        p.adjust(-1)
        p.finished("paper", ("ood_disturbed", sp, 1), {"cnn/raw": (3.0, 2.5)}, rows)
    p.close()
    assert p.done == 2 and p.total == 3
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 2
    assert lines[0].startswith("job 1/4 done, 3 left") and "bench ood_disturbed gear3 seed 0" \
        in lines[0] and "'cnn/raw': 0.5" in lines[0]
    assert lines[1].startswith("job 2/3 done, 1 left") and "paper" in lines[1]
