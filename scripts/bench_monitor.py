"""Cost of the condition monitor per window, on one core: health features, scoring
(normal behaviour z-scores, diagnosis model, novelty), conformal p-values and the CUSUM update;
and the cost of a gear life's windows (records and windows, swgsim.datasets.life).

    python scripts/bench_monitor.py [--dataset bench] [--windows 3000]

Trains a small diagnosis model on two gears of the preset (a few minutes), commissions
gear 3 and times the monitor on its windows two ways: in blocks (as the evaluation runs
it, cost amortised) and one window at a time (as a live monitor receives them:
``GearMonitor.step``; ``run`` on blocks of one window for comparison). The
simulation of the windows is timed apart: the records of a healthy life (six operating
points) and the windows cut from them, with the records spread over a 1000-h life.
Prints ms per window; target for the monitor: at most 1 ms.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one core: before numpy and sklearn load
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dataset", default="bench", help="data-set preset (default bench)")
    ap.add_argument("--windows", type=int, default=3000, help="windows timed (default 3000)")
    args = ap.parse_args()

    from learn.inputs.health import window_features
    from swgcli import dataset_preset
    from swgmon.assessment.gear_monitor import GearMonitor
    from swgmon.evaluation.study import MonitorStudyConfig
    from swgmon.evaluation.training import features_of, train_model
    from swgsim.datasets.life import LifeSimulator
    from swgsim.datasets.plan import plan
    from swgsim.datasets.records import record_bank
    from swgsim.datasets.schedule import LifeConfig

    p = plan(dataset_preset(args.dataset))
    cfg = MonitorStudyConfig(train_variants=2, train_healthy_h=4.0)
    banks = {g: record_bank(p, g) for g in (1, 2, 3)}
    t0 = time.perf_counter()
    model = train_model(p, banks, [1, 2], cfg)
    print(f"diagnosis model trained in {time.perf_counter() - t0:.0f} s")
    n_c = int(cfg.commissioning_h * 60)
    life = LifeConfig(hours=cfg.commissioning_h + args.windows / 60 + 1, life_seed=0)
    fresh = record_bank(p, 3)
    sim = LifeSimulator(p, 3, life, fresh)
    t0 = time.perf_counter()
    fresh.simulate()
    t_rec = time.perf_counter() - t0
    t0 = time.perf_counter()
    sim.windows(0, 2000)
    t_win = (time.perf_counter() - t0) / 2000
    f, pts, _ = features_of(sim, 0, n_c)
    mon = GearMonitor(model, cfg.rule, 1.0)
    mon.commission(f, pts)
    sig, meta = sim.windows(n_c, n_c + args.windows)
    fs = p.config.chain.sample_rate_hz
    n_in, eff = meta["n_in_rpm"], meta["efficiency"]
    pw = np.stack([n_in, meta["t_out_nm"]], axis=1)

    t0 = time.perf_counter()
    for a in range(0, args.windows, 1024):
        b = slice(a, a + 1024)
        ff = window_features(sig[b], n_in[b], eff[b], fs)
        mon.run(ff, pw[b], meta["hour"][b], latch=False)
    block = (time.perf_counter() - t0) / args.windows * 1e3

    n1 = min(args.windows, 1000)
    t0 = time.perf_counter()
    for i in range(n1):
        ff = window_features(sig[i:i + 1], n_in[i:i + 1], eff[i:i + 1], fs)
        mon.step(ff[0], pw[i], meta["hour"][i])
    single = (time.perf_counter() - t0) / n1 * 1e3
    t0 = time.perf_counter()
    for i in range(n1):
        ff = window_features(sig[i:i + 1], n_in[i:i + 1], eff[i:i + 1], fs)
        mon.run(ff, pw[i:i + 1], meta["hour"][i:i + 1], latch=False)
    single_run = (time.perf_counter() - t0) / n1 * 1e3

    t0 = time.perf_counter()
    for a in range(0, args.windows, 1024):
        b = slice(a, a + 1024)
        window_features(sig[b], n_in[b], eff[b], fs)
    feat = (time.perf_counter() - t0) / args.windows * 1e3
    print(f"{args.dataset}: {args.windows} windows of {sig.shape[-1]} samples x 5 bridges, "
          f"one core (OMP_NUM_THREADS={os.environ['OMP_NUM_THREADS']})")
    print(f"  in blocks of 1024: {block:.3f} ms per window (features {feat:.3f} ms)")
    print(f"  one at a time:     {single:.3f} ms per window ({n1} windows, GearMonitor.step; "
          f"run() on blocks of one: {single_run:.3f} ms)")
    print("  target: <= 1 ms per window")
    print(f"life generation: records of a healthy life {t_rec:.1f} s, windows "
          f"{t_win * 1e3:.3f} ms each; over a 1000-h life (60,000 windows) "
          f"{(t_rec / 60000 + t_win) * 1e3:.3f} ms per window")


if __name__ == "__main__":
    main()
