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
Prints ms per window; target for the monitor: at most 1 ms. Then the cost of naming
an alarm: each registered hypothesis (``swgmon.assessment.hypotheses``) fitted once to a
day of the timed windows (1440 at most; a recurring change renames up to a day), the
largest piece of a long life's time on robot_joint (issue 85's profile).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one core: before numpy and sklearn load
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
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
    warm = LifeSimulator(p, 3, dataclasses.replace(life, conditions=cfg.nuisances["warm_up"]),
                         record_bank(p, 3))  # a day's warm-ups, read by a sensor
    for title, s in (("without a temperature reading", sim), ("with one (warm-ups)", warm)):
        _time_naming(title, s, n_c, min(args.windows, 1440), model, cfg)
    print(f"life generation: records of a healthy life {t_rec:.1f} s, windows "
          f"{t_win * 1e3:.3f} ms each; over a 1000-h life (60,000 windows) "
          f"{(t_rec / 60000 + t_win) * 1e3:.3f} ms per window")


def _time_naming(title: str, sim, n_c: int, n: int, model, cfg) -> None:
    """Print the seconds each registered hypothesis takes to fit ``n`` windows after
    commissioning on ``sim``'s first ``n_c`` (its conditions as the life has them)."""
    from swgmon.assessment.gear_monitor import GearMonitor
    from swgmon.assessment.hypotheses import Windows, registered
    from swgmon.detection.normal import Conditions
    from swgmon.evaluation.training import features_of

    f, pts, meta = features_of(sim, 0, n_c + n)
    cond = Conditions.of(meta)
    mon = GearMonitor(model, cfg.rule, 1.0)
    mon.commission(f[:n_c], pts[:n_c], cond[:n_c])
    nb, day, c = mon.normal, slice(n_c, n_c + n), cond[n_c:n_c + n]
    w = Windows(nb, f[day], pts[day], c, np.ones(n), nb.index(pts[day]),
                *nb.z_and_spread(f[day], pts[day], c, 1.0), meta["hour"][day], mon.naming,
                tuple(model.classes), c.temperature_c is not None)
    print(f"naming an alarm over {n} windows {title}, each hypothesis once:")
    for h in registered(mon.naming):
        t0 = time.perf_counter()
        h.candidates(w)
        print(f"  {h.name:20s} {time.perf_counter() - t0:6.2f} s")


if __name__ == "__main__":
    main()
