"""Figure of the transfer comparison (:mod:`learn.transfer.study`): worst-split accuracy
against the number of labelled windows of the held-out gear, ``accuracy_vs_k.png``.

It reads the comparison's ``results`` table (:data:`learn.transfer.study.RESULT_COLUMNS`)
through :func:`learn.transfer.report.summarise`; its tables are in
:mod:`learn.transfer.report`.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from matplotlib import colormaps
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from learn.studies.protocols import OOD_PROTOCOLS
from learn.transfer.report import model_rank, observable_share, row_label, summarise
from learn.transfer.study import TargetSpec
from swgsim.base.lazy import lazy_module
from swgsim.files.ownership import save_figure

pd = lazy_module("pandas")


def plot_accuracy_vs_k(results: pd.DataFrame, path: str | Path,
                       targets: Mapping[str, TargetSpec] | None = None,
                       separability: Mapping | None = None) -> Path:
    """Figure: worst-split accuracy against k, one panel per (data set, leave-one-gear-out
    protocol).

    Solid / dashed lines: a net fine-tuned on all layers / the last layer, dash-dotted:
    MiniRocket's ridge refitted (k = 0 is the model trained on the source gears); dotted
    horizontal lines: runs without target labels (including the unsupervised
    adaptations). One colour per (model, input) in every panel; error bars: std over
    seeds; stars: the accuracy targets of the data set; grey band: the observability
    estimate of the evaluated windows (mean over classes of the share beyond the healthy
    p95, :func:`observable_share`), when ``separability`` is given. One legend below the
    panels.
    """
    summ = summarise(results)
    panels = [(d, p) for d in dict.fromkeys(results["dataset"]) for p in OOD_PROTOCOLS
              if ((results["dataset"] == d) & (results["protocol"] == p)).any()]
    panels = panels or [("", "ood_disturbed")]
    w_all = summ[summ["split"] == "worst"]
    colour = _run_colours(w_all)
    k_max = max(1, int(results["k_shot"].max()) if len(results) else 1)
    ncol = min(3, len(panels))
    nrow = -(-len(panels) // ncol)
    fig = Figure(figsize=(5.2 * ncol, 3.6 * nrow + 0.5 + 0.2 * len(colour)),
                 layout="constrained")
    handles: dict = {}
    for n, (ds, p) in enumerate(panels):
        ax = fig.add_subplot(nrow, ncol, n + 1)
        w = w_all[(w_all["dataset"] == ds) & (w_all["protocol"] == p)]
        _draw_adapted(ax, w, colour, handles)
        _draw_unlabelled(ax, w, colour, handles)
        _draw_targets(ax, (targets or {}).get(ds), p, handles)
        _draw_observable(ax, observable_share(separability, ds, p), handles)
        ax.set_xlim(-0.5, k_max + 0.5)
        ax.set_xlabel("labelled windows per class of the held-out gear, k")
        ax.set_ylabel("accuracy, worst split [%]")
        ax.set_title(f"{ds}: {p}" if ds else p)
        ax.grid(alpha=0.3)
    fig.legend(list(handles.values()), list(handles.keys()), loc="outside lower center",
               ncol=3, fontsize=7, frameon=False)
    return save_figure(fig, path, 130)


def _run_colours(w_all: pd.DataFrame) -> dict:
    """One colour per (model, input, unsupervised adaptation) in every panel."""
    keys = sorted({(m.split("+")[0], i, m.partition("+")[2])
                   for m, i in zip(w_all["model"], w_all["input"], strict=True)
                   if not m.partition("+")[2].startswith("ft_")},
                  key=lambda t: (model_rank(t[0]), t[1], t[2]))
    cmap = colormaps["tab20"]
    return {k: cmap(n % 20) for n, k in enumerate(keys)}


def _draw_adapted(ax, w: pd.DataFrame, colour: Mapping, handles: dict) -> None:
    """Accuracy against k of every run adapted with k labelled windows (k = 0: the
    source model)."""
    styles = {"ft_all": "-", "ft_last": "--", "ft_head": "-."}
    for (m, i), g in w[w["model"].str.contains(r"\+ft_")].groupby(["model", "input"]):
        base_name, _, mode = m.partition("+")
        base = w[(w["model"] == base_name) & (w["input"] == i) & (w["k_shot"] == 0)]
        g = pd.concat([base, g]).sort_values("k_shot")
        ls = styles.get(mode, "-")
        c = colour.get((base_name, i, ""), "k")
        ax.errorbar(g["k_shot"], 100 * g["mean"], yerr=100 * g["std"], marker="o",
                    ms=4, capsize=3, ls=ls, color=c)
        lab = row_label(m, i, 0).replace(" with k=0", "").replace(", k=0", "")
        handles.setdefault(lab, Line2D([], [], color=c, ls=ls, marker="o", ms=4))


def _draw_unlabelled(ax, w: pd.DataFrame, colour: Mapping, handles: dict) -> None:
    """Horizontal lines of the runs without target labels (and the unsupervised
    adaptations), but for those drawn as the k = 0 point of adapted lines."""
    ft_pairs = {(m.partition("+")[0], i) for m, i in zip(w["model"], w["input"],
                                                         strict=True) if "+ft_" in m}
    for _, r in w[w["k_shot"] == 0].iterrows():
        base_name, _, suffix = r["model"].partition("+")
        if not suffix and (base_name, r["input"]) in ft_pairs:
            continue  # drawn as the k = 0 point of its adapted lines
        c = colour[(base_name, r["input"], suffix)]
        ax.axhline(100 * r["mean"], ls=":", lw=1.4, color=c)
        handles.setdefault(row_label(r["model"], r["input"], 0),
                           Line2D([], [], color=c, ls=":", lw=1.4))


def _draw_targets(ax, tgt: TargetSpec | None, protocol: str, handles: dict) -> None:
    """Stars at the data set's accuracy targets, when they refer to ``protocol``."""
    acc_t = tgt.accuracy if tgt is not None else {}
    if acc_t and protocol == tgt.protocol:
        tk = sorted((int(k), 100 * float(v)) for k, v in acc_t.items())
        ax.plot([k for k, _ in tk], [v for _, v in tk], "k*", ms=10)
        handles.setdefault("target (issue)", Line2D([], [], color="k", marker="*", ls="",
                                                    ms=10))


def _draw_observable(ax, share: pd.Series | None, handles: dict) -> None:
    """Grey band at the observability estimate (mean share beyond the healthy p95)."""
    if share is not None:
        ax.axhline(100 * float(share.mean()), color="0.6", lw=6, alpha=0.35, zorder=0)
        handles.setdefault("observability estimate (signals)",
                           Line2D([], [], color="0.6", lw=6, alpha=0.35))
