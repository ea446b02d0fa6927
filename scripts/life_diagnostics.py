"""One held-out gear's life through the monitor: its events, and where its z-scores stand.

    python scripts/life_diagnostics.py \\
        reports/monitor/models/robot_joint_without_gear3.skops \\
        --dataset robot_joint --gear 3 --seed 0 --nuisance payload

Lives the healthy life that ``swgsim-train experiment=monitor`` lives for a held-out gear,
seed and nuisance, or a family's draw for the seed (``family:<key>``: the families of
``scripts/monitor_families.py`` but its ``trace``)
(:func:`swgmon.evaluation.evaluate.healthy_life`: the same windows, the same monitor seed),
commissions the monitor on its first ``commissioning_h`` hours with the diagnosis model
the evaluation saved for that gear, runs it as the evaluation counts false alarms (the
CUSUM restarted after each alarm) and prints:

- every event in time order: each alarm with the fault it names (a gear fault, or a
  sensor fault with its bridge), each advisory with its condition and operating point,
  each recommissioning;
- per operating point: its windows, the share beyond commissioning's temperature, load
  and friction (bits of ``Trace.outside``), the share with a p-value below 0.01, and the
  features whose mean z-score lies furthest from 0 (against commissioning's normal
  behaviour, before any recommissioning, at the friction factor in force).

``--csv FILE`` writes every window's hour, operating point, outside bits, friction factor,
p-value, both scores and every feature's z-score. The run takes the life's simulation
and scoring (a 224-h nuisance life of robot_joint: a few minutes on one core).
A wrong model, preset, gear or nuisance ends in one line naming it (exit 2).

``--benchmark`` lives a benchmark family's draw instead (issue 83;
:func:`swgmon.evaluation.families.benchmark_families`, ``--nuisance family:<key>``) on the
benchmark's lot of gears (``--gear`` one of its held-out instances), with the model its
design part saved (``reports/benchmark/models/<dataset>_benchmark.skops``), for the
diagnosis of a miss on design seeds only (a scored seed, 1000 and up, is refused):

    python scripts/life_diagnostics.py reports/benchmark/models/bench_benchmark.skops \\
        --benchmark --dataset bench --gear 9 --seed 300 --nuisance family:all
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from learn.inputs.health import feature_names
from learn.tracking.ledger import check_seeds
from swgcli import dataset_preset
from swgmon.advisories.report import advisories, recommissionings
from swgmon.assessment.gear_monitor import GearMonitor, Trace
from swgmon.assessment.model_io import CARD_SUFFIX, MODEL_SUFFIX, load_model
from swgmon.detection.normal import (
    Outside,
)
from swgmon.detection.rule import Alarm
from swgmon.evaluation.benchmark import BenchmarkConfig, population_plan
from swgmon.evaluation.evaluate import healthy_life, monitor_healthy
from swgmon.evaluation.families import benchmark_families, default_families
from swgmon.evaluation.study import MonitorStudyConfig, family_of
from swgmon.evaluation.training import has_twist
from swgsim.datasets.plan import plan as make_plan
from swgsim.datasets.records import record_bank
from swgsim.files.ownership import atomic_write_bytes

#: Features listed per operating point, furthest from 0 first.
TOP = 4


def parse(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=__doc__.split("\n\n", 2)[2])
    ap.add_argument("model", type=Path, help="a diagnosis model (.skops with its card) of "
                    "reports/monitor/models/, trained without the gear looked at")
    ap.add_argument("--dataset", default="bench", help="data-set preset (default bench)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="an override of the preset, e.g. "
                         "profile.angles.output_encoder_bits=null (the _hall variant)")
    ap.add_argument("--gear", type=int, default=3, help="held-out gear (default 3)")
    ap.add_argument("--seed", type=int, default=0, help="life seed (default 0)")
    ap.add_argument("--nuisance", default="none", help="none (default), one of "
                    f"{', '.join(MonitorStudyConfig().nuisances)}, or a family's draw for "
                    "the seed: family:<key>, key one of "
                    f"{', '.join(default_families())}")
    ap.add_argument("--hours", type=float, default=None,
                    help="operating hours of the life, commissioning included (default: "
                         "the study's, 1000 without a nuisance, 224 under one)")
    ap.add_argument("--csv", type=Path, default=None, help="write every window's z-scores")
    ap.add_argument("--benchmark", action="store_true",
                    help="a benchmark family's draw on the benchmark's lot (design seeds)")
    return ap.parse_args(argv)


def setup(args: argparse.Namespace):
    """The plan, the study design and the held-out gear's healthy life; one line on bad
    input (raises ValueError)."""
    if args.benchmark:
        return _benchmark_setup(args)
    cfg = MonitorStudyConfig(families=default_families())
    fam = family_of(args.nuisance)
    if args.nuisance != "none" and args.nuisance not in cfg.nuisances \
            and fam not in cfg.families:
        raise ValueError(f"--nuisance {args.nuisance!r}: allowed none, "
                         f"{', '.join(cfg.nuisances)}, family:<key> with key one of "
                         f"{', '.join(cfg.families)}")
    if args.hours is not None:
        if not cfg.commissioning_h < args.hours <= 1e5:
            raise ValueError(f"--hours {args.hours:g}: must lie in ({cfg.commissioning_h:g}, "
                             "1e5] (longer than commissioning)")
        key = "healthy_hours" if args.nuisance == "none" else "nuisance_hours"
        cfg = dataclasses.replace(cfg, **{key: float(args.hours)})
    p = make_plan(dataset_preset(args.dataset, args.set))
    trained_on(args.model, p, args.dataset)
    gears = [int(x.id) for x in p.config.gears]
    if args.gear not in gears:
        raise ValueError(f"--gear {args.gear}: {args.dataset} has gears {gears}")
    life = healthy_life(p, record_bank(p, args.gear), args.gear, cfg, args.seed,
                        args.nuisance)
    return p, cfg, life


def _benchmark_setup(args: argparse.Namespace):
    """:func:`setup` for a benchmark family's draw (module docstring)."""
    bc = BenchmarkConfig()
    fam = family_of(args.nuisance)
    if fam not in benchmark_families():
        raise ValueError(f"--nuisance {args.nuisance!r}: with --benchmark, family:<key> with "
                         f"key one of {', '.join(benchmark_families())}")
    check_seeds([args.seed], False, "--seed (a diagnosis)")
    cfg = bc.study_of(fam, design=True, seeds=[args.seed])
    if args.hours is not None:
        raise ValueError("--hours: with --benchmark the life is the benchmark's "
                         f"({bc.healthy_hours:g} h)")
    p = population_plan(make_plan(dataset_preset(args.dataset, args.set)), bc)
    trained_on(args.model, p, args.dataset)
    gears = [int(x.id) for x in p.config.gears]
    if args.gear not in gears:
        raise ValueError(f"--gear {args.gear}: the benchmark's lot of {args.dataset} has "
                         f"instances {gears}")
    return p, cfg, healthy_life(p, record_bank(p, args.gear), args.gear, cfg, args.seed,
                                args.nuisance)


def trained_on(path: Path, p, dataset: str) -> None:
    """Refuse a model whose card names training data sets other than the preset's (their
    config hashes differ), in one line (raises ValueError)."""
    card = path.with_name(path.name.removesuffix(MODEL_SUFFIX) + CARD_SUFFIX)
    training = json.loads(card.read_text(encoding="utf-8")).get("training", [])
    hashes = {t.get("config_hash") for t in training} - {None}
    if hashes and p.config_hash not in hashes:
        names = ", ".join(str(t.get("name")) for t in training)
        raise ValueError(f"model: {path.name} was trained on {names}, not on --dataset "
                         f"{dataset} as given (config hash {p.config_hash[:12]} not in its "
                         "card; --set overrides count)")


def events(mon: GearMonitor, tr: Trace, alarms: list[Alarm], windows) -> pd.DataFrame:
    """Alarms, advisories and recommissionings of a run, in time order."""
    pts = windows[1]
    rows = []
    for al in alarms:
        kind = al.kind.replace("_", "-") + " alarm"
        what = al.fault if al.bridge is None else f"{al.fault} on {al.bridge}"
        sev = f", severity {al.severity:.3g}" if np.isfinite(al.severity) else ""
        rows.append((al.hour, kind, what + sev, pts[al.index]))
    rows += [(x["hour"], "advisory", x["condition"], x["operating_point"])
             for x in advisories(tr, mon)]
    rows += [(x["hour"], "recommissioned", "relearnt" if x["relearnt"] else "range grew",
              x["operating_point"]) for x in recommissionings(tr, mon)]
    out = pd.DataFrame(rows, columns=["hour", "event", "what", "point"])
    out["point"] = [f"{float(q[0]):g} rpm, {float(q[1]):g} N m" for q in out["point"]]
    return out.sort_values("hour", kind="stable").reset_index(drop=True)


def points_table(commissioned: GearMonitor, tr: Trace, windows, names: list[str]
                 ) -> pd.DataFrame:
    """Per operating point: windows, shares outside and with p < 0.01, and the features
    furthest from commissioning's normal behaviour (mean z)."""
    f, p, c = windows
    z = commissioned.normal.z(f, p, c, tr.friction)
    rows = []
    for k in np.unique(tr.op_index):
        m = tr.op_index == k
        o = commissioned.normal.points[k]
        mz = z[m].mean(axis=0)
        top = np.argsort(-np.abs(mz))[:TOP]
        rows.append({"point": f"{o[0]:g} rpm, {o[1]:g} N m", "windows": int(m.sum()),
                     **{f"beyond {n}": float(np.mean(tr.outside[m] & b != 0))
                        for n, b in (("temperature", Outside.TEMPERATURE),
                                     ("load", Outside.LOAD), ("friction", Outside.FRICTION))},
                     "p < 0.01": float(np.mean(tr.p[m] < 0.01)),
                     "mean z, furthest": ", ".join(f"{names[j]} {mz[j]:+.2f}" for j in top)})
    return pd.DataFrame(rows)


def write_csv(path: Path, commissioned: GearMonitor, tr: Trace, windows,
              names: list[str]) -> None:
    f, p, c = windows
    z = commissioned.normal.z(f, p, c, tr.friction)
    cols = {"hour": tr.hour, "n_in_rpm": p[:, 0], "t_out_nm": p[:, 1],
            "t_out_mean_nm": c.torque_nm, "outside": tr.outside, "friction": tr.friction,
            "p": tr.p, "evidence": tr.score[:, 0], "novelty": tr.score[:, 1],
            **{f"z_{n}": z[:, j] for j, n in enumerate(names)}}
    if c.temperature_c is not None:
        cols["temperature_c"] = c.temperature_c
    atomic_write_bytes(path, pd.DataFrame(cols).to_csv(index=False).encode())


def main(argv: list[str] | None = None) -> int:
    args = parse(argv)
    try:
        model = load_model(args.model, key="model")
        p, cfg, life = setup(args)
        names = feature_names(twist=has_twist(p))
        if model.n_features != len(names):
            raise ValueError(f"model: {args.model} scores {model.n_features} features, "
                             f"{args.dataset} has {len(names)} (a model of another preset?)")
    except (OSError, ValueError) as e:
        print(f"life_diagnostics: {e}", file=sys.stderr)
        return 2
    commissioned, mon, tr, alarms, windows = monitor_healthy(model, cfg, life, args.seed,
                                                             args.nuisance)
    hours = float(tr.hour[-1] - tr.hour[0]) if len(tr.hour) else 0.0
    print(f"{args.dataset} gear {args.gear}, seed {args.seed}, nuisance {args.nuisance}: "
          f"{len(tr.hour)} windows after commissioning ({hours:.0f} h), threshold "
          f"h = {mon.h:.2f}")
    ev = events(mon, tr, alarms, windows)
    with pd.option_context("display.width", 200, "display.max_colwidth", 90,
                           "display.max_rows", 500, "display.float_format", "{:.3f}".format):
        print(f"\n{len(ev)} events" + (":\n" + ev.to_string(index=False) if len(ev) else ""))
        print("\n" + points_table(commissioned, tr, windows, names).to_string(index=False))
    if args.csv is not None:
        write_csv(args.csv, commissioned, tr, windows, names)
        print(f"\nevery window: {args.csv}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
