"""Seconds per run of the transfer comparison on one data set and one seed.

Composes ``swgsim-train experiment=transfer`` with the given overrides (Hydra syntax),
runs its jobs for one seed on one data set (leave-one-gear-out: three jobs, one per
held-out gear) and prints, per (model, input) run, the wall time summed over the jobs
(fit, adaptations, fine-tuning and scoring) and how it divides (fit on the source gears;
AdaBN / CORAL; k-shot fine-tuning or ridge refits), beside its accuracy at every k
(worst split); then the same by stage over all runs, with building the inputs (scoring
and the rest: predicting every variant's evaluation windows, k-shot draws, bookkeeping).
CPU seconds (this process's, one torch thread by default) are what a run costs on a core
of its own; wall seconds grow with what else runs on the machine. The figures of
docs/learners_transfer.md come from it::

    python scripts/bench_transfer.py data/bench
    python scripts/bench_transfer.py data/bench --runs mlp_torch/raw cnn/diff
    python scripts/bench_transfer.py data/bench --runs mlp_torch/raw \\
        transfer.models.mlp_torch.estimator.batch_size=64     # a before/after pair

``--jobs 1`` (default) runs the jobs one after the other in this process with
``--threads`` torch threads, so that a run's seconds are its own; ``--jobs 2`` runs
them as the comparison does (one process per job, ``transfer.threads_per_job``).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def _args(argv=None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("data", help="a data set (folder of swgsim-generate)")
    p.add_argument("overrides", nargs="*", help="Hydra overrides of swgsim-train")
    p.add_argument("--seed", type=int, default=0, help="model seed and k-shot draw")
    p.add_argument("--runs", nargs="*", default=None,
                   help="runs to time, model/input (default: every run of transfer.runs)")
    p.add_argument("--jobs", type=int, default=1, help="jobs in parallel processes")
    p.add_argument("--threads", type=int, default=1, help="torch threads (--jobs 1)")
    p.add_argument("--json", default=None, help="also write the figures to this file")
    return p.parse_args(argv)


def _by_stage(table: dict, input_s: float, wall: float) -> dict[str, float]:
    """Seconds by stage over every run, printed (module docstring)."""
    stages = {"inputs": input_s}
    for key, label in (("fit_s", "fitting"), ("adapt_s", "adaptation"),
                       ("finetune_s", "fine-tuning")):
        stages[label] = sum(r[key] for r in table.values())
    stages["scoring and the rest"] = (sum(r["wall_s"] for r in table.values())
                                      - sum(stages[k] for k in list(stages)[1:]))
    print("by stage: " + ", ".join(f"{k} {v:.1f} s ({100 * v / wall:.0f} %)"
                                   for k, v in stages.items()) + f" of {wall:.1f} s wall")
    return stages


def main(argv=None) -> dict:
    """Run the benchmark; returns what it prints, by run label."""
    import torch
    from omegaconf import OmegaConf

    from learn.transfer.picks import primary_row
    from learn.transfer.report import summarise
    from learn.transfer.study import run_comparison
    from swgcli import compose_app
    from swgsim.base.typed import check_tree
    from swgsim.datasets.schema import load

    a = _args(argv)
    cfg = compose_app("train", ["experiment=transfer", *a.overrides])
    tc = OmegaConf.to_object(cfg.transfer)
    runs = [r for r in tc.runs if a.runs is None or r.label in set(a.runs)]
    if not runs:
        raise SystemExit(f"--runs: none of {a.runs} in transfer.runs "
                         f"{[r.label for r in tc.runs]}")
    primary = tc.primary if tc.primary and tc.primary.label in {r.label for r in runs} else None
    tc = replace(tc, runs=runs, primary=primary, seeds=[a.seed], cv_seeds=[a.seed],
                 n_jobs=a.jobs, latency=False, progress=False)
    check_tree(tc, "transfer")
    torch.set_num_threads(a.threads)
    ds = load(a.data)
    t0 = time.perf_counter()
    out = run_comparison(ds, tc, dataset=Path(a.data).name,
                         feature_kwargs=OmegaConf.to_object(cfg.features).kwargs(),
                         split_seed=int(cfg.seed), checked=True)
    wall = time.perf_counter() - t0
    res, run_s = out["results"], out["run_s"]
    summ = summarise(res)
    worst = summ[summ["split"] == "worst"]
    ks = sorted(set(res["k_shot"].astype(int)))
    table = {}
    for spec in runs:
        mine = res[(res["model"].str.partition("+")[0] == spec.model)
                   & (res["input"] == spec.input)]
        kind = mine["model"].str.partition("+")[2]
        w = worst[(worst["model"].str.partition("+")[0] == spec.model)
                  & (worst["input"] == spec.input)]
        acc = {}  # at k > 0 its first adaptation in the declared order (learn/transfer/picks.py)
        for k in ks:
            r = primary_row(w, spec, k)
            if r is not None and int(r["k_shot"]) == k:
                acc[k] = float(r["mean"])
        sel = (run_s["model"] == spec.model) & (run_s["input"] == spec.input)
        table[spec.label] = {
            "wall_s": float(run_s.loc[sel, "seconds"].sum()),
            "cpu_s": float(run_s.loc[sel, "cpu_s"].sum()),
            "fit_s": float(mine.loc[kind == "", "train_s"].sum()),
            "adapt_s": float(mine.loc[kind.isin(["adabn", "coral"]), "train_s"].sum()),
            "finetune_s": float(mine.loc[kind.str.startswith("ft"), "train_s"].sum()),
            "accuracy": acc}
    print(f"{Path(a.data).name}, seed {a.seed}, {len(set(run_s['split']))} jobs, "
          f"{a.jobs} process(es) x {a.threads if a.jobs == 1 else tc.threads_per_job} "
          f"torch thread(s); inputs {out['input_s']:.1f} s, wall {wall:.1f} s")
    head = (f"{'run':<22s} {'wall s':>8s} {'CPU s':>8s} {'fit s':>8s} {'adapt s':>8s} "
            f"{'ft s':>8s}")
    print(head + "".join(f" {'k=' + str(k):>7s}" for k in ks))
    for label, r in table.items():
        print(f"{label:<22s} {r['wall_s']:8.1f} {r['cpu_s']:8.1f} {r['fit_s']:8.1f} "
              f"{r['adapt_s']:8.1f} "
              f"{r['finetune_s']:8.1f}" + "".join(
                  f" {100 * r['accuracy'][k]:7.2f}" if k in r["accuracy"] else f" {'':>7s}"
                  for k in ks))
    print(f"{'sum':<22s} {sum(r['wall_s'] for r in table.values()):8.1f} "
          f"{sum(r['cpu_s'] for r in table.values()):8.1f}")
    stages = _by_stage(table, out["input_s"], wall)
    result = {"data": str(a.data), "seed": a.seed, "overrides": a.overrides,
              "jobs": a.jobs, "threads": a.threads, "input_s": out["input_s"],
              "wall_s": wall, "stages_s": stages, "runs": table}
    if a.json:
        Path(a.json).write_text(json.dumps(result, indent=1, default=float))
    return result


if __name__ == "__main__":
    main()
