"""The thermal kind of calibration (swgcal.thermal): known constants recovered from
synthetic joint logs, a planted library effect found, an effect outside the library left
unexplained, the app path, and the real UR3 day where it lies beside the repository."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from planted_thermal import SyntheticThermal, synthetic_joint_log

from swgcal import build_problem, calibrate, detect_kind, render_report
from swgcal.thermal import summarize
from swgcli import compose_app
from swgcli.calibrate import run_calibrate
from swgsim.datasets.joint_log import write_joint_log

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))
from thermal_ur3 import transfer_effects  # noqa: E402  (a study, in scripts/)


def _run(c: SyntheticThermal):
    return calibrate(build_problem(synthetic_joint_log(c), joint=1))


def _values(result, term):
    return {k: (e.value, e.std) for k, e in result.final.estimates_of(term).items()}


def test_a_clean_log_gets_its_constants_back_and_no_effect():
    truth = SyntheticThermal()
    res = _run(truth)
    assert res.added == [] and not res.unexplained
    got = _values(res, "first_order")
    for name in ("r_th_k_per_w", "tau_min", "ambient_c", "initial_k"):
        value, std = got[name]
        assert abs(value - getattr(truth, name)) < 4 * std, (name, value, std)
    # the errors are the noise's, on held-out data too
    assert res.rmse["test"]["after"] == pytest.approx(truth.noise_k, rel=0.1)


#: One planted library effect per log, its constants (of the UR3 day's size [choice]).
SINGLE_EFFECTS = {
    "copper": SyntheticThermal(k_cu_k_per_a2=1.0, r_th_k_per_w=0.2),
    "housing": SyntheticThermal(r2_k_per_w=0.5, tau2_min=150.0),
    "standstill": SyntheticThermal(dt_still_k=-1.5, tau_still_min=20.0, pause_blocks=3),
    "powered": SyntheticThermal(k_pw_k=3.0, tau_pw_min=20.0, off_h=0.5),
}
#: A recovered constant lies within this many of its standard errors of the truth [choice:
#: 3 s.e., missed by a correct estimate 0.3 % of the time].
WITHIN_SE = 3.0


@pytest.mark.parametrize("effect", list(SINGLE_EFFECTS))
def test_a_single_planted_effect_is_found_alone_with_its_constants(effect):
    """Copper loss, a second slow time constant, cooling at standstill, the motor's and
    drive's heat while powered (the arm off for half an hour): each found as that one
    effect in the first iteration (not as a pair: the base's τ, gain and offset are
    refitted with every candidate screened), its constants and the base's within
    3 standard errors, the held-out error down to the noise's."""
    truth = SINGLE_EFFECTS[effect]
    res = _run(truth)
    assert res.iterations[0].accepted == effect
    assert res.added == [effect] and not res.unexplained
    for name, (value, std) in {**_values(res, effect), **_values(res, "first_order")}.items():
        planted = getattr(truth, name)
        assert abs(value - planted) < WITHIN_SE * std, (name, value, std, planted)
    assert res.rmse["test"]["after"] < res.rmse["test"]["before"]
    assert res.rmse["test"]["after"] == pytest.approx(truth.noise_k, rel=0.1)


def test_a_clean_log_is_physical_and_cross_validated_both_ways():
    """Nothing on a bound, every constant in its range; both directions across the gap
    score the base alone at the noise's level; the resolution is the data's."""
    res = _run(SyntheticThermal())
    assert res.problem.meta["physical"] == {"before": [], "after": []}
    cv = res.problem.meta["crossval"]
    assert [r["model"] for r in cv["rows"]] == ["first_order"]
    for way in ("forward", "backward"):
        # 2 x the noise: the held-out block's prediction error adds to it [choice]
        assert cv["rows"][0][way]["rmse"] < 2 * SyntheticThermal().noise_k
    s = summarize(res)
    assert s["scored"] is True and s["rmse_before"] is not None


def test_a_negative_thermal_resistance_comes_back_on_its_bound_and_is_not_scored():
    """Planted R_th < 0 (the loss cools the joint: unphysical): unbounded, the fit goes
    negative; bounded it stops at 0, flagged on its bound, and the run is not scored."""
    import dataclasses

    from swgcal.core import fit_terms
    from swgcal.thermal.library import FirstOrderJoint

    truth = SyntheticThermal(r_th_k_per_w=-0.3)
    p = build_problem(synthetic_joint_log(truth), joint=1)

    class Unbounded(FirstOrderJoint):
        def linear_bounds(self, sig):
            return [(-np.inf, np.inf)] * 3

    free = fit_terms([Unbounded()], p.signals, p.y, p.split.fit)
    assert free.estimates_of("first_order")["r_th_k_per_w"].value < -0.1
    res = calibrate(dataclasses.replace(p, library={}))
    est = res.base_model_final.estimates_of("first_order")["r_th_k_per_w"]
    assert est.value == 0.0 and est.on_bound and est.bound == "on its lower bound 0"
    assert any("r_th_k_per_w" in w for w in res.problem.meta["physical"]["before"])
    s = summarize(res)
    assert s["scored"] is False and s["rmse_before"] is None
    assert "Not scored as a calibration" in s["not_scored"]


def test_the_sensor_resolution_is_the_smallest_step_between_readings():
    from swgcal.thermal.problem import sensor_resolution

    y = 20.0 + 0.0625 * np.array([0, 0, 1, 3, 3, 2, np.nan, 5])
    assert sensor_resolution(y) == 0.0625


def test_a_fan_switching_with_the_cycle_count_is_left_unexplained():
    """A cooling fan (outside the library) is not forced onto a library effect: no effect
    is kept and the residual is reported structured, periodic in time."""
    res = _run(SyntheticThermal(fan_k=1.0))
    assert res.added == []
    assert res.unexplained and "periodic in time" in res.residual_signature
    assert res.rmse["test"]["after"] > 5 * SyntheticThermal().noise_k
    # the fitted constants go out with the caveat
    assert "still structured" in summarize(res)["joint_thermal"]["caveat"]


def test_a_bad_thermal_option_is_refused_naming_its_key():
    log = synthetic_joint_log(SyntheticThermal(hours_before=0.3, hours_after=0.3))
    with pytest.raises(ValueError, match=r"^thermal.joint must lie in \[0, 5\], got 7$"):
        build_problem(log, joint=7)
    with pytest.raises(ValueError, match=r"unknown thermal effects \['fan'\]"):
        build_problem(log, candidates=["fan"])


def test_swgsim_calibrate_takes_a_joint_log(tmp_path):
    path = tmp_path / "day.csv"
    write_joint_log(synthetic_joint_log(SyntheticThermal()), path)
    assert detect_kind(path) == "thermal"
    out = tmp_path / "out"
    run_calibrate(compose_app("calibrate", [f"measured={path}", f"out_dir={out}",
                                            "~logger", "thermal.joint=1"]))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["kind"] == "thermal" and summary["data"]["joint"] == 1
    assert summary["effects_added"] == [] and summary["unexplained"] is False
    jt = yaml.safe_load((out / "joint_thermal.yaml").read_text())
    assert jt["tau_min"] == pytest.approx(SyntheticThermal().tau_min, rel=0.02)
    assert (out / "figures" / "temperature.png").stat().st_size > 10_000
    assert "doi:10.24432/C5J891" in (out / "report.md").read_text()
    with pytest.raises(ValueError, match=r"^thermal.joint must lie in \[0, 5\], got 6$"):
        run_calibrate(compose_app("calibrate", [f"measured={path}", f"out_dir={out}2",
                                                "~logger", "thermal.joint=6"]))


def test_a_calibration_into_a_folder_of_an_earlier_one_leaves_only_its_own_files(tmp_path):
    """Issue 82, cause 5: a thermal calibration after a friction one into the same out_dir
    left friction_effects.yaml (an input of the generator) and the friction figures beside
    the thermal report. swgsim-calibrate claims its folder fresh: an earlier run's files
    go before this run writes, its summary last."""
    from bad_input import friction_csv

    t = np.arange(2000) * 0.002
    rec = friction_csv(tmp_path / "rec.csv", t, np.sin(t), np.cos(t),
                       0.1 * np.tanh(20 * np.cos(t)))
    out = tmp_path / "out"
    run_calibrate(compose_app("calibrate", [f"measured={rec}", f"out_dir={out}", "~logger"]))
    assert (out / "friction_effects.yaml").is_file()
    friction = {p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file()}
    log = tmp_path / "day.csv"
    write_joint_log(synthetic_joint_log(SyntheticThermal()), log)
    run_calibrate(compose_app("calibrate", [f"measured={log}", f"out_dir={out}", "~logger",
                                            "thermal.joint=1"]))
    now = {p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file()
           and not p.name.startswith(".swg-owner")}
    summary = json.loads((out / "summary.json").read_text())
    assert summary["kind"] == "thermal" and "friction_effects.yaml" not in now
    assert now == {"summary.json", "report.md", "joint_thermal.yaml",
                   *(f for f in summary["figures"].values())}, now - friction


def test_the_ur3_days_shoulder_is_no_physical_first_order_fit(ur3_day):
    """Issue 86: with the room no warmer than the coolest joint's first reading, the gear's
    loss alone does not warm the shoulder as measured: the base alone leaves a parameter
    on a bound or outside its range and is not scored; held out: after the gap, and
    before it the other way; the resolution is the sensor's 0.0625 K step."""
    res = calibrate(build_problem(ur3_day, joint=1))
    assert res.problem.split.description["hours"]["validation"][0] > 5.0  # after the gap
    assert res.problem.meta["physical"]["before"]
    assert summarize(res)["scored"] is False
    assert res.problem.meta["resolution"] == 0.0625
    row = res.problem.meta["crossval"]["rows"][0]
    assert np.isfinite(row["forward"]["rmse"]) and np.isfinite(row["backward"]["rmse"])


def test_an_effect_kept_on_one_joint_is_checked_on_the_joints_not_fitted():
    """Copper kept on two logs is carried, with its time constant, to the others: it
    lowers the held-out error where the loss is there (even where too small to be kept
    alone: 0.002 K/A², a rise of at most 0.05 K) and not on a clean log."""
    logs = [SyntheticThermal(k_cu_k_per_a2=1.0, r_th_k_per_w=0.2, seed=0),
            SyntheticThermal(k_cu_k_per_a2=1.0, r_th_k_per_w=0.2, seed=1),
            SyntheticThermal(k_cu_k_per_a2=0.002, r_th_k_per_w=0.3, seed=2),
            SyntheticThermal(seed=3)]
    results = [_run(c) for c in logs]
    assert [r.added for r in results] == [["copper"], ["copper"], [], []]
    carried = transfer_effects(results)
    assert [c["effect"] for c in carried] == ["copper", "copper"]
    for c in carried:
        passes = [t["passes"] for t in c["to"]]
        assert passes == [True, True, False] and c["holds_for_arm"]


def test_a_measured_room_holds_the_ambient_so_a_cold_start_is_not_flagged():
    """Issue 86: a log that starts after a long stop, every other joint at the room's
    temperature, leaves the fitted room on its bound, the coolest joint's first reading
    (an unphysical fit, not scored); the room measured (``thermal.room_c``) holds the
    ambient at it, and the fit is physical with its constants back."""
    truth = SyntheticThermal(others_k=0.0, initial_k=0.5)
    log = synthetic_joint_log(truth)
    free = calibrate(build_problem(log, joint=1))
    assert any("ambient_c" in w and "on its upper bound" in w
               for w in free.problem.meta["physical"]["before"])
    held = calibrate(build_problem(log, joint=1, room_c=truth.ambient_c))
    assert held.problem.meta["physical"] == {"before": [], "after": []}
    assert held.problem.meta["room_c"] == truth.ambient_c
    est = held.base_model_final.estimates_of("first_order")
    assert est["ambient_c"].value == truth.ambient_c and est["ambient_c"].bound == "held at 24"
    for name in ("r_th_k_per_w", "tau_min", "initial_k"):
        assert abs(est[name].value - getattr(truth, name)) < 4 * est[name].std, name
    s = summarize(held)
    assert s["scored"] is True and "Room: measured, 24 °C" in render_report(held, s)
    with pytest.raises(ValueError, match=r"^thermal.room_c must lie in \[0, 50\]"):
        build_problem(log, joint=1, room_c=80.0)


def test_a_final_model_without_effects_is_the_base_models_optimum(ur3_day):
    """Issue 86: J5's bounded first-order fit has two optima on the UR3 day (τ 3.1 min,
    and τ on its 600-min bound with 3.5 times less RSS on fit + validation); the final
    model, nothing kept, is refitted from the base's optimum too and is the base model."""
    res = calibrate(build_problem(ur3_day, joint=5))
    assert res.added == []
    assert res.final.thetas[0] == pytest.approx(res.base_model_final.thetas[0])
    assert res.rmse["test"]["after"] == pytest.approx(res.rmse["test"]["before"])
