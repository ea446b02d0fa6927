"""Gear lives on an operating profile (swgsim.datasets.slots): the slots, the windows of a
life along the profile, eq. (10) in the angle domain, and the monitor's features of such
windows (angle domain, twist from an output encoder) against closed forms."""

import dataclasses

import numpy as np
import pytest

from learn.inputs.health import TWIST_FEATURES, feature_names
from swgcli import dataset_preset
from swgmon.evaluation.training import has_twist, life_features
from swgsim.datasets.config import dataset_config
from swgsim.datasets.life import LifeSimulator, life_dataset
from swgsim.datasets.plan import plan
from swgsim.datasets.records import ProfileRecordBank, record_bank
from swgsim.datasets.schedule import FaultOnset, LifeConfig
from swgsim.datasets.slots import profile_slots
from swgsim.sensing.disturbance import (
    DisturbanceSpec,
    apply_disturbance,
    disturb,
    draw_disturbance,
)

# tiny_motion with 0.07 s windows: two slots turn the WG 2 revolutions one way, at
# +2000 rpm under 7 N m and at -2000 rpm under 30 N m (the load step at 0.2 s)
OVERRIDES = ["chain.window_s=0.07", "profile.angles.output_encoder_bits=20"]


@pytest.fixture(scope="module")
def motion():
    return plan(dataset_config(dataset_preset("tiny_motion", OVERRIDES)))


@pytest.fixture(scope="module")
def bank(motion):
    return record_bank(motion, 1)


def test_slots_are_the_commanded_points_of_the_turning_windows(motion):
    sl = profile_slots(motion)
    assert sl.starts.tolist() == [500, 2600]  # 0.05 s and 0.26 s at 10 kHz
    assert sl.n_in_rpm.tolist() == [2000.0, -2000.0]
    assert sl.t_out_nm.tolist() == [7.0, 30.0]
    assert [d.dwell_min for d in sl.duty(2.0)] == [2.0, 2.0]


def test_a_profile_without_turning_windows_is_refused_naming_the_key():
    p = plan(dataset_config(dataset_preset("tiny_motion")))  # 0.04 s: 1.3 revolutions
    with pytest.raises(ValueError, match=r"^dataset.profile: no window turns the wave "
                                         r"generator 2 revolutions"):
        profile_slots(p)


def test_profile_life_windows_cycle_through_the_slots(motion, bank):
    assert isinstance(bank, ProfileRecordBank)
    life = LifeConfig(hours=0.5, interval_min=1.0, commissioning_h=0.25,
                      fault=FaultOnset("reduced_stiffness", 0.4, 0.25))
    sim = LifeSimulator(motion, 1, life, bank)
    sig, meta = sim.windows(0, len(sim))
    n_t = sig.shape[-1]
    assert sig.shape == (30, 5, 700) and meta["phi_out_meas"].shape == (30, n_t)
    assert np.array_equal(meta["n_in_rpm"], np.tile([2000.0, -2000.0], 15))
    assert np.array_equal(meta["t_out_nm"], np.tile([7.0, 30.0], 15))
    assert np.array_equal(meta["fault"] == "reduced_stiffness", meta["hour"] >= 0.4 - 1e-9)
    # the measured speed follows the slot; windows of one slot differ (start, noise)
    assert np.allclose(meta["n_in_mean_rpm"], meta["n_in_rpm"], rtol=0.035)  # 3.0 % reached
    assert not np.allclose(sig[0], sig[2])
    # a slice is the same as the whole
    s2, m2 = sim.windows(7, 12)
    assert np.array_equal(s2, sig[7:12]) and np.array_equal(m2["phi_in_meas"],
                                                            meta["phi_in_meas"][7:12])
    ds = life_dataset(sim, 0, 4)
    assert ds["phi_out_meas"].dims == ("sample", "time") and ds["phi_out_meas"].shape == (4, n_t)


def test_start_jitter_spreads_a_slots_windows_and_is_refused_beyond_one_window(motion, bank):
    life = LifeConfig(hours=0.1, interval_min=1.0, commissioning_h=0.05)
    assert motion.config.profile.start_jitter_s == 0.025  # the preset's: the module's records
    phi = {0.025: LifeSimulator(motion, 1, life, bank).windows(0, 6)[1]["phi_in_meas"]}
    p = plan(dataset_config(dataset_preset(
        "tiny_motion", [*OVERRIDES, "profile.start_jitter_s=0.0"])))
    phi[0.0] = LifeSimulator(p, 1, life).windows(0, 6)[1]["phi_in_meas"]
    assert np.array_equal(phi[0.0][0], phi[0.0][2]) and np.array_equal(phi[0.0][1], phi[0.0][5])
    assert not np.array_equal(phi[0.025][0], phi[0.025][2])
    with pytest.raises(ValueError, match=r"^dataset.profile.start_jitter_s must lie in "
                                         r"\[0, 0.07\] s .*, got 0.08$"):
        plan(dataset_config(dataset_preset("tiny_motion",
                                           [*OVERRIDES, "profile.start_jitter_s=0.08"])))


def test_disturbance_in_the_input_angle_equals_the_time_form_at_steady_speed():
    t = np.arange(1200) / 10e3
    n = np.array([2000.0, 3000.0])
    x = np.zeros((2, 5, t.size))
    spec = DisturbanceSpec(0.01, 0.02)
    a = disturb(x, t, n, spec, np.random.default_rng(3))
    b = disturb(x, t, n, spec, np.random.default_rng(3),
                phi_in=2 * np.pi * n[:, None] / 60 * t[None, :])
    assert np.max(np.abs(a - b)) < 1e-15


def _disturbance_arrays(signals, time_s, n_in_rpm, draws, phi_in=None):
    """eq. (10) on arrays, as apply_disturbance computed it before it was compiled."""
    a0, aj, alpha = draws
    f_in = np.asarray(n_in_rpm, float) / 60.0
    j = np.arange(1, 5)
    if phi_in is None:
        wt = 2 * np.pi * (f_in[:, None] / j[None, :])[:, :, None] * time_s[None, None, :]
    else:
        wt = np.asarray(phi_in, float)[:, None, :] / j[None, :, None]
    cs = (aj * np.cos(alpha))[..., 0]
    sn = (aj * np.sin(alpha))[..., 0]
    harm = np.einsum("wsj,wjt->wst", cs, np.sin(wt)) + np.einsum("wsj,wjt->wst", sn, np.cos(wt))
    return signals + a0 + harm


@pytest.mark.parametrize("angle", [False, True])
def test_compiled_disturbance_equals_the_array_form(angle):
    """apply_disturbance (compiled) gives the array form's numbers, in time and along a
    measured input angle (bit for bit on the developers' machine; 1e-14 of the signal
    range allowed for another libm)."""
    rng = np.random.default_rng(5)
    t = np.arange(1000) / 10e3
    n = rng.uniform(100.0, 3000.0, 7)
    x = rng.normal(0.0, 0.1, (7, 5, t.size))
    draws = draw_disturbance(DisturbanceSpec(0.01, 0.02), rng, (7, 5))
    phi = 2 * np.pi * n[:, None] / 60 * t[None, :] + rng.normal(0, 0.01, (7, t.size)) \
        if angle else None
    ref = _disturbance_arrays(x, t, n, draws, phi)
    got = apply_disturbance(x, t, n, draws, phi)
    assert np.max(np.abs(got - ref)) <= 1e-14 * np.ptp(ref)


def test_twist_features_follow_the_stiffness_closed_form(motion, bank):
    """The mean twist of a slot's windows with k1 · 0.75 against the closed form: the same
    stiffness torque T_s = k1 d + k2 d³ (paper eq. (3); friction and load unchanged)
    solved for d with 0.75 k1, d = N δ / ((N + 1) tan α) (swgsim.gear.dynamics.steady_state's
    relation), T_s taken from the healthy windows' measured twist."""
    assert has_twist(motion)
    names = feature_names(twist=True)
    assert names[-2:] == list(TWIST_FEATURES)
    twist = {}
    for sev in (0.0, 0.25):
        sim = LifeSimulator(motion, 1, LifeConfig(hours=0.2, commissioning_h=0.0, fault=(
            FaultOnset("reduced_stiffness", 0.0, sev) if sev else FaultOnset())), bank)
        sig, meta = sim.windows(0, len(sim))
        f = life_features(motion, sig, meta)
        assert f.shape == (len(sim), len(names))
        twist[sev] = [f[sim.schedule.duty_index == s, -2].mean() * np.pi / (180 * 60)
                      for s in (0, 1)]
    g = bank.healthy.gear
    scale = (g.ratio + 1) * np.tan(g.alpha_tooth_rad) / g.ratio  # δ = scale · d
    for s in (0, 1):
        d_h = twist[0.0][s] / scale
        t_s = g.k1_nm_per_rad * d_h + g.k2_nm_per_rad3 * d_h ** 3
        roots = np.roots([g.k2_nm_per_rad3, 0.0, 0.75 * g.k1_nm_per_rad, -t_s])
        d_w = roots[np.isreal(roots)].real[np.argmin(np.abs(roots[np.isreal(roots)].real
                                                            - d_h))]
        assert twist[0.25][s] == pytest.approx(d_w * scale, rel=1e-3), s  # 2.3e-4 reached
        assert twist[0.25][s] / twist[0.0][s] > 1.1  # the loss shows


def test_steady_lives_keep_their_bank_and_features(motion):
    p = plan(dataset_config(dataset_preset("tiny_life")))
    assert type(record_bank(p, 1)).__name__ == "RecordBank" and not has_twist(p)
    no_enc = dataclasses.replace(motion.config.profile.angles, output_encoder_bits=None)
    cfg = dataclasses.replace(motion.config, profile=dataclasses.replace(
        motion.config.profile, angles=no_enc))
    assert not has_twist(plan(cfg))


def test_a_profile_stream_gives_the_lifes_features_and_a_model_mismatch_is_named(
        motion, bank, tmp_path):
    from types import SimpleNamespace

    import xarray as xr

    from swgmon.advisories.stream import check_stream, stream_features
    from swgmon.detection.rule import RuleConfig

    sim = LifeSimulator(motion, 1, LifeConfig(hours=0.3, commissioning_h=0.2), bank)
    sig, meta = sim.windows(0, len(sim))
    ds = life_dataset(sim)
    ds.to_netcdf(tmp_path / "life.nc", engine="h5netcdf")
    back = xr.load_dataset(tmp_path / "life.nc", engine="h5netcdf")
    assert np.allclose(stream_features(back), life_features(motion, sig, meta), rtol=0,
                       atol=1e-9)
    model = SimpleNamespace(sample_rate_hz=back.attrs["sample_rate_hz"], window_s=0.07,
                            n_features=len(feature_names()), points_range=None)
    with pytest.raises(ValueError, match=r"^stream: its windows give 73 health features "
                                         r"\(with an output encoder's twist\); the model "
                                         r"was trained on 71; a model for it: "
                                         r"swgsim-train experiment=monitor"):
        check_stream(back, model, RuleConfig())


def test_a_life_on_a_profile_is_a_data_set_and_its_duty_is_the_profile(tmp_path):
    from swgsim.datasets.generate import generate
    from swgsim.datasets.schema import load

    cfg = dataset_config(dataset_preset("tiny_motion_life"))
    s = generate(cfg, tmp_path / "life", n_jobs=1, progress=False)
    assert s["complete"] and s["windows"] == 60
    ds = load(tmp_path / "life")
    assert ds["phi_out_meas"].shape == (60, 700)
    assert set(ds["fault"].values[ds["hour"].values >= 0.75]) == {"wear"}
    bad = dataset_config(dataset_preset("tiny_motion_life", ["life.duty=[{n_in_rpm: 2000}]"]))
    with pytest.raises(ValueError, match=r"^dataset.life.duty must be empty with "
                                         r"dataset.profile"):
        plan(bad)
