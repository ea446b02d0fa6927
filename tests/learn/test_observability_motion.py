"""The motion map (learn.observability.motion, swgsim-observability map=motion):
its separation measure, the smallest detectable severity, refusals, and (slow) one output
inertia end to end."""

import numpy as np
import pandas as pd
import pytest

from learn.observability.motion import (
    MotionMapConfig,
    separations,
    smallest_detectable,
    stiffness_left,
)
from swgsim.base.typed import check_tree


def test_separation_is_the_mean_square_z_score_per_point():
    rng = np.random.default_rng(0)
    ref = rng.normal(size=(40000, 3)) * [1.0, 2.0, 3.0] + [0.0, 10.0, -5.0]
    pts = np.repeat([[2000.0, 7.0], [2000.0, 39.0]], 20000, axis=0)
    ref[pts[:, 1] == 39.0] += 100.0  # another point, another mean
    x = np.array([[1.0, 12.0, -5.0], [101.0, 110.0, 95.0]])
    s = separations(ref, pts, x, np.array([[2000.0, 7.0], [2000.0, 39.0]]))
    assert s[0] == pytest.approx((1 + 1 + 0) / 3, rel=0.03)
    assert s[1] == pytest.approx((1 + 0 + 0) / 3, rel=0.03)
    with pytest.raises(ValueError, match="reference windows"):
        separations(ref, pts, x[:1], np.array([[3000.0, 7.0]]))


def test_smallest_detectable_and_stiffness_left():
    t = pd.DataFrame({"j_out_kgm2": 0.69, "view": "profile", "fault": "wear",
                      "severity": [0.1, 0.2, 0.3], "stiffness_left": [0.925, 0.85, 0.775],
                      "fraction_beyond_p95": [0.2, 0.6, 0.9]})
    s = smallest_detectable(t)
    assert s.smallest_severity.tolist() == [0.2] and s.stiffness_left.tolist() == [0.85]
    assert np.isnan(smallest_detectable(t.assign(fraction_beyond_p95=0.1)).smallest_severity[0])
    assert stiffness_left("wear", 1.0) == 0.25 and stiffness_left("reduced_stiffness", 0.25) == 0.75


@pytest.mark.parametrize("change, key", [({"windows": 5}, "motion.windows"),
                                         ({"wear": [1.5]}, "motion.wear"),
                                         ({"reduced_stiffness": []}, "motion.reduced_stiffness")])
def test_bad_designs_are_refused_naming_the_key(change, key):
    with pytest.raises(ValueError, match=f"^{key} must"):
        check_tree(MotionMapConfig(**change), "motion")


def test_the_app_refuses_an_unknown_map_and_names_a_bad_preset_key(tmp_path):
    from learn.observability.task import run_observability
    from swgcli import compose_app

    cfg = compose_app("observability", ["map=steadyy", f"report_dir={tmp_path}/r"])
    with pytest.raises(ValueError, match=r"^map: must be one of \['steady', 'motion'\]"):
        run_observability(cfg)
    cfg = compose_app("observability", [
        "map=motion", "j_out_kgm2=[0.5]", f"report_dir={tmp_path}/r",
        "motion_profile.profile.segments=[{move: {target_rpm: 9000, accel_rpm_s: 1000}}]"])
    with pytest.raises(ValueError, match=r"^motion_profile.profile.segments\[0\].move."
                                         r"target_rpm must be within ±6500 rpm"):
        run_observability(cfg)


@pytest.mark.slow
def test_motion_map_on_the_robot_link_end_to_end(tmp_path):
    """One output inertia, 20 windows per state: the files, healthy near 5 % at the steady
    points, wear at its largest severity seen in every view."""
    from learn.observability.task import run_observability
    from swgcli import compose_app

    cfg = compose_app("observability", ["map=motion", "j_out_kgm2=[0.69]", "motion.windows=20",
                                        "motion.reduced_stiffness=[0.25]", "motion.wear=[1.0]",
                                        f"report_dir={tmp_path}/r", "progress=false"])
    out = run_observability(cfg)
    t = out["table"]
    assert set(t.view) == {"steady", "profile", "profile + output encoder"}
    assert (t[t.fault == "wear"].fraction_beyond_p95 >= 0.9).all()
    for f in ("csv", "smallest", "figure"):
        assert (tmp_path / "r" / out["files"][f].split("/")[-1]).is_file()
