"""Observability map: the share beyond the healthy percentile, the torsional modes and the
app end to end on the tiny bench grid."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from learn.observability.study import (
    COLUMNS,
    J_OUT_BENCH,
    J_OUT_ROBOT,
    j_out_grid,
    observability_table,
    plot_observability,
    torsional_modes,
)


def _records(rng, shift: float, n: int = 200) -> pd.DataFrame:
    rows = []
    for op in ((2000.0, 7.0), (4000.0, 70.0)):
        for fault, z in (("healthy", rng.normal(size=n)),
                         ("far", rng.normal(size=n) + 100.0),
                         ("mixed", np.r_[rng.normal(size=n // 2),
                                         rng.normal(size=n // 2) + shift])):
            rows.append(pd.DataFrame({"gear": 1, "fault": fault, "n_in_rpm": op[0],
                                      "t_out_nm": op[1], "z": np.abs(z)}))
    return pd.concat(rows, ignore_index=True)


def test_share_beyond_the_healthy_percentile():
    rng = np.random.default_rng(0)
    tab = observability_table(_records(rng, shift=100.0), j_out=0.1)
    assert set(COLUMNS) <= set(tab.columns)
    assert (tab["j_out_kgm2"] == 0.1).all() and len(tab) == 2 * 3
    share = tab.groupby("fault")["fraction_beyond_p95"].mean()
    assert share["far"] == 1.0
    assert share["healthy"] == pytest.approx(0.05, abs=0.01)
    # half the windows far away, half healthy look-alikes: 50 % + 5 % of the rest
    assert share["mixed"] == pytest.approx(0.5 + 0.5 * 0.05, abs=0.05)
    with pytest.raises(ValueError, match="no healthy windows at 2000"):
        observability_table(_records(rng, 1.0).query("fault != 'healthy'"), 0.1)


def test_j_out_grid_spans_bench_to_robot_link():
    g = j_out_grid(6)
    assert g[0] == pytest.approx(J_OUT_BENCH) and g[-1] == pytest.approx(J_OUT_ROBOT)
    assert np.allclose(np.diff(np.log(g)), np.log(g[1] / g[0]))
    with pytest.raises(ValueError):
        j_out_grid(1)


def test_torsional_mode_follows_the_inertia():
    m = torsional_modes([J_OUT_BENCH, J_OUT_ROBOT], [7.0, 70.0])
    f = m.set_index(["j_out_kgm2", "t_out_nm"])["f_hz"]
    from swgsim.gear.dynamics import rt1_size20

    # stiffer under load (cubic stiffness of eq. 2)
    assert f[(J_OUT_BENCH, 70.0)] > f[(J_OUT_BENCH, 7.0)]
    assert 200 < f[(J_OUT_BENCH, 7.0)] < 260 and 25 < f[(J_OUT_ROBOT, 7.0)] < 35
    # two-mass closed form: f ~ sqrt(1/J_out + 1/(N² J_in)) at the same stiffness (the
    # speed loop, left out here, shifts it by a few per cent)
    p = rt1_size20()
    j_r = p.ratio**2 * p.j_in_kgm2
    two_mass = np.sqrt((1 / J_OUT_BENCH + 1 / j_r) / (1 / J_OUT_ROBOT + 1 / j_r))
    ratio = f[(J_OUT_BENCH, 7.0)] / f[(J_OUT_ROBOT, 7.0)]
    assert ratio == pytest.approx(two_mass, rel=0.05)


def test_app_end_to_end_on_the_tiny_bench_grid(tmp_path):
    from learn.observability.task import data_set_configs, run_observability
    from swgcli import compose_app

    cfg = compose_app("observability", [
        "dataset=tiny_bench", "j_out_kgm2=[0.0088,0.2]", f"data_root={tmp_path}/data",
        f"report_dir={tmp_path}/rep", "n_jobs=1", "progress=false"])
    cfgs = data_set_configs(cfg)
    assert cfgs[0.0088].config.chain.settle_s == 0.05  # the preset's
    assert cfgs[0.2].config.chain.settle_s > 0.05      # raised for the longer ring-down
    out = run_observability(cfg)
    tab = pd.read_csv(tmp_path / "rep" / "observability.csv")
    assert tuple(tab.columns[:5]) == COLUMNS
    assert set(tab["j_out_kgm2"]) == {0.0088, 0.2}
    assert tab["fraction_beyond_p95"].between(0, 1).all()
    assert (tmp_path / "rep" / "observability.png").stat().st_size > 10_000
    assert len(out["data_sets"]) == 2
    # a rerun keeps the data sets and redraws
    again = run_observability(cfg)
    pd.testing.assert_frame_equal(again["table"].reset_index(drop=True),
                                  out["table"].reset_index(drop=True))
    plot = compose_app("observability", [f"report_dir={tmp_path}/rep", "plot_only=true"])
    assert "figure" in run_observability(plot)["files"]


def test_app_refuses_bad_input_before_any_work(tmp_path):
    from learn.observability.task import data_set_configs, run_observability
    from swgcli import compose_app

    for over, msg in ((["n_j_out=1"], "n_j_out: must be in"),
                      (["j_out_kgm2=[0.1,0.1]"], "j_out_kgm2: must list distinct"),
                      (["j_out_kgm2=[1000.0]"], "outside the allowed range")):
        with pytest.raises(ValueError, match=msg):
            data_set_configs(compose_app("observability", over))
    with pytest.raises(FileNotFoundError):
        run_observability(compose_app("observability", [f"report_dir={tmp_path}/none",
                                                        "plot_only=true"]))
    assert not (tmp_path / "none").exists()


def test_plot_without_modes(tmp_path):
    rng = np.random.default_rng(1)
    tab = pd.concat([observability_table(_records(rng, 3.0), j) for j in (0.01, 0.1)])
    tab["fault"] = tab["fault"].replace({"far": "eccentric_wg", "mixed": "tip_tooth_crack"})
    assert plot_observability(tab, tmp_path / "o.png").is_file()
