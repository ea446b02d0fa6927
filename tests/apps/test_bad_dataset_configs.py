"""A data set's config keys, refused before any work naming the key itself rather than a
consequence (the mesh, the integrator, an unknown key): the measurement chain, tolerances,
mesh, gauge layout and grid of operating points, a gear life (hours, fault, growth) and a
motion profile (angles, load steps, segments), also as swgsim-generate's command line."""

from __future__ import annotations

import json

import numpy as np
import pytest
from bad_input import app_line, message, small_cfg

from swgcli import dataset_preset
from swgsim.datasets import generate as gen
from swgsim.datasets.plan import plan


def test_generate_refuses_a_plain_dict_with_an_unknown_key(tmp_path):
    cfg = small_cfg()
    cfg["chain"]["windows_s"] = 0.1
    msg = message(lambda: gen.generate(cfg, tmp_path / "never", progress=False))
    assert msg.startswith("dataset.chain.windows_s: unknown key")
    assert not (tmp_path / "never").exists()


# ------------------------------------------------------------------ ranges, physics
@pytest.mark.parametrize("edit, key", [
    (lambda c: c["chain"].update(window_s=0.02), "dataset.chain.window_s=0.02"),
    (lambda c: c["chain"].update(contact_half_width_deg=95.0),
     "dataset.chain.contact_half_width_deg"),
    (lambda c: c["chain"].update(ecc_load_share=20.0), "dataset.chain.ecc_load_share"),
    (lambda c: c["tolerances"].update(sd_theta_deg=-0.1), "dataset.tolerances.sd_theta_deg"),
    (lambda c: c.update(seed=-1), "dataset.seed"),
    (lambda c: c["gears"][0].update(tolerance_seed=-5), "dataset.gears[0].tolerance_seed"),
    (lambda c: c["mesh"].update(n_theta=20), "dataset.mesh.n_theta"),
    (lambda c: c["disturbance"].update(offset_mvv=2.0), "dataset.disturbance.offset_mvv"),
])
def test_out_of_range_and_unphysical_data_sets_are_refused(tmp_path, edit, key):
    cfg = small_cfg()
    edit(cfg)
    msg = message(lambda: gen.generate(cfg, tmp_path / "never", progress=False))
    assert key in msg and ("must" in msg or "allowed" in msg or "raise" in msg)
    assert not (tmp_path / "never").exists()


def test_an_integrator_step_too_long_is_refused_before_work(tmp_path):
    cfg = small_cfg(sample_rate_hz=500.0, substeps=1, window_s=0.5, settle_s=0.1)
    cfg["disturbance"]["harmonic_mvv"] = 0.0
    msg = message(lambda: gen.generate(cfg, tmp_path / "never", progress=False))
    assert msg.startswith("dataset.chain.substeps=1 at dataset.chain.sample_rate_hz=500 Hz")
    assert "dataset.gears[0]" in msg and "allowed: dataset.chain.substeps >= 2" in msg
    assert not (tmp_path / "never").exists()
    cfg = small_cfg()
    cfg["load"]["j_out_kgm2"] = 1e-4  # in range, but overdamped: no torsional mode
    assert message(lambda: plan(cfg)).startswith("dataset.load.j_out_kgm2=0.0001")


def test_a_diverged_simulation_names_shard_window_and_keys(tmp_path, monkeypatch):
    from swgsim.datasets import grid_shard as shard

    real = shard.dynamics.simulate

    def diverging(*a, **k):
        res = real(*a, **k)
        res.states[:, -1] = np.nan  # the last motion of the shard blows up
        res.success, res.message = False, "non-finite states"
        return res

    monkeypatch.setattr(shard.dynamics, "simulate", diverging)
    out = tmp_path / "ds"
    msg = message(lambda: gen.generate(small_cfg(), out, n_jobs=1, progress=False))
    assert msg.startswith("dataset.chain.substeps=1, dataset.chain.sample_rate_hz=10000 Hz")
    assert "shard gear1_n4000rpm.nc (gear 1, 4000 rpm, 39 N m, fault" in msg
    assert "non-finite states" in msg and "dataset.load.j_out_kgm2" in msg
    assert not list(out.glob("*.tmp")) and not list(out.glob("*.nc"))


# ------------------------------------------------------------------ gauges, grid
@pytest.mark.parametrize("edit, words", [
    (lambda c: c["sensors"].update(grid_length_mm=0.001),
     "dataset.sensors.grid_length_mm must lie in [0.2, 13.6] mm"),
    (lambda c: c["sensors"].update(grid_length_mm=37.9),
     "dataset.sensors.grid_length_mm must lie in [0.2, 13.6] mm"),
    (lambda c: c["operating_points"].update(n_in_rpm=[]),
     "dataset.operating_points.n_in_rpm must list one or more distinct values, got []"),
    (lambda c: c["operating_points"].update(t_out_nm=[]),
     "dataset.operating_points.t_out_nm must list one or more"),
])
def test_an_empty_or_zero_grid_is_named_not_the_mesh(tmp_path, edit, words):
    cfg = small_cfg()
    edit(cfg)
    msg = message(lambda: gen.generate(cfg, tmp_path / "never", progress=False))
    assert msg.startswith(words) and "n_theta" not in msg
    assert not (tmp_path / "never").exists()


@pytest.mark.parametrize("key, value", [("grid_length_mm", 0.0), ("gauge_factor", -2.0),
                                        ("r_pairs_mm", 50.0), ("r_torque_mm", 0.0)])
def test_gauge_layout_keys_are_blamed_not_the_mesh(key, value):
    cfg = small_cfg()
    cfg["sensors"] = {**cfg.get("sensors", {}), key: value}
    with pytest.raises(ValueError, match=rf"^dataset\.sensors\.{key} must lie in"):
        plan(cfg)


# ------------------------------------------------------------------ lives
LIFE_CASES = {  # case -> (change to the tiny_life preset, the key the line must name)
    "hours=-1": ({"hours": -1.0}, "dataset.life.hours"),
    "hours=nan": ({"hours": float("nan")}, "dataset.life.hours"),
    "interval_min=0": ({"interval_min": 0.0}, "dataset.life.interval_min"),
    "commissioning beyond the life": ({"commissioning_h": 9.0},
                                      "dataset.life.commissioning_h"),
    "an unknown fault": ({"fault": {"fault": "bogus"}}, "dataset.life.fault.fault"),
    "a fault before commissioning ends": ({"fault": {"onset_h": 1.0}},
                                          "dataset.life.fault.onset_h"),
    "a linear growth of 0 h": ({"fault": {"growth": "linear", "growth_h": 0.0}},
                               "dataset.life.fault.growth_h"),
    "an unknown growth": ({"fault": {"growth": "bogus"}}, "dataset.life.fault.growth"),
    "points going back": ({"fault": {"growth": "points",
                                     "points": [[6.0, 0.0], [5.0, 0.1]]}},
                          "dataset.life.fault.points"),
    "a sensor fault on bridge 7": ({"fault": {"fault": "sensor_offset_step", "sensor": 7,
                                              "severity": 0.05}},
                                   "dataset.life.fault.sensor"),
    "a position of nan degrees": ({"fault": {"position_deg": float("nan")}},
                                  "dataset.life.fault.position_deg"),
    "a sensor fault on bridge -1": ({"fault": {"fault": "sensor_offset_step", "sensor": -1,
                                               "severity": 0.05}},
                                    "dataset.life.fault.sensor"),
    "hours=1e30": ({"hours": 1e30}, "dataset.life.hours"),
    "a severity beyond Table V": ({"fault": {"severity": 5.0}},
                                  "dataset.life.fault.severity"),
}


def _life_cfg(change: dict) -> dict:
    cfg = dataset_preset("tiny_life")
    fault = change.pop("fault", {})
    cfg["life"].update(change)
    cfg["life"]["fault"].update(fault)
    return cfg


@pytest.mark.parametrize("case", LIFE_CASES)
def test_a_bad_life_is_refused_naming_its_key(tmp_path, case):
    change, key = LIFE_CASES[case]
    cfg = _life_cfg(json.loads(json.dumps(change)))
    msg = message(lambda: plan(cfg))
    assert msg.startswith(key) or f" {key}" in msg, msg


def test_integer_hours_in_points_are_explained(tmp_path):
    line = app_line("generate", ["dataset=tiny_life", "dataset.life.fault.growth=points",
                                 "dataset.life.fault.points=[[6,0.0],[7,0.1]]",
                                 f"out_dir={tmp_path}/ds"], tmp_path)
    assert line == ("swgsim-generate: error: dataset.life.fault.points[0]: 6 is an integer "
                    "where a float is required (OmegaConf checks the numbers of nested lists "
                    "strictly); write it with a decimal point: 6.0")
    assert not (tmp_path / "ds").exists()


# ------------------------------------------------------------------ motion profiles
PROFILE_CASES = {  # case -> (change to the tiny_motion preset's profile, the key)
    "input_counts_per_rev=0": ({"angles": {"input_counts_per_rev": 0}},
                               "dataset.profile.angles.input_counts_per_rev must be an "
                               "integer in [1, 4294967296]"),
    "output_encoder_bits=40": ({"angles": {"output_encoder_bits": 40}},
                               "dataset.profile.angles.output_encoder_bits must be an "
                               "integer in [8, 32]"),
    "output_encoder_bits=7": ({"angles": {"output_encoder_bits": 7}},
                              "dataset.profile.angles.output_encoder_bits"),
    "a load step after the profile": (
        {"load": {"steps": {"initial_nm": 7.0, "steps": [{"time_s": 5.0,
                                                          "torque_nm": 30.0}]}}},
        "dataset.profile.load.steps.steps[0].time_s must lie in [0, 0.4] s"),
    "a load step before it": (
        {"load": {"steps": {"initial_nm": 7.0, "steps": [{"time_s": -1.0,
                                                          "torque_nm": 30.0}]}}},
        "dataset.profile.load.steps.steps[0].time_s"),
    "a load beyond the peak torque": (
        {"load": {"steps": {"initial_nm": 200.0, "steps": []}}},
        "dataset.profile.load.steps.initial_nm"),
    "a speed beyond the catalogue": (
        {"segments": [{"move": {"target_rpm": 9000.0, "accel_rpm_s": 4e4}}]},
        "dataset.profile.segments[0].move.target_rpm"),
    "an acceleration beyond the torque": (
        {"segments": [{"move": {"target_rpm": 2000.0, "accel_rpm_s": 1e9}}]},
        "dataset.profile.segments[0].move.accel_rpm_s"),
    "a negative hold": (
        {"segments": [{"move": {"target_rpm": 2000.0, "accel_rpm_s": 4e4}},
                      {"hold": {"duration_s": -0.1}}]},
        "dataset.profile.segments[1].hold.duration_s"),
    "a window start after the profile": ({"window_starts_s": [0.39]},
                                         "dataset.profile.window_starts_s[0]"),
    "a negative start jitter": ({"start_jitter_s": -0.01},
                                "dataset.profile.start_jitter_s"),
    "a hold of 1e9 s": (
        {"segments": [{"move": {"target_rpm": 2000.0, "accel_rpm_s": 4e4}},
                      {"hold": {"duration_s": 1e9}}]},
        "dataset.profile.segments last 1e+09 s; allowed: at most 600 s"),
}


@pytest.mark.parametrize("case", PROFILE_CASES)
def test_a_bad_profile_is_refused_naming_its_key(case):
    change, key = PROFILE_CASES[case]
    cfg = dataset_preset("tiny_motion")
    for k, v in change.items():
        if isinstance(v, dict) and isinstance(cfg["profile"].get(k), dict) and k != "load":
            cfg["profile"][k].update(v)
        else:
            cfg["profile"][k] = v
    msg = message(lambda: plan(cfg))
    assert msg.startswith(key), msg
