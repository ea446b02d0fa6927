"""Seconds per model of the transfer comparison's torch nets, one by one and stacked, on
the CPU and on a GPU, with their accuracies on the held-out gear.

Two steps, so that the second needs only torch, NumPy and scikit-learn (a GPU machine
without the project's other packages):

``save``: the nets of ``swgsim-train experiment=transfer`` (their settings as that
comparison makes them) and one leave-one-gear-out split of a data set's disturbed
windows (``ood_disturbed``: train on the other gears, test on the held-out one), one
input kind, written to one compressed ``.npz`` (signals in float16: half the size; both
steps then read the same numbers)::

    python scripts/bench_nets.py save data/bench bench_nets.npz --input diff --gear 3

``save-monitor``: the same for the monitor's CNN detector (``cnn_res`` of
:mod:`swgmon.evaluation.detectors`, as ``swgsim-train experiment=monitor`` makes it): its
training set of one part (:func:`swgmon.evaluation.training.detector_windows` of the gears
other than the held-out one) and, to score, the same windows of the held-out gear's
training lives (no data set on disk needed; the records are simulated, minutes)::

    python scripts/bench_nets.py save-monitor bench_cnn_res.npz --dataset bench --gear 3

``run``: for each net and device, ``--seeds`` models trained one by one
(:meth:`learn.learners.nets.TorchClassifier.fit`) and at once
(:func:`learn.learners.stacked.fit_seeds`; ``compiled``: the same with ``torch.compile``,
its compilation counted); prints seconds per model (fit only; the data on the device
included), milliseconds per 1000 windows to predict (the held-out windows, as a monitor's
evaluation labels every window of its lives) and the held-out gear's accuracy (mean and
spread over the seeds), and whether each mode's mean accuracy agrees with the first
mode's of that net within the seed spread (the larger standard deviation of the two, at
least one window)::

    python scripts/bench_nets.py run bench_nets.npz --devices cpu cuda --json out.json

Figures: ``docs/results/speed.md`` ("Nets on a GPU").
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

NETS = ("cnn", "mlp_torch")
#: The monitor's torch detector (``save-monitor``).
DETECTOR = "cnn_res"


def _args(argv=None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="step", required=True)
    s = sub.add_parser("save", help="write the nets' settings and one split to an .npz")
    s.add_argument("data", help="a data set (folder of swgsim-generate)")
    s.add_argument("out", help="the .npz to write")
    s.add_argument("--input", default="diff", help="input kind (learn.inputs.signals)")
    s.add_argument("--gear", type=int, default=3, help="held-out gear")
    s.add_argument("overrides", nargs="*", help="Hydra overrides of swgsim-train")
    m = sub.add_parser("save-monitor", help="write the monitor's CNN detector and one "
                       "part's windows to an .npz")
    m.add_argument("out", help="the .npz to write")
    m.add_argument("--dataset", default="bench", help="data set of the evaluation")
    m.add_argument("--gear", type=int, default=3, help="held-out gear")
    m.add_argument("--seed", type=int, default=0, help="the part's seed (class balance)")
    m.add_argument("overrides", nargs="*", help="Hydra overrides of swgsim-train")
    r = sub.add_parser("run", help="time the nets of an .npz written by save")
    r.add_argument("file", help="the .npz of save")
    r.add_argument("--nets", nargs="*", default=None, choices=[*NETS, DETECTOR],
                   help="default: every net in the file")
    r.add_argument("--devices", nargs="*", default=["cpu"], help="cpu, cuda, cuda:N")
    r.add_argument("--modes", nargs="*", default=["one", "stacked"],
                   choices=["one", "stacked", "compiled"],
                   help="compiled: stacked with torch.compile (its compilation counted)")
    r.add_argument("--seeds", type=int, default=5, help="models per net and mode")
    r.add_argument("--threads", type=int, default=None, help="torch CPU threads")
    r.add_argument("--json", default=None, help="also write the figures to this file")
    return p.parse_args(argv)


def save(a: argparse.Namespace) -> None:
    """The ``save`` step (module docstring)."""
    from omegaconf import OmegaConf

    from learn.inputs.signals import build_input
    from learn.studies.protocols import protocol_splits
    from learn.studies.runs import final_step, make_estimator
    from swgcli import compose_app
    from swgsim.datasets.schema import load

    cfg = compose_app("train", ["experiment=transfer", *a.overrides])
    tc = OmegaConf.to_object(cfg.transfer)
    inp = build_input(load(a.data), a.input, aux=tuple(tc.aux), disturbed=True)
    split = next((s for s in protocol_splits(inp.meta, "ood_disturbed")
                  if set(inp.meta["gear"].to_numpy()[s.test]) == {a.gear}), None)
    if split is None:
        raise SystemExit(f"--gear: {a.gear} is not a gear of {a.data}")
    labels = inp.meta["fault"].to_numpy().astype(str)
    nets = {}
    for name in NETS:
        est = final_step(make_estimator(tc.models[name], 0, inp.n_aux))
        nets[name] = {"class": type(est).__name__, "params": est.get_params(deep=False)}
    np.savez_compressed(
        a.out, X_train=inp.X[split.train].astype(np.float16), y_train=labels[split.train],
        X_test=inp.X[split.test].astype(np.float16), y_test=labels[split.test],
        about=json.dumps({"data": str(a.data), "input": a.input, "gear": a.gear,
                          "nets": nets}))
    print(f"{a.out}: {len(split.train)} training and {len(split.test)} test windows of "
          f"shape {inp.X.shape[1:]}, nets {list(nets)}")


def save_monitor(a: argparse.Namespace) -> None:
    """The ``save-monitor`` step (module docstring)."""
    from learn.tasks.config import typed_app
    from swgcli import compose_app
    from swgmon.evaluation.detectors import DETECTORS
    from swgmon.evaluation.evaluate import banks_of
    from swgmon.evaluation.training import detector_windows

    mc = typed_app(compose_app("train", ["experiment=monitor", *a.overrides])).monitor
    plan = mc.plans("monitor").get(a.dataset)
    if plan is None:
        raise SystemExit(f"--dataset: {a.dataset} is not in monitor.run_on {mc.run_on}")
    gears = [int(x.id) for x in plan.config.gears]
    if a.gear not in gears:
        raise SystemExit(f"--gear: {a.gear} is not a gear of {a.dataset} {gears}")
    kind = DETECTORS[DETECTOR].input
    banks = banks_of(plan)
    x, y = detector_windows(plan, banks, [g for g in gears if g != a.gear], mc.study, {kind},
                            a.seed)
    xt, yt = detector_windows(plan, banks, [a.gear], mc.study, {kind}, a.seed)
    est = DETECTORS[DETECTOR].make(a.seed, "cpu")[-1]
    nets = {DETECTOR: {"class": type(est).__name__, "params": est.get_params(deep=False)}}
    np.savez_compressed(
        a.out, X_train=x[kind].astype(np.float16), y_train=y,
        X_test=xt[kind].astype(np.float16), y_test=yt,
        about=json.dumps({"data": a.dataset, "input": kind, "gear": a.gear, "nets": nets}))
    print(f"{a.out}: {len(y)} training and {len(yt)} test windows of shape "
          f"{x[kind].shape[1:]}, net {DETECTOR}")


def _timed(fn) -> float:
    import torch

    if torch.cuda.is_available():
        torch.cuda.synchronize()
    t0 = time.perf_counter()
    fn()
    if torch.cuda.is_available():
        torch.cuda.synchronize()
    return time.perf_counter() - t0


def _one_row(est, data, mode: str, seeds: list[int]) -> dict:
    from sklearn.base import clone

    from learn.learners.stacked import fit_seeds

    X, y, X_test, y_test = data
    models = []
    if mode == "one":
        seconds = _timed(lambda: models.extend(
            clone(est).set_params(random_state=s).fit(X, y) for s in seeds))
    else:
        seconds = _timed(lambda: models.extend(
            fit_seeds(est, X, y, seeds, compile=mode == "compiled")))
    pred = []
    predict_s = _timed(lambda: pred.extend(m.predict(X_test) for m in models))
    acc = np.array([np.mean(p == y_test) for p in pred])
    return {"device": models[0].device_.type, "mode": mode,
            "precision": models[0].precision_, "s_per_model": seconds / len(seeds),
            "predict_ms_per_1000": 1e6 * predict_s / (len(models) * len(y_test)),
            "accuracy_mean": float(acc.mean()), "accuracy_sd": float(acc.std(ddof=1)),
            "accuracy": acc.tolist()}


def run(a: argparse.Namespace) -> dict:
    """The ``run`` step (module docstring); returns what it prints."""
    import torch
    from sklearn.base import clone

    from learn.learners import nets as nets_module
    from learn.learners.devices import device_label

    if a.threads:
        torch.set_num_threads(a.threads)
    f = np.load(a.file)
    about = json.loads(str(f["about"]))
    data = (f["X_train"].astype(np.float32), f["y_train"], f["X_test"].astype(np.float32),
            f["y_test"])
    seeds = list(range(a.seeds))
    print(f"{about['data']}, input {about['input']}, held-out gear {about['gear']}: "
          f"{len(data[1])} training windows {data[0].shape[1:]}, {len(data[3])} test; "
          f"{a.seeds} seeds; torch {torch.__version__}, {torch.get_num_threads()} CPU "
          f"threads of {os.cpu_count()} cores")
    rows = []
    print(f"{'net':<10s} {'device':<26s} {'mode':<8s} {'arith':<9s} {'s/model':>8s} "
          f"{'ms/1000':>8s} {'accuracy %':>14s}  agrees")
    for name in a.nets or list(about["nets"]):
        spec = about["nets"][name]
        first = None
        for device in a.devices:
            est = getattr(nets_module, spec["class"])(**{**spec["params"], "device": device})
            # untimed: the device's context, kernel libraries and their tuning
            clone(est).set_params(max_epochs=1).fit(data[0][:256], data[1][:256])
            for mode in a.modes:
                r = {"net": name, **_one_row(est, data, mode, seeds)}
                r["device"] = device_label(torch.device(device))
                first = first or r
                spread = max(first["accuracy_sd"], r["accuracy_sd"], 1 / len(data[3]))
                r["agrees"] = bool(abs(r["accuracy_mean"] - first["accuracy_mean"]) <= spread)
                rows.append(r)
                print(f"{name:<10s} {r['device'][:26]:<26s} {mode:<8s} {r['precision']:<9s} "
                      f"{r['s_per_model']:8.2f} {r['predict_ms_per_1000']:8.1f} "
                      f"{100 * r['accuracy_mean']:7.2f} "
                      f"± {100 * r['accuracy_sd']:4.2f}  {'yes' if r['agrees'] else 'NO'}")
    result = {"about": {k: v for k, v in about.items() if k != "nets"}, "seeds": seeds,
              "threads": torch.get_num_threads(), "cores": os.cpu_count(),
              "torch": torch.__version__, "rows": rows}
    if a.json:
        Path(a.json).write_text(json.dumps(result, indent=1))
    return result


def main(argv=None):
    a = _args(argv)
    return {"save": save, "save-monitor": save_monitor, "run": run}[a.step](a)


if __name__ == "__main__":
    main()
