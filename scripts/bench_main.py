"""The main job's wall time by stage, from nothing, over several runs.

    python scripts/bench_main.py [--runs 3] [--keep DIR] [overrides ...]

Runs the README's main command (``swgsim-paper``, the console script beside this
interpreter) ``--runs`` times as a whole process, each time into a fresh folder (its data
sets, reports and MLflow store there, so every run simulates both data sets and fits every
study), and prints each run's stages (``wall time per stage`` of the app's last words,
their ``total`` among them) and the process's wall time, then the minimum, median and
maximum of each. The target of the stages' total is 240 s on the 2-core machine with
nothing else running (docs/results/speed.md, "The main job"). Hydra overrides after the
options are passed on, e.g. ``grid=tiny`` for a quick check of the script itself.
"""

from __future__ import annotations

import argparse
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: the app's last line of times: "wall time per stage: generate paper 6.4 s, ..."
STAGES = re.compile(r"^wall time per stage: (.*)$", re.MULTILINE)
ONE = re.compile(r"(.+?) ([0-9.]+) s$")


def stage_times(stdout: str) -> dict[str, float]:
    """The stages and their wall times [s] of one run's console output.

    Raises
    ------
    ValueError
        No line of stage times in ``stdout``.
    """
    m = STAGES.search(stdout)
    if m is None:
        raise ValueError("the run printed no 'wall time per stage' line")
    out = {}
    for part in m.group(1).split(", "):
        one = ONE.match(part.strip())
        if one is None:
            raise ValueError(f"cannot read the stage time {part!r}")
        out[one.group(1)] = float(one.group(2))
    return out


def run_once(root: Path, overrides: list[str]) -> tuple[dict[str, float], float]:
    """One main job into ``root``: its stage times and the process's wall time [s]."""
    exe = Path(sys.executable).parent / "swgsim-paper"
    cmd = [str(exe), f"data_root={root / 'data'}", f"report_root={root / 'reports'}",
           f"tracking_uri=sqlite:///{root / 'mlflow.db'}", f"hydra.run.dir={root / 'hydra'}",
           *overrides]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)}: exit code {proc.returncode}:\n"
                         f"{proc.stderr[-3000:]}")
    return stage_times(proc.stdout), wall


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3, help="runs from nothing (default 3)")
    ap.add_argument("--keep", type=Path, default=None,
                    help="keep each run's folder under DIR/run<k> (default: removed)")
    args, overrides = ap.parse_known_args()
    if args.runs < 1:
        ap.error(f"--runs must be >= 1, got {args.runs}")
    rows = []
    for k in range(args.runs):
        if args.keep is not None:
            root = args.keep / f"run{k}"
            root.mkdir(parents=True, exist_ok=False)
            stages, wall = run_once(root, overrides)
        else:
            with tempfile.TemporaryDirectory(prefix="bench_main_") as tmp:
                stages, wall = run_once(Path(tmp), overrides)
        if "total" not in stages:  # the app's own sum of its stages
            stages["total"] = sum(stages.values())
        rows.append({**stages, "wall": wall})
        print(f"run {k + 1}: " + ", ".join(f"{n} {v:.1f} s" for n, v in rows[-1].items()),
              flush=True)
    print(f"\n{'':<20s} {'min':>8s} {'median':>8s} {'max':>8s}   [s], {args.runs} run(s)")
    for name in rows[0]:
        v = [r[name] for r in rows]
        print(f"{name:<20s} {min(v):8.1f} {statistics.median(v):8.1f} {max(v):8.1f}")


if __name__ == "__main__":
    main()
