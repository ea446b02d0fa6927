"""Report of the transfer comparison (:mod:`learn.transfer.study`): tables and targets
(its figure: :mod:`learn.transfer.figure`; its MLflow runs:
:mod:`learn.transfer.runs`).

Everything here reads the comparison's two tables: ``results`` (one row per run:
:data:`learn.transfer.study.RESULT_COLUMNS`) and ``confusion``
(:data:`learn.transfer.study.CONFUSION_COLUMNS`, counts per split and seed). Nothing is
fitted or chosen here. The result of a data set is the primary run declared before the
comparison (``transfer.primary``); the "best" run, a statement about the evaluation
windows made afterwards, stands beside it, marked so (:mod:`learn.transfer.picks`).
Accuracies are worst-split means over seeds, and so are the per-class recalls beside them
(:func:`class_recall`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from learn.learners.models import model_label
from learn.paper.results import PAPER_RESULTS
from learn.studies.latency import latency_heading
from learn.studies.protocols import ALL_PROTOCOLS, OOD_PROTOCOLS
from learn.studies.runs import RunRef
from learn.transfer.picks import (
    BEST,
    headline_md,
    headline_table,
    picks,
)
from learn.transfer.study import TargetSpec
from swgsim.base.lazy import lazy_module
from swgsim.base.markdown import md_table
from swgsim.files.ownership import write_owned

pd = lazy_module("pandas")

_INPUTS = {"raw": "raw", "diff": "differenced", "sel1": "Selection 1", "sel3": "Selection 3",
           "raw_res": "synchronous residual", "diff_res": "differenced residual",
           "res_spec": "residual spectrum"}
_SPLIT_ORDER = {"gear3": 0, "gear1": 1, "gear2": 2}
_ADAPTED = {"ft_all": ", fine-tuned all layers, k={k}", "ft_last": ", fine-tuned last layer, k={k}",
            "ft_head": ", ridge refitted with k={k}", "adabn": ", AdaBN (unsupervised)",
            "coral": ", CORAL (unsupervised)"}
#: The columns that name one cell of the comparison (a run summarised over seeds).
CELL_KEYS = ["dataset", "protocol", "model", "input", "k_shot"]


def row_label(model: str, inp: str, k: int) -> str:
    """Human-readable row name, e.g. ``CNN, raw, fine-tuned all layers, k=5``."""
    base, _, suffix = model.partition("+")
    return (f"{model_label(base)}, {_INPUTS.get(inp, inp)}"
            + _ADAPTED.get(suffix, "").format(k=k))


def summarise(results: pd.DataFrame) -> pd.DataFrame:
    """Mean and std over seeds per (dataset, protocol, model, input, k, split), plus the
    worst split (lowest mean) per (dataset, protocol, model, input, k).

    Parameters
    ----------
    results : pandas.DataFrame
        :data:`learn.transfer.study.RESULT_COLUMNS`.

    Returns
    -------
    pandas.DataFrame
        Columns dataset, protocol, model, input, k_shot, split, mean, std, n_seeds; the
        worst split appears as ``split == "worst"`` with ``worst_of`` naming it (its std
        is that split's std).
    """
    g = results.groupby([*CELL_KEYS, "split"])["accuracy"]
    per = g.agg(["mean", "std", "count"]).reset_index().rename(columns={"count": "n_seeds"})
    per["std"] = per["std"].fillna(0.0)
    worst = per.loc[per.groupby(CELL_KEYS)["mean"].idxmin()].copy()
    worst["worst_of"] = worst["split"]
    worst["split"] = "worst"
    return pd.concat([per, worst], ignore_index=True)


def class_recall(confusion: pd.DataFrame, summ: pd.DataFrame) -> pd.DataFrame:
    """Recall per class on the accuracy's basis: on the worst split of each run (the
    split of its worst-split mean accuracy, :func:`summarise`), mean over seeds.

    Parameters
    ----------
    confusion : pandas.DataFrame
        :data:`learn.transfer.study.CONFUSION_COLUMNS` (counts per split and seed).
    summ : pandas.DataFrame
        :func:`summarise` of the same comparison.

    Returns
    -------
    pandas.DataFrame
        Columns dataset, protocol, model, input, k_shot, true, split (the worst one),
        recall (0..1, mean over seeds), windows (summed over seeds).
    """
    keys = [*CELL_KEYS, "split", "seed", "true"]
    tot = confusion.groupby(keys)["count"].sum().rename("windows")
    hit = confusion[confusion["true"] == confusion["predicted"]].groupby(keys)["count"].sum()
    per = pd.concat([tot, hit.rename("hit")], axis=1).fillna(0.0).reset_index()
    per["recall"] = per["hit"] / per["windows"]
    out = per.groupby([*CELL_KEYS, "split", "true"], as_index=False).agg(
        recall=("recall", "mean"), windows=("windows", "sum"))
    worst = summ.loc[summ["split"] == "worst", [*CELL_KEYS, "worst_of"]]
    out = out.merge(worst, on=CELL_KEYS)
    return out[out["split"] == out["worst_of"]].drop(columns="worst_of").reset_index(
        drop=True)


def _kind(protocol: str) -> str:
    return "disturbed" if protocol.endswith("disturbed") else "clean"


def observable_share(separability: Mapping | None, dataset: str, protocol: str
                     ) -> pd.Series | None:
    """Per class, the share of windows beyond the healthy p95 (:mod:`learn.studies.separability`)
    in the data the protocol evaluates (clean or disturbed windows); healthy: the share
    *within* it (0.95). None when not measured."""
    tab = ((separability or {}).get(dataset) or {}).get(_kind(protocol))
    if tab is None or not len(tab):
        return None
    share = tab.set_index("fault")["beyond_p95"].copy()
    if "healthy" in share.index:
        share["healthy"] = 1.0 - share["healthy"]
    return share


#: The columns of :func:`target_table`.
TARGET_COLUMNS = ["dataset", "condition", "target", "who", "run", "split", "reached", "met",
                  "observable"]


def target_table(summ: pd.DataFrame, recall: pd.DataFrame, targets: Mapping[str, TargetSpec],
                 primary: RunRef | None = None,
                 separability: Mapping | None = None) -> pd.DataFrame:
    """Check the targets of ``transfer.targets`` per data set: the primary run's first,
    the best run's beside it (:func:`learn.transfer.picks.picks`).

    Parameters
    ----------
    summ : pandas.DataFrame
        :func:`summarise`.
    recall : pandas.DataFrame
        :func:`class_recall` (the worst split, mean over seeds: the accuracy's basis).
    targets : mapping of str to TargetSpec
        Data set -> :class:`learn.transfer.study.TargetSpec` (protocol, accuracy: {k: min
        worst-split mean}, recall: {class: min recall at k = 0}; fractions).
    primary : RunRef, optional
        The run declared before the comparison (``transfer.primary``): the result; the
        best one beside it is marked as chosen afterwards.
    separability : mapping, optional
        Data set -> {"clean", "disturbed"} -> :func:`learn.studies.separability.summary_table`.

    Returns
    -------
    pandas.DataFrame
        :data:`TARGET_COLUMNS`: who (:data:`~learn.transfer.picks.PRIMARY`, ``BEST``
        or why there is no primary: then run is empty, reached NaN, met None), split
        (the run's worst split), observable: for a recall, the class's share beyond the
        healthy p95; for an accuracy, the mean of those shares over the classes (healthy:
        0.95), an estimate of what the signals allow, not a bound (NaN when not measured).
    """
    rows = []
    for ds, spec in targets.items():
        w = summ[(summ["dataset"] == ds) & (summ["protocol"] == spec.protocol)
                 & (summ["split"] == "worst")]
        if w.empty:
            continue
        share = observable_share(separability, ds, spec.protocol)
        obs_acc = float(share.mean()) if share is not None else float("nan")
        for k, tgt in sorted(spec.accuracy.items(), key=lambda t: int(t[0])):
            for who, b in picks(w, primary, int(k)):
                reached = np.nan if b is None else float(b["mean"])
                rows.append(_target_row(ds, f"accuracy, worst split, k = {k}", tgt, who, b,
                                        reached, obs_acc))
        if spec.recall:
            rows += _recall_targets(ds, spec, w, recall, primary, share)
    return pd.DataFrame(rows, columns=TARGET_COLUMNS)


def _target_row(ds: str, condition: str, target: float, who: str, b: pd.Series | None,
                reached: float, observable: float) -> dict:
    """One row of :func:`target_table` (``b``: the run's worst-split row, or None)."""
    return {"dataset": ds, "condition": condition, "target": float(target), "who": who,
            "run": "" if b is None else row_label(b["model"], b["input"], int(b["k_shot"])),
            "split": "" if b is None else b["worst_of"], "reached": reached,
            "met": None if b is None else bool(reached >= float(target)),
            "observable": observable}


def _recall_targets(ds: str, spec: TargetSpec, w: pd.DataFrame, recall: pd.DataFrame,
                    primary: RunRef | None, share: pd.Series | None) -> list[dict]:
    """Recall targets at k = 0 of the primary and the best run, on their worst split."""
    rows = []
    for who, b in picks(w, primary, 0):
        r = pd.Series(dtype=float)
        if b is not None:
            r = recall[(recall["dataset"] == ds) & (recall["protocol"] == spec.protocol)
                       & (recall["model"] == b["model"]) & (recall["input"] == b["input"])
                       & (recall["k_shot"] == 0)].set_index("true")["recall"]
        for cls, tgt in spec.recall.items():
            if b is not None and cls not in r.index:
                continue
            obs = float(share.get(cls, np.nan)) if share is not None else float("nan")
            rows.append(_target_row(ds, f"recall of {cls}, worst split, k = 0", tgt, who, b,
                                    float(r.get(cls, np.nan)), obs))
    return rows


def model_rank(m: str) -> int:
    """Position of a run's model (with its adaptation suffix) in the tables' row order."""
    order = ["rf", "rf+coral", "minirocket", "minirocket+ft_head", "mlp_torch",
             "mlp_torch+adabn", "mlp_torch+ft_last", "mlp_torch+ft_all", "cnn", "cnn+adabn",
             "cnn+ft_last", "cnn+ft_all"]
    return order.index(m) if m in order else len(order)


def _paper_rows(protocol: str, splits: Sequence[str]) -> list[list[str | None]]:
    table = {"ood_clean": "IX", "ood_disturbed": "X"}[protocol]
    out = []
    for sel in ("selection1", "selection3"):
        res = PAPER_RESULTS.get(table) or {}
        if sel not in res:
            continue
        vals = [res[sel].get(s, {}).get("rf") for s in splits]
        if any(v is None for v in vals):
            continue
        out.append([f"paper Table {table}: RF, Selection {sel[-1]} (its data)",
                    *(f"{v:.2f}" for v in vals), f"**{min(vals):.2f}**", None])
    return out


def confusable_pairs(conf: pd.DataFrame, threshold: float = 0.25) -> list[tuple[str, str]]:
    """Class pairs (a, b) with a -> b and b -> a each above ``threshold`` of the class.

    Parameters
    ----------
    conf : pandas.DataFrame
        Columns true, predicted, count (one model).
    """
    tot = conf.groupby("true")["count"].sum()
    rate = {(t, p): c / tot[t] for t, p, c in conf[["true", "predicted", "count"]].itertuples(
        index=False) if t != p}
    return [(a, b) for (a, b), r in rate.items()
            if a < b and r > threshold and rate.get((b, a), 0.0) > threshold]


def _diagnosis_md(ds: str, summ: pd.DataFrame, confusion: pd.DataFrame,
                  separability: Mapping | None, primary: RunRef | None) -> list[str]:
    """Per leave-one-gear-out protocol, the diagnosis of the primary run without target
    labels and of the best one (chosen afterwards), on each run's worst split."""
    lines = []
    sd = summ[(summ["dataset"] == ds) & (summ["split"] == "worst")]
    for prot in [p for p in OOD_PROTOCOLS if p in set(sd["protocol"])]:
        chosen = picks(sd[sd["protocol"] == prot], primary, 0)
        runs: dict[tuple, list[str]] = {}
        for who, b in chosen:
            if b is None:
                lines += [f"### Diagnosis: {prot}: {who}", ""]
                continue
            runs.setdefault((b["model"], b["input"], b["worst_of"]), []).append(who)
        for (m, i, split), whos in runs.items():
            c = confusion[(confusion["dataset"] == ds) & (confusion["protocol"] == prot)
                          & (confusion["model"] == m) & (confusion["input"] == i)
                          & (confusion["k_shot"] == 0) & (confusion["split"] == split)]
            if len(c):
                lines += [f"### Diagnosis: {prot}, {row_label(m, i, 0)} ({'; '.join(whos)})",
                          ""] + _diagnosis_of(c, split, _kind(prot),
                                              observable_share(separability, ds, prot))
    return lines


def _diagnosis_of(c: pd.DataFrame, split: str, kind: str, share: pd.Series | None
                  ) -> list[str]:
    """Main confusions, confusable pairs and the observability ceiling of one run on its
    worst split (``c``: its confusion rows there, every seed)."""
    tot = c.groupby("true")["count"].sum()
    off = c[c["true"] != c["predicted"]].groupby(["true", "predicted"], as_index=False)[
        "count"].sum()
    off["rate"] = off["count"] / off["true"].map(tot)
    top = off.sort_values("rate", ascending=False).head(5)
    lines = [f"Main confusions (worst split {split}, counts summed over seeds; share of "
             "the true class):", ""]
    lines += [f"- {r.true} → {r.predicted}: {100 * r.rate:.1f} %" for r in top.itertuples()
              if r.rate > 0] or ["- none: every window classified right"]
    pairs = confusable_pairs(c.groupby(["true", "predicted"], as_index=False)["count"].sum())
    if pairs:
        ceiling = 1.0 - sum(0.5 * (tot[a] + tot[b]) for a, b in pairs) / tot.sum()
        lines += ["", "Confused both ways (> 25 % each): "
                  + ", ".join(f"{a} ↔ {b}" for a, b in pairs) + ". If these classes "
                  "leave no trace in the data, no classifier beats chance between them: "
                  f"accuracy ceiling {100 * ceiling:.1f} %."]
    if share is not None and "reduced_stiffness" in share.index:
        f = float(share["reduced_stiffness"])
        lines += ["", f"Healthy / reduced stiffness: recall {100 * _recall_of(c, 'healthy'):.1f}"
                  f" % / {100 * _recall_of(c, 'reduced_stiffness'):.1f} % (worst split, mean "
                  f"over seeds). Observability ceiling: {100 * f:.1f} % of the {kind} "
                  "reduced-stiffness windows lie beyond the healthy 95th percentile "
                  "(separability below); if the rest are healthy look-alikes, the best "
                  "a classifier can do on these two classes together is "
                  f"{100 * (1 - (1 - f) / 2):.1f} % (calling every look-alike healthy)."]
    return lines + [""]


def _recall_of(conf: pd.DataFrame, cls: str) -> float:
    """Recall of ``cls``, mean over the seeds of ``conf`` (one run, one split)."""
    c = conf[conf["true"] == cls]
    if not c["count"].sum():
        return float("nan")
    hit = c[c["predicted"] == cls].groupby("seed")["count"].sum()
    return float((hit.reindex(c["seed"].unique(), fill_value=0)
                  / c.groupby("seed")["count"].sum()).mean())


def _separability_md(tabs: Mapping[str, pd.DataFrame]) -> list[str]:
    kinds = [k for k in ("clean", "disturbed") if k in tabs and len(tabs[k])]
    if not kinds:
        return []
    p95 = ", ".join(f"{tabs[k].attrs.get('p95', float('nan')):.2f} ({k})" for k in kinds)
    lines = ["### Class separability in the signals (independent of any classifier)", "",
             "Each window reduced to the amplitudes of the first harmonics of the "
             "wave-generator angle in the five bridges and η; its separation = the largest "
             "distance from the healthy windows of the same gear and operating point, in "
             "their spreads (`learn/studies/separability.py`). Healthy windows scored "
             f"leave-one-out reach {p95} at their 95th percentile by chance. Share of each "
             "class beyond it:", ""]
    base = tabs[kinds[-1]].set_index("fault")
    rows = []
    for f in base.index:
        cells = [f"{100 * tabs[k].set_index('fault').loc[f, 'beyond_p95']:.1f} %"
                 for k in kinds]
        med = base["median"].get(f, np.nan) if "median" in base else np.nan
        rows.append([f"{f}", *cells, f"{med:.3g}"])
    return lines + [md_table(["class", *(f"{k} windows" for k in kinds),
                              f"median ({kinds[-1]})"], rows, "l" + "r" * (len(kinds) + 1)), ""]


def _recall_md(recall: pd.DataFrame, summ: pd.DataFrame, primary: RunRef | None,
               separability: Mapping | None, order: Sequence[str]) -> list[str]:
    """Per-class recall at k = 0 of the primary and the best run of each data set, on
    the basis of the accuracy beside it (worst split, mean over seeds)."""
    rec = recall[(recall["protocol"] == "ood_disturbed") & (recall["k_shot"] == 0)]
    if rec.empty:
        return []
    classes = sorted(set(rec["true"]))
    lines = ["## Per-class recall without target labels (ood_disturbed)", "",
             "On the accuracy's basis: each run's worst split (the split of its worst-split "
             "mean accuracy), mean over seeds. The primary run (declared before the "
             "comparison) first; the best run chosen afterwards on the held-out windows "
             "beside it.", ""]
    rows: list[list[str | None]] = []
    for ds in order:
        w = summ[(summ["dataset"] == ds) & (summ["protocol"] == "ood_disturbed")
                 & (summ["split"] == "worst")]
        for who, b in picks(w, primary, 0):
            if b is None:
                rows.append([f"{ds}", f"*{who}*", *[None] * (2 + len(classes))])
                continue
            r = rec[(rec["dataset"] == ds) & (rec["model"] == b["model"])
                    & (rec["input"] == b["input"])].set_index("true")["recall"]
            rows.append([f"{ds}", f"{row_label(b['model'], b['input'], 0)} ({who})",
                         f"{b['worst_of']}", f"{100 * b['mean']:.2f}",
                         *(f"{100 * r.get(c, np.nan):.1f}" for c in classes)])
        share = observable_share(separability, ds, "ood_disturbed")
        if share is not None:
            rows.append([f"{ds}", "*observable: share beyond the healthy p95 (healthy: "
                         "within), all splits*", None, None,
                         *(f"*{100 * share.get(c, np.nan):.1f}*" for c in classes)])
    return lines + [md_table(["data set", "run", "worst split", "accuracy", *classes], rows,
                             "lllr" + "r" * len(classes)), ""]


def write_table(results: pd.DataFrame, confusion: pd.DataFrame, path: str | Path, *,
                targets: Mapping[str, TargetSpec] | None = None, primary: RunRef | None = None,
                separability: Mapping[str, Mapping[str, pd.DataFrame]] | None = None,
                latency: pd.DataFrame | None = None, timings: Mapping | None = None,
                adapt_windows: int | None = None, run_times: pd.DataFrame | None = None
                ) -> Path:
    """Write ``table.md``: headline, targets, per-class recall, then per data set and
    protocol the accuracy [%] per split and worst split (and the paper's RF rows of Tables
    IX and X), a diagnosis and the separability.

    Parameters
    ----------
    results, confusion : pandas.DataFrame
        The comparison's tables.
    path : path
    targets : mapping of str to TargetSpec, optional
    primary : RunRef, optional
        See :func:`target_table`.
    separability : mapping, optional
        Data set -> {"clean", "disturbed"} -> :func:`learn.studies.separability.summary_table`.
    latency : pandas.DataFrame, optional
        :data:`learn.studies.latency.LATENCY_COLUMNS`; its heading says what was timed
        (:func:`learn.studies.latency.latency_heading`).
    timings : mapping, optional
        ``wall_s``, ``input_s``, ``generate_s``, ``threads``, ``cpus``, ``device``.
    adapt_windows : int, optional
        The held-out gear's unlabelled healthy windows the unsupervised adaptations saw
        (``transfer.adapt_windows``); stated in the introduction.
    run_times : pandas.DataFrame, optional
        :data:`learn.transfer.study.RUN_TIME_COLUMNS`: wall and CPU time of every run
        in every job, summed per run and data set in the time section.
    """
    summ = summarise(results)
    recall = class_recall(confusion, summ) if len(confusion) else None
    order = list(dict.fromkeys(results["dataset"]))
    lines = _intro_md(adapt_windows)
    lines += headline_md(headline_table(summ, primary), row_label, order)
    if targets and recall is not None:
        lines += _targets_md(target_table(summ, recall, targets, primary, separability))
    if recall is not None:
        lines += _recall_md(recall, summ, primary, separability, order)
    train_s = results.groupby(CELL_KEYS)["train_s"].mean()
    for ds in order:
        lines += _dataset_md(ds, summ, confusion, recall, separability, primary, train_s)
    if latency is not None and len(latency):
        lines += _latency_md(latency)
    if timings:
        lines += _time_md(results, timings, run_times)
    path = Path(path)
    write_owned(path, lambda tmp: tmp.write_text("\n".join(lines) + "\n"))
    return path


def _intro_md(adapt_windows: int | None) -> list[str]:
    """The introduction of ``table.md``: what the numbers are, what saw which windows."""
    stream = (f"at least {adapt_windows} windows" if adapt_windows is not None
              else "a set of windows")
    return ["# Transfer to the unseen gear: deep learners, MiniRocket and the paper's "
            "pipeline", "",
            "Accuracy [%] on the test windows, mean ± std over seeds; `worst` = the split "
            "with the lowest mean. Leave-one-gear-out splits `gearN` hold out gear N "
            "(paper: `1,2 → 3` is `gear3`); they are scored on the held-out gear's windows "
            "outside the k-shot pool and the unlabelled healthy windows, for every k and every run "
            "alike. The result of a data set is the *primary* run, declared before the "
            "comparison (`transfer.primary`); the *best* run stands beside it, marked "
            f"\"{BEST}\": it describes the results, nothing more.", "",
            "What was chosen on what data: net sizes, epochs, MiniRocket's kernel count and "
            "the list of runs were set for the CPU budget on an earlier data set (random "
            "start angles, no amplifier), before these; early stopping, where enabled, "
            "splits the source gears; MiniRocket's ridge penalty is chosen by "
            "leave-one-out CV on the source windows and kept when its ridge is refitted "
            "with k target windows; fine-tuning runs a fixed number of steps with "
            "source replay. Nothing is chosen on an evaluation window.", "",
            "Unsupervised adaptation (AdaBN, CORAL) sees what a real gear offers without "
            f"labels: its unlabelled healthy windows, {stream} of the held-out gear's "
            "healthy class (whole healthy variants, each one pass over the operating points; "
            "`transfer.adapt_windows`), removed from the evaluation windows; never the "
            "class-balanced k-shot pool. Both align statistics of every source class to "
            "those of the target's healthy windows alone: AdaBN's batch-norm statistics and "
            "CORAL's mean and covariance then describe a healthy gear, not the mixture the "
            "classifier was trained on, so they adapt less than with the class balance of "
            "the held-out windows and may harm; they are kept to show what they do with "
            "the data a gear offers.", ""]


def _targets_md(tt: pd.DataFrame) -> list[str]:
    """The targets section of ``table.md`` (rows of :func:`target_table`)."""
    if not len(tt):
        return []
    lines = ["## Targets", "", "*Observable*: for a class, the share of its windows beyond "
             "the healthy 95th percentile in the evaluated (disturbed) windows; for an "
             "accuracy, their mean over the classes (healthy: 95 %), an estimate of what the "
             "signals carry, not a bound. Accuracies and recalls alike: the run's worst "
             "split, mean over seeds; the primary run first, the best beside it chosen "
             "afterwards on the held-out windows.", ""]
    rows = []
    for r in tt.itertuples():
        obs = "" if np.isnan(r.observable) else f"{100 * r.observable:.1f} %"
        reached = ("—" if r.met is None else
                   f"{100 * r.reached:.2f} % ({'met' if r.met else 'not met'})")
        run = f"{r.run} ({r.who})" if r.run else f"*{r.who}*"
        rows.append([f"{r.dataset}", f"{r.condition}", f"{100 * r.target:.1f} %", run,
                     f"{r.split}", reached, obs])
    return lines + [md_table(["data set", "condition", "target", "run", "worst split", "reached",
                              "observable"], rows, "llrllrr"), ""]


def _dataset_md(ds: str, summ: pd.DataFrame, confusion: pd.DataFrame, recall,
                separability, primary: RunRef | None, train_s: pd.Series) -> list[str]:
    """One data set's section: diagnosis, separability, a table per protocol (a row per
    run and k, with its mean training time: ``train_s`` by :data:`CELL_KEYS`)."""
    lines = [f"## Data set `{ds}`", ""]
    sep = (separability or {}).get(ds)
    if recall is not None:
        lines += _diagnosis_md(ds, summ, confusion, separability, primary)
    if sep:
        lines += _separability_md(sep)
    sd = summ[summ["dataset"] == ds]
    for p in [q for q in ALL_PROTOCOLS if q in set(sd["protocol"])]:
        sp = sd[sd["protocol"] == p]
        splits = sorted({s for s in sp["split"] if s != "worst"},
                        key=lambda s: (_SPLIT_ORDER.get(s, 9), s))
        lines += [f"### {ds}: {p}", "", "Training time: per split and seed, the fit on the "
                  "source gears, or the adaptation alone.", ""]
        rows: list[list[str | None]] = []
        order = sp[sp["split"] == "worst"].sort_values(
            ["k_shot", "model", "input"], key=lambda c: c.map(model_rank)
            if c.name == "model" else c)
        for _, w in order.iterrows():
            cells = []
            for s in splits:
                r = sp[(sp["model"] == w["model"]) & (sp["input"] == w["input"])
                       & (sp["k_shot"] == w["k_shot"]) & (sp["split"] == s)]
                cells.append(f"{100 * r['mean'].iloc[0]:.2f} ± {100 * r['std'].iloc[0]:.2f}"
                             if len(r) else "")
            cells.append(f"**{100 * w['mean']:.2f}** ({w['worst_of']})")
            key = (ds, p, w["model"], w["input"], w["k_shot"])
            cells.append(f"{train_s.get(key, np.nan):.1f}")
            rows.append([row_label(w["model"], w["input"], int(w["k_shot"])), *cells])
        if p in OOD_PROTOCOLS:
            rows += _paper_rows(p, splits)
        lines += [md_table(["run", *splits, "worst", "train [s]"], rows,
                           "l" + "r" * (len(splits) + 2)), ""]
    return lines


def _latency_md(latency: pd.DataFrame) -> list[str]:
    """The latency section of ``table.md``."""
    return [f"## Inference latency per window ({latency_heading(latency)})", "",
            md_table(["model", "input", "input build [ms]", "model [ms]"],
                     [[model_label(r["model"]), f"{r['input']}", f"{r['input_ms']:.2f}",
                       f"{r['model_ms']:.2f}"] for _, r in latency.iterrows()], "llrr"), ""]


def _time_md(results: pd.DataFrame, timings: Mapping,
             run_times: pd.DataFrame | None = None) -> list[str]:
    """The time section of ``table.md``: the whole comparison, then per run the sum of
    its fit and adaptation times and, where measured, of its wall and CPU time in the
    jobs (fit, adaptations and scoring) per data set."""
    tt = results.groupby(["model", "input"])["train_s"].sum().sort_values(ascending=False)
    lines = ["## Time", "",
             f"Whole comparison: {timings.get('wall_s', float('nan')) / 60:.1f} min wall "
             f"time on {timings.get('device', 'CPU')}, {timings.get('threads', '?')} on a "
             f"machine with {timings.get('cpus', '?')} CPU cores (data sets generated "
             f"{timings.get('generate_s', 0.0):.1f} s, inputs "
             f"{timings.get('input_s', float('nan')):.1f} s). Sum of fit times per run "
             "over data sets, splits and seeds (adaptation: the adaptation alone):", "",
             md_table(["model", "input", "train [s]"],
                      [[f"{m}", f"{i}", f"{v:.1f}"] for (m, i), v in tt.items()], "llr"), ""]
    if run_times is None or not len(run_times):
        return lines
    per = run_times.groupby(["model", "input", "dataset"], sort=False)[
        ["seconds", "cpu_s"]].sum()
    order = list(dict.fromkeys(run_times["dataset"]))
    lines += ["Each run in its jobs, fit, adaptations and scoring together, summed over "
              "splits and seeds: wall / CPU seconds of its worker process per data set.", ""]
    rows = []
    for (m, i), g in per.groupby(level=[0, 1], sort=False):
        g = g.droplevel([0, 1])
        cells = [f"{g.loc[d, 'seconds']:.0f} / {g.loc[d, 'cpu_s']:.0f}" if d in g.index
                 else "" for d in order]
        rows.append([f"{m}/{i}", *cells, f"{g['cpu_s'].sum():.0f}"])
    return lines + [md_table(["run", *order, "all, CPU [s]"], rows,
                             "l" + "r" * (len(order) + 1)), ""]
