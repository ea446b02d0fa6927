"""The main job (swgsim-paper): both acquisitions, reports, summary, safe data folders."""

import pandas as pd
import pytest

from swgcli import compose_app
from swgcli.paper import run_paper


def main_cfg(tmp_path, tracking_uri, *extra):
    """The main job on the tiny grid into ``tmp_path``, its runs in the session's MLflow
    store (a new store's tables take seconds to create; the runs are told apart by their
    ids)."""
    return compose_app("paper", [
            "grid=tiny", f"data_root={tmp_path}/data", f"report_root={tmp_path}/reports",
            f"tracking_uri={tracking_uri}", "study.figures=false",
            "study.tables=[VII,X]", "study.models=[rf,nb]",
            *extra])


def test_main_job_runs_both_recordings_side_by_side(tmp_path, tracking_uri, capsys):
    out = run_paper(main_cfg(tmp_path, tracking_uri))
    printed = capsys.readouterr().out
    for p in ("paper", "bench"):
        res = pd.read_csv(tmp_path / "reports" / p / "results.csv")
        assert set(res["table"]) == {"VII", "X"} and set(res["model"]) == {"rf", "nb"}
        conf = pd.read_csv(tmp_path / "reports" / p / "confusion.csv")
        assert list(conf.columns) == ["table", "protocol", "selection", "model", "true",
                                      "predicted", "count"]
        assert (tmp_path / "data" / p / "manifest.json").is_file()
    md = (tmp_path / "reports" / "summary.md").read_text()
    assert "| paper | VII | 15 |" in md and "| bench | X | 24 |" in md
    assert "Reproduction scorecard" in printed and "wall time per stage" in printed
    assert set(out["stages_s"]) == {"generate paper", "generate bench", "study paper",
                                    "study bench", "summary", "total"}
    # every study job is an MLflow run with the data set as input and its last-split model
    import mlflow

    client = mlflow.MlflowClient(tracking_uri)
    exps = [e.experiment_id for e in client.search_experiments()
            if e.name.startswith("paper/")]
    run_ids = set()
    for p in ("paper", "bench"):
        run_ids |= set(pd.read_csv(tmp_path / "reports" / p / "results.csv")["run_id"])
    runs = {r.info.run_id: r for r in client.search_runs(exps)}
    assert run_ids <= set(runs)
    for rid in run_ids:
        assert runs[rid].inputs.dataset_inputs and len(runs[rid].outputs.model_outputs) == 1
        assert runs[rid].data.tags["mlflow.source.git.commit"]
    # the second run finds both data sets valid and simulates nothing (its study the
    # smallest, one model and table without its models logged: only generation is asked)
    again = run_paper(main_cfg(tmp_path, tracking_uri, "study.tables=[X]",
                               "study.models=[nb]", "log_models=false"))
    assert all(not g["computed"] for g in again["generate"].values())


def test_main_job_never_deletes_what_it_did_not_create(tmp_path, tracking_uri):
    folder = tmp_path / "data" / "paper"
    folder.mkdir(parents=True)
    (folder / "thesis.pdf").write_bytes(b"%PDF years of work")
    with pytest.raises(ValueError, match=f"{folder}.*thesis.pdf"):
        run_paper(main_cfg(tmp_path, tracking_uri))
    assert (folder / "thesis.pdf").read_bytes() == b"%PDF years of work"


@pytest.mark.parametrize("override, match", [
    ("run_on=[paper,robot]", "not among the configured data sets"),
    ("run_on=[]", "at least one"),
    ("datasets.bench.acquisition.start=sometimes", "datasets.bench: dataset.acquisition.start"),
    ("n_jobs=0", r"n_jobs must lie in \[1, inf\)"),
])
def test_main_job_refuses_bad_input_before_any_work(tmp_path, tracking_uri, override, match):
    with pytest.raises(ValueError, match=match):
        run_paper(main_cfg(tmp_path, tracking_uri, override))
    assert not (tmp_path / "data").exists()


@pytest.mark.parametrize("app, override, new", [
    ("swgsim-paper", "protocols=[paper]", "run_on"),
    ("swgsim-paper", "~protocols", "run_on"),
    ("swgsim-train", "data=tiny", "stored"),
    ("swgsim-train", "data.path=/x", "stored"),
])
def test_old_names_are_refused_naming_the_new_one(tmp_path, app, override, new):
    import subprocess
    import sys
    from pathlib import Path

    exe = Path(sys.executable).parent / app
    r = subprocess.run([str(exe), override, f"hydra.run.dir={tmp_path}/run"],
                       capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert r.returncode == 2
    old = override.lstrip("~").split("=")[0].split(".")[0]
    assert r.stderr.strip().splitlines()[-1].startswith(
        f"{app}: error: {old}: renamed {new}")
    assert not (tmp_path / "run").exists() and not (tmp_path / "data").exists()
