"""Profile data sets (``dataset.profile``): windows cut from one simulation of each variant
along a duty cycle, with the profile's per-window variables and the input angle channel."""

from __future__ import annotations

import json

import numpy as np
import pytest
from data_sets import PRESET_HASHES

from swgcli import dataset_preset
from swgsim.datasets import generate as gen
from swgsim.datasets import schema as dsio
from swgsim.datasets.config import DatasetConfig, dataset_config
from swgsim.datasets.plan import plain_config, plan
from swgsim.datasets.profile_shard import profile_motion
from swgsim.gear import profile_dynamics
from swgsim.sensing.angles import psi_estimate


@pytest.fixture(scope="module")
def motion_set(tmp_path_factory):
    out = tmp_path_factory.mktemp("tiny_motion")
    cfg = dataset_preset("tiny_motion")
    gen.generate(cfg, out, n_jobs=1, progress=False)
    return plan(cfg), dsio.load(out)


def test_tiny_motion_generates_and_loads(motion_set):
    pl, ds = motion_set
    (shard,) = pl.shards
    assert ds.sizes["sample"] == shard.n_windows == len(shard.windows) * len(
        shard.window_starts_s)
    assert np.isfinite(ds["strain_signal"].values).all()
    assert not ds["disturbed"].values.any()
    assert ds["reference"].values.sum() == len(shard.window_starts_s)


def test_windows_carry_the_profile_coordinates(motion_set):
    pl, ds = motion_set
    (shard,) = pl.shards
    n_v = len(shard.windows)
    starts = np.tile(shard.window_starts_s, n_v)
    np.testing.assert_allclose(ds["window_start_s"].values, starts)
    lo, mean, hi = (ds[k].values for k in ("n_d_min_rpm", "n_d_mean_rpm", "n_d_max_rpm"))
    assert (lo <= mean + 1e-9).all() and (mean <= hi + 1e-9).all()
    np.testing.assert_allclose(ds["n_in_rpm"].values, mean)
    assert ((lo < 0) & (hi > 0)).any(), "a window holds the reversal"
    load = ds["load_mean_nm"].values
    assert load.min() == pytest.approx(7.0) and load.max() == pytest.approx(30.0)
    assert ((load > 7.0 + 1e-6) & (load < 30.0 - 1e-6)).any(), "a window holds the load step"
    # the desired speed of each window is the profile's, the same for every variant
    assert np.allclose(mean.reshape(n_v, -1), mean.reshape(n_v, -1)[0])
    assert "phi_out_meas" not in ds  # no output encoder in tiny_motion


def test_input_angle_tracks_the_simulated_psi(motion_set):
    pl, ds = motion_set
    (shard,) = pl.shards
    mo = profile_motion(pl, shard)
    fs, n_t = pl.config.chain.sample_rate_hz, ds.sizes["time"]
    win = mo.starts[:, None] + np.arange(n_t)[None, :]
    n_v = len(shard.windows)
    phi_in = mo.res.states[0][:, win].reshape(n_v * mo.starts.size, n_t)
    psi = mo.res.psi[:, win].reshape(n_v * mo.starts.size, n_t)
    meas = ds["phi_in_meas"].values
    res = pl.config.profile.angles.input_sensor().resolution_rad
    err = phi_in - meas
    assert (err >= 0).all() and (err < res).all()  # floor-quantised, one count
    ratio = mo.params[0].gear.ratio
    # ψ from the input channel alone: one count (1 + 1/N), the output's start within one
    # WG revolution / N and the gear's twist (< 0.01 rad at 30 N m)
    bound = res * (1 + 1 / ratio) + 2 * np.pi / ratio + 0.01
    assert np.abs(psi_estimate(meas, None, ratio) - psi).max() < bound
    assert fs == ds.attrs["sample_rate_hz"]


def test_steady_presets_keep_their_config_hash():
    """A data set that sets no profile keeps its hash (and its stored config)."""
    for name, want in PRESET_HASHES.items():
        if dataset_preset(name).get("profile") is None:
            assert plan(dataset_preset(name)).config_hash == want, name
    assert "profile" not in plan(dataset_preset("tiny")).plain
    assert "profile" not in plain_config(DatasetConfig())


@pytest.mark.parametrize("override, key", [
    ({"segments": [{"move": {"target_rpm": 2000.0, "accel_rpm_s": 1e9}}]},
     "dataset.profile.segments[0].move.accel_rpm_s"),
    ({"segments": [{"move": {"target_rpm": 9000.0, "accel_rpm_s": 4e4}}]},
     "dataset.profile.segments[0].move.target_rpm"),
    ({"load": {"steps": {"initial_nm": 200.0, "steps": []}}},
     "dataset.profile.load.steps.initial_nm"),
    ({"segments": [{"move": None, "hold": None}]}, "dataset.profile.segments[0]"),
    ({"window_starts_s": [0.39]}, "dataset.profile.window_starts_s[0]"),
])
def test_bad_profile_refused_before_work(tmp_path, monkeypatch, override, key):
    cfg = dataset_preset("tiny_motion")
    cfg["profile"].update(override)

    def no_work(*a, **k):
        raise AssertionError("simulated before the config was checked")

    monkeypatch.setattr(profile_dynamics, "simulate_profile", no_work)
    with pytest.raises(ValueError, match=r"^" + key.replace("[", r"\[").replace("]", r"\]")):
        gen.generate(cfg, tmp_path / "bad", n_jobs=1, progress=False)
    assert not (tmp_path / "bad" / "manifest.json").exists()


def test_window_shorter_than_one_wg_revolution_refused():
    cfg = dataset_preset("tiny_motion")
    cfg["chain"]["window_s"] = 0.02  # one WG revolution at 2000 rpm is 0.03 s
    with pytest.raises(ValueError, match=r"^dataset\.chain\.window_s=0\.02 s .* 2000 rpm"):
        plan(cfg)


def test_profile_config_round_trips():
    cfg = dataset_config(dataset_preset("tiny_motion"))
    pl = plan(cfg)
    stored = json.loads(json.dumps(pl.plain))
    assert plan(stored).config_hash == pl.config_hash
    assert pl.profile == cfg.profile.to_profile()


def test_robot_joint_motion_plans():
    pl = plan(dataset_preset("robot_joint_motion"))
    assert pl.config.profile.angles.output_encoder() is not None
    assert pl.config.load.j_out_kgm2 == pytest.approx(0.69)
    assert all(s.window_starts_s for s in pl.shards)
