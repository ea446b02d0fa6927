"""Study: how visible a fault is to the monitor's features, steady against in motion, at the
load the gear transmits and with the window trigger a joint has.

A crack is seen in proportion to the torque it carries. The robot joint in motion
(``robot_joint_motion``: the UR3e shoulder's links under gravity, at most 18.25 N m
without payload) transmits much less than the steady study's points, so its windows are
compared here with steady windows at the *same* loads as well as at the motion map's
steady points, and with the two things a joint's operation can change: the UR3e's rated
payload, and windows triggered from the controller's motion command
(``dataset.profile.start_jitter_s``). Each row is
:func:`learn.observability.motion.fault_visibility`: the share of one fault's
windows beyond the healthy 95th percentile of their point or slot (0.05: unseen), per
fault life (each seed its own fault position), on training gear 1 of the data set.

    python scripts/fault_visibility.py
    python scripts/fault_visibility.py --fault tip_tooth_crack --severity 0.5 --windows 120

Prints one line per condition and view (mean and range over the fault lives), then the
rows as one JSON object. Several minutes on one core (a profile condition about 3 min).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from learn.observability.motion import (  # noqa: E402
    STEADY_POINTS,
    fault_visibility,
)
from swgcli import dataset_preset  # noqa: E402
from swgsim.datasets.config import dataset_config  # noqa: E402
from swgsim.datasets.plan import plan  # noqa: E402
from swgsim.datasets.slots import profile_slots  # noqa: E402


def conditions(payload_kg: float, jitter_s: float) -> list[tuple[str, str, list[str], object]]:
    """(name, preset, overrides, steady points or None for the profile) of each row."""
    motion = plan(dataset_config(dataset_preset("robot_joint_motion")))
    sl = profile_slots(motion)
    same_load = tuple(sorted({(abs(float(n)), round(abs(float(t)), 2))
                              for n, t in zip(sl.n_in_rpm, sl.t_out_nm, strict=True)}))
    pay = [f"profile.load.gravity.payload_kg={payload_kg:g}"]
    jit = [f"profile.start_jitter_s={jitter_s:g}"]
    return [
        ("steady, the motion map's points", "robot_joint", [], STEADY_POINTS),
        ("steady, the profile's slot loads", "robot_joint", [], same_load),
        ("profile as the preset", "robot_joint_motion", [], None),
        (f"profile, {payload_kg:g} kg payload", "robot_joint_motion", pay, None),
        (f"profile, trigger {jitter_s * 1e3:g} ms", "robot_joint_motion", jit, None),
        (f"profile, {payload_kg:g} kg payload, trigger {jitter_s * 1e3:g} ms",
         "robot_joint_motion", pay + jit, None),
    ]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fault", default="tip_tooth_crack", help="fault class")
    ap.add_argument("--severity", type=float, default=0.5, help="its severity")
    ap.add_argument("--windows", type=int, default=120,
                    help="windows per fault life (healthy: twice per point or slot)")
    ap.add_argument("--seeds", type=int, default=5, help="fault lives (positions)")
    ap.add_argument("--payload-kg", type=float, default=3.0,
                    help="payload at the wrist [kg] (UR3e rated: 3)")
    ap.add_argument("--jitter-s", type=float, default=0.005,
                    help="window trigger spread of a controller-triggered monitor [s]")
    a = ap.parse_args(argv)
    if a.windows < 20 or a.seeds < 1:
        ap.error(f"--windows must be >= 20 and --seeds >= 1, got {a.windows}, {a.seeds}")
    rows = []
    for name, preset, over, points in conditions(a.payload_kg, a.jitter_s):
        t0 = time.perf_counter()
        p = plan(dataset_config(dataset_preset(preset, over)))
        loads = (sorted({abs(t) for _, t in points}) if points is not None
                 else np.abs(profile_slots(p).t_out_nm))
        res = fault_visibility(p, a.fault, a.severity, a.windows, range(1, a.seeds + 1), points)
        for view, fr in res.items():
            rows.append({"condition": name, "view": view, "loads_nm": [round(float(x), 2) for x in
                                                                      (min(loads), max(loads))],
                         "beyond_p95": [round(float(x), 4) for x in fr],
                         "mean": round(float(fr.mean()), 4)})
            print(f"{name:<44} {view:<26} loads {min(loads):5.1f}-{max(loads):5.1f} N m  "
                  f"beyond p95 {fr.mean():.3f} ({fr.min():.3f}-{fr.max():.3f})  "
                  f"{time.perf_counter() - t0:.0f} s", flush=True)
    print(json.dumps({"fault": a.fault, "severity": a.severity, "windows": a.windows,
                      "seeds": a.seeds, "rows": rows}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
