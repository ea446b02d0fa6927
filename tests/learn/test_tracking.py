"""MLflow runs through learn.tracking.log_run: git commit, data set, config, model, groups."""

from __future__ import annotations

import hashlib
import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from learn.tracking import GROUP_PARENT_TAG, log_run, repo_root
from learn.tracking.provenance import (
    DIGEST_CHARS,
    GIT_COMMIT_TAG,
    GIT_DIRTY_TAG,
    dataset_ref,
    git_tags,
)


def _client(uri):
    import mlflow

    return mlflow.MlflowClient(uri)


def _xy(n=240, seed=0):
    """Three separable classes in 6 features (string labels, as the study's)."""
    rng = np.random.default_rng(seed)
    y = np.array(["healthy", "eccentric_wg", "tip_tooth_crack"])[np.arange(n) % 3]
    X = rng.normal(size=(n, 6)) + 2.0 * (np.arange(n) % 3)[:, None]
    return X, y


def _head():
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=repo_root(), capture_output=True,
                             text=True, timeout=20)
    except OSError:
        return "unknown"
    return out.stdout.strip() if out.returncode == 0 else "unknown"


def _inputs(client, run_id):
    return client.get_run(run_id).inputs.dataset_inputs


def test_run_carries_commit_dataset_config_and_model(tiny_dataset, tracking_uri, tmp_path):
    import mlflow

    from learn.learners.models import make_model

    X, y = _xy()
    model = make_model("rf", random_state=0).set_params(rf__n_estimators=20).fit(X, y)
    cfg = {"model": {"name": "rf", "n_estimators": 20}, "data": {"path": str(tiny_dataset)}}
    with log_run("test-tracking", "rf-job", tracking_uri=tracking_uri, params=cfg, config=cfg,
                 dataset=tiny_dataset, tags={"task": "test"}) as run:
        run.log_metrics({"mean_test_accuracy": 0.5})
        model_id = run.log_model(model, X_sample=X[:5], tags={"split": "fold4"})
    client = _client(tracking_uri)
    got = client.get_run(run.run_id)
    assert got.info.status == "FINISHED"
    # git commit and dirty flag
    assert got.data.tags[GIT_COMMIT_TAG] == _head()
    assert got.data.tags[GIT_DIRTY_TAG] in ({"true", "false"} if _head() != "unknown"
                                           else {"unknown"})
    # the data set: path and digest (this manifest has no content_sha256: shard hashes)
    manifest = json.loads((tiny_dataset / "manifest.json").read_text())
    listed = "".join(f"{k}:{v['sha256']}\n" for k, v in sorted(manifest["shards"].items()))
    want = hashlib.sha256(listed.encode()).hexdigest()
    (inp,) = _inputs(client, run.run_id)
    assert inp.dataset.digest == want[:DIGEST_CHARS]
    assert str(tiny_dataset.resolve()) in inp.dataset.source
    assert json.loads(inp.dataset.profile)["sha256"] == want
    assert {t.key: t.value for t in inp.tags}["mlflow.data.context"] == "training"
    # the config: flattened params and config.yaml
    assert got.data.params["model.n_estimators"] == "20"
    path = client.download_artifacts(run.run_id, "config.yaml", str(tmp_path))
    assert yaml.safe_load(open(path)) == cfg
    # the model: linked to the run, loadable, predicts the same
    assert model_id is not None
    assert model_id in [o.model_id for o in got.outputs.model_outputs]
    lm = client.get_logged_model(model_id)
    assert lm.source_run_id == run.run_id and lm.tags["serialization_format"] == "cloudpickle"
    assert lm.tags["split"] == "fold4"
    loaded = mlflow.sklearn.load_model(lm.artifact_location)
    X2, _ = _xy(seed=1)
    np.testing.assert_array_equal(loaded.predict(X2), model.predict(X2))
    np.testing.assert_array_equal(loaded.predict_proba(X2), model.predict_proba(X2))


def test_content_hash_of_the_manifest_is_the_digest(tiny_dataset, tmp_path):
    d = tmp_path / "ds"
    shutil.copytree(tiny_dataset, d)
    m = json.loads((d / "manifest.json").read_text())
    m["content_sha256"] = hashlib.sha256(b"planted").hexdigest()
    (d / "manifest.json").write_text(json.dumps(m))
    ref = dataset_ref(d)
    assert ref.digest_of == "content_sha256" and ref.sha256 == m["content_sha256"]
    assert ref.digest == m["content_sha256"][:DIGEST_CHARS] and ref.name == "ds"
    # a changed manifest is read again, not served from the cache
    m["content_sha256"] = hashlib.sha256(b"other").hexdigest()
    (d / "manifest.json").write_text(json.dumps(m, indent=1))
    assert dataset_ref(d).sha256 == m["content_sha256"]
    f = tmp_path / "rec.csv"
    f.write_text("t,q\n0,1\n")
    assert dataset_ref(f).sha256 == hashlib.sha256(f.read_bytes()).hexdigest()
    with pytest.raises(ValueError, match="dataset=.*manifest.json"):
        dataset_ref(tmp_path / "nowhere")


def test_no_git_gives_unknown(tmp_path, monkeypatch):
    assert git_tags(tmp_path) == {GIT_COMMIT_TAG: "unknown", GIT_DIRTY_TAG: "unknown"}
    monkeypatch.setenv("PATH", str(tmp_path))  # no git executable at all
    assert git_tags(repo_root() / "tests") == {GIT_COMMIT_TAG: "unknown",
                                               GIT_DIRTY_TAG: "unknown"}


def test_grouped_runs_are_children_of_one_parent(tiny_dataset, tracking_uri):
    group = "sweep /tmp/multirun/test-group"
    ids = []
    for name in ("a", "b", "c"):
        with log_run("test-groups", name, tracking_uri=tracking_uri, dataset=tiny_dataset,
                     group=group) as run:
            run.log_metrics({"x": 1.0})
        ids.append(run.run_id)
    client = _client(tracking_uri)
    parents = {client.get_run(i).data.tags["mlflow.parentRunId"] for i in ids}
    assert len(parents) == 1
    parent = client.get_run(parents.pop())
    assert parent.data.tags[GROUP_PARENT_TAG] == group
    assert parent.info.run_name == "sweep multirun/test-group"  # a short name to browse
    assert parent.info.status == "FINISHED" and GIT_COMMIT_TAG in parent.data.tags
    assert len(_inputs(client, parent.info.run_id)) == 1
    assert {client.get_run(i).data.tags["group"] for i in ids} == {group}
    # a failing child is FAILED, and so is its group's parent; the error propagates
    with pytest.raises(RuntimeError, match="boom"):
        with log_run("test-groups", "d", tracking_uri=tracking_uri, group=group):
            raise RuntimeError("boom")
    runs = client.search_runs([parent.info.experiment_id], "attributes.run_name = 'd'")
    assert runs[0].info.status == "FAILED"
    assert client.get_run(parent.info.run_id).info.status == "FAILED"


@pytest.mark.parametrize("kind", ["mlp_torch", "minirocket"])
def test_own_estimators_are_logged_in_cloudpickle_quietly(kind, tracking_uri, capfd):
    """The torch nets and MiniRocket inside their pipelines round-trip through
    mlflow.sklearn, and MLflow's per-model pickle warning stays off the console."""
    import mlflow

    from learn.learners.models import make_pipeline

    if kind == "mlp_torch":
        from learn.learners.nets import MLPClassifierTorch

        X, y = _xy(n=120)
        est = MLPClassifierTorch(hidden=(8,), max_epochs=3, device="cpu", random_state=0)
    else:
        from learn.learners.rocket import MiniRocketClassifier

        X2, y = _xy(n=60)
        X = X2[:, :2, None] * np.sin(np.linspace(0, 6, 64))  # (n, 2 channels, 64 samples)
        est = MiniRocketClassifier(n_kernels=84, random_state=0)
    model = make_pipeline(est, kind).fit(X, y)
    capfd.readouterr()
    with log_run("test-tracking", kind, tracking_uri=tracking_uri) as run:
        model_id = run.log_model(model, X_sample=X[:5])
    err = capfd.readouterr().err
    assert "WARNING" not in err and "pickle" not in err, err
    lm = _client(tracking_uri).get_logged_model(model_id)
    assert lm.tags["serialization_format"] == "cloudpickle"
    loaded = mlflow.sklearn.load_model(lm.artifact_location)
    np.testing.assert_array_equal(loaded.predict(X), model.predict(X))


def test_a_nets_learning_curve_is_logged_per_epoch(tracking_uri):
    """Issue 87: the nets logged no learning curves."""
    from learn.learners.models import make_pipeline
    from learn.learners.nets import MLPClassifierTorch

    X, y = _xy(n=120)
    est = MLPClassifierTorch(hidden=(8,), max_epochs=4, device="cpu", random_state=0)
    model = make_pipeline(est, "mlp_torch").fit(X, y)
    with log_run("test-tracking", "curve", tracking_uri=tracking_uri) as run:
        n = run.log_learning_curve(model)
    assert n == len(est.history_) > 0
    hist = _client(tracking_uri).get_metric_history(run.run_id, "epoch/loss")
    assert [m.step for m in hist] == [r["epoch"] for r in est.history_]
    assert [m.value for m in hist] == pytest.approx([r["loss"] for r in est.history_])


def test_study_job_logs_dataset_and_last_split_model(tiny_dataset, tracking_uri, tmp_path):
    """swgsim-train's job: the logged model is the last split's, so it reproduces that
    split's reported test accuracy exactly (same seed, same rows)."""
    import mlflow
    from omegaconf import OmegaConf

    from learn.inputs.features import extract_features
    from learn.studies.protocols import make_splits
    from swgcli import compose_app
    from swgcli.tasks import run_train
    from swgsim.datasets.schema import load

    cfg = compose_app("train", [f"stored.path={tiny_dataset}",
                                f"logger.tracking_uri={tracking_uri}",
                                f"paths.root_dir={tmp_path}", "model=rf", "features=selection1",
                                "protocol=ood_disturbed", "model.estimator.n_estimators=20",
                                "logger.log_models=true"])
    out = run_train(cfg)
    client = _client(tracking_uri)
    run = client.get_run(out["run_id"])
    (inp,) = _inputs(client, out["run_id"])
    assert inp.dataset.digest == dataset_ref(tiny_dataset).digest
    assert GIT_COMMIT_TAG in run.data.tags and "mlflow.parentRunId" not in run.data.tags
    (mo,) = run.outputs.model_outputs
    lm = client.get_logged_model(mo.model_id)
    model = mlflow.sklearn.load_model(lm.artifact_location)
    feats = extract_features(load(tiny_dataset), 1, **OmegaConf.to_object(cfg.features).kwargs())
    pcfg = OmegaConf.to_container(cfg.protocol, resolve=True)
    pcfg.pop("name")
    last = make_splits(feats.meta, **pcfg)[-1]
    assert lm.tags["split"] == last.label
    y = feats.meta["fault"].to_numpy().astype(str)
    acc = float(np.mean(model.predict(feats.X[last.test]) == y[last.test]))
    assert acc == pytest.approx(out["test_accuracy"][-1], abs=1e-12)


def test_transfer_cells_log_seed_statistics_not_steps(tiny_dataset, tracking_uri):
    from learn.tracking.config import LoggerConfig
    from learn.transfer.runs import log_transfer
    from learn.transfer.study import TransferConfig

    rows = [{"dataset": "tiny", "protocol": "ood_disturbed", "split": f"gear{g}", "model": m,
             "input": "sel1", "k_shot": 0, "seed": sd, "accuracy": 0.5 + 0.1 * g + 0.01 * sd,
             "train_s": 1.0, "n_test": 10}
            for m in ("rf", "cnn") for g in (1, 2, 3) for sd in (0, 1)]
    res = pd.DataFrame(rows)
    logger = LoggerConfig(tracking_uri=tracking_uri, experiment="test-transfer",
                          run_name="transfer")
    tc = TransferConfig(run_on=[], data_root="unused", seeds=[0, 1])
    pid = log_transfer(res, {}, logger, tc, [("tiny", str(tiny_dataset))], {"wall_s": 3.0})
    client = _client(tracking_uri)
    exp = client.get_run(pid).info.experiment_id
    runs = client.search_runs([exp], max_results=100)
    children = [r for r in runs if r.data.tags.get("mlflow.parentRunId") == pid]
    assert sorted(r.info.run_name for r in children) == ["tiny-ood_disturbed-cnn-sel1-k0",
                                                         "tiny-ood_disturbed-rf-sel1-k0"]
    rf = next(r for r in children if "-rf-" in r.info.run_name)
    assert rf.data.params["seeds"] == "[0, 1]"
    assert rf.data.metrics["gear3/accuracy_mean"] == pytest.approx(0.8 + 0.005, abs=1e-12)
    assert rf.data.metrics["gear3/accuracy_std"] == pytest.approx(0.005, abs=1e-12)
    assert rf.data.metrics["gear1/accuracy_min"] == pytest.approx(0.6, abs=1e-12)
    assert rf.data.metrics["worst_split_accuracy"] == pytest.approx(0.605, abs=1e-12)
    assert len(runs) == 3  # the parent and two cells: no run, metric or step per seed
    for r in [client.get_run(pid), *children]:
        assert GIT_COMMIT_TAG in r.data.tags
        assert not any("seed" in key for key in r.data.metrics)
        assert _inputs(client, r.info.run_id)[0].dataset.digest == dataset_ref(
            tiny_dataset).digest
        for key in r.data.metrics:
            assert {m.step for m in client.get_metric_history(r.info.run_id, key)} == {0}


@pytest.mark.slow  # ~30 s: a Hydra multirun in a subprocess
def test_hydra_sweep_jobs_share_one_parent(tiny_dataset, tracking_uri, tmp_path):
    import sys

    sweep = tmp_path / "multirun"
    cmd = [sys.executable, "-m", "swgcli.train", "-m", "model=nb,knn", "features=selection1",
           "protocol=ood_disturbed", f"stored.path={tiny_dataset}",
           f"logger.tracking_uri={tracking_uri}", "logger.experiment=test-sweep",
           f"paths.root_dir={tmp_path}", f"hydra.sweep.dir={sweep}"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "WARNING" not in proc.stderr, proc.stderr[-3000:]
    client = _client(tracking_uri)
    exp = client.get_experiment_by_name("test-sweep")
    runs = client.search_runs([exp.experiment_id])
    jobs = [r for r in runs if r.info.run_name in ("selection1-nb", "selection1-knn")]
    assert len(jobs) == 2
    (pid,) = {r.data.tags["mlflow.parentRunId"] for r in jobs}
    parent = client.get_run(pid)
    assert parent.data.tags[GROUP_PARENT_TAG] == f"sweep {sweep.resolve()}"
    assert all(len(r.outputs.model_outputs) == 1 for r in jobs)  # log_models default: a job's


@pytest.mark.parametrize("labels", [["a", "b"], ["healthy", "eccentric_wg", "reduced_damping",
                                                  "root_crack", "tip_crack", "wear"]])
def test_the_confusion_figure_holds_every_label_and_its_title(labels):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from learn.tracking.mlflow_runs import confusion_figure

    n = len(labels)
    fig = confusion_figure(np.arange(n * n).reshape(n, n), labels,
                           "selection2-svm: mean test accuracy 87.5 %")
    canvas = FigureCanvasAgg(fig)
    canvas.draw()  # places the axis labels
    renderer = canvas.get_renderer()
    inside = fig.bbox.padded(1.0)  # pixels
    for text in [*fig.axes[0].get_xticklabels(), *fig.axes[0].get_yticklabels(),
                 fig.axes[0].xaxis.label, fig.axes[0].yaxis.label, fig._suptitle]:
        box = text.get_window_extent(renderer)
        assert inside.contains(box.x0, box.y0) and inside.contains(box.x1, box.y1), text


def test_a_reused_confusion_figure_draws_what_a_new_one_draws():
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from learn.tracking.mlflow_runs import ConfusionFigure, confusion_figure

    def pixels(fig):
        canvas = FigureCanvasAgg(fig)
        canvas.draw()
        return np.asarray(canvas.buffer_rgba()).copy()

    labels = ["healthy", "eccentric_wg", "tip_crack"]
    cm = np.array([[9, 1, 0], [2, 7, 1], [0, 0, 10]])
    reused = ConfusionFigure()
    for earlier in (np.eye(3, dtype=int) * 5, np.ones((2, 2), dtype=int)):  # other counts,
        reused.draw(earlier, labels[:len(earlier)], "x" * 80)  # labels and width first
        np.testing.assert_array_equal(pixels(reused.draw(cm, labels, "selection1-rf: 86.7 %")),
                                      pixels(confusion_figure(cm, labels, "selection1-rf: 86.7 %")))


def test_the_suite_never_writes_into_the_users_store():
    """Runs a test makes without a store of its own go to a throw-away store, not the
    checkout's mlflow.db nor a store the user named in MLFLOW_TRACKING_URI."""
    import tempfile

    from learn.tracking.provenance import repo_root
    from learn.tracking.store import default_tracking_uri

    uri = default_tracking_uri()
    assert uri.startswith(f"sqlite:///{tempfile.gettempdir()}")
    assert str(repo_root()) not in uri


#: Every experiment of conf/experiment/ (a new one is covered without a word here).
EXPERIMENTS = sorted(p.stem for p in (Path(__file__).parents[2] / "conf" / "experiment"
                                      ).glob("*.yaml"))
APPS_WITH_TRACKING = [("train", [f"experiment={e}"]) for e in EXPERIMENTS] + [
    ("train", []), ("monitor", ["stream=s.csv", "diagnosis_model=m.skops"]),
    ("calibrate", ["measured=m.csv", "out_dir=out"])]


@pytest.mark.parametrize(("app", "overrides"), APPS_WITH_TRACKING)
def test_one_switch_turns_tracking_off_for_every_app_and_experiment(app, overrides):
    """`~logger` leaves no logger (issue 87: experiments that set logger keys brought one
    back, and the tests wrote runs into the user's store)."""
    from swgcli import compose_app

    assert compose_app(app, overrides).get("logger") is not None
    assert compose_app(app, [*overrides, "~logger"]).get("logger") is None
