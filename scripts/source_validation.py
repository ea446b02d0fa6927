"""Accuracy of a transfer run's learner on validation windows of the source gears.

Settings of the transfer comparison's learners (epochs, batch size, kernels, widths) are
chosen here, never on the held-out gear: for every leave-one-gear-out split of a data set
the held-out gear's windows are set aside unseen, a fraction of the source gears' fault
variants (whole variants: every operating point of one variant) is kept back as
validation, the learner is fitted on the rest and scored on them. Prints, per setting,
the validation accuracy (mean and worst over the splits) and the fit time (one process,
``--threads`` torch threads)::

    python scripts/source_validation.py data/bench --runs mlp_torch/raw --compare \\
        transfer.models.mlp_torch.estimator.max_epochs=30 \\
        transfer.models.mlp_torch.estimator.max_epochs=60
    python scripts/source_validation.py data/paper --runs cnn/raw cnn/diff --compare \\
        'transfer.models.cnn.estimator.channels=[16,32,32,32]'

Each setting of ``--compare`` is one Hydra override of ``swgsim-train
experiment=transfer``, compared with the others (without ``--compare``: the config as
it is); overrides common to all may follow the data set.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def _args(argv=None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("data", help="a data set (folder of swgsim-generate)")
    p.add_argument("overrides", nargs="*", help="Hydra overrides of swgsim-train")
    p.add_argument("--runs", nargs="+", required=True, help="runs of transfer.runs, model/input")
    p.add_argument("--compare", nargs="+", default=None, metavar="OVERRIDE",
                   help="settings to compare, one Hydra override each")
    p.add_argument("--seed", type=int, default=0, help="model seed and validation draw")
    p.add_argument("--val", type=float, default=0.2,
                   help="fraction of the source gears' fault variants kept for validation")
    p.add_argument("--threads", type=int, default=1, help="torch threads")
    p.add_argument("--json", default=None, help="also write the figures to this file")
    a = p.parse_args(argv)
    if not 0.0 < a.val < 1.0:
        p.error(f"--val: a fraction in (0, 1), got {a.val}")
    bad = [o for o in a.compare or [] if "=" not in o]
    if bad:
        p.error(f"--compare: KEY=VALUE overrides expected, got {bad}")
    return a


def _validation_rows(groups: np.ndarray, rows: np.ndarray, frac: float,
                     seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``rows`` split by whole groups: (fit rows, validation rows)."""
    uniq = np.unique(groups[rows])
    rng = np.random.default_rng(seed)
    val = rng.choice(uniq, size=max(1, int(round(frac * uniq.size))), replace=False)
    is_val = np.isin(groups[rows], val)
    return rows[~is_val], rows[is_val]


def evaluate(data: str, overrides: list[str], labels: list[str], seed: int,
             frac: float) -> dict[str, dict]:
    """Validation accuracy and fit seconds of each run, per leave-one-gear-out split."""
    from omegaconf import OmegaConf

    from learn.studies.protocols import fit_with_groups, protocol_splits, window_groups
    from learn.studies.runs import make_estimator
    from learn.transfer.study import _inputs
    from swgcli import compose_app
    from swgsim.base.typed import check_tree
    from swgsim.datasets.schema import load

    cfg = compose_app("train", ["experiment=transfer", *overrides])
    tc = OmegaConf.to_object(cfg.transfer)
    runs = [r for r in tc.runs if r.label in set(labels)]
    missing = set(labels) - {r.label for r in runs}
    if missing:
        raise SystemExit(f"--runs: {sorted(missing)} not in transfer.runs "
                         f"{[r.label for r in tc.runs]}")
    tc = replace(tc, runs=runs, primary=None)
    check_tree(tc, "transfer")
    inputs = _inputs(load(data), runs, tc, True,
                     OmegaConf.to_object(cfg.features).kwargs())
    out = {}
    for spec in runs:
        inp = inputs[spec.input]
        groups = window_groups(inp.meta)
        per_split = {}
        for split in protocol_splits(inp.meta, "ood_disturbed", random_state=int(cfg.seed)):
            fit_rows, val_rows = _validation_rows(groups, split.train, frac, seed)
            est = make_estimator(tc.models[spec.model], seed, inp.n_aux, spec.params)
            t0 = time.perf_counter()
            fit_with_groups(est, inp.X[fit_rows], inp.y[fit_rows], groups[fit_rows])
            fit_s = time.perf_counter() - t0
            acc = float(np.mean(est.predict(inp.X[val_rows]) == inp.y[val_rows]))
            per_split[split.name] = {"accuracy": acc, "fit_s": fit_s,
                                     "n_fit": int(fit_rows.size), "n_val": int(val_rows.size)}
        out[spec.label] = per_split
    return out


def main(argv=None) -> list[dict]:
    """Run the comparison; returns one record per (setting, run)."""
    import torch

    a = _args(argv)
    torch.set_num_threads(a.threads)
    settings = a.compare or [None]
    records = []
    print(f"{Path(a.data).name}: validation = {100 * a.val:.0f} % of the source gears' "
          f"fault variants, seed {a.seed}, {a.threads} torch thread(s)")
    print(f"{'setting':<52s} {'run':<20s} {'mean %':>7s} {'worst %':>7s} {'fit s':>7s}")
    for s in settings:
        res = evaluate(a.data, [*a.overrides, *([s] if s else [])], a.runs, a.seed, a.val)
        for label, per in res.items():
            acc = [r["accuracy"] for r in per.values()]
            fit = sum(r["fit_s"] for r in per.values())
            print(f"{s or '(config)':<52s} {label:<20s} {100 * np.mean(acc):7.2f} "
                  f"{100 * min(acc):7.2f} {fit:7.1f}", flush=True)
            records.append({"setting": s, "run": label, "splits": per})
    if a.json:
        Path(a.json).write_text(json.dumps(records, indent=1))
    return records


if __name__ == "__main__":
    main()
