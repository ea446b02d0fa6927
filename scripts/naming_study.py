"""How the monitor names a fault, compared on training gears only (no held-out gear).

    python scripts/naming_study.py [--dataset bench] [--train 1] [--judge 2] [--lives 4]
                                   [--variants 5]

For a pair of *training* gears of a leave-one-gear-out split (default: gears 1 and 2, the
training gears of held-out gear 3), the diagnosis classifier is trained on one gear's
training lives (``--train``) and judged on the other's (``--judge``): a commissioned
monitor of the judged gear sees ``--lives`` fault lives per class and Table V severity
(fault positions drawn per life, as the evaluation's), and each naming rule names the
fault from the first hour of windows after the onset. Prints the share named right per
class and rule. The held-out gear is never simulated, so a rule chosen here is chosen
before the evaluation sees it.

Sensor faults are judged on each of the five bridges at five severities from the mild to
the severe one (a growing sensor fault is named while between them); ``--sensor-levels``
sets how many severities the training lives have.

Rules: ``monitor`` (the monitor's, :func:`swgmon.assessment.naming.name`: a
sensor fault where one bridge's fitted offset step or gain drift explains the windows,
else ``sum``), ``sum`` (summed evidence relative to the gear's calibration windows),
``vote`` (the most frequent per-window argmax among the faults), ``clip`` (summed
evidence, each window's clipped to +-2 nats), ``mean_z`` (a classifier trained on hour
means of the training gear's z-scores, applied to the hour's mean z-score). Each life
prints the best plausible one-bridge sensor fit, the log posterior odds and median p-value
it leaves and the mean shift left on the other bridges (``rest``), and the first line that
shift on the judged gear's healthy hour after commissioning, for every bridge
(:attr:`swgmon.assessment.sensor_check.NamingConfig.rest_max` was read off these).
"""

from __future__ import annotations

import argparse

import numpy as np


def _best_sensor_fit(mon, z, q, opi):
    """The plausible one-bridge sensor fit (swgmon.assessment.sensor_check) after which the
    windows look most healthy (the largest log posterior odds,
    :func:`swgmon.assessment.hypotheses.log_odds`), the odds and the median p-value then
    (None, -inf, 0 if none)."""
    from swgmon.assessment.hypotheses import log_odds
    from swgmon.assessment.model import design_matrix
    from swgmon.assessment.sensor_check import fit_sensor_faults

    b = mon.normal
    best, o_best, p_best = None, -np.inf, 0.0
    for f in fit_sensor_faults(z, b.mean[opi], b.std[opi]):
        if not f.plausible():
            continue
        score = np.stack([mon.model.score(mon.model.log_proba(
            design_matrix(f.z, q))), np.sum(f.z ** 2, axis=1)], axis=1)
        p = mon.p_values(score, opi, np.full(score.shape, 0.5))
        o = log_odds(p, mon.naming.prior_odds, mon.naming.right_median_p,
                         mon.naming.wrong_median_p)
        if o > o_best:
            best, o_best, p_best = f, o, float(np.median(p))
    return best, o_best, p_best


def _healthy_rest(mon, healthy, n_comm: int) -> None:
    """Print the mean shift each one-bridge fit leaves on the other bridges over the
    healthy hour after commissioning (about 1 where the windows are independent)."""
    from swgmon.assessment.sensor_check import fit_sensor_faults
    from swgmon.evaluation.training import features_of

    f, q, _ = features_of(healthy, n_comm, len(healthy))
    opi = mon.normal.index(q)
    fits = fit_sensor_faults(mon.normal.z(f, q, index=opi), mon.normal.mean[opi],
                             mon.normal.std[opi])
    print("healthy hour: rest of each bridge's fit "
          + " ".join(f"s{x.bridge} {x.rest:.2f}" for x in fits[::2]), flush=True)


def _name_rules(mon, lp, opi, z_mean, agg_clf, classes, f, q):
    from swgmon.assessment.naming import name

    ev = mon.evidence(lp, opi)[:, 1:]
    out = {"sum": 1 + int(np.argmax(ev.sum(axis=0))),
           "clip": 1 + int(np.argmax(np.clip(ev, -2, 2).sum(axis=0)))}
    am = np.argmax(lp[:, 1:], axis=1)
    out["vote"] = 1 + int(np.bincount(am, minlength=len(classes) - 1).argmax())
    out["mean_z"] = 1 + int(np.argmax(agg_clf.predict_proba(z_mean[None])[0][1:]))
    # the monitor may name what is no class (an unexplained change): named wrong
    return {k: classes[v] for k, v in out.items()} | {
        "monitor": name(mon, mon.evidence(lp, opi), f, q)[0]}


def _train(p, gear: int, cfg, cls: list[str], n_comm: int):
    """The window classifier and the hour-mean classifier (rule ``mean_z``) trained on
    one training gear's lives."""
    from sklearn.ensemble import HistGradientBoostingClassifier

    from swgmon.assessment.gear_monitor import normal_windows
    from swgmon.assessment.model import HEALTHY, design_matrix
    from swgmon.detection.normal import Conditions, NormalBehaviour
    from swgmon.evaluation.training import features_of, training_lives
    from swgsim.datasets.records import record_bank

    bank = record_bank(p, gear)
    lives = training_lives(p, bank, gear, cfg)
    f0, p0, m0 = features_of(lives[0][0], 0, len(lives[0][0]))
    fit = normal_windows(p0[:n_comm])
    base = NormalBehaviour.fit(f0[:n_comm][fit], p0[:n_comm][fit],
                               Conditions.of(m0)[:n_comm][fit])
    xs, ys, agg_x, agg_y = [], [], [], []
    rng = np.random.default_rng(0)
    for sim, c, _ in lives:
        f, q = (f0[n_comm:], p0[n_comm:]) if c == HEALTHY else features_of(sim, 1, len(sim))[:2]
        z = base.z(f, q)
        xs.append(design_matrix(z, q))
        ys += [cls.index(c)] * len(f)
        for _ in range(10):  # hour means of random halves of the life's windows
            idx = rng.choice(len(z), max(2, len(z) // 2), replace=False)
            agg_x.append(z[idx].mean(axis=0))
            agg_y.append(cls.index(c))
    clf = HistGradientBoostingClassifier(max_iter=200, early_stopping=False, random_state=0)
    clf.fit(np.concatenate(xs), np.array(ys))
    agg = HistGradientBoostingClassifier(max_iter=200, early_stopping=False,
                                         random_state=0).fit(np.array(agg_x), np.array(agg_y))
    return clf, agg


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dataset", default="bench")
    ap.add_argument("--train", type=int, default=1)
    ap.add_argument("--judge", type=int, default=2)
    ap.add_argument("--lives", type=int, default=4)
    ap.add_argument("--judge-faults", nargs="*", default=None,
                    help="classes judged (default: every fault class)")
    ap.add_argument("--sensor-levels", type=int, default=None,
                    help="training severities per sensor fault (default: the evaluation's, "
                    "MonitorStudyConfig.sensor_train_levels)")
    ap.add_argument("--variants", type=int, default=None,
                    help="training fault positions per class and severity (default: the "
                    "evaluation's, MonitorStudyConfig.train_variants)")
    args = ap.parse_args()

    from swgcli import dataset_preset
    from swgmon.assessment.gear_monitor import GearMonitor
    from swgmon.assessment.model import DiagnosisModel
    from swgmon.evaluation.study import MonitorStudyConfig
    from swgmon.evaluation.training import classes, features_of, table_v_severities
    from swgsim.datasets.life import LifeSimulator
    from swgsim.datasets.plan import plan
    from swgsim.datasets.records import record_bank
    from swgsim.datasets.schedule import FaultOnset, LifeConfig
    from swgsim.sensing.sensor_faults import SENSOR_FAULTS

    p = plan(dataset_preset(args.dataset))
    cfg = MonitorStudyConfig()
    if args.variants is not None:
        cfg.train_variants = args.variants
    if args.sensor_levels is not None:
        cfg.sensor_train_levels = args.sensor_levels
    cls = classes(p, cfg)
    unknown = sorted(set(args.judge_faults or []) - set(cls[1:]))
    if unknown:
        ap.error(f"--judge-faults: unknown class {unknown[0]}; allowed: {', '.join(cls[1:])}")
    n_comm = int(cfg.commissioning_h * 60)
    clf, agg = _train(p, args.train, cfg, cls, n_comm)
    model = DiagnosisModel(cls, clf)

    jb = record_bank(p, args.judge)
    healthy = LifeSimulator(p, args.judge, LifeConfig(hours=cfg.commissioning_h + 1,
                                                      life_seed=7), jb)
    fh, ph, _ = features_of(healthy, 0, n_comm)
    mon = GearMonitor(model, cfg.rule, 1.0)
    mon.commission(fh, ph)
    _healthy_rest(mon, healthy, n_comm)
    right: dict[tuple[str, str], list[bool]] = {}
    k = 0
    for c in args.judge_faults or cls[1:]:
        sensor = c in SENSOR_FAULTS
        sevs = table_v_severities(p, c)
        if sensor:  # a growing sensor fault is named while between mild and severe
            sevs = [float(v) for v in np.geomspace(sevs[0], sevs[-1], 5)]
        for s in sevs:
            for i in range(5 if sensor else args.lives):
                k += 1
                on = cfg.commissioning_h + 1.0
                life = LifeConfig(hours=on + 1.0, life_seed=5000 + k,
                                  fault=FaultOnset(c, on, s, sensor=i if sensor else None))
                sim = LifeSimulator(p, args.judge, life, jb)
                a = int(np.searchsorted(sim.schedule.hour, on))
                f, q, _ = features_of(sim, a, len(sim))
                opi = mon.normal.index(q)
                _, lp = mon.scores(f, q, index=opi)
                z = mon.normal.z(f, q, index=opi)
                fit, o_fit, p_fit = _best_sensor_fit(mon, z, q, opi)
                print(f"  {c} {s:.4g}{f' on s{i}' if sensor else ''}: best plausible "
                      "one-bridge fit " + ("none" if fit is None else
                                           f"log odds {o_fit:.2f}, median p {p_fit:.3f} "
                                           f"({fit.fault} s{fit.bridge} {fit.severity:.4g}) "
                                           f"rest {fit.rest:.2f}"),
                      flush=True)
                rules = _name_rules(mon, lp, opi, z.mean(axis=0), agg, cls, f, q)
                for rule, name in rules.items():
                    right.setdefault((c, rule), []).append(name == c)
                    if rule in ("sum", "monitor") and name != c:
                        print(f"    {rule} named {name}", flush=True)
        print(c, {r: f"{np.mean(v):.2f}" for (cc, r), v in right.items() if cc == c},
              flush=True)
    rules = sorted({r for _, r in right})
    print("all", {r: f"{np.mean([x for (c, rr), v in right.items() if rr == r for x in v]):.3f}"
                  for r in rules})


if __name__ == "__main__":
    main()
