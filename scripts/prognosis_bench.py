"""The prognosis's cost per update and its intervals' coverage on synthetic lives
(swgmon/prognosis/growth.py; docs/monitor/prognosis.md, "Prognosis").

A synthetic life: the paper's duty (2000 and 4000 rpm, 7, 39 and 70 N m, 10 min each,
20 °C), a window every 2 min, the fault grown from hour 0 by swgsim.datasets.growth's law
with the gear's scale drawn with the default scatter, the monitor's estimates the true
severity plus N(0, σ) with the matching 90 % interval, the alarm at a fixed severity.

Cost: one update of each predictor for a track of 100 h since the alarm, an estimate per
window (3000 estimates), one core (BLAS and OpenMP threads set to 1 here), the median of
repeats, per update and per hour of operation. Coverage: the share of lives whose true
failure hour lies in the 90 % interval, and the interval's median width over the true
remaining hours, at 10, 30 and 60 % of the way from the alarm to failure. Calibration:
the estimates' errors correlated (AR(1)), the split-conformal scale from half the lives,
the other half's coverage without and with it. The tiny_failure preset's lives: the data
set's own (staircase) severity plus noise.

    python scripts/prognosis_bench.py [--lives 100]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core, before numpy loads its BLAS

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from scipy.signal import lfilter  # noqa: E402

from swgmon.prognosis.baselines import predict_linear, predict_wiener  # noqa: E402
from swgmon.prognosis.calibration import tail_scales  # noqa: E402
from swgmon.prognosis.growth import (  # noqa: E402
    Z90,
    Duty,
    Prognosis,
    PrognosisConfig,
    Track,
    predict_growth,
)
from swgmon.prognosis.inputs import scaled_interval  # noqa: E402
from swgsim.datasets.growth import (  # noqa: E402
    LAWS,
    RunToFailure,
    failure_hour,
    grown_severity,
)

#: The paper's duty's speeds [rpm] and loads [N m], 10 min each; a window every 2 min.
SPEEDS, LOADS, WINDOW_H = (2000.0, 4000.0), (7.0, 39.0, 70.0), 2.0 / 60.0
#: Severity at which the synthetic monitor alarms, the severity at hour 0 and the hours
#: simulated (beyond failure at the default scatter's ±3σ) [choice].
ALARM = {"root_tooth_crack": 0.1, "wear": 0.15}
INITIAL = {"root_tooth_crack": 0.05, "wear": 0.0}
HOURS = {"root_tooth_crack": 1500.0, "wear": 800.0}
#: The estimates' σ (about the diagnosis model's on the bench lives [choice]).
SIGMA = 0.03
#: Correlation of consecutive estimates' errors in the calibration's lives [choice].
PHI = 0.9


def paper_duty(h: np.ndarray, load_factor: float = 1.0, temp_c: float = 20.0
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Input speed [rpm], acting load [N m] and temperature [°C] of the paper's duty at
    operating hours ``h`` (shape (W,)), the loads times ``load_factor``."""
    blk = np.floor(h * 6).astype(int) % 6
    n = np.where(blk < 3, SPEEDS[0], SPEEDS[1])
    return n, np.array(LOADS)[blk % 3] * load_factor, np.full(h.shape, temp_c)


def synthetic_life(fault: str, seed: int, frac: float, sigma: float = SIGMA, every: int = 15,
                   track_h: float | None = None, phi: float = 0.0,
                   paris_m: float | None = None
                   ) -> tuple[Track, float, Duty, np.ndarray, float]:
    """A gear's life to failure and the monitor's track of it (module docstring).

    Parameters
    ----------
    fault : str
        ``root_tooth_crack`` or ``wear``.
    seed : int
        The gear's scale and the estimates' noise.
    frac : float
        The track ends this share of the way from the alarm to failure.
    sigma : float
        The estimates' σ [-].
    every : int
        An estimate every this many windows.
    track_h : float or None
        The track's hours since the alarm instead of ``frac``.
    phi : float
        Correlation of consecutive estimates' errors, an AR(1) process of stationary σ
        ``sigma``, in [0, 1) (0: independent).
    paris_m : float or None
        The life's own Paris exponent (a crack grown by a law the prognosis, which takes
        ``RunToFailure().paris_m``, does not know); None: the prognosis's.

    Returns
    -------
    track, alarm_hour, recorded duty, the recorded windows' hours (shape (W,)), the true
    failure hour [h].
    """
    rng = np.random.default_rng(seed)
    tf = RunToFailure() if paris_m is None else dataclasses.replace(RunToFailure(),
                                                                     paris_m=paris_m)
    law = next(g for g, fs in LAWS.items() if fault in fs)
    h = np.arange(0.0, HOURS[fault], WINDOW_H)
    n, t, tc = paper_duty(h)
    scale = float(np.exp(tf.scatter * rng.standard_normal()))
    sev = grown_severity(fault, law, tf, 0.0, INITIAL[fault], h, 2.0, n, t, tc, scale=scale)
    fail = failure_hour(h, sev, tf.failure_severity(fault))
    alarm = float(h[np.argmax(sev >= ALARM[fault])])
    now = alarm + (frac * (fail - alarm) if track_h is None else track_h)
    since = (h >= alarm) & (h <= now)
    idx = np.flatnonzero(since)[::every]
    z = rng.standard_normal(idx.size)
    if phi > 0:  # AR(1): e_k = phi e_(k-1) + sqrt(1 - phi^2) z_k, e_0 = z_0
        z[1:] *= np.sqrt(1.0 - phi ** 2)
        z = lfilter([1.0], [1.0, -phi], z)
    est = sev[idx] + sigma * z
    track = Track(h[idx], est, est - Z90 * sigma, est + Z90 * sigma)
    return (track, alarm, Duty.from_windows(h[since], n[since], t[since], tc[since]),
            h[since], fail)


def cost(fault: str, repeats: int = 7) -> dict[str, float]:
    """Median seconds of one update of each predictor on a 100 h track, an estimate per
    window."""
    track, alarm, duty, wh, _ = synthetic_life(fault, 0, 0.0, every=1, track_h=100.0)
    calls = {"growth": lambda: predict_growth(track, fault, alarm, duty, wh),
             "linear": lambda: predict_linear(track, fault, alarm),
             "wiener": lambda: predict_wiener(track, fault, alarm)}
    out = {}
    for name, call in calls.items():
        call()  # imports and caches out of the timing
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            call()
            times.append(time.perf_counter() - t0)
        out[name] = float(np.median(times))
    out["estimates"] = float(track.hours.size)
    out["track_h"] = float(track.hours[-1] - alarm)
    return out


def coverage(fault: str, frac: float, lives: int) -> dict[str, tuple[float, float]]:
    """Per predictor: the share of ``lives`` whose failure hour the 90 % interval holds,
    and the interval's median width / true remaining hours (inf: an open interval)."""
    hits: dict[str, list[float]] = {"growth": [], "linear": [], "wiener": []}
    width: dict[str, list[float]] = {k: [] for k in hits}
    for seed in range(lives):
        track, alarm, duty, wh, fail = synthetic_life(fault, seed, frac)
        for name, p in (("growth", predict_growth(track, fault, alarm, duty, wh, seed=seed)),
                        ("linear", predict_linear(track, fault, alarm, seed=seed)),
                        ("wiener", predict_wiener(track, fault, alarm, seed=seed))):
            hits[name].append(p.failure_hour_q05 <= fail <= p.failure_hour_q95)
            open_ = np.isinf(p.failure_hour_q95)
            width[name].append(np.inf if open_ else
                               (p.failure_hour_q95 - p.failure_hour_q05) / (fail - p.hour))
    return {k: (float(np.mean(hits[k])), float(np.median(width[k]))) for k in hits}


def calibration(fault: str, frac: float, lives: int, phi: float,
                paris_m: tuple[float, float] | None = None) -> tuple[float, ...]:
    """Split conformal with correlated estimates: the lower and upper scales from lives
    0 .. lives/2 − 1 (the training gears'), the coverage of lives/2 .. lives − 1 without
    and with them; returns (the larger scale, coverage before, after). ``paris_m``: each
    life's Paris exponent drawn uniformly in this range from its seed (out of the
    prognosis's model, which takes 3)."""
    half = lives // 2
    ps, fails = [], []
    for seed in range(lives):
        m = None if paris_m is None else float(
            np.random.default_rng([seed, 85]).uniform(*paris_m))
        track, alarm, duty, wh, fail = synthetic_life(fault, seed, frac, phi=phi, paris_m=m)
        ps.append(predict_growth(track, fault, alarm, duty, wh, seed=seed))
        fails.append(fail)
    fails_a = np.array(fails)
    lower, upper = tail_scales(ps[:half], fails_a[:half])

    def held(p: Prognosis, f: float, kl: float, ku: float) -> bool:
        lo, hi = scaled_interval(p.remaining_h_q05, p.remaining_h_median, p.remaining_h_q95,
                                 kl, ku)
        return p.hour + lo <= f <= p.hour + hi

    test = list(zip(ps[half:], fails_a[half:], strict=True))
    return (max(lower, upper), float(np.mean([held(p, f, 1.0, 1.0) for p, f in test])),
            float(np.mean([held(p, f, lower, upper) for p, f in test])))


def tiny_failure(fracs: tuple[float, ...] = (0.2, 0.4), seeds: int = 5
                 ) -> dict[float, tuple[int, int]]:
    """The ``tiny_failure`` preset's lives (the schedule only, no window simulated): the
    data set's severity (a staircase of ``severity_levels`` steps, what the windows hold)
    plus N(0, σ) at every window from the first at 0.15 to ``frac`` of the way to the
    exact law's failure hour; per ``frac``, (intervals holding it, prognoses) over the
    gears and ``seeds`` noise seeds, the growth constants the preset's."""
    from swgcli import dataset_preset
    from swgsim.datasets.life import LifeSimulator
    from swgsim.datasets.plan import plan
    from swgsim.datasets.records import record_bank

    p = plan(dataset_preset("tiny_failure"))
    life = p.config.life
    cfg = PrognosisConfig(min_track_h=0.25, to_failure=life.fault.to_failure)
    out = {f: [0, 0] for f in fracs}
    for g in p.config.gears:
        sch = LifeSimulator(p, int(g.id), life, record_bank(p, int(g.id))).schedule
        n = np.array([sch.duty[d].n_in_rpm for d in sch.duty_index])
        t = np.array([sch.duty[d].t_out_nm for d in sch.duty_index])
        alarm = float(sch.hour[np.argmax(sch.severity >= 0.15)])
        for frac, seed in ((f, k) for f in fracs for k in range(seeds)):
            on = (sch.hour >= alarm) & (sch.hour <= alarm + frac * (sch.failure_h - alarm))
            est = sch.severity[on] + SIGMA * np.random.default_rng(seed).standard_normal(
                on.sum())
            track = Track(sch.hour[on], est, est - Z90 * SIGMA, est + Z90 * SIGMA)
            duty = Duty.from_windows(sch.hour[on], n[on], t[on], np.full(on.sum(), 20.0))
            pr = predict_growth(track, life.fault.fault, alarm, duty, sch.hour[on], cfg,
                                seed=seed)
            out[frac][0] += pr.failure_hour_q05 <= sch.failure_h <= pr.failure_hour_q95
            out[frac][1] += 1
    return {f: (a, b) for f, (a, b) in out.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--lives", type=int, default=100, help="synthetic lives per cell")
    args = ap.parse_args()
    print("cost of one update, 100 h track, an estimate every 2 min, one core:")
    for fault in ALARM:
        c = cost(fault)
        for name in ("growth", "linear", "wiener"):
            print(f"  {fault:17s} {name:7s} {c[name] * 1e3:7.1f} ms per update, "
                  f"{c[name] * 1e3 / c['track_h']:6.2f} ms per hour of operation "
                  f"({c['estimates']:.0f} estimates)")
    print(f"coverage of the 90 % interval and its median width / true remaining hours, "
          f"{args.lives} lives, an estimate every 30 min, sigma {SIGMA}:")
    for fault in ALARM:
        for frac in (0.1, 0.3, 0.6):
            row = coverage(fault, frac, args.lives)
            cells = "  ".join(f"{k} {v[0]:.2f} (width {v[1]:.2f})" for k, v in row.items())
            print(f"  {fault:17s} at {frac:.0%} of the way: {cells}")
    print(f"split conformal, estimates' errors AR(1) with phi {PHI} (neighbours share "
          f"windows), at 30 % of the way: scale from {args.lives // 2} lives, coverage "
          f"of the other {args.lives - args.lives // 2} without and with it:")
    for fault in ALARM:
        scale, before, after = calibration(fault, 0.3, args.lives, PHI)
        print(f"  {fault:17s} scale {scale:.2f}: coverage {before:.2f} -> {after:.2f}")
    print(f"tiny_failure preset, the data set's staircase severity + N(0, {SIGMA}), "
          f"intervals holding the failure hour (gears x 5 noise seeds):")
    for frac, (hit, total) in tiny_failure().items():
        print(f"  at {frac:.0%} of the way: {hit}/{total}")


if __name__ == "__main__":
    main()
