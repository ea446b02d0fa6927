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

With ``--benchmark REPORT_DIR`` it profiles one lives part of the benchmark instead
(``swgsim-train experiment=benchmark``, issue 83): the data set's first held-out
instance under ``--family``, the monitor, its ablation and the baselines on the design
seeds ``--seeds`` (default 300), with the models and thresholds of the design part
already in ``REPORT_DIR`` (its ``models/`` and ``parts/``); the stage ``baselines`` is
the charts' fitting and statistics.

    python scripts/profile_monitor_part.py --benchmark reports/benchmark --family all
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
    "features": [("learn/inputs/health.py", "health_features"),
                 ("swgmon/evaluation/detectors.py", "window_inputs")],
    "training": [("swgmon/assessment/model.py", "fit_diagnosis"),
                 ("swgmon/evaluation/detectors.py", "fit_detector")],
    "monitoring": [("swgmon/assessment/gear_monitor.py", n) for n in
                   ("commission", "run", "score_only", "diagnose", "fork")]
    + [("swgmon/evaluation/detectors.py", "labels")],
    "baselines": [("swgmon/evaluation/baselines.py", n) for n in ("fit", "statistic")],
    "reports and tracking": [("swgmon/evaluation/report.py", n) for n in
                             ("figures", "write_table")]
    + [("swgmon/assessment/model_io.py", "save_model"),
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
    ap.add_argument("--seeds", default=None,
                    help="life seeds, comma-separated (default 0; the benchmark's 300)")
    ap.add_argument("--detector", default=None,
                    help="also this per-window detector's part (after the monitor's)")
    ap.add_argument("--save", default=None, metavar="FILE",
                    help="also write the profile (pstats) to FILE, to read by function")
    ap.add_argument("--benchmark", default=None, metavar="REPORT_DIR",
                    help="profile a lives part of the benchmark whose design is in REPORT_DIR")
    ap.add_argument("--family", default="all", help="the benchmark family (--benchmark)")
    args = ap.parse_args(argv)
    if args.benchmark:
        prof, wall, part = _benchmark_part(args)
    else:
        prof, wall, part = _monitor_part(args)
    if args.save:
        prof.dump_stats(args.save)
    sec = stage_seconds(pstats.Stats(prof))
    sec["other"] = max(0.0, wall - sum(sec.values()))
    print(f"part {args.dataset} {part} seeds {args.seeds}, {wall:.1f} s "
          f"under the profiler ({platform.machine()}, {platform.python_version()}):")
    for k, v in sec.items():
        print(f"  {k:<22s} {v:7.1f} s  {100 * v / wall:5.1f} %")
    out = {"dataset": args.dataset, "gear": args.gear, "seeds": args.seeds,
           "part": part, "wall_s": round(wall, 1),
           "stages_s": {k: round(v, 1) for k, v in sec.items()}}
    print(json.dumps(out))
    return out


def _benchmark_part(args) -> tuple[cProfile.Profile, float, str]:
    """One lives part of the benchmark (module docstring) under the profiler."""
    import dataclasses

    from learn.tasks.parts import DESIGN, Job
    from swgcli import dataset_preset
    from swgmon.assessment.model_io import load_model
    from swgmon.evaluation import benchmark as bm
    from swgmon.evaluation.benchmark_task import _model_path, _monitors
    from swgmon.evaluation.evaluate import banks_of
    from swgsim.datasets.plan import plan

    seeds = [int(s) for s in (args.seeds or "300").split(",")]
    cfg = dataclasses.replace(bm.BenchmarkConfig(), seeds=seeds)
    cfg.check()
    p = bm.population_plan(plan(dataset_preset(args.dataset)), cfg)
    report = Path(args.benchmark)
    part = Job(args.dataset, 0, DESIGN, "").file  # the design part's file, as the task names it
    design = json.loads((report / "parts" / part).read_text())
    models = {n: load_model(_model_path(report, args.dataset, n)) for n in _monitors(cfg)}
    g = bm.instances(cfg)[1][0]
    args.gear, args.seeds = g, ",".join(map(str, seeds))
    prof = cProfile.Profile()
    t0 = time.perf_counter()
    prof.runcall(bm.benchmark_part, p, {g: banks_of(p)[g]}, models, g, args.family, cfg,
                 design["thresholds"], args.dataset)
    return prof, time.perf_counter() - t0, f"benchmark instance {g} family {args.family}"


def _monitor_part(args) -> tuple[cProfile.Profile, float, str]:
    """One part of the monitor's evaluation (module docstring) under the profiler."""
    from swgcli.train import main as train

    args.seeds = args.seeds or "0"

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
    part = f"monitor + {args.detector}" if args.detector else "monitor"
    return prof, wall, f"gear {args.gear} {part}"


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    main()
