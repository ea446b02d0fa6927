"""swgsim-train's options checked before any work: feature orders the stored data cannot
carry (named with the data set), and the monitor evaluation's study keys (one line, exit 2,
no report folder made)."""

from __future__ import annotations

import pytest
from bad_input import app_line, message

from swgcli import compose_app


@pytest.mark.parametrize("override, key", [
    ("features.max_order=100", "features.max_order=100"),   # above Nyquist at 4000 rpm
    ("features.order_step=0.05", "features.order_step=0.05"),  # finer than the window
])
def test_feature_orders_the_data_cannot_carry_are_refused(small, tmp_path, override, key):
    from swgcli.tasks import run_train

    cfg = compose_app("train", [f"stored.path={small}", "~logger", "features=selection3",
                                override, f"paths.report_dir={tmp_path}"])
    msg = message(lambda: run_train(cfg))
    assert key in msg and str(small) in msg


EVAL_CASES = {  # case -> (overrides of swgsim-train experiment=monitor, the key)
    "an unknown fault": (["monitor.study.faults=[bogus]"], "monitor.study.faults: ['bogus']"),
    "a gear the data sets lack": (["monitor.study.gears=[7]"], "monitor.study.gears: [7]"),
    "an unknown detector": (["monitor.study.detectors=[bogus]"], "monitor.study.detectors"),
    "an unknown data set": (["monitor.run_on=[nope]"], "monitor.run_on"),
    "no data set": (["monitor.run_on=[]"], "monitor.run_on: empty; allowed: keys of "
                                           "monitor.datasets ["),
    "n_jobs=0": (["monitor.n_jobs=0"], "monitor.n_jobs"),
    "commissioning as long as the life": (["monitor.study.commissioning_h=1000"],
                                          "monitor.study.commissioning_h"),
    "a negative seed": (["monitor.study.seeds=[-1]"], "monitor.study.seeds[0]"),
    "design_hours=0": (["monitor.study.rule.design_hours=0"],
                       "monitor.study.rule.design_hours"),
    "a naming number out of range": (["monitor.study.naming.rest_max=0"],
                                     "monitor.study.naming.rest_max"),
    "an old key": (["monitor.study.baselines=[paper_rf]"], "monitor.study.detectors"),
    "a device that is none": (["monitor.device=gpu"], "monitor.device: must be one of"),
    "training severities not increasing": (
        ["+monitor.study.fault_severities.root_tooth_crack=[0.5,0.3]"],
        "monitor.study.fault_severities.root_tooth_crack must be increasing in (0, "),
    "training severities of no gear fault": (
        ["+monitor.study.fault_severities.sensor_stuck=[0.5]"],
        "monitor.study.fault_severities: 'sensor_stuck' is no gear fault; allowed: "),
}


@pytest.mark.parametrize("case", EVAL_CASES)
def test_a_bad_evaluation_is_one_line_before_any_work(tmp_path, case):
    over, key = EVAL_CASES[case]
    line = app_line("train", ["experiment=monitor", "~logger",
                              f"monitor.report_dir={tmp_path}/rep", *over], tmp_path)
    assert line.startswith("swgsim-train: error: ") and key in line, line
    assert not (tmp_path / "rep").exists()
