"""swgsim-calibrate: kind detection, the task function end to end, MLflow logging."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml

from swgcal import MeasuredDataError, build_problem, detect_kind
from swgcal.friction import load_friction_csv, write_friction_csv
from swgcal.friction.synthetic import PLANTED, synthetic_recording
from swgcli import compose_app
from swgcli.calibrate import run_calibrate
from swgsim.datasets.schema import DataSetError
from swgsim.gear.friction import FrictionEffects
from swgsim.sensing.effects import parse_sensor_effects


def _cfg(overrides):
    return compose_app("calibrate", overrides)


@pytest.fixture(scope="module")
def planted_csv(tmp_path_factory):
    rec, truth = synthetic_recording(
        [{"kind": "stribeck", "params": PLANTED["stribeck"]["params"]}],
        rng=np.random.default_rng(4), duration_s=40)
    return write_friction_csv(rec, tmp_path_factory.mktemp("data") / "planted.csv"), truth


def test_detect_kind(tmp_path, planted_csv):
    assert detect_kind(planted_csv[0]) == "friction"
    ds = tmp_path / "ds"
    ds.mkdir()
    (ds / "manifest.json").write_text("{}")
    assert detect_kind(ds) == "strain"
    with pytest.raises(DataSetError, match="schema_version"):  # the strain builder reads it
        build_problem(ds)
    bad = tmp_path / "bad.csv"
    bad.write_text("a,b\n1,2\n")
    with pytest.raises(MeasuredDataError, match="bad.csv.*expected a friction CSV"):
        detect_kind(bad)
    with pytest.raises(MeasuredDataError, match="does not exist"):
        detect_kind(tmp_path / "nope.csv")
    with pytest.raises(MeasuredDataError, match="without manifest.json"):
        detect_kind(tmp_path)


def test_csv_round_trip_and_estimated_acceleration(tmp_path, planted_csv):
    rec = load_friction_csv(planted_csv[0])
    assert rec.ddq_source == "measured" and rec.n == 4000
    # without an acceleration column the loader estimates it
    cols = "time_s,q_rad,dq_rad_per_s,tau_friction_Nm"
    data = np.column_stack([rec.t_s, rec.q_rad, rec.dq_rad_s, rec.tau_nm])
    p = tmp_path / "noacc.csv"
    np.savetxt(p, data, delimiter=",", header=cols, comments="")
    r2 = load_friction_csv(p)
    assert r2.ddq_source.startswith("estimated")
    inner = slice(50, -50)
    err = r2.ddq_rad_s2[inner] - rec.ddq_rad_s2[inner]
    assert np.sqrt(np.mean(err ** 2)) < 0.05 * np.sqrt(np.mean(rec.ddq_rad_s2 ** 2))


def test_run_calibrate_end_to_end(tmp_path, planted_csv, tracking_uri):
    path, truth = planted_csv
    out = tmp_path / "out"
    cfg = _cfg([f"measured={path}", f"out_dir={out}", f"base_model.v_s={truth.v_s}",
                f"logger.tracking_uri={tracking_uri}", "logger.experiment=test-calibration"])
    res = run_calibrate(cfg)
    summary = json.loads((out / "summary.json").read_text())
    for key in ("rmse_before", "rmse_after", "effects_added", "unexplained",
                "residual_signature", "heldout"):
        assert key in summary
    assert summary["rmse_after"] < summary["rmse_before"]
    assert [e["name"] for e in summary["effects_added"]] == ["stribeck"]
    p = summary["effects_added"][0]["params"]["f_s"]
    assert set(p) >= {"value", "std", "unit", "identifiable"}
    assert summary["unexplained"] is False
    assert summary["heldout"]["method"].startswith("contiguous time blocks")
    assert (out / "report.md").read_text().startswith("# Calibration report")
    for k in ("velocity", "position", "hysteresis", "time", "overlay"):
        assert (out / "figures" / f"{k}.png").stat().st_size > 10_000
    # the accepted effects as a simulation option
    fx_cfg = yaml.safe_load((out / "friction_effects.yaml").read_text())
    fx = FrictionEffects(fx_cfg["effects"], v_s=fx_cfg["v_s"], base_model=fx_cfg["base_model"],
                         t0=fx_cfg["t0_s"])
    rec = load_friction_csv(path)
    assert np.ptp(fx(rec.t_s, rec.q_rad, rec.dq_rad_s, rec.ddq_rad_s2)) > 0.1
    # MLflow
    import mlflow

    run = mlflow.MlflowClient(tracking_uri).get_run(res["mlflow_run_id"])
    assert run.data.metrics["rmse_after"] == pytest.approx(summary["rmse_after"])
    assert run.data.tags["effects_added"] == "stribeck"


def test_run_calibrate_rejects_unknown_data(tmp_path):
    bad = tmp_path / "x.txt"
    bad.write_text("hello\n")
    cfg = _cfg([f"measured={bad}", f"out_dir={tmp_path / 'o'}", "~logger"])
    with pytest.raises(MeasuredDataError, match="x.txt"):
        run_calibrate(cfg)


def test_run_calibrate_strain_data_set(tmp_path, tracking_uri):
    """Kind 2: a schema-v1 data-set directory is recognised and calibrated end to end."""
    import planted_strain as syn

    from swgsim.datasets import schema as dsio
    from swgsim.files.ownership import atomic_write_json
    from swgsim.gear.chain import SimulationChain

    clean = syn.simulate_windows(SimulationChain(), seed=0)
    ds, _ = syn.bench_dataset(clean, [{"name": "offset",
                                       "params": {"offset_mvv": {"s1": 0.02}}}])
    d = tmp_path / "bench"
    sha = dsio.write_shard(ds, d / "bench.nc")
    atomic_write_json(d / "manifest.json", {"schema_version": 1, "complete": True,
                                            "shards": {"bench.nc": {"sha256": sha}}})
    assert detect_kind(d) == "strain"
    out = tmp_path / "out"
    cfg = _cfg([f"measured={d}", f"out_dir={out}", f"logger.tracking_uri={tracking_uri}",
                "logger.experiment=test-strain"])
    res = run_calibrate(cfg)
    summary = json.loads((out / "summary.json").read_text())
    assert [e["name"] for e in summary["effects_added"]][0] == "offset"
    assert summary["rmse_after"] < summary["rmse_before"]
    assert res["mlflow_run_id"]
    # the accepted effects as the data-set option sensor_effects, read by the generator
    assert summary["files"] == ["report.md", "summary.json", "sensor_effects.yaml"]
    fx = yaml.safe_load((out / "sensor_effects.yaml").read_text())["sensor_effects"]
    assert fx == summary["sensor_effects"] and fx[0]["name"] == "offset"
    parse_sensor_effects(fx)


def test_gear_ratio_option_is_checked_and_reaches_the_summary(tmp_path, planted_csv):
    """gear_ratio (friction option): refused below 1, carried into the summary."""
    path, truth = planted_csv
    cfg = _cfg([f"measured={path}", f"out_dir={tmp_path / 'o'}", "~logger",
                "gear_ratio=0.5"])
    with pytest.raises(ValueError,
                       match=r"^gear_ratio must lie in \(1, 10000\] or be null, got 0.5$"):
        run_calibrate(cfg)
    out = tmp_path / "ok"
    cfg = _cfg([f"measured={path}", f"out_dir={out}", "~logger", "figures=false",
                f"base_model.v_s={truth.v_s}", "gear_ratio=100",
                "selection.candidates=[stribeck,position_ripple]"])
    run_calibrate(cfg)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["data"]["gear_ratio"] == 100
    assert summary["ripples"]["gear_ratio"] == 100
    assert [e["name"] for e in summary["effects_added"]] == ["stribeck"]
    assert summary["effects_added"][0]["ranges"]["v_st"]["inside"]


def test_app_defaults_and_ranges_are_the_librarys(tmp_path, planted_csv):
    """The app's schema is built from the library's option dataclasses (defaults written
    once) and its option errors are the library's (ranges written once), raised before
    any work."""
    from omegaconf import OmegaConf

    from swgcal import SelectionConfig
    from swgcal.friction import FrictionOptions
    from swgsim.base.typed import plain

    cfg = OmegaConf.to_container(_cfg(["measured=a.csv", "out_dir=b"]), resolve=True)
    assert cfg["selection"] == plain(SelectionConfig())
    assert {k: cfg[k] for k in plain(FrictionOptions())} == plain(FrictionOptions())
    path, _ = planted_csv
    for override, words in [
        ("selection.max_rel_se=-1", "selection.max_rel_se must lie in (0, inf), got -1.0"),
        ("selection.max_iter=-1", "selection.max_iter must lie in [0, inf), got -1"),
        ("split.n_blocks=2", "split.n_blocks must lie in [3, inf), got 2"),
        ("accel_window=20",
         "accel_window must be an odd integer in [5, 1001] (samples), got 20"),
        ("split.test_blocks=[12]", "split.test_blocks must list blocks in [-10, 9]")]:
        out = tmp_path / override.split("=")[0]
        with pytest.raises(ValueError) as err:
            run_calibrate(_cfg([f"measured={path}", f"out_dir={out}", "~logger",
                                override]))
        assert str(err.value).startswith(words), (override, str(err.value))
        assert not out.exists()
        # the library refuses the same value with the same words
        key, value = override.split("=")
        with pytest.raises(ValueError, match=key.split(".")[-1] + " must"):
            if key.startswith("selection."):
                SelectionConfig(**{key.split(".")[1]: int(value)})
            else:
                build_problem(path, **{key.split(".")[-1]: yaml.safe_load(value)})
