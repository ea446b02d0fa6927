"""Benchmark data generation: fast influence path against the naive per-step solver.

Generates a data set from scratch into a temporary folder (or ``--out``), measures wall
time and peak memory (resident memory of this process and its live workers summed,
sampled every 50 ms from /proc), then times the naive reference (one
sparse solve of the whole truss per time step, ``signals_naive`` of the tests'
``tests/physics_reference.py``) on a
sample of windows of the same data set, and prints what it measured. The last line is one
JSON object: windows, wall_s, windows_per_s, peak_rss_mib, speedup_vs_naive, and the
figures behind them.

    python scripts/bench_generate.py                 # the paper grid, 2 workers
    python scripts/bench_generate.py --dataset tiny --n-jobs 1
    python scripts/bench_generate.py --profile       # + whole-process wall, stage breakdown
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the slow reference paths (physics_reference.py)


def _tree_rss_kib(pid: int) -> int:
    """Resident memory of a process and all its descendants now [KiB] (Linux /proc)."""
    total, todo = 0, [pid]
    while todo:
        p = todo.pop()
        try:
            for line in open(f"/proc/{p}/status"):
                if line.startswith("VmRSS:"):
                    total += int(line.split()[1])
                    break
            for task in os.listdir(f"/proc/{p}/task"):
                with open(f"/proc/{p}/task/{task}/children") as f:
                    todo += [int(c) for c in f.read().split()]
        except (FileNotFoundError, ProcessLookupError, PermissionError):
            continue
    return total


class TreeMemory:
    """Samples the resident memory of this process tree every ``interval_s`` seconds and
    keeps the peak (the sum over the parent and its live workers)."""

    def __init__(self, interval_s: float = 0.05):
        self.interval_s = interval_s
        self.peak_kib = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self):
        while not self._stop.is_set():
            self.peak_kib = max(self.peak_kib, _tree_rss_kib(os.getpid()))
            self._stop.wait(self.interval_s)

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()
        own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        self.peak_kib = max(self.peak_kib, own)


def peak_rss_mib(mem: TreeMemory) -> float:
    """Peak resident memory of the process tree [MiB]."""
    return mem.peak_kib / 1024.0


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dataset", default="paper", help="preset in conf/dataset (paper, tiny)")
    ap.add_argument("--n-jobs", type=int, default=2, help="worker processes (default 2)")
    ap.add_argument("--out", default=None, help="output folder (default: a temporary one)")
    ap.add_argument("--naive-windows", type=int, default=3,
                    help="windows timed with the naive solver (default 3)")
    ap.add_argument("--naive-steps", type=int, default=40,
                    help="time steps timed per naive window, extrapolated to the window")
    ap.add_argument("--profile", action="store_true",
                    help="also time swgsim-generate as a whole process and break one shard "
                         "down by stage (cProfile)")
    args = ap.parse_args(argv)

    from physics_reference import signals_naive

    from swgcli import dataset_preset
    from swgsim.datasets.config import gear_params, layout_for
    from swgsim.datasets.generate import generate
    from swgsim.datasets.plan import plan
    from swgsim.gear.chain import SimulationChain
    from swgsim.gear.faults import apply_fault

    cfg = plan(dataset_preset(args.dataset))  # checked once; generate takes the plan
    tmp = None
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="bench_gen_")) / "ds"
    if args.out is None:
        tmp = out.parent
    elif out.exists() and any(out.iterdir()):
        ap.error(f"--out {out} is not empty; give a new or empty folder (nothing is deleted)")
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores; "
          f"data set '{args.dataset}', n_jobs={args.n_jobs}, out={out}")
    with TreeMemory() as mem:
        t0 = time.perf_counter()
        summary = generate(cfg, out, n_jobs=args.n_jobs, progress=False)
        wall = time.perf_counter() - t0
    rss = peak_rss_mib(mem)
    windows = int(summary["windows"])
    print(f"fast path: {windows} windows in {wall:.1f} s ({windows / wall:.0f} windows/s), "
          f"peak RSS {rss:.0f} MiB")

    # naive reference on a sample of windows of the same data set (gear 1, first speed)
    dc = cfg.config
    chain = SimulationChain(layout_for(dc, dc.gears[0]), settings=dc.chain, mesh=dc.mesh)
    h = gear_params(dc, dc.gears[0])
    cases = [h, apply_fault(h, "eccentric_wg", 0.1, 36.0),
             apply_fault(h, "tip_tooth_crack", 1.0, 90.0),
             apply_fault(h, "root_tooth_crack", 0.9, 54.0)][: max(args.naive_windows, 1)]
    n_in = dc.operating_points.n_in_rpm[0]
    t_out = dc.operating_points.t_out_nm[-1]
    sig, res = chain.simulate(cases, n_in, t_out, 0.3)
    n_t = res.time.size
    k = min(args.naive_steps, n_t)
    per_window = []
    max_err = 0.0
    for i, p in enumerate(cases):
        signals_naive(chain, p, res.psi[i, :1], res.t_out[i, :1])  # factorisation outside
        t1 = time.perf_counter()
        naive = signals_naive(chain, p, res.psi[i, :k], res.t_out[i, :k])
        per_window.append((time.perf_counter() - t1) / k * n_t)
        max_err = max(max_err, float(np.abs(naive - sig[i, :, :k]).max() / np.abs(naive).max()))
    naive_s = float(np.mean(per_window))
    fast_s = wall / windows
    speedup = naive_s / fast_s
    print(f"naive reference: {naive_s:.2f} s per window ({n_t} steps, timed on {k} steps of "
          f"{len(cases)} windows); fast path {fast_s * 1e3:.2f} ms per window (everything "
          f"included); speed-up {speedup:.0f}x; max relative difference {max_err:.1e}")
    extra = {}
    if args.profile:
        with tempfile.TemporaryDirectory(prefix="bench_gen_profile_") as work:
            extra = profile(args.dataset, cfg, args.n_jobs, Path(work))
    if tmp is not None:
        shutil.rmtree(tmp, ignore_errors=True)
    result = {**extra, "windows": windows, "wall_s": round(wall, 2),
              "windows_per_s": round(windows / wall, 1), "peak_rss_mib": round(rss, 1),
              "speedup_vs_naive": round(speedup, 1), "naive_s_per_window": round(naive_s, 3),
              "fast_ms_per_window": round(fast_s * 1e3, 3), "n_jobs": args.n_jobs,
              "dataset": args.dataset, "naive_max_rel_diff": max_err,
              "dynamics_included_in_naive": False}
    print(json.dumps(result))
    return result


#: Stages of one shard: (label, module file, function) timed cumulatively by cProfile.
STAGES = (
    ("dynamics (RK4, distinct motions)", "dynamics.py", "simulate"),
    ("fine grid (acquisition only)", "shard.py", "fine_motion"),
    ("gauge signals (distinct windows)", "chain.py", "signals_batch"),
    ("amplifier: filter, noise, ADC", "acquisition.py", "acquire"),
    ("eq. (10) disturbance", "disturbance.py", "disturb"),
    ("xarray data set", "data.py", "make_dataset"),
    ("NetCDF write + SHA-256", "data.py", "write_shard"),
)


def profile(dataset: str, cfg: dict, n_jobs: int, work: Path) -> dict:
    """Whole-process wall time of ``swgsim-generate`` and a stage breakdown of one shard.

    ``work`` is an empty folder of the caller's (a temporary one); everything goes there.

    Returns
    -------
    dict
        ``process_wall_s`` and ``shard_stages_s`` (stage -> seconds for shard 0, plus
        ``influences (parent, all gears)`` and ``other``).
    """
    import cProfile
    import pstats
    import subprocess

    from swgsim.datasets import schema as dsio
    from swgsim.datasets.generate import simulate_shard
    from swgsim.datasets.steps import gear_influences

    exe = Path(sys.executable).parent / "swgsim-generate"
    t0 = time.perf_counter()
    subprocess.run([str(exe), f"dataset={dataset}", f"out_dir={work / 'whole'}",
                    f"n_jobs={n_jobs}", "progress=false"], check=True, capture_output=True)
    wall = time.perf_counter() - t0
    shards = cfg.shards
    t0 = time.perf_counter()
    infl = gear_influences(cfg, shards)
    t_infl = time.perf_counter() - t0
    simulate_shard(cfg, shards[-1], infl[shards[-1].gear])  # warm: lazy imports, caches
    pr = cProfile.Profile()
    t0 = time.perf_counter()
    pr.enable()
    ds, _ = simulate_shard(cfg, shards[0], infl[shards[0].gear])
    dsio.write_shard(ds, work / "profile_shard.nc")
    pr.disable()
    total = time.perf_counter() - t0
    st = pstats.Stats(pr).stats
    stages = {"influences (parent, all gears)": round(t_infl, 3)}
    for label, fname, func in STAGES:
        ct = sum(v[3] for k, v in st.items() if k[0].endswith(fname) and k[2] == func)
        stages[label] = round(ct, 3)
    stages["other"] = round(total - sum(v for k, v in stages.items() if "parent" not in k), 3)
    print(f"swgsim-generate dataset={dataset} as a whole process: {wall:.1f} s wall")
    print(f"one shard ({shards[0].name}, {2 * len(shards[0].windows)} windows) by stage:")
    for k, v in stages.items():
        print(f"  {k:<34s} {v:7.3f} s")
    return {"process_wall_s": round(wall, 2), "shard_stages_s": stages}


if __name__ == "__main__":
    main(sys.argv[1:])
