"""Strain side of the calibration loop: measurement effects, planted-effect recovery,
clean data, two effects, out-of-library residuals, held-out split.

"Measured" data come from the chain's standard path (random WG start angles, settling
transient) with planted measurement effects and white noise of 1 % of the signal range
(:mod:`swgsim.calibration.strain_synthetic`); the calibration models them with one
steady trajectory per operating point. Tiny: 2 operating points × 5 windows of 40 ms.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from swgsim.calibration import strain_synthetic as syn
from swgsim.calibration.strain import StrainModel, calibrate_strain, gear_with_ke
from swgsim.chain import SimulationChain
from swgsim.dynamics import rt1_size20
from swgsim.measurement import (
    QUARTER_BRIDGE_K,
    apply_sensor_effects,
    fractional_delay,
    lowpass,
    parse_sensor_effects,
    psi_rate,
)

FS = 10e3


# ---------------------------------------------------------------------------------------
# measurement effects (swgsim.measurement)


def test_lowpass_first_order_response():
    t = np.arange(4000) / FS
    for f, gain in ((0.0, 1.0), (250.0, 2 ** -0.5)):
        x = np.cos(2 * np.pi * f * t)
        y = lowpass(x, 250.0, FS)[2000:]
        amp = np.hypot(*(2 * np.mean(y * b(2 * np.pi * f * t[2000:])) for b in (np.cos, np.sin))
                       ) if f else y.mean()
        assert amp == pytest.approx(gain, rel=2e-3)


def test_fractional_delay_and_misplacement_delay_one_channel():
    t = np.arange(600) / FS
    x = np.sin(2 * np.pi * 130 * t)
    y = fractional_delay(x[None, :], np.array([2.3]))[0]
    assert np.allclose(y[50:-50], np.sin(2 * np.pi * 130 * (t - 2.3 / FS))[50:-50], atol=2e-4)
    sig = np.broadcast_to(x, (2, 5, t.size)).copy()
    fx = [{"name": "gauge_misplacement", "params": {"delta_deg": {"s2": 1.0}}}]
    out = apply_sensor_effects(sig, t, [2000.0, 4000.0], fx)
    d = np.deg2rad(1.0) / psi_rate(np.array([2000.0, 4000.0]))  # delay [s]
    for w in range(2):
        assert np.allclose(out[w, [0, 1, 3, 4]], x)
        assert np.allclose(out[w, 2, 50:-50], np.sin(2 * np.pi * 130 * (t - d[w]))[50:-50],
                           atol=2e-4)


def test_bridge_offset_drift_gain_and_lead():
    t = (np.arange(120) - 20) / FS
    s = np.linspace(-0.3, 0.3, 120)[None, None, :] * np.ones((2, 5, 1))
    fx = [{"name": "bridge_nonlinearity", "params": {"bridge": "quarter"}},
          {"name": "gain_mismatch", "params": {"gain": [1.0, 1.02, 1.0, 1.0, 1.0]}},
          {"name": "offset", "params": {"offset_mvv": {"s3": 0.01}}},
          {"name": "thermal_drift", "params": {"rate_mvv_per_s": 0.5}}]
    out = apply_sensor_effects(s, t, 2000.0, fx, t_start_s=[0.0, 1.0], n_lead=20)
    assert out.shape == (2, 5, 100)
    ref = s[..., 20:] / (1 + QUARTER_BRIDGE_K * s[..., 20:])
    ref = ref * np.array([1, 1.02, 1, 1, 1])[None, :, None]
    ref[:, 3] += 0.01
    ref += 0.5 * (np.array([0.0, 1.0])[:, None, None] + t[None, None, 20:])
    assert np.allclose(out, ref)


@pytest.mark.parametrize("bad, match", [
    ([{"name": "wobble", "params": {}}], "unknown effect"),
    ([{"name": "gain_mismatch", "params": {"gain": 3.0}}], r"gain must lie in \(0.5, 2\]"),
    ([{"name": "offset", "params": {"offset_mvv": {"s7": 0.1}}}], "unknown channel 's7'"),
    ([{"name": "amplifier_lowpass", "params": {"fc": 100}}], "unknown parameters"),
])
def test_sensor_effect_errors_name_the_parameter(bad, match):
    with pytest.raises(ValueError, match=match):
        parse_sensor_effects(bad)


def test_gear_with_ke_appends_harmonic():
    g = gear_with_ke(rt1_size20(), [{"order": 3, "amp_rad": 1e-4, "phase_rad": 0.5}])
    assert g.ke_orders[-1] == 3 and g.ke_amp_rad[-1] == 1e-4 and g.ke_phase_rad[-1] == 0.5
    with pytest.raises(ValueError, match="positive integer"):
        gear_with_ke(rt1_size20(), [{"order": 2.5, "amp_rad": 1e-4}])


# ---------------------------------------------------------------------------------------
# calibration on planted data


@pytest.fixture(scope="module")
def bench():
    """Chain (nominal layout), shared model and clean bench windows."""
    chain = SimulationChain()
    return {"chain": chain, "model": StrainModel(chain=chain),
            "clean": syn.simulate_windows(chain, seed=0)}


def _run(bench, effects=(), hidden=(), ke=None, out_dir=None, **kw):
    clean = (syn.simulate_windows(bench["chain"], seed=0, ke=ke) if ke else bench["clean"])
    ds, truth = syn.bench_dataset(clean, effects, hidden=hidden, noise_rel=0.01, seed=1)
    data = ds if out_dir is None else syn.write_dataset(ds, out_dir / "data")
    s = calibrate_strain(data, None if out_dir is None else out_dir / "report",
                         model=bench["model"], figures=out_dir is not None, **kw)
    return s, truth


@pytest.mark.parametrize("key", list(syn.PLANTED))
def test_planted_effect_is_found_and_recovered(bench, key):
    spec = syn.PLANTED[key]
    s, truth = _run(bench, spec.get("sensor_effects", ()), ke=spec.get("ke"))
    ranking = s["iterations"][0]["candidates"]
    assert ranking[0]["name"] == key, [c["name"] for c in ranking[:3]]
    assert [e["name"] for e in s["effects_added"]] == [key]
    eff = s["effects_added"][0]
    primary, others = syn.expected_values(key, eff)
    for name, true in primary.items():
        p = eff["params"][name]
        assert p["value"] == pytest.approx(true, rel=0.10), name
        assert p["stderr"] > 0 and p["identifiable"]
    for name, true in others.items():
        p = eff["params"][name]
        assert abs(p["value"] - true) < 4 * p["stderr"] + 1e-12, name
    assert s["rmse_after"] < 1.2 * truth["sigma"]
    assert s["rmse_after"] < s["rmse_before"]
    assert not s["unexplained"]


def test_clean_data_get_no_effect(bench):
    s, truth = _run(bench)
    assert s["effects_added"] == []
    assert not s["unexplained"]
    assert s["rmse_after"] < 1.2 * truth["sigma"]
    base = s["baseline"]["params"]
    assert base["w0_mm"]["value"] == pytest.approx(0.254, rel=0.01)
    assert base["gauge_gain"]["value"] == pytest.approx(1.0, abs=0.01)


def test_two_effects_found_and_report_written(bench, tmp_path):
    fx = (syn.PLANTED["offset"]["sensor_effects"]
          + syn.PLANTED["amplifier_lowpass"]["sensor_effects"])
    s, truth = _run(bench, fx, out_dir=tmp_path)
    assert sorted(e["name"] for e in s["effects_added"]) == ["amplifier_lowpass", "offset"]
    assert s["rmse_after"] < 1.2 * truth["sigma"]
    # report, figures and summary on disk; the summary's sensor effects are a valid option
    rep = tmp_path / "report"
    for f in ("report.md", "summary.json"):
        assert (rep / f).is_file()
    for key in ("order_spectrum", "offsets", "channel_differences", "speed_load", "overlay"):
        assert (rep / "figures" / f"{key}.png").is_file()
    js = json.loads((rep / "summary.json").read_text())
    for k in ("rmse_before", "rmse_after", "effects_added", "unexplained", "residual_signature",
              "heldout"):
        assert k in js
    assert "whole windows" in js["heldout"].lower()
    assert {e.name for e in parse_sensor_effects(js["sensor_effects"])} == {
        "offset", "amplifier_lowpass"}
    f_c = js["sensor_effects"][[e["name"] for e in js["sensor_effects"]].index(
        "amplifier_lowpass")]["params"]["f_c_hz"]
    assert f_c == pytest.approx(250.0, rel=0.1)
    assert "amplifier_lowpass" in (rep / "report.md").read_text()


@pytest.mark.parametrize("hidden, text", [("tone_3p5", "order 3.50"),
                                          ("square_glitch", "170 Hz")])
def test_out_of_library_residual_is_unexplained(bench, hidden, text):
    s, _ = _run(bench, hidden=[syn.HIDDEN[hidden]])
    assert s["effects_added"] == []
    assert s["unexplained"]
    assert text in s["residual_signature"]


def test_heldout_windows_are_whole_and_last_is_test(bench):
    s, _ = _run(bench, max_iter=0)
    res = s["_result"]
    sig, sp = res.problem.signals, res.problem.split
    roles = [set(sig.window[idx].tolist()) for idx in (sp.fit, sp.validation, sp.test)]
    assert not (roles[0] & roles[1]) and not (roles[0] & roles[2]) and not (roles[1] & roles[2])
    n_w = sig.n_windows
    assert np.bincount(sig.window[sp.test], minlength=n_w).max() == 5 * sig.n_t  # whole
    assert s["heldout_split"]["test_samples"] == [8, 9]  # the last window of each op
