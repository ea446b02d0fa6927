"""Where one part of the monitor's evaluation spends its time, by stage.

Runs one job of ``swgsim-train experiment=monitor`` (a data set, a held-out gear, its seeds)
in this process under :mod:`cProfile` and sums the time of the functions that make each
stage. The job is the monitor's part, and with ``--detector`` that detector's part too
(a job runs the monitor and its detectors in turn on one set of records), so then the
stages hold both: subtract the monitor's run alone to see the detector's. The stages:

- simulating lives: the gears' records and the windows cut from them, under the life's
  conditions and through the measurement chain (``LifeSimulator.windows``),
- features: the monitor's health features of the windows, or a detector's inputs,
- training: fitting the diagnosis model and its severity regressors, or a detector,
- monitoring: the monitor's scores, p-values, CUSUMs, naming and recommissioning, or a
  detector's predictions,
- reports and tracking: tables, figures, model files and MLflow,
- other: the rest (start-up, the plan, bookkeeping).

The stages do not nest (none of these functions calls another's), so they add up. The
profiler slows Python-heavy code more than compiled code, so the shares are indicative;
the part's wall time without the profiler is in its ``timing.json`` (``swgsim-train``).
The last line is one JSON object.

    python scripts/profile_monitor_part.py                        # bench, gear 3, seed 0
    python scripts/profile_monitor_part.py --dataset robot_joint --detector paper_rf  # both
"""

from __future__ import annotations

import argparse
import cProfile
import json
import platform
import pstats
import sys
import tempfile
import time
from pathlib import Path

#: Functions (file suffix, name) whose cumulative time makes each stage.
STAGES = {
    "simulating lives": [("swgsim/datasets/life.py", "windows")],
    "features": [("learn/monitor/features.py", "health_features"),
                 ("learn/monitor/detectors.py", "window_inputs")],
    "training": [("learn/monitor/model.py", "fit_diagnosis"),
                 ("learn/monitor/detectors.py", "fit_detector")],
    "monitoring": [("learn/monitor/gear_monitor.py", n) for n in
                   ("commission", "run", "score_only", "diagnose", "fork")]
    + [("learn/monitor/detectors.py", "labels")],
    "reports and tracking": [("learn/monitor_evaluation/report.py", n) for n in
                             ("figures", "write_table")]
    + [("learn/monitor/model_io.py", "save_model"),
       ("learn/tracking/mlflow_runs.py", "log_run")],
}


def stage_seconds(stats: pstats.Stats) -> dict[str, float]:
    """Cumulative seconds of each stage's functions in a profile (:data:`STAGES`)."""
    out = dict.fromkeys(STAGES, 0.0)
    for (file, _, name), (_, _, _, cum, _) in stats.stats.items():
        for stage, funcs in STAGES.items():
            if any(file.endswith(f) and name == n for f, n in funcs):
                out[stage] += cum
    return out


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dataset", default="bench", help="data set of the evaluation")
    ap.add_argument("--gear", type=int, default=3, help="held-out gear")
    ap.add_argument("--seeds", default="0", help="life seeds, comma-separated")
    ap.add_argument("--detector", default=None,
                    help="also this per-window detector's part (after the monitor's)")
    ap.add_argument("--save", default=None, metavar="FILE",
                    help="also write the profile (pstats) to FILE, to read by function")
    args = ap.parse_args(argv)
    from swgcli.train import main as train

    with tempfile.TemporaryDirectory() as tmp:
        dets = f"[{args.detector}]" if args.detector else "[]"
        sys.argv = ["swgsim-train", "experiment=monitor", f"monitor.run_on=[{args.dataset}]",
                    f"monitor.study.gears=[{args.gear}]", f"monitor.study.seeds=[{args.seeds}]",
                    f"monitor.study.detectors={dets}", "monitor.n_jobs=1",
                    "monitor.progress=false", f"paths.root_dir={tmp}",
                    f"logger.tracking_uri=sqlite:///{tmp}/mlflow.db",
                    f"hydra.run.dir={tmp}/out"]
        prof = cProfile.Profile()
        t0 = time.perf_counter()
        try:
            prof.runcall(train)
        except SystemExit as e:
            if e.code:
                raise
        wall = time.perf_counter() - t0
    if args.save:
        prof.dump_stats(args.save)
    sec = stage_seconds(pstats.Stats(prof))
    sec["other"] = max(0.0, wall - sum(sec.values()))
    part = f"monitor + {args.detector}" if args.detector else "monitor"
    print(f"part {args.dataset} gear {args.gear} seeds {args.seeds} {part}, {wall:.1f} s "
          f"under the profiler ({platform.machine()}, {platform.python_version()}):")
    for k, v in sec.items():
        print(f"  {k:<22s} {v:7.1f} s  {100 * v / wall:5.1f} %")
    out = {"dataset": args.dataset, "gear": args.gear, "seeds": args.seeds,
           "part": part, "wall_s": round(wall, 1),
           "stages_s": {k: round(v, 1) for k, v in sec.items()}}
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    main()
