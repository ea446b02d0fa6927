"""Hours to failure of an example life that runs to failure (docs/DATASET.md, "Lives that
run to failure"): the paper's duty (2000 and 4000 rpm, 7, 39 and 70 N m, 10 min each), one
window every 10 min over 5000 h, the fault from 48 h on; per law, the failure hour
without scatter at payload 1.0 and 1.2 and in a hall +0 K and +15 K (the real day's
thermal model and viscosity law), then with the default scatter across five life seeds.
Only schedules are computed (no window is simulated): seconds.

With ``--prognosis``: the prognosis evaluation's lives (issue 85; its default design,
swgmon/evaluation/prognosis_evaluation.py): hours from onset to failure per data set and
fault over the lot's 12 instances and the seeds and calibration seeds, each life's law and
day drawn (about a minute per data set).

    python scripts/failure_hours.py [--prognosis]
"""

from __future__ import annotations

import argparse
import dataclasses
import json

import numpy as np

from swgcli import dataset_preset
from swgsim.base.typed import check_tree
from swgsim.datasets.conditions import ConditionsConfig
from swgsim.datasets.growth import RunToFailure
from swgsim.datasets.life import LifeSimulator
from swgsim.datasets.plan import plan
from swgsim.datasets.records import record_bank
from swgsim.datasets.schedule import DutyPoint, FaultOnset, LifeConfig
from swgsim.gear.thermal import JointThermal

PAPER_DUTY = [DutyPoint(n, t, 10.0) for n in (2000.0, 4000.0) for t in (7.0, 39.0, 70.0)]
EXAMPLES = {"root_tooth_crack": ("paris", 0.05), "tip_tooth_crack": ("paris", 0.05),
            "eccentric_wg": ("archard", 0.0), "wear": ("archard", 0.0)}


def _conditions(payload: float = 1.0, hall_k: float = 0.0) -> ConditionsConfig:
    """The life's conditions: the thermal day (16 h a day, a hall offset), a payload."""
    return ConditionsConfig(thermal=JointThermal(ambient_points=[[0.0, hall_k]]),
                            viscosity=True, payload=[[0.0, payload]], bridge_drift=None,
                            temperature_sensor=None)


def failure_h(p, bank, fault: str, conditions: ConditionsConfig, life_seed: int = 0,
              **law) -> float:
    """The failure hour of the example life [h] (NaN: none within it)."""
    growth, s0 = EXAMPLES[fault]
    life = LifeConfig(hours=5000.0, commissioning_h=24.0, interval_min=10.0, duty=PAPER_DUTY,
                      fault=FaultOnset(fault, 48.0, s0, growth=growth,
                                       to_failure=RunToFailure(**law)),
                      life_seed=life_seed, conditions=conditions)
    check_tree(life, "dataset.life")
    return LifeSimulator(p, bank.gear_id, life, bank).schedule.failure_h


def prognosis_lives() -> None:
    """The prognosis evaluation's lives: hours from onset to failure, per fault."""
    from swgmon.evaluation.benchmark import instances, population_plan
    from swgmon.evaluation.prognosis_evaluation import PrognosisStudyConfig, life_of

    sc = PrognosisStudyConfig()
    check_tree(sc, "prognosis.study")
    train, held = instances(sc)
    for name in ("bench", "robot_joint"):
        lot = population_plan(plan(dataset_preset(name)), sc)
        hours: dict[str, list[float]] = {}
        for g in train + held:
            bank = record_bank(lot, g)
            for s in sc.seeds + sc.calibration_seeds:
                for f in ("root_tooth_crack", "tip_tooth_crack", "eccentric_wg"):
                    sim = life_of(lot, bank, g, sc, f, s)
                    hours.setdefault(f, []).append(sim.schedule.failure_h
                                                   - sim.life.fault.onset_h)
        for f, v in hours.items():
            h = np.array(v)
            print(f"{name:12s} {f:17s} lives {h.size}, not failed {int(np.isnan(h).sum())}; "
                  f"h from onset to failure: min {np.nanmin(h):.1f}, median "
                  f"{np.nanmedian(h):.1f}, max {np.nanmax(h):.1f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--prognosis", action="store_true",
                    help="the prognosis evaluation's lives instead of the example")
    if ap.parse_args().prognosis:
        prognosis_lives()
        return
    p = plan(dataset_preset("tiny_bench"))
    gear = int(p.config.gears[0].id)
    bank = record_bank(p, gear)
    out = {}
    for fault in EXAMPLES:
        row = {
            "payload_1.0_h": failure_h(p, bank, fault, _conditions(), scatter=0.0),
            "payload_1.2_h": failure_h(p, bank, fault, _conditions(1.2), scatter=0.0),
            "hall_+15K_h": failure_h(p, bank, fault, _conditions(hall_k=15.0), scatter=0.0),
        }
        seeds = [failure_h(p, bank, fault, _conditions(), s) for s in range(5)]
        row["scatter_0.3_seeds_h"] = [round(h, 1) for h in seeds]
        row["scatter_0.3_cv_pct"] = float(100 * np.std(seeds) / np.mean(seeds))
        out[fault] = {k: (round(v, 1) if isinstance(v, float) else v) for k, v in row.items()}
        print(fault, out[fault])
    ref = dataclasses.replace(_conditions(), thermal=None, viscosity=False)
    out["root_tooth_crack_20C_no_day_h"] = round(failure_h(p, bank, "root_tooth_crack", ref,
                                                           scatter=0.0), 1)
    out["wear_20C_no_day_h"] = round(failure_h(p, bank, "wear", ref, scatter=0.0), 1)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
