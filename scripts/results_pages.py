"""Rebuild the tables of the results pages (``docs/results/*.md``) from a run's reports.

Each generated table of a results page sits between two markers in its Markdown source::

    <!-- results:begin paper.scorecard -->
    *Run*: `swgsim-paper` at commit `abc1234`, 2026-11-25 ... Source: `reports/summary.md`.
    | acquisition | table | ... |
    <!-- results:end paper.scorecard -->

This script reads a run's ``reports/`` folder (it reruns nothing: the reports of
``swgsim-paper``, ``swgsim-train experiment=transfer``, ``swgsim-train
experiment=monitor``, ``swgsim-train experiment=prognosis``, ``swgsim-observability``,
``swgsim-export``, ``swgsim-train experiment=benchmark``,
``scripts/monitor_families.py --out`` and
``scripts/calibrate_real.py --out``) and writes each block whose report is there, with
the run named: the command, the commit (``--commit``, else the checkout's HEAD) and the
date the report was written (its modification time). A block showing figures copies them
to the pages' ``figures/`` folder. A block whose report is missing is left as it is, and
said so. The readings around the blocks are not touched.

    python scripts/results_pages.py reports/
    python scripts/results_pages.py reports/ --commit abc1234 --check   # exit 1 if stale

Bad input (no such folder, a page without a block's markers, a report that lacks the
section a block copies) ends in one line naming it, exit code 2, before any page is
written.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import re
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from learn.paper.results import CELL_COLUMNS, our_cells, paper_cells
from learn.paper.summary import recall
from learn.tasks.parts import resumed_note
from swgmon.evaluation.benchmark import BenchmarkConfig
from swgmon.evaluation.benchmark_task import (
    FAMILY_TARGETS,
    SECOND_TARGETS,
    benchmark_targets,
    second_targets,
)
from swgmon.evaluation.report import false_alarm_table, labelled, with_nuisance
from swgsim.files.ownership import atomic_write_bytes
from swgsim.gear.faults import display_name
from swgsim.sensing.sensor_faults import SENSOR_FAULTS

ROOT = Path(__file__).resolve().parents[1]
PAGES = ROOT / "docs" / "results"
BLOCK_RE = re.compile(r"(?P<begin><!-- results:begin (?P<name>[\w.]+) -->\n)(?P<body>.*?)"
                      r"(?P<end><!-- results:end (?P=name) -->)", re.S)


class ReportError(ValueError):
    """A report or page this script cannot use; the message names it."""


@dataclass(frozen=True)
class Block:
    """One generated table: where it goes, what it reads, how it is made.

    Attributes
    ----------
    name : str
        The block's name in its page's markers.
    page : str
        File name of the page in ``docs/results``.
    sources : tuple of str
        Reports it reads, relative to the reports folder (glob patterns allowed); the
        block is rebuilt only when each matches a file.
    command : str
        The command that writes those reports (named on the page).
    build : callable
        ``build(reports) -> str``: the block's Markdown below its run line.
    figures : callable or None
        ``figures(reports) -> {name: file}``: the report images the block's Markdown
        shows as ``figures/<name>``, copied to ``<pages>/figures/<name>`` when the pages
        are written; None: the block shows none.
    """

    name: str
    page: str
    sources: tuple[str, ...]
    command: str
    build: Callable[[Path], str]
    figures: Callable[[Path], dict[str, Path]] | None = None


# ------------------------------------------------------------------- reading markdown
def section(path: Path, title: str, level: int = 2) -> str:
    """Body of the first heading of ``level`` whose text starts with ``title``."""
    text = path.read_text(encoding="utf-8")
    marks = "#" * level
    m = re.search(rf"^{marks} {re.escape(title)}[^\n]*\n(?P<body>.*?)(?=^#{{1,{level}}} |\Z)",
                  text, re.M | re.S)
    if m is None:
        raise ReportError(f"{path}: no section '{marks} {title}...'")
    return m["body"].strip()


def tables_of(body: str) -> str:
    """The Markdown tables of a section (lines starting with ``|``), blank-line separated."""
    out, table = [], []
    for line in body.splitlines() + [""]:
        if line.startswith("|"):
            table.append(line)
        elif table:
            out.append("\n".join(table))
            table = []
    return "\n\n".join(out)


def tidy(md: str) -> str:
    """Report Markdown made safe for the site: images and relative links named, not
    followed (they point into ``reports/``); headings as bold lines."""
    md = re.sub(r"!\[([^\]]*)\]\(([^)\s]+)\)", r"(figure: `\2` in the reports)", md)
    md = re.sub(r"\[([^\]]+)\]\((?![a-z]+:)([^)\s]+)\)", r"\1 (`\2`)", md)
    return re.sub(r"^#{1,6} (.+)$", r"**\1**", md, flags=re.M)


def md_table(df: pd.DataFrame) -> str:
    """A Markdown table of a frame, cells as they are."""
    rows = ["| " + " | ".join(map(str, df.columns)) + " |",
            "|" + "|".join("---" for _ in df.columns) + "|"]
    rows += ["| " + " | ".join(map(str, r)) + " |" for r in df.itertuples(index=False)]
    return "\n".join(rows)


def pct(v: float) -> str:
    """A share in per cent as the pages print it: 3 significant digits, at most 100."""
    return "-" if not np.isfinite(v) else f"{v:.3g}"


# ------------------------------------------------------------------------ the builders
def paper_scorecard(rep: Path) -> str:
    summary = rep / "summary.md"
    card = tables_of(section(summary, "Reproduction scorecard"))
    found = section(summary, "Qualitative findings")
    line = next((x for x in found.splitlines() if x.startswith("Reproduced:")), None)
    if line is None:
        raise ReportError(f"{summary}: no 'Reproduced:' line under 'Qualitative findings'")
    return f"{card}\n\nQualitative findings of Sec. IV {line[0].lower()}{line[1:]}"


def _acquisitions(rep: Path) -> dict[str, Path]:
    """Acquisition name -> its study folder (one with ``results.csv`` and the tables)."""
    return {p.parent.name: p.parent for p in sorted(rep.glob("*/results.csv"))
            if (p.parent / "tables_vii_x.md").is_file()}


#: (table, model, selection, words): the cells the paper's claims rest on.
KEY_CELLS = (("VII", "rf", "selection1", "Table VII, RF, Selection 1 (mean over folds)"),
             ("X", "rf", "selection3", "Table X, RF, Selection 3 (held-out gears)"),
             ("X", "mlp", "selection3", "Table X, MLP, Selection 3 (held-out gears)"))


def _span(v: pd.Series, digits: int) -> str:
    v = v.dropna()
    if v.empty:
        return "-"
    lo, hi = v.min(), v.max()
    return f"{lo:.{digits}f}" if np.isclose(lo, hi) else f"{lo:.{digits}f}-{hi:.{digits}f}"


def paper_key_cells(rep: Path) -> str:
    paper = paper_cells()
    rows = []
    for name, folder in _acquisitions(rep).items():
        ours = our_cells(pd.read_csv(folder / "results.csv"))
        both = paper.merge(ours, on=list(CELL_COLUMNS), how="outer")
        for table, model, sel, words in KEY_CELLS:
            c = both[(both.table == table) & (both.model == model) & (both.selection == sel)]
            rows.append((name, words, _span(c.ours, 1), _span(c.paper, 2)))
    if not rows:
        raise ReportError(f"{rep}: no acquisition folder with results.csv and tables_vii_x.md")
    return md_table(pd.DataFrame(rows, columns=["acquisition", "cell", "ours [%]",
                                                "paper [%]"]))


def paper_phase_lock(rep: Path) -> str:
    rows = {}
    for name, folder in _acquisitions(rep).items():
        r = recall(pd.read_csv(folder / "confusion.csv"))
        r = r[(r.table == "VII") & (r.model == "rf") & (r.selection == "selection1")]
        rows[name] = r.set_index("true").recall * 100.0
    if not rows:
        raise ReportError(f"{rep}: no acquisition folder with confusion.csv")
    tab = pd.DataFrame(rows)
    tab.index = [display_name(c) for c in tab.index]
    tab = tab.map(lambda v: f"{v:.0f}").reset_index(names="class")
    spread = tables_of(section(rep / "summary.md", "What changes when windows are not"))
    return ("RF on Selection 1 (Table VII), per-class recall [%] under each acquisition:\n\n"
            f"{md_table(tab)}\n\nSpread of the clean healthy windows' features and how far "
            "each fault class lies from the healthy median (`reports/summary.md`):\n\n"
            f"{spread}")


#: The figures of an acquisition's folder (``learn/paper/report.py``, the confusion
#: matrices of ``swgsim-paper``) and the caption each gets, in the page's order.
PAPER_FIGURES = (
    ("fig6_signals", "Fig. 6 analogue: healthy (solid) and faulty (dashed) signals s0-s4, "
                     "one panel per fault, and how far each fault moves each signal (RMS "
                     "of the difference, log scale)"),
    ("fig7_dft", "Fig. 7 analogue: the DFT of s0, s1 and the pair differences Δs13, Δs24 "
                 "over the order of the input rotation, every class; below, each fault's "
                 "distance from healthy's (where the small faults show)"),
    ("fig8_disturbed", "Fig. 8 analogue: a healthy window clean (solid) and disturbed by "
                       "eq. (10) (dashed)"),
    ("confusion_VII", "Table VII (4-fold CV, clean): test confusion summed over the "
                      "folds, per selection and model (rows true, columns predicted; the "
                      "title gives the accuracy)"),
    ("confusion_VIII", "Table VIII (4-fold CV, disturbed): test confusion summed over the "
                       "folds"),
    ("confusion_IX", "Table IX (each gear held out, clean): test confusion summed over the "
                     "held-out gears"),
    ("confusion_X", "Table X (each gear held out, disturbed): test confusion summed over "
                    "the held-out gears"),
)


def paper_figure_files(rep: Path) -> dict[str, Path]:
    """``<acquisition>_<figure>.png`` -> the run's file, the paper acquisition first, then
    the others by name; a figure an acquisition lacks is left out."""
    folders = sorted((p for p in rep.iterdir() if p.is_dir()),
                     key=lambda p: (p.name != "paper", p.name))
    return {f"{d.name}_{name}.png": d / f"{name}.png" for d in folders
            for name, _ in PAPER_FIGURES if (d / f"{name}.png").is_file()}


def paper_figures(rep: Path) -> str:
    """The run's figures per acquisition, each with its caption, shown from the pages'
    ``figures/`` folder (:func:`paper_figure_files` names them)."""
    captions = dict(PAPER_FIGURES)
    out, last = [], None
    for copy, file in paper_figure_files(rep).items():
        acq = file.parent.name
        if acq != last:
            out.append(f"**{acq} acquisition** (`reports/{acq}/`):")
            last = acq
        out.append(f"![{acq}: {file.stem}](figures/{copy})\n\n"
                   f"{captions[file.stem]} (`reports/{acq}/{file.name}`).")
    if not out:
        raise ReportError(f"{rep}: no acquisition folder with the paper's figures")
    return "\n\n".join(out)


def transfer_headline(rep: Path) -> str:
    return tidy(section(rep / "transfer" / "table.md", "Headline"))


def transfer_recall(rep: Path) -> str:
    return tidy(section(rep / "transfer" / "table.md", "Per-class recall"))


def monitor_targets(rep: Path) -> str:
    table = rep / "monitor" / "table.md"
    head = table.read_text(encoding="utf-8").split("\n## ", 1)[0].splitlines()[1:]
    intro = " ".join(x for x in head if x.strip())
    return tidy(f"{intro}\n\n{section(table, 'Targets')}")


def _per_gear(v: pd.Series) -> str:
    return " / ".join(f"{x:.2g}" for x in v)


def monitor_real_day(rep: Path) -> str:
    """The monitor's healthy lives per data set and nuisance, per held-out gear; then each
    gear fault at its mildest severity per nuisance: detected lives and median time to
    detect."""
    folder = rep / "monitor"
    res = with_nuisance(labelled(pd.read_csv(folder / "results.csv")))
    fat = false_alarm_table(pd.read_csv(folder / "false_alarms.csv"))
    fat = fat[fat.detector == "monitor"].sort_values("held_out_gear", kind="stable")
    mon = res[(res.detector == "monitor") & ~res.fault.isin(list(SENSOR_FAULTS))]
    mon = mon.assign(detected=mon.detected.astype(bool))
    rows = []
    for (ds, n), g in fat.groupby(["dataset", "nuisance"], sort=False):
        d = mon[(mon.dataset == ds) & (mon.nuisance == n) & mon.detected]
        rows.append({"data set": ds, "nuisance": n,
                     "hours per gear": f"{g.healthy_hours.max():.0f}",
                     "gear-fault alarms per 1000 h, gear 1 / 2 / 3":
                         _per_gear(g.gear_fault_per_1000_h),
                     "advisories per 1000 h": _per_gear(g.advisories_per_1000_h),
                     "sensor-fault alarms per 1000 h": _per_gear(g.sensor_fault_per_1000_h),
                     "unexplained changes per 1000 h": _per_gear(g.unexplained_per_1000_h),
                     "gear faults named right 1 h after the alarm":
                         f"{int((d.fault_after_1h == d.fault).sum())} of {len(d)}"})
    step = mon[mon.onset == "step"]
    mild = step[step.severity.abs() == step.groupby(["dataset", "fault"]).severity.transform(
        lambda v: v.abs().min())]
    cells = mild.groupby(["dataset", "fault", "nuisance"], sort=False).agg(
        n=("detected", "size"), k=("detected", "sum"), sev=("severity", "first"),
        ttd=("time_to_detect_h", lambda t: float(np.nanmedian(t)) * 60 if t.notna().any()
             else np.nan))
    cells["cell"] = [f"{r.k}/{r.n}" + (f", {r.ttd:.3g} min" if np.isfinite(r.ttd) else "")
                     for r in cells.itertuples()]
    wide = cells.cell.unstack("nuisance", sort=False).reset_index()
    wide.insert(2, "mildest", [f"{v:g}" for v in cells.sev.groupby(level=[0, 1],
                                                                   sort=False).first()])
    wide["fault"] = wide.fault.map(display_name)
    wide = wide.rename(columns={"dataset": "data set"})
    return ("Healthy lives of the monitor (held-out gears; five seeds of `nuisance_hours` "
            "per nuisance, of `healthy_hours` stationary):\n\n"
            f"{md_table(pd.DataFrame(rows))}\n\nGear faults at their mildest Table V "
            "severity, step onsets: lives detected of those lived, median time to detect "
            f"of the detected ones:\n\n{md_table(wide.fillna('-'))}")


#: The families table's columns (``scripts/monitor_families.py``'s ``table.csv``) and how
#: each cell prints.
FAMILY_COLUMNS = {
    "gear_fault_alarms_per_1000h": ("gear-fault alarms /1000 h", "{:.0f}"),
    "unexplained_changes_per_1000h": ("unexplained changes /1000 h", "{:.0f}"),
    "advisories_per_1000h": ("advisories /1000 h", "{:.0f}"),
    "targets_detected": ("target faults detected", "{}"),
    "mildest_step_ttd_h": ("median time to detect, mildest step [h]", "{:.2f}"),
    "targets_named_right": ("target faults named right 1 h after", "{:.2f}"),
    "sensor_reported_h": ("failed sensors named, longest [h]", "{}"),
}


def _cells(v: pd.Series, form: str) -> str:
    """A column's values over the held-out gears, ``a / b / c`` (``-``: none)."""
    return " / ".join("-" if pd.isna(x) else form.format(x) for x in v)


def monitor_families(rep: Path) -> str:
    """The monitor through every family of benign changes (``scripts/monitor_families.py
    --out reports/monitor_families/<name>``, one folder per data set and held-out gear):
    per data set, a row per family, each cell its held-out gears' figures in order."""
    t = pd.concat([pd.read_csv(p, keep_default_na=False, na_values=[""])
                   for p in sorted(rep.glob("monitor_families/*/table.csv"))])
    out, walls = [], []
    for ds, d in t.groupby("dataset", sort=False):
        d = d.sort_values("held_out_gear", kind="stable")
        gears = " / ".join(str(g) for g in d.held_out_gear.unique())
        rows = [{"family": f"`{fam}`", **{name: _cells(f[c], form)
                                          for c, (name, form) in FAMILY_COLUMNS.items()}}
                for fam, f in d.groupby("family", sort=False)]
        seeds = ", ".join(sorted(set(d.seeds.astype(str))))
        out.append(f"**{ds}**, held-out gears {gears} (cells in that order); seeds "
                   f"{seeds}:\n\n{md_table(pd.DataFrame(rows))}")
        walls += [f"{ds} gear {g} {w.sum() / 60:.1f} min"
                  for g, w in d.groupby("held_out_gear").wall_s if w.notna().all()]
    wall = (f"Wall time per data set and held-out gear (one process each): "
            f"{', '.join(walls)}." if walls else "Wall times not recorded (tables read "
            "again from the rows, `--read`).")
    return "\n\n".join(out) + f"\n\n{wall}"


def monitor_timing(rep: Path) -> str:
    """Worker-minutes per data set and stage (``timing.json``) and the wall time."""
    t = json.loads((rep / "monitor" / "timing.json").read_text(encoding="utf-8"))
    parts = pd.DataFrame(t["parts"])
    parts["detector"] = parts.detector.fillna("monitor") if "detector" in parts else "monitor"
    g = parts.groupby(["dataset", "detector"], sort=False)[["train_s", "evaluate_s"]].sum()
    g = (g / 60.0).assign(total=lambda x: x.train_s + x.evaluate_s)
    g.loc[("all", ""), :] = g.sum()
    out = g.reset_index().rename(columns={"dataset": "data set", "detector": "part",
                                          "train_s": "train [worker-min]",
                                          "evaluate_s": "evaluate [worker-min]",
                                          "total": "total [worker-min]"})
    for c in out.columns[2:]:
        out[c] = [f"{v:.1f}" for v in out[c]]
    return (f"{_wall(t)}; per data set and part (the monitor "
            "with its diagnosis model, each per-window detector), summed over the held-out "
            f"gears:\n\n{md_table(out)}")


def _wall(t: dict) -> str:
    """The wall time of a ``timing.json``, saying how many parts were resumed."""
    return (f"Wall time **{t['wall_s'] / 60:.1f} min**"
            + resumed_note(int(t.get("resumed", 0)), len(t["parts"])))


def prognosis_section(title: str) -> Callable[[Path], str]:
    """A builder copying the tables of one section of the prognosis's ``table.md``."""
    def build(rep: Path) -> str:
        return tables_of(section(rep / "prognosis" / "table.md", title))
    return build


def prognosis_timing(rep: Path) -> str:
    """Seconds per data set and stage of the prognosis's evaluation (``timing.json``): its
    design part's training and calibration, its lives' parts summed and the longest."""
    t = json.loads((rep / "prognosis" / "timing.json").read_text(encoding="utf-8"))
    parts = pd.DataFrame(t["parts"]).reindex(columns=["dataset", "train_s", "calibrate_s",
                                                      "evaluate_s"])
    parts[parts.columns[1:]] = parts[parts.columns[1:]].apply(pd.to_numeric)
    by = parts.groupby("dataset", sort=False)
    tab = pd.DataFrame({"train [s]": by.train_s.sum(), "calibrate [s]": by.calibrate_s.sum(),
                        "lives [s]": by.evaluate_s.sum(),
                        "longest lives part [s]": by.evaluate_s.max()})
    tab = tab.map(lambda v: f"{v:.0f}").rename_axis("data set").reset_index()
    return (f"{_wall(t)} (target 40); per data set, seconds of one "
            f"worker:\n\n{md_table(tab)}")


def benchmark_targets_block(rep: Path) -> str:
    """The protocol's targets (docs/results/protocol.md) judged on the benchmark's rows:
    per data set, 1-6 per family (the value, ``met`` or ``missed``), then 7 and 8."""
    t = benchmark_targets(pd.read_csv(rep / "benchmark" / "results.csv"),
                          pd.read_csv(rep / "benchmark" / "false_alarms.csv"),
                          BenchmarkConfig().level)  # the targets judge values only
    out = []
    for d, g in t.groupby("dataset", sort=False):
        fam = g[g.family != "pooled"]
        cells = fam.pivot(index="family", columns="target", values="value").reindex(
            fam.family.unique())
        met = fam.pivot(index="family", columns="target", values="met").reindex(cells.index)
        table = pd.DataFrame({f"{n} {q} ({'<=' if most else '>='} {b:g})": [
            f"{v:.3g} {'met' if ok else '**missed**'}" for v, ok in zip(cells[n], met[n],
                                                                        strict=True)]
            for n, q, _, b, most in FAMILY_TARGETS}, index=cells.index).reset_index()
        pooled = g[g.family == "pooled"]
        lines = "\n".join(f"- target {r.target}, {r.question}: monitor "
                          f"{_pair(r.value)}, bound {_pair(r.bound)}: "
                          f"{'met' if r.met else '**missed**'}" for r in pooled.itertuples())
        out.append(f"**{d}**: {int(g.met.sum())} of {len(g)} targets met.\n\n"
                   f"{md_table(table)}\n\n{lines}")
    return "\n\n".join(out)


def benchmark_second(rep: Path) -> str:
    """The second protocol's targets A-F (docs/results/protocol.md) judged on the
    benchmark's rows: per data set, A per family (its instances met, the worst cell with
    its Clopper-Pearson upper bound), B-D per gear fault, then E and F."""
    cfg = BenchmarkConfig()
    t = second_targets(pd.read_csv(rep / "benchmark" / "results.csv"),
                       pd.read_csv(rep / "benchmark" / "false_alarms.csv"),
                       cfg.study.family_growth_h, cfg.level)
    spec = {n: (q, b, most) for n, q, b, most in SECOND_TARGETS}

    def verdict(v: float, ok: bool, judged: bool = True) -> str:
        return f"{v:.3g}" + ("" if not judged else " met" if ok else " **missed**")
    out = []
    for d, g in t.groupby("dataset", sort=False):
        judged = g[g.judged.astype(bool)]
        a = g[g.target == "A"].assign(family=lambda x: x.cell.str.split(", ").str[0])
        fam = pd.DataFrame([{
            "family": f, "instances met": f"{int(x[x.judged].met.sum())} of {int(x.judged.sum())}",
            "worst instance (CP upper)": "{:.2g} ({:.2g})".format(
                *x[x.judged].sort_values("value").iloc[-1][["value", "high"]]),
            "over its lives": f"{x[~x.judged].value.iloc[0]:.2g}"}
            for f, x in a.groupby("family", sort=False)])
        per = g[g.target.isin(["B", "C", "D"])]
        faults = pd.DataFrame([{"fault": fault, "lives": int(x[x.target == "B"].n.iloc[0]),
                                **{f"{n} {spec[n][0]} ({'<=' if spec[n][2] else '>='} "
                                   f"{spec[n][1]:g})": verdict(r.value, r.met, r.judged)
                                   for n in "BCD" for r in x[x.target == n].itertuples()}}
                               for fault, x in per.groupby("cell", sort=False)])
        e = g[g.target == "E"].iloc[0]
        lines = [f"- E, {e.question}: {int(e.value)} of {int(e.n)}: "
                 f"{'met' if e.met else '**missed**'}"]
        lines += [f"- F, {r.question}: monitor {_pair(r.value)}, bound {_pair(r.bound)}: "
                  f"{'met' if r.met else '**missed**'}"
                  for r in g[g.target == "F"].itertuples()]
        out.append(f"**{d}**: {int(judged.met.sum())} of {len(judged)} judged cells met.\n\n"
                   f"A, healthy lives touched (at most 1 in 20: none of an instance's "
                   f"5):\n\n{md_table(fam)}\n\nB-D per gear fault, over every family "
                   f"(reduced stiffness not judged):\n\n{md_table(faults)}\n\n"
                   + "\n".join(lines))
    return "\n\n".join(out)


def _pair(v) -> str:
    return " / ".join(f"{float(x):.3g}" for x in v)


def benchmark_tables_block(rep: Path) -> str:
    """Every detector per data set and family, over the held-out instances (the
    benchmark's ``table.md``, a table per data set)."""
    body = (rep / "benchmark" / "table.md").read_text(encoding="utf-8")
    return "\n\n".join(f"**{sec.splitlines()[0]}**\n\n{tables_of(sec)}"
                         for sec in body.split("\n## ")[1:])


def benchmark_timing(rep: Path) -> str:
    """Seconds per lives part (``timing.json``) and the wall time, resumed parts said."""
    t = json.loads((rep / "benchmark" / "timing.json").read_text(encoding="utf-8"))
    parts = pd.DataFrame(t["parts"])
    g = parts.groupby("dataset", sort=False).wall_s.agg(["count", "sum", "median", "max"])
    g = g.reset_index().rename(columns={"dataset": "data set", "count": "parts",
                                        "sum": "summed [s]", "median": "median [s]",
                                        "max": "longest [s]"})
    for c in g.columns[2:]:
        g[c] = [f"{v:.0f}" for v in g[c]]
    return (f"{_wall(t)} (the last sitting); "
            f"lives parts, seconds of one worker:\n\n{md_table(g)}")


def observability_map(rep: Path) -> str:
    t = pd.read_csv(rep / "observability" / "observability.csv")
    t = t[t.fault != "healthy"]
    piv = t.pivot_table(index="fault", columns="j_out_kgm2", values="fraction_beyond_p95",
                        aggfunc="mean", sort=False) * 100.0
    piv.columns = [f"J_out {j:.2g} kg m²" if i == 0 else f"{j:.2g}"
                   for i, j in enumerate(piv.columns)]
    piv.index = [display_name(f) for f in piv.index]
    return md_table(piv.map(pct).reset_index(names="fault"))


def observability_motion(rep: Path) -> str:
    folder = rep / "observability"
    small = pd.read_csv(folder / "smallest_detectable.csv")
    full = pd.read_csv(folder / "observability_motion.csv")

    def cell(r) -> str:
        if np.isfinite(r.smallest_severity):
            return f"{r.smallest_severity:.2g} ({r.stiffness_left:.2f})"
        g = full[(full.j_out_kgm2 == r.j_out_kgm2) & (full.view == r.view)
                 & (full.fault == r.fault)]
        top = g[g.severity == g.severity.max()]
        return (f"none up to {g.severity.max():.2g} "
                f"({100 * top.fraction_beyond_p95.mean():.0f} %)")

    small["cell"] = [cell(r) for r in small.itertuples()]
    piv = small.pivot_table(index=["fault", "view"], columns="j_out_kgm2", values="cell",
                            aggfunc="first", sort=False)
    piv.columns = [f"J_out {j:.2g} kg m²" if i == 0 else f"{j:.2g}"
                   for i, j in enumerate(piv.columns)]
    out = piv.reset_index()
    out["fault"] = out.fault.map(display_name)
    return md_table(out)


def export_size(rep: Path) -> str:
    s = json.loads((rep / "export" / "size.json").read_text(encoding="utf-8"))

    def val(key: str, unit: str = "") -> str:
        v = s.get(key)
        return f"not measured ({s.get('why', 'no reason given')})" if v is None else f"{v:,}{unit}"

    rows = [("flash (text + data)", val("flash_bytes", " B"), "≤ 32 kB"),
            ("RAM (data + bss + stack high-water mark)", val("ram_bytes", " B"), "≤ 16 kB"),
            ("cycles per window (high bound)", val("cycles_per_window"), "≤ 10 ms at 168 MHz"),
            ("accuracy on the held-out gear, exported Python / C",
             f"{s['accuracy_python']:.4f} / {s['accuracy_c']:.4f}", "within 1 point"),
            ("the full monitor's classifier on the same windows",
             f"{s['accuracy_full_monitor_model']:.4f}", "-")]
    return (f"Data set `{s['dataset']}`, gear {s['held_out_gear']} held out, "
            f"{s['held_out_windows']} held-out windows.\n\n"
            + md_table(pd.DataFrame(rows, columns=["Cortex-M4F", "measured", "target"])))


def calibration_real(rep: Path) -> str:
    rows = []
    for p in sorted((rep / "calibration_real").glob("*/summary.json")):
        s = json.loads(p.read_text(encoding="utf-8"))
        names = [e["name"] for e in s.get("effects_added", [])]
        rows.append((p.parent.name, f"{s['rmse_before']:.4f}", f"{s['rmse_after']:.4f}",
                     f"{s['rmse_after'] / s['rmse_before']:.3f}",
                     f"{len(names)}: {', '.join(names)}" if len(names) > 3
                     else ", ".join(names) or "none"))
    return md_table(pd.DataFrame(rows, columns=["recording", "paper law", "after", "ratio",
                                                "effects added"]))


BLOCKS = (
    Block("paper.scorecard", "paper.md", ("summary.md",), "swgsim-paper", paper_scorecard),
    Block("paper.key_cells", "paper.md", ("*/tables_vii_x.md",), "swgsim-paper",
          paper_key_cells),
    Block("paper.phase_lock", "paper.md", ("*/tables_vii_x.md", "summary.md"), "swgsim-paper",
          paper_phase_lock),
    Block("paper.figures", "paper.md", ("*/fig*.png", "*/confusion_*.png"), "swgsim-paper",
          paper_figures, paper_figure_files),
    Block("transfer.headline", "transfer.md", ("transfer/table.md",),
          "swgsim-train -m experiment=transfer", transfer_headline),
    Block("transfer.recall", "transfer.md", ("transfer/table.md",),
          "swgsim-train -m experiment=transfer", transfer_recall),
    Block("monitor.targets", "monitor.md", ("monitor/table.md",),
          "swgsim-train experiment=monitor", monitor_targets),
    Block("monitor.real_day", "monitor.md",
          ("monitor/results.csv", "monitor/false_alarms.csv"),
          "swgsim-train experiment=monitor", monitor_real_day),
    Block("monitor.families", "monitor.md", ("monitor_families/*/table.csv",),
          "python scripts/monitor_families.py --dataset D --gear G --seeds family --trace "
          "FILE --out reports/monitor_families/D_gG", monitor_families),
    Block("monitor.timing", "monitor.md", ("monitor/timing.json",),
          "swgsim-train experiment=monitor", monitor_timing),
    Block("prognosis.targets", "prognosis.md", ("prognosis/table.md",),
          "swgsim-train experiment=prognosis", prognosis_section("Targets")),
    Block("prognosis.scores", "prognosis.md", ("prognosis/table.md",),
          "swgsim-train experiment=prognosis", prognosis_section("Scores per fault")),
    Block("prognosis.buckets", "prognosis.md", ("prognosis/table.md",),
          "swgsim-train experiment=prognosis", prognosis_section("The 90 % interval")),
    Block("prognosis.changes", "prognosis.md", ("prognosis/table.md",),
          "swgsim-train experiment=prognosis", prognosis_section("After a payload change")),
    Block("prognosis.timing", "prognosis.md", ("prognosis/timing.json",),
          "swgsim-train experiment=prognosis", prognosis_timing),
    Block("observability.map", "observability.md", ("observability/observability.csv",),
          "swgsim-observability", observability_map),
    Block("observability.motion", "observability.md",
          ("observability/smallest_detectable.csv", "observability/observability_motion.csv"),
          "swgsim-observability map=motion", observability_motion),
    Block("export.size", "export.md", ("export/size.json",), "swgsim-export", export_size),
    Block("benchmark.targets", "benchmark.md",
          ("benchmark/results.csv", "benchmark/false_alarms.csv"),
          "swgsim-train experiment=benchmark", benchmark_targets_block),
    Block("benchmark.second", "benchmark.md",
          ("benchmark/results.csv", "benchmark/false_alarms.csv"),
          "swgsim-train experiment=benchmark", benchmark_second),
    Block("benchmark.tables", "benchmark.md", ("benchmark/table.md",),
          "swgsim-train experiment=benchmark", benchmark_tables_block),
    Block("benchmark.timing", "benchmark.md", ("benchmark/timing.json",),
          "swgsim-train experiment=benchmark", benchmark_timing),
    Block("calibration.real", "calibration.md", ("calibration_real/*/summary.json",),
          "python scripts/calibrate_real.py --out reports/calibration_real",
          calibration_real),
)


# ----------------------------------------------------------------------------- the run
def head_commit() -> str:
    """The checkout's HEAD, short; ``unknown`` outside a git checkout."""
    try:
        out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                             capture_output=True, text=True, check=True)
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return out.stdout.strip()


def sources_of(block: Block, rep: Path) -> list[Path] | None:
    """The report files of a block, or None when one of its sources is missing."""
    files = []
    for pattern in block.sources:
        found = sorted(rep.glob(pattern))
        if not found:
            return None
        files += found
    return files


def figure_copies(rep: Path, pages: Path) -> dict[Path, Path]:
    """Where each figure a block of this run shows goes (``<pages>/figures/<name>``) ->
    the run's file; a block whose reports are missing copies none."""
    return {pages / "figures" / name: file for b in BLOCKS
            if b.figures is not None and sources_of(b, rep) is not None
            for name, file in b.figures(rep).items()}


def run_line(block: Block, rep: Path, files: list[Path], commit: str) -> str:
    """The block's first line: the command, the commit and the date of the run."""
    newest = max(files, key=lambda p: p.stat().st_mtime)
    day = dt.datetime.fromtimestamp(newest.stat().st_mtime, dt.UTC).date().isoformat()
    names = ", ".join(f"`reports/{p}`" for p in block.sources)
    return (f"*Run*: `{block.command}` at commit `{commit}`, {day} (when "
            f"`reports/{newest.relative_to(rep)}` was written). Source: {names}, tables "
            "rebuilt by `scripts/results_pages.py`.")


def rebuild(rep: Path, pages: Path, commit: str) -> tuple[dict[Path, str], list[str]]:
    """New text of every page a block of this run changes, and a line per block."""
    texts = {p: p.read_text(encoding="utf-8") for p in sorted(pages.glob("*.md"))}
    for b in BLOCKS:  # every page and marker before any work
        page = pages / b.page
        if page not in texts:
            raise ReportError(f"{page}: missing (block {b.name})")
        if not any(m["name"] == b.name for m in BLOCK_RE.finditer(texts[page])):
            raise ReportError(f"{page}: no markers of block {b.name}")
    notes = []
    for b in BLOCKS:
        files = sources_of(b, rep)
        if files is None:
            notes.append(f"{b.name}: kept (no {' or '.join(b.sources)} in {rep})")
            continue
        body = f"{run_line(b, rep, files, commit)}\n\n{b.build(rep).strip()}\n"
        page = pages / b.page
        texts[page] = BLOCK_RE.sub(
            lambda m, b=b, body=body: (m["begin"] + body + m["end"]) if m["name"] == b.name
            else m[0], texts[page])
        notes.append(f"{b.name}: from {', '.join(b.sources)}")
    return texts, notes


def main(argv: list[str] | None = None) -> int:
    """Command-line entry (module docstring); returns the exit code."""
    ap = argparse.ArgumentParser(prog="results_pages", description=__doc__.split("\n")[0])
    ap.add_argument("reports", type=Path, help="a run's reports/ folder")
    ap.add_argument("--commit", default=None, help="the run's commit (default: HEAD)")
    ap.add_argument("--pages", type=Path, default=PAGES, help="the results pages' folder")
    ap.add_argument("--check", action="store_true",
                    help="write nothing; exit 1 when a page would change")
    args = ap.parse_args(argv)
    try:
        if not args.reports.is_dir():
            raise ReportError(f"reports folder {args.reports} does not exist")
        if not args.pages.is_dir():
            raise ReportError(f"pages folder {args.pages} does not exist")
        texts, notes = rebuild(args.reports.resolve(), args.pages,
                               args.commit or head_commit())
        copies = figure_copies(args.reports.resolve(), args.pages)
    except (ReportError, FileNotFoundError, KeyError, pd.errors.ParserError) as e:
        print(f"results_pages: error: {e}", file=sys.stderr)
        return 2
    changed = [p for p, t in texts.items() if t != p.read_text(encoding="utf-8")]
    figures = [d for d, f in copies.items() if not d.is_file()
               or d.read_bytes() != f.read_bytes()]
    for line in notes:
        print(line)
    if args.check:
        print(f"{len(changed)} page(s) would change: {', '.join(p.name for p in changed)}"
              + (f"; {len(figures)} figure(s)" if copies else ""))
        return 1 if changed or figures else 0
    for p in changed:
        atomic_write_bytes(p, texts[p].encode("utf-8"))
    for d in figures:
        atomic_write_bytes(d, copies[d].read_bytes())
    print(f"{len(changed)} page(s) written: {', '.join(p.name for p in changed) or 'none'}"
          + (f"; {len(figures)} figure(s) copied to {args.pages / 'figures'}" if copies
             else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
