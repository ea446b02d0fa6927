"""learn.learners.devices: the device choice on this (CPU) machine, its refusals in one
line naming the key, what a run records; the latency table says what it timed and leaves
torch's thread count as it found it."""

from __future__ import annotations

import sys

import numpy as np
import pandas as pd
import pytest
import torch
from data_sets import make_toy_dataset

from learn.learners.devices import (
    DEVICE_CHOICES,
    check_device,
    device_label,
    device_record,
    resolve_device,
)
from learn.studies.latency import LATENCY_COLUMNS, latency_heading, measure_latency

no_cuda = pytest.mark.skipif(torch.cuda.is_available(), reason="the machine has CUDA")


@pytest.mark.parametrize("value", ["cpu", "cuda", "cuda:0", "cuda:12", "auto"])
def test_the_allowed_settings_pass_the_check(value):
    assert check_device(value, "monitor.device") == value


@pytest.mark.parametrize("value", ["gpu", "CUDA", "cuda:", "cuda:x", "cpu:0", "", None, 1])
def test_a_bad_setting_is_one_line_naming_the_key(value):
    with pytest.raises(ValueError) as e:
        check_device(value, "monitor.device")
    line = str(e.value)
    assert "\n" not in line and line.startswith("monitor.device:"), line
    assert all(c in line for c in ("cpu", "cuda", "auto")) and repr(value) in line


def test_the_check_needs_no_torch():
    """The config check runs without torch (the apps' --help and refusals stay fast)."""
    import subprocess

    code = ("import sys; from learn.learners.devices import check_device; "
            "check_device('auto', 'k'); assert 'torch' not in sys.modules")
    subprocess.run([sys.executable, "-c", code], check=True)


@no_cuda
def test_auto_is_the_cpu_here():
    assert resolve_device("auto") == torch.device("cpu")
    assert resolve_device("cpu") == torch.device("cpu")
    assert device_label(resolve_device("auto")) == "cpu"


@no_cuda
@pytest.mark.parametrize("value", ["cuda", "cuda:1"])
def test_cuda_is_refused_in_one_line_on_a_machine_without_it(value):
    with pytest.raises(ValueError) as e:
        resolve_device(value, "monitor.device")
    line = str(e.value)
    assert "\n" not in line and line.startswith(f"monitor.device={value}:"), line
    assert "no CUDA" in line and "monitor.device=cpu" in line


def test_a_net_refuses_a_bad_device_before_it_fits():
    from learn.learners.nets import MLPClassifierTorch

    net = MLPClassifierTorch(device="gpu")
    with pytest.raises(ValueError, match="device: must be one of"):
        net.check_params()


def test_the_record_says_where_and_whether_deterministic():
    rec = device_record(torch.device("cpu"))
    assert set(rec) == {"device", "torch_threads", "deterministic", "deterministic_algorithms",
                        "cudnn_deterministic", "cudnn_benchmark"}
    assert rec["device"] == "cpu" and rec["deterministic"] is True
    assert rec["torch_threads"] == torch.get_num_threads()
    assert DEVICE_CHOICES == ("cpu", "cuda", "cuda:N", "auto")


def test_the_latency_heading_comes_from_the_columns():
    table = pd.DataFrame([{"model": "cnn", "input": "raw", "input_ms": 1.0, "model_ms": 2.0,
                           "device": "cuda:0 (NVIDIA H100)", "batch": 1, "torch_threads": 1},
                          {"model": "rf", "input": "sel1", "input_ms": 1.0, "model_ms": 2.0,
                           "device": "cpu", "batch": 1, "torch_threads": 1}])
    assert latency_heading(table) == "cuda:0 (NVIDIA H100) and cpu, batch 1, 1 torch thread(s)"
    old = table[["model", "input", "input_ms", "model_ms"]]  # written before the columns
    assert "not recorded" in latency_heading(old)


def test_latency_records_what_it_timed_and_restores_torch_threads():
    """MiniRocket's fit puts torch's threads back to the core count: each model is timed
    on one thread all the same, and the caller's count is restored afterwards."""
    from learn.inputs.signals import build_input
    from learn.studies.runs import RunSpec

    ds = make_toy_dataset(n_variants=3, n_time=64)
    inputs = {k: build_input(ds, k, disturbed=True) for k in ("diff", "raw")}
    models = {"minirocket": {"_target_": "learn.learners.rocket.MiniRocketClassifier",
                             "n_kernels": 84, "random_state": 0},
              "cnn": {"_target_": "learn.learners.nets.CNN1DClassifier", "max_epochs": 1,
                      "device": "auto", "random_state": 0}}
    specs = [RunSpec(model="minirocket", input="diff"), RunSpec(model="cnn", input="raw")]
    before = torch.get_num_threads()
    try:
        torch.set_num_threads(2)
        table = measure_latency(ds, specs, models, inputs, repeats=3, n_fit=40)
        assert torch.get_num_threads() == 2
    finally:
        torch.set_num_threads(before)
    assert tuple(table.columns) == LATENCY_COLUMNS
    assert (table["torch_threads"] == 1).all() and (table["batch"] == 1).all()
    expect = device_label(resolve_device("auto"))
    assert table.set_index("model")["device"].to_dict() == {"minirocket": "cpu",
                                                             "cnn": expect}
    assert np.isfinite(table[["input_ms", "model_ms"]].to_numpy()).all()


@no_cuda
@pytest.mark.parametrize("detectors", [["cnn_res"], ["paper_rf"]])
def test_the_monitor_refuses_cuda_here_before_any_work(tmp_path, detectors):
    """monitor.device=cuda on a machine without CUDA: one line naming the key, nothing
    written, when the CNN detector is evaluated; without it the device is only checked."""
    from swgcli import compose_app
    from swgmon.evaluation.task import run_monitor_evaluation

    cfg = compose_app("train", ["experiment=monitor", "~logger", "monitor.device=cuda",
                                "monitor.run_on=[bench]", "monitor.n_jobs=1",
                                f"monitor.study.detectors=[{detectors[0]}]",
                                f"monitor.report_dir={tmp_path}/rep"])
    if detectors == ["paper_rf"]:
        from omegaconf import OmegaConf

        from swgmon.evaluation.task import _nets

        assert _nets(OmegaConf.to_object(cfg).monitor) == {}
        return
    with pytest.raises(ValueError) as e:
        run_monitor_evaluation(cfg)
    assert str(e.value).startswith("monitor.device=cuda: this machine has no CUDA GPU")
    assert not (tmp_path / "rep").exists()


def test_a_runs_net_record_is_that_of_its_torch_net_or_empty():
    from sklearn.ensemble import RandomForestClassifier
    from sklearn.pipeline import make_pipeline

    from learn.learners.devices import net_record
    from learn.learners.nets import MLPClassifierTorch

    rec = net_record(make_pipeline(MLPClassifierTorch(device="cpu")))
    assert rec["device"] == "cpu" and rec["deterministic"] is True
    assert net_record(RandomForestClassifier()) == {}
