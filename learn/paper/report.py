"""Report of the paper study: Tables VII-X beside the paper's numbers, a CSV, Fig. 6-8.

Files written to ``report_dir`` (e.g. ``reports/paper/``):

* ``tables_vii_x.md`` - our scores beside the paper's (:data:`PAPER_RESULTS`), in the
  paper's layout;
* ``results.csv`` - one row per (table, selection, model, split);
* ``fig6_signals.png``, ``fig7_dft.png``, ``fig8_disturbed.png`` - figures in the manner
  of the paper's Fig. 6-8, drawn from the data set.
"""

from __future__ import annotations

import itertools
import logging
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from learn.inputs.features import order_spectrum, reference_index
from learn.learners.models import model_label
from learn.paper.results import (
    GEAR_SPLITS,
    PAPER_RESULTS,
    PAPER_TABLES,
    SPLIT_LABELS,
    score_text,
)
from swgsim.base.lazy import lazy_module
from swgsim.base.markdown import md_table
from swgsim.files.ownership import save_figure, write_owned
from swgsim.gear.faults import display_name, fault_classes

pd = lazy_module("pandas")

log = logging.getLogger(__name__)

def _table_md(name: str, results: pd.DataFrame) -> list[str]:
    t = PAPER_TABLES[name]
    title, protocol, models, selections = t.title, t.protocol, t.models, t.selection_names
    paper = PAPER_RESULTS[name]
    res = results[results["table"] == name] if "table" in results else results.iloc[:0]
    lines = [f"## Table {name}: {title}", "", f"Protocol `{protocol}`. Cells: ours (paper) [%].",
             ""]
    if name == "VIII":
        lines += ["The paper's Table VIII gives no numbers (its text only quotes some: best "
                  "KNN test score about 80 % and NB 73.72 % on Selection 1, SVM at most about "
                  "47 %), so the paper's cells read (–).", ""]
    # a registered model beyond the paper's (learn.learners.models.register_model)
    models = (*models, *(m for m in dict.fromkeys(res["model"]) if m not in models))
    rows = []
    for sel in selections:
        rows.append([f"**Selection {sel[-1]}**", *[None] * len(models)])
        rs = res[res["selection"] == sel]
        if name in ("VII", "VIII"):
            for kind, label in (("train", "Avg. training score [%]"),
                                ("test", "Avg. test score [%]")):
                rows.append([label, *(_cell(rs.loc[rs["model"] == m, f"{kind}_accuracy"],
                                            paper[sel][m][kind] if paper and m in paper[sel]
                                            else None) for m in models)])
        else:
            for split in GEAR_SPLITS:
                rows.append([SPLIT_LABELS[split], *(_cell(
                    rs.loc[(rs["model"] == m) & (rs["split"] == split), "test_accuracy"],
                    paper[sel][split].get(m) if paper and sel in paper else None)
                    for m in models)])
    return [*lines, md_table([None, *map(model_label, models)], rows, "l" + "r" * len(models)),
            ""]


def _cell(v: pd.Series, ref: float | None) -> str:
    """``ours (paper)`` [%]: the mean of the accuracies ``v`` [-] (– if none), the paper's."""
    ours = 100 * float(v.mean()) if len(v) else None
    return f"{score_text(ours, 2)} ({score_text(ref, 2)})"


def write_tables(
    results: pd.DataFrame,
    path: str | Path,
    timings_s: Mapping[str, float] | None = None,
    dataset_path: str | None = None,
) -> Path:
    """Write ``tables_vii_x.md``: our Tables VII-X beside the paper's numbers.

    Parameters
    ----------
    results : pandas.DataFrame
        One row per (table, selection, model, split) with columns ``table``
        ("VII".."X"), ``selection`` ("selection1"..), ``model`` ("mlp"..), ``split``
        ("fold0".. or "gear1".."gear3"), ``train_accuracy``, ``test_accuracy`` [-]
        (as returned by :func:`learn.paper.task.run_paper_study`). Missing jobs read "–".
    path : path-like
        Markdown file to write.
    timings_s : mapping, optional
        Wall time per table (and ``features``) [s].
    dataset_path : str, optional
        Named in the header.

    Returns
    -------
    Path
    """
    path = Path(path)
    lines = ["# Paper study: our scores beside the paper's", ""]
    if dataset_path:
        lines += [f"Data set: `{dataset_path}`.", ""]
    lines += ["Each cell reads *ours (paper)* in per cent; the paper's numbers are "
              "`learn.paper.results.PAPER_RESULTS`, transcribed from its Tables VII, "
              "IX and X. "
              "CV tables: mean over 4 folds whose groups are (gear, fault, variant); "
              "out-of-distribution tables: test score on the held-out gear.", ""]
    for name in PAPER_TABLES:
        lines += _table_md(name, results)
    if timings_s:
        lines += ["## Run time", "", md_table(["step", "wall time [s]"],
                                              [[k, f"{v:.1f}"] for k, v in timings_s.items()],
                                              "lr"), ""]
    path.parent.mkdir(parents=True, exist_ok=True)
    write_owned(path, lambda tmp: tmp.write_text("\n".join(lines)))
    return path


def _example_windows(ds, gear=None, n_in_rpm=None, t_out_nm=None, disturbed=False):
    """Sample index of one window per class at one operating point of one gear.

    Healthy: variant 0 (lowest); faulty: the most severe variant (lowest variant on ties).
    """
    df = pd.DataFrame({k: np.asarray(ds[k].values) for k in
                       ("gear", "fault", "variant", "severity", "n_in_rpm", "t_out_nm",
                        "disturbed", "reference")})
    df["fault"] = df["fault"].astype(str)
    df = df[~df["reference"].astype(bool) & (df["disturbed"].astype(bool) == disturbed)]
    if df.empty:
        raise ValueError(f"no non-reference windows with disturbed={disturbed}")
    gear = int(df["gear"].min()) if gear is None else gear
    ops = df[df["gear"] == gear][["n_in_rpm", "t_out_nm"]].drop_duplicates()
    ops = ops.sort_values(["n_in_rpm", "t_out_nm"])
    if n_in_rpm is None or t_out_nm is None:
        pick = ops[(ops["n_in_rpm"] == 2000) & (ops["t_out_nm"] == 39)]
        n_in_rpm, t_out_nm = (pick if len(pick) else ops).iloc[0]
    sel = df[(df["gear"] == gear) & (df["n_in_rpm"] == n_in_rpm) & (df["t_out_nm"] == t_out_nm)]
    sel = sel.sort_values(["severity", "variant"], ascending=[False, True])
    idx = {f: int(g.index[0]) for f, g in sel.groupby("fault", sort=False)}
    return idx, int(gear), float(n_in_rpm), float(t_out_nm)


def _align(ref: np.ndarray, other: np.ndarray, channel: int = 1) -> int:
    """Lag [samples] that best aligns ``other`` to ``ref`` (windows start at random WG
    angles): the maximum of the cross-correlation of one zero-mean channel over the first
    half of the window."""
    a = ref[channel] - ref[channel].mean()
    b = other[channel] - other[channel].mean()
    n = a.size
    lags = np.arange(n // 2)
    score = [np.dot(a[: n - k], b[k:]) / (n - k) for k in lags]
    return int(lags[int(np.argmax(score))])


def write_figures(ds, report_dir: str | Path, gear: int | None = None,
                  n_in_rpm: float | None = None, t_out_nm: float | None = None) -> dict[str, Path]:
    """Figures in the manner of the paper's Fig. 6, 7 and 8.

    Fig. 6: the five signals of the healthy gear (solid) and of each faulty class
    (dashed, shifted in time onto the healthy window's WG angle), one panel per fault,
    and a panel of the RMS difference per fault and signal (log scale: a small fault the
    overlay hides shows there). Fig. 7: DFT amplitude of zero-mean s0, s1, ds13 = s1 - s3
    and ds24 = s2 - s4 versus order of the input rotation, one line per class, log scale,
    and below each each fault's distance from healthy's (where the small faults show).
    Fig. 8: clean (solid) versus disturbed (dashed) healthy signals. Legends outside the
    data. One gear and operating point (default: the
    lowest gear at 2000 rpm, 39 N m, where present); the most severe variant of each
    fault.

    Parameters
    ----------
    ds : xarray.Dataset
        Schema-v1 data set.
    report_dir : path-like
    gear : int, optional
    n_in_rpm : float, optional
        Desired input speed [rpm].
    t_out_nm : float, optional
        Desired load torque [N m].

    Returns
    -------
    dict of str to Path
        ``fig6``, ``fig7`` and, if the data set has disturbed windows, ``fig8``.
    """
    report_dir = Path(report_dir)
    report_dir.mkdir(parents=True, exist_ok=True)
    idx, gear, n_in_rpm, t_out_nm = _example_windows(ds, gear, n_in_rpm, t_out_nm)
    where = f"gear {gear}, {n_in_rpm:g} rpm, {t_out_nm:g} N m"
    healthy = idx.get("healthy")
    if healthy is None:  # fall back to the reference window of this operating point
        samples, refs = reference_index(ds)
        healthy = int(refs[np.flatnonzero(np.isin(samples, list(idx.values())))[0]])
    faults = [f for f in fault_classes() if f in idx and f != "healthy"]
    faults += sorted(set(idx) - set(fault_classes()))  # e.g. "unknown" of measured data
    t = np.asarray(ds["time"].values)
    sig = np.asarray(ds["strain_signal"].values)  # (n_samples, 5, n_t), read once
    f_in = np.asarray(ds["n_in_mean_rpm"].values) / 60.0
    rows = [healthy] + [idx[f] for f in faults]
    out = {"fig6": _fig6(t, sig, rows, faults, where, report_dir / "fig6_signals.png"),
           "fig7": _fig7(t, sig[rows], f_in[rows], faults, where, report_dir / "fig7_dft.png")}
    try:
        idx_d, *_ = _example_windows(ds, gear, n_in_rpm, t_out_nm, disturbed=True)
    except ValueError:
        log.info("no disturbed windows: Fig. 8 skipped")
        return out
    common = [f for f in ("healthy", *faults) if f in idx_d and f in idx]
    if not common:
        log.info("no class with clean and disturbed windows: Fig. 8 skipped")
        return out
    out["fig8"] = _fig8(t, sig[idx[common[0]]], sig[idx_d[common[0]]], common[0], where,
                        report_dir / "fig8_disturbed.png")
    return out


_COLORS = [f"C{i}" for i in range(5)]


def _fig6(t, sig, rows: list[int], faults: list[str], where: str, path: Path) -> Path:
    """Fig. 6: healthy (solid, ``rows[0]``) and each faulty class (dashed, the other rows)
    aligned on the WG angle."""
    from matplotlib.figure import Figure

    healthy = rows[0]
    fig = Figure(figsize=(12, 7), layout="constrained")
    axes = fig.subplots(2, 3).ravel()
    rms = np.zeros((len(faults), 5))
    for k, (ax, f, row, letter) in enumerate(zip(axes, faults, rows[1:], "abcdef",
                                                 strict=False)):
        # windows start at random WG angles: shift the faulty one onto the healthy one
        lag = _align(sig[healthy], sig[row])
        n = t.size - lag
        for i in range(5):
            ax.plot(t[:n], sig[healthy, i, :n], color=_COLORS[i], lw=1.0, label=f"$s_{i}$")
            ax.plot(t[:n], sig[row, i, lag:], color=_COLORS[i], lw=1.0, ls="--")
        rms[k] = np.sqrt(np.mean((sig[row, :, lag:] - sig[healthy, :, :n]) ** 2, axis=1))
        ax.set_title(f"({letter}) {display_name(f)}", fontsize=9)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("signal [mV/V]")
    rest = list(axes[len(faults):])
    if rest and faults:  # how far each fault moves each signal: small faults made visible
        ax, width = rest.pop(0), 0.8 / 5
        for i in range(5):
            ax.bar(np.arange(len(faults)) + (i - 2) * width, rms[:, i], width,
                   color=_COLORS[i])
        ax.set_yscale("log")
        ax.set_xticks(range(len(faults)), [display_name(f) for f in faults], rotation=30,
                      fontsize=7, ha="right")
        ax.set_ylabel("RMS faulty − healthy [mV/V]")
        ax.set_title(f"({'abcdef'[len(faults)]}) how far each fault moves each signal",
                     fontsize=9)
    for ax in rest:
        ax.axis("off")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", fontsize=7, ncol=5,
               title="solid: healthy, dashed: faulty", title_fontsize=7)
    fig.suptitle(f"Healthy and faulty sensor signals ({where})", fontsize=10)
    return save_figure(fig, path, 110)


def _fig7(t, sig, f_in, faults: list[str], where: str, path: Path) -> Path:
    """Fig. 7: DFT of s0, s1, ds13 and ds24 against the order, one line per class
    (``sig`` and ``f_in``: healthy first, then ``faults``), and below each view how far
    each fault's amplitude lies from healthy's (a small fault's line lies under a large
    one's above; its difference does not)."""
    from matplotlib.figure import Figure

    orders = np.arange(1, 161) * 0.05  # 0.05 .. 8
    classes = ["healthy", *faults]
    s = sig.astype(np.float64)  # (n_classes, 5, T)
    views = np.stack([s[:, 0], s[:, 1], s[:, 1] - s[:, 3], s[:, 2] - s[:, 4]], axis=1)
    amp = order_spectrum(views, t, f_in, orders)  # (n_classes, 4, n_orders)
    fig = Figure(figsize=(11, 12), layout="constrained")
    axes = fig.subplots(4, 2, sharex=True)
    spectra, diffs = axes[:2].ravel(), axes[2:].ravel()
    names = (r"$\bar s_0$", r"$\bar s_1$", r"$\Delta\bar s_{1,3}$", r"$\Delta\bar s_{2,4}$")
    for j, name in enumerate(names):
        ax, dx = spectra[j], diffs[j]
        for c, cls in enumerate(classes):
            ax.plot(orders, amp[c, j], lw=1.0, color=f"C{c}", label=display_name(cls))
            if c:
                dx.plot(orders, np.abs(amp[c, j] - amp[0, j]), lw=1.0, color=f"C{c}")
        ax.set_title(f"({'abcdefgh'[j]}) DFT of {name}", fontsize=9)
        dx.set_title(f"({'abcdefgh'[4 + j]}) |DFT - healthy's| of {name}", fontsize=9)
        for a in (ax, dx):
            a.set_ylabel("amplitude [mV/V]")
            a.set_yscale("log")  # a small fault's orders beside a large one's
    for a in axes[-1]:
        a.set_xlabel("order of input rotation [-]")
    handles, labels = spectra[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside right upper", fontsize=7)
    fig.suptitle(f"DFT of sensor signals ({where})", fontsize=10)
    return save_figure(fig, path, 110)


def _fig8(t, clean, dist, cls: str, where: str, path: Path) -> Path:
    """Fig. 8: one class's clean (solid) and disturbed (dashed) window, shape (5, n_t)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 4.5), layout="constrained")
    ax = fig.add_subplot()
    for i in range(5):
        ax.plot(t, clean[i], color=_COLORS[i], lw=1.0, label=f"$s_{i}$")
        ax.plot(t, dist[i], color=_COLORS[i], lw=1.0, ls="--")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("signal [mV/V]")
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", fontsize=7,
               ncol=5, title="solid: clean, dashed: disturbed (eq. 10)", title_fontsize=7)
    ax.set_title(f"Clean and disturbed signals, {display_name(cls)} ({where})", fontsize=10)
    return save_figure(fig, path, 110)


def write_confusion_figures(confusion: pd.DataFrame, report_dir: str | Path
                            ) -> dict[str, Path]:
    """One figure of confusion matrices per table: rows the feature selections, columns
    the models, each matrix the test windows of a true class (rows) by the class
    predicted (columns) as a share of the true class, summed over splits.

    Parameters
    ----------
    confusion : pandas.DataFrame
        Columns table, protocol, selection, model, true, predicted, count
        (:data:`learn.paper.study.CONFUSION_COLUMNS`).
    report_dir : path-like

    Returns
    -------
    dict of str to Path
        ``confusion_<table>`` -> ``confusion_<table>.png`` (e.g. ``confusion_VII``).
    """
    from matplotlib.figure import Figure

    out = {}
    for table, tab in confusion.groupby("table", sort=True):
        sels, models = sorted(tab["selection"].unique()), list(dict.fromkeys(tab["model"]))
        classes = list(dict.fromkeys(tab["true"]))
        fig = Figure(figsize=(2.3 * len(models) + 1.0, 2.3 * len(sels) + 0.8),
                     layout="constrained")
        axes = np.atleast_2d(fig.subplots(len(sels), len(models), squeeze=False))
        image = None
        for (i, sel), (j, model) in itertools.product(enumerate(sels), enumerate(models)):
            ax = axes[i, j]
            cell = tab[(tab["selection"] == sel) & (tab["model"] == model)]
            m = (cell.pivot_table(index="true", columns="predicted", values="count",
                                  aggfunc="sum").reindex(index=classes, columns=classes)
                 .fillna(0.0).to_numpy(float))
            share = m / np.maximum(m.sum(axis=1, keepdims=True), 1.0)
            image = ax.imshow(share, vmin=0.0, vmax=1.0, cmap="Blues")
            names = [display_name(c) for c in classes]  # whole: "reduced da..." helps none
            ax.set_xticks(range(len(classes)), names if i == len(sels) - 1 else [],
                          rotation=90, fontsize=6)
            ax.set_yticks(range(len(classes)), names if j == 0 else [], fontsize=6)
            ax.set_title(f"{sel}, {model}: {np.trace(m) / max(m.sum(), 1):.2f}", fontsize=7)
        fig.colorbar(image, ax=axes, shrink=0.6, label="share of the true class")
        fig.suptitle(f"Table {table}: test confusion (rows true, columns predicted)",
                     fontsize=9)
        key = f"confusion_{table}"
        out[key] = save_figure(fig, Path(report_dir) / f"{key}.png", 110)
    return out


def write_report(
    results: pd.DataFrame,
    report_dir: str | Path,
    ds=None,
    timings_s: Mapping[str, float] | None = None,
    dataset_path: str | None = None,
    confusion: pd.DataFrame | None = None,
) -> dict[str, Path]:
    """Write the study's report: tables (markdown), all results (CSV), figures.

    Parameters
    ----------
    results : pandas.DataFrame
        See :func:`write_tables`.
    report_dir : path-like
        Output folder, created if absent.
    ds : xarray.Dataset, optional
        Data set for Fig. 6-8; no figures without it.
    timings_s : mapping, optional
        Wall time per step [s].
    dataset_path : str, optional
    confusion : pandas.DataFrame, optional
        Test confusion counts (table, protocol, selection, model, true, predicted, count),
        written to ``confusion.csv``.

    Returns
    -------
    dict of str to Path
        ``tables`` (tables_vii_x.md), ``csv`` (results.csv), ``confusion``
        (confusion.csv, if given), the figures and ``confusion_<table>`` (one figure of
        confusion matrices per table, :func:`write_confusion_figures`).
    """
    report_dir = Path(report_dir)
    report_dir.mkdir(parents=True, exist_ok=True)
    files = {"tables": write_tables(results, report_dir / "tables_vii_x.md", timings_s,
                                    dataset_path)}
    files["csv"] = report_dir / "results.csv"
    write_owned(files["csv"], lambda tmp: results.to_csv(tmp, index=False))
    if confusion is not None:
        files["confusion"] = report_dir / "confusion.csv"
        write_owned(files["confusion"], lambda tmp: confusion.to_csv(tmp, index=False))
        files.update(write_confusion_figures(confusion, report_dir))
    if ds is not None:
        files.update(write_figures(ds, report_dir))
    log.info("report written to %s", report_dir)
    return files
