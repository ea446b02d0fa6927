"""The monitor through drawn benign changes: one table row per family of
``monitor.study.families`` (swgmon/evaluation/families.py).

    python scripts/monitor_families.py [--dataset tiny_real_day] [--gear 3]
        [--seeds family|design] [--n-seeds N] [--families warm_up all]
        [--study interval_min=2] [--study nuisance_hours=100] [--out DIR]
    python scripts/monitor_families.py --dataset robot_joint --read DIR

Trains the diagnosis model on the data set's other gears (as the evaluation does,
:func:`swgmon.evaluation.training.train_model`) and lives the held-out gear through every
family's draws, one per seed (the study's family seeds, or its design seeds, the only
ones to choose the monitor's settings on): a healthy life of ``nuisance_hours`` and every
gear fault at its mildest and largest Table V severity with a step onset and at its
mildest growing over ``family_growth_h`` (:func:`swgmon.evaluation.evaluate.evaluate_gear`).
The monitor only: no per-window detectors.

A preset with the held-out gear alone (the default, ``tiny_real_day``, as
tests/learn/test_real_day.py trains) gets its training gears from ``--train-from``
(default ``tiny_bench``: gears 1 and 2), at the preset's operating points.

Printed per family: the healthy lives' gear-fault alarms and advisories per 1000 h after
commissioning, fault lives detected of lived (growing ones apart), the median time to
detect [h], the share of detected faults named right an hour after the alarm, the same
for the issue's target faults (eccentric WG, reduced damping, root and tip crack; the
time to detect of their step onsets at the mildest severity), how many failed temperature
sensors were named and the longest hours to it, and the family's wall time [s]. With
``--out DIR`` every family's rows are written there as it ends, with its key (what made
it: the preset's config hash, the held-out gear, the seeds, the study with that family
alone) and wall time in ``DIR/<family>_part.json``, and the table as ``DIR/table.csv``
(``scripts/results_pages.py`` builds the results page from
``reports/monitor_families/*/table.csv``). The same command again resumes: a family whose
rows and key are there (the ownership stamp proving them this script's) is read back, not
run. A folder holding files of anything else is refused before any work. ``--read DIR``
prints the table of its rows again without running (and writes ``DIR/table.csv``, its
wall times unknown: NaN). A bad preset, gear, family, study key or output folder ends in
one line (exit 2), before any work; so does a refusal raised while running
(:func:`swgcli.app.one_line`: a bug still ends in its traceback).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import time
from contextlib import nullcontext

from swgsim.base.lazy import lazy_module

np = lazy_module("numpy")
pd = lazy_module("pandas")
evaluate = lazy_module("swgmon.evaluation.evaluate")
families = lazy_module("swgmon.evaluation.families")
study = lazy_module("swgmon.evaluation.study")
training = lazy_module("swgmon.evaluation.training")
typed = lazy_module("swgsim.base.typed")
swgcli = lazy_module("swgcli")
app = lazy_module("swgcli.app")
plans = lazy_module("swgsim.datasets.plan")
records = lazy_module("swgsim.datasets.records")
ownership = lazy_module("swgsim.files.ownership")
report = lazy_module("swgmon.evaluation.report")
parts = lazy_module("learn.tasks.parts")

#: The tag this script claims its ``--out`` folder with (swgsim.files.writers.WRITERS).
TAG = "monitor-families"


def parse(argv: list[str] | None = None) -> argparse.Namespace:
    """The command line (module docstring); ``--help`` without any heavy import."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=__doc__.split("\n\n", 2)[2])
    ap.add_argument("--dataset", default="tiny_real_day",
                    help="data-set preset (default tiny_real_day)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="an override of the preset")
    ap.add_argument("--train-from", default="tiny_bench",
                    help="preset whose gears train the model where --dataset has the "
                         "held-out gear alone (default tiny_bench)")
    ap.add_argument("--gear", type=int, default=3, help="held-out gear (default 3)")
    ap.add_argument("--seeds", choices=("family", "design"), default="family",
                    help="the study's family seeds (default) or design seeds")
    ap.add_argument("--n-seeds", type=int, default=None,
                    help="the first N of those seeds (default all)")
    ap.add_argument("--families", nargs="*", default=None,
                    help="families lived (default every one of the study)")
    ap.add_argument("--trace", default=None, metavar="CSV",
                    help="a measured warm-up (UR3 CobotOps format): adds the family "
                         "'trace' (its joints' rises, scaled, and a friction law drawn)")
    ap.add_argument("--out", default=None, metavar="DIR",
                    help="also write each family's rows: DIR/<family>_results.csv and "
                         "DIR/<family>_false_alarms.csv (as the evaluation's), and the "
                         "table: DIR/table.csv")
    ap.add_argument("--read", default=None, metavar="DIR",
                    help="print the table of rows an earlier run wrote with --out DIR "
                         "and write it as DIR/table.csv (nothing is run; --study and "
                         "--trace as that run's)")
    ap.add_argument("--study", action="append", default=[], metavar="KEY=VALUE",
                    help="a field of MonitorStudyConfig, the value as JSON (e.g. "
                         "interval_min=2, faults='[\"eccentric_wg\"]')")
    return ap.parse_args(argv)


def study_config(overrides: list[str], trace: str | None = None):
    """The study's design with ``KEY=VALUE`` overrides and, with ``trace``, the family
    ``trace``, checked (ValueError: one line)."""
    schema = study.MonitorStudyConfig
    names = {f.name for f in dataclasses.fields(schema)}
    changes = {}
    for item in overrides:
        key, sep, value = item.partition("=")
        if not sep or key not in names:
            raise ValueError(f"--study {item!r}: KEY=VALUE with KEY one of "
                             f"{', '.join(sorted(names))}")
        try:
            changes[key] = json.loads(value)
        except json.JSONDecodeError:
            changes[key] = value
    # the values typed and checked as every config's (one line naming the key)
    cfg = typed.build(typed.complete({**typed.plain(schema()), **changes}, schema,
                                     "monitor.study"), schema, "monitor.study")
    if not cfg.families:  # the study lives none by default; this script every one
        cfg = dataclasses.replace(cfg, families=families.default_families())
    if trace is not None:
        fam = families.NuisanceFamily(parts=["trace", "friction_law"], trace_path=trace)
        cfg = dataclasses.replace(cfg, families={**cfg.families, "trace": fam})
    typed.check_tree(cfg, "monitor.study")
    return cfg


def preset(option: str, name: str, overrides: list[str] | None = None) -> dict:
    """A data-set preset named by ``option``; ValueError naming the option and the
    presets there are."""
    try:
        return swgcli.dataset_preset(name, overrides or [])
    except Exception as e:  # noqa: BLE001 - Hydra's many errors, said in one line
        raise ValueError(f"{option} {name}: {app.one_line(e) or e}") from None


def setup(args: argparse.Namespace):
    """The plan, the study, the training gears, the families and the seeds; ValueError
    in one line on bad input."""
    cfg = study_config(args.study, args.trace)
    raw = preset("--dataset", args.dataset, args.set)
    ids = [int(g["id"]) for g in raw["gears"]]
    if args.gear not in ids:
        raise ValueError(f"--gear {args.gear}: {args.dataset} has gears {ids}")
    if len(ids) == 1:
        extra = [g for g in preset("--train-from", args.train_from)["gears"]
                 if int(g["id"]) != args.gear]
        raw["gears"] = extra + raw["gears"]
    p = plans.plan(raw)
    fams = list(cfg.families) if args.families is None else args.families
    bad = sorted(set(fams) - set(cfg.families))
    if not fams:
        raise ValueError(f"--families: give one or more of {', '.join(cfg.families)} "
                         "(or leave the option out for every one)")
    if bad:
        raise ValueError(f"--families: unknown {bad}; allowed: {', '.join(cfg.families)}")
    seeds = cfg.family_seeds if args.seeds == "family" else cfg.design_seeds
    if args.n_seeds is not None:
        if not 1 <= args.n_seeds <= len(seeds):
            raise ValueError(f"--n-seeds {args.n_seeds}: must lie in [1, {len(seeds)}]")
        seeds = seeds[:args.n_seeds]
    train = [int(g.id) for g in p.config.gears if int(g.id) != args.gear]
    return p, cfg, train, fams, list(seeds)


def summary(rows: list[dict], fa: list[dict], cfg) -> dict:
    """One family's row of the table from its result and false-alarm rows (the
    monitor's); ``cfg`` the study (the lives' drawn conditions). Beside every fault, the
    issue's target faults (``report.GEAR_TARGET_FAULTS``: eccentric WG, reduced damping,
    root and tip crack): detected of lived, the median time to detect of their step
    onsets at the mildest severity, and the share named right an hour after the alarm."""
    r = pd.DataFrame(rows)
    r = r[r.detector == "monitor"]
    a = pd.DataFrame(fa)
    a = a[a.detector == "monitor"]
    hours = float(a.healthy_hours.sum())
    det = r[r.detected.astype(bool)]
    grow = r[r.onset == "growing"]
    t = r[r.fault.isin(report.GEAR_TARGET_FAULTS)]
    mild = report.mildest_steps(r)
    t_det, mild_det = t[t.detected.astype(bool)], mild[mild.detected.astype(bool)]
    return {"gear_fault_alarms_per_1000h": 1000 * a.gear_fault_alarms.sum() / hours,
            "unexplained_changes_per_1000h": 1000 * a.unexplained_changes.sum() / hours,
            "advisories_per_1000h": 1000 * a.advisories.sum() / hours,
            "detected": f"{len(det)}/{len(r)}",
            "growing_detected": f"{int(grow.detected.astype(bool).sum())}/{len(grow)}",
            "median_ttd_h": float(det.time_to_detect_h.median()) if len(det) else np.nan,
            "named_right_1h": float((det.fault_after_1h == det.fault).mean())
            if len(det) else np.nan,
            "targets_detected": f"{len(t_det)}/{len(t)}",
            "mildest_step_ttd_h": float(mild_det.time_to_detect_h.median())
            if len(mild_det) else np.nan,
            "targets_named_right": float((t_det.fault_after_1h == t_det.fault).mean())
            if len(t_det) else np.nan,
            "sensor_reported_h": sensor_delays(a, cfg)}


def sensor_delays(fa, cfg) -> str:
    """The healthy lives whose temperature sensor failed (stuck, drifting, dropped out)
    before their end: how many named it, and the longest operating hours from its failure
    to the first alarm naming it, e.g. ``"2/3, 0.35"`` (``"-"``: no such life)."""
    delays = []
    for row in fa.itertuples(index=False):
        ts = study.life_conditions(cfg, row.nuisance, int(row.seed)).temperature_sensor
        end = cfg.commissioning_h + row.healthy_hours
        if ts is not None and ts.fault != "none" and ts.fault_hour < end:
            delays.append(float(row.temperature_sensor_h) - ts.fault_hour)
    if not delays:
        return "-"
    d = np.asarray(delays)
    named = d[np.isfinite(d)]
    return f"{named.size}/{d.size}, {named.max():.2f}" if named.size else f"0/{d.size}"


def main(argv: list[str] | None = None) -> int:
    """Run the families (module docstring) and print the table; 2 on bad input."""
    args = parse(argv)
    try:
        p, cfg, train, fams, seeds = setup(args)
        if args.read is not None and not os.path.isdir(args.read):
            raise ValueError(f"--read {args.read}: no such folder")
        folder, what = (args.read, "--read") if args.read is not None else (args.out, "--out")
        claim = nullcontext() if folder is None else ownership.claim(folder, TAG, what,
                                                                      strict=True)
    except Exception as e:  # noqa: BLE001 - bad input in one line, the apps' way
        return error(e)
    try:
        with claim:
            if args.read is not None:
                return read_table(args.read, fams, cfg)
            return run(args, p, cfg, train, fams, seeds)
    except KeyboardInterrupt:
        print("monitor_families: interrupted (SIGINT); " + (
            ownership.stop_note() or "nothing written yet; rerun the same command to start "
            "again"), file=sys.stderr)
        return 130
    except Exception as e:  # noqa: BLE001 - a refusal while running: one line too
        return error(e)


def error(e: Exception) -> int:
    """Say an error in one line, the apps' way (:func:`swgcli.app.one_line`), and return
    2; an error that is no bad input (a bug) is raised again, with its traceback.

    Parameters
    ----------
    e : Exception
        The error being handled.

    Returns
    -------
    int
        2, the exit status of bad input.

    Raises
    ------
    Exception
        ``e`` itself where :func:`swgcli.app.one_line` gives no line for it.
    """
    msg = app.one_line(e)
    if msg is None:  # not bad input: a bug, with its traceback
        raise e
    print(f"monitor_families: error: {msg}", file=sys.stderr)
    return 2


def run(args: argparse.Namespace, p, cfg, train: list[int], fams: list[str],
        seeds: list[int]) -> int:
    """Live the families into the table, each family resumed from ``--out`` where its
    part is there (:func:`finished`), else run and saved as it ends (:func:`save`)."""
    t0 = time.perf_counter()
    fit, table = None, []  # (record banks, diagnosis model): trained at the first run
    for fam in fams:
        key = family_key(p, cfg, fam, seeds, args.gear)
        done = None if args.out is None else finished(args.out, fam, key)
        resumed = done is not None
        if not resumed:
            if fit is None:
                fit = trained(p, cfg, args, train, seeds)
            t1 = time.perf_counter()
            rows, fa, _ = evaluate.evaluate_gear(p, fit[0], args.gear, fit[1], cfg,
                                                 args.dataset, study.FAMILY_PREFIX + fam,
                                                 seeds)
            done = rows, fa, time.perf_counter() - t1
            if args.out is not None:
                save(args.out, fam, key, *done)
        table.append({"family": fam, **labels(done[0]), **summary(done[0], done[1], cfg),
                      "wall_s": done[2]})
        row = ", ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}"
                        for k, v in table[-1].items() if k not in ("family", *LABELS))
        print(f"  {fam}: {row}" + (f" (resumed from {args.out})" if resumed else ""),
              flush=True)
        if args.out is not None:  # the table so far: a stopped run leaves it too
            write_table(table, args.out)
    show(table)
    print(f"wall time {time.perf_counter() - t0:.0f} s")
    return 0


def trained(p, cfg, args: argparse.Namespace, train: list[int], seeds: list[int]):
    """The gears' record banks and the diagnosis model trained on ``train``, as the
    evaluation trains it, with the line that says so."""
    t0 = time.perf_counter()
    banks = {g: records.record_bank(p, g) for g in [*train, args.gear]}
    model = training.train_model(p, banks, train, cfg)
    print(f"{args.dataset}, held-out gear {args.gear}, trained on gears {train} in "
          f"{time.perf_counter() - t0:.0f} s; {args.seeds} seeds {seeds}", flush=True)
    return banks, model


def family_key(p, cfg, fam: str, seeds: list[int], gear: int) -> str:
    """What made a family's rows (:func:`learn.tasks.parts.part_key`): the preset's
    config hash (its gears, the training ones among them), the held-out gear, the seeds
    and the study with that family alone (another family's draws do not change it)."""
    alone = dataclasses.replace(cfg, families={fam: cfg.families[fam]})
    return parts.part_key([p.config_hash, gear, seeds, dataclasses.asdict(alone)])


def _paths(folder: str, fam: str) -> dict[str, str]:
    return {n: os.path.join(folder, f"{fam}_{n}.{'json' if n == 'part' else 'csv'}")
            for n in ("results", "false_alarms", "part")}


def finished(folder: str, fam: str, key: str) -> tuple[list, list, float] | None:
    """A family's rows and wall time [s] from an earlier run into ``folder`` with the
    same key (its part file written last, so a stop between leaves it to run again);
    None where they are not all there or were made otherwise."""
    q = _paths(folder, fam)
    try:
        with open(q["part"]) as f:
            part = json.load(f)
        if part.get("key") != key:
            return None
        rows, fa = (pd.read_csv(q[n]).to_dict("records") for n in ("results", "false_alarms"))
    except (OSError, ValueError):
        return None
    return rows, fa, float(part.get("wall_s", np.nan))


def _wall(part: str) -> float:
    """A family's wall time [s] from its part file; NaN where there is none (rows of a run
    before part files were written)."""
    try:
        with open(part) as f:
            return float(json.load(f).get("wall_s", np.nan))
    except (OSError, ValueError):
        return np.nan


def save(folder: str, fam: str, key: str, rows: list[dict], fa: list[dict],
         wall_s: float) -> None:
    """A family's rows as the evaluation's (``<family>_results.csv``,
    ``<family>_false_alarms.csv``), then its part (key and wall time) that proves them."""
    q = _paths(folder, fam)
    for name, part in (("results", rows), ("false_alarms", fa)):
        ownership.atomic_write_bytes(q[name], pd.DataFrame(part).to_csv(index=False).encode())
    ownership.atomic_write_json(q["part"], {"key": key, "wall_s": wall_s})


#: The columns of ``table.csv`` that say whose lives a row counts.
LABELS = ("dataset", "held_out_gear", "seeds")


def labels(rows: list[dict]) -> dict:
    """The data set, held-out gear and seeds of one family's result rows, as its lives
    record them (``seeds``: space-separated)."""
    r = pd.DataFrame(rows)
    return {"dataset": str(r.dataset.iloc[0]), "held_out_gear": int(r.held_out_gear.iloc[0]),
            "seeds": " ".join(str(s) for s in sorted(r.seed.unique()))}


def show(table: list[dict]) -> None:
    """Print the families' rows as one table."""
    out = pd.DataFrame(table).set_index("family")
    with pd.option_context("display.width", 250, "display.max_columns", 20):
        print(out.drop(columns=list(LABELS)).round(3).to_string())


def write_table(table: list[dict], folder: str) -> None:
    """The families' rows as ``folder/table.csv`` (``scripts/results_pages.py`` builds
    the results page's block from every ``reports/monitor_families/*/table.csv``)."""
    ownership.atomic_write_bytes(os.path.join(folder, "table.csv"),
                                 pd.DataFrame(table).set_index("family").to_csv().encode())


def read_table(folder: str, fams: list[str], cfg) -> int:
    """The table of the families whose rows ``folder`` holds (``--out`` of an earlier
    run); 2 where it holds none of them."""
    table = []
    for fam in fams:
        q = _paths(folder, fam)
        paths = [q[n] for n in ("results", "false_alarms")]
        if all(os.path.isfile(x) for x in paths):
            rows, fa = (pd.read_csv(x).to_dict("records") for x in paths)
            table.append({"family": fam, **labels(rows), **summary(rows, fa, cfg),
                          "wall_s": _wall(q["part"])})
    if not table:
        print(f"monitor_families: error: --read {folder}: no family's rows there "
              f"(<family>_results.csv and <family>_false_alarms.csv)", file=sys.stderr)
        return 2
    show(table)
    write_table(table, folder)
    return 0


if __name__ == "__main__":
    sys.exit(main())
