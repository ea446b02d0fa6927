"""Benchmark: cost of a profile window (``profile_dynamics.simulate_profile``) against a steady
window of the same length (``dynamics.simulate``), the issue's target being a profile
window at most twice a steady one (docs/PHYSICS.md sec. 1.8).

Each case simulates V copies of the robot-joint gear (3 by default) for the data sets' window,
0.12 s recorded at 10 kHz with one RK4 substep; the steady window has no settling (the
same number of RK4 steps). Best of ``--repeat`` runs; the last line is one JSON object.

    python scripts/bench_profile.py
    python scripts/bench_profile.py --variants 24 --repeat 7
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from swgsim.gear import dynamics as dy  # noqa: E402
from swgsim.gear import profile as pf  # noqa: E402
from swgsim.gear import profile_dynamics as pd  # noqa: E402


def best_of(fn, repeat: int) -> float:
    """Smallest wall time of ``repeat`` calls [s]."""
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return min(out)


def cases(window_s: float) -> dict[str, pf.Profile]:
    """Profiles of one window: a brake at constant speed, a trapezoidal reversal with a
    load step, and the UR3e link under gravity lifted and dwelling."""
    w = window_s
    return {
        "constant (brake)": pf.Profile(pf.SpeedProfile(2000.0, (pf.Hold(w),)),
                                       pf.ConstantLoad(39.0)),
        "reversal + load step": pf.Profile(
            pf.SpeedProfile(1000.0, (pf.Hold(w / 6), pf.Move(-1000.0, 2000.0 / (w / 3)),
                                     pf.Hold(w / 6), pf.Move(0.0, 1000.0 / (w / 6)))),
            pf.LoadSteps(7.0, ((w / 2, 39.0),))),
        "gravity link": pf.Profile(
            pf.SpeedProfile(0.0, (pf.Move(1000.0, 1000.0 / (w / 4)), pf.Hold(w / 4),
                                  pf.Move(0.0, 1000.0 / (w / 4)))),
            pf.GravityLink()),
    }


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--variants", type=int, default=3)
    ap.add_argument("--window-s", type=float, default=0.12)
    ap.add_argument("--sample-rate-hz", type=float, default=10e3)
    ap.add_argument("--substeps", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args(argv)
    gear = dy.rt1_size20(j_out_kgm2=0.69)  # the robot link: the accelerations stay in limits
    params = [gear] * a.variants
    kw = {"sample_rate_hz": a.sample_rate_hz, "substeps": a.substeps}
    steady = best_of(lambda: dy.simulate(params, 2000.0, 39.0, window_s=a.window_s,
                                         settle_s=0.0, **kw), a.repeat)
    print(f"steady window ({a.variants} variants, {a.window_s} s at "
          f"{a.sample_rate_hz:g} Hz, {a.substeps} substep): {steady * 1e3:.1f} ms")
    ratios = {}
    for name, prof in cases(a.window_s).items():
        t = best_of(lambda prof=prof: pd.simulate_profile(params, prof, duration_s=a.window_s,
                                                          **kw), a.repeat)
        ratios[name] = t / steady
        print(f"profile window, {name}: {t * 1e3:.1f} ms = {t / steady:.2f} x steady")
    out = {"variants": a.variants, "window_s": a.window_s, "steady_ms": steady * 1e3,
           "ratio": ratios, "worst_ratio": max(ratios.values()), "target_ratio": 2.0,
           "python": platform.python_version()}
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()
