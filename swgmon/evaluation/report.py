"""The monitor evaluation's table and figures (``reports/monitor``).

``table.md``: per data set, detector, fault and severity: detection rate, median and
95th-percentile time to detect [min], isolation at the alarm and one hour after (share of
detected lives named correctly), severity error (median ``|estimate − true severity|`` at
the alarm) and, per fault, the smallest severity detected in every life; then false alarms
per 1000 h per held-out gear. Lives under a nuisance of a real day (``nuisance`` other
than ``none``: warm-ups, the hall's heat, run-in, a payload change, all together) are
reported beside the stationary ones: per data set, detector and figure, one column per
nuisance (gear-fault alarms and advisories per 1000 h counted apart, detection, time to
detect at the mildest severity, naming), the per-window detectors under the same
nuisance. Figures: time to detect against severity per fault, false-alarm rate
against time to detect per detector, and the real day (``real_day.png``: alarms and
advisories per nuisance, gear faults at their mildest detected under each).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from swgsim.base.lazy import lazy_module
from swgsim.base.markdown import md_table
from swgsim.files.ownership import atomic_write_bytes, save_figure
from swgsim.gear.faults import FAULTS
from swgsim.sensing.sensor_faults import SENSOR_FAULTS

pd = lazy_module("pandas")


def display(fault: str) -> str:
    """Report name of a gear or sensor fault."""
    if fault in SENSOR_FAULTS:
        return SENSOR_FAULTS[fault].display
    return FAULTS[fault].display if fault in FAULTS else fault


def labelled(df: pd.DataFrame | None) -> pd.DataFrame | None:
    """``df`` with the lives of a joint with an output encoder told apart in the data-set
    label: ``<dataset> (output encoder)`` where the column ``output_encoder`` is True."""
    if df is None or "output_encoder" not in df or not df["output_encoder"].any():
        return df
    enc = df["output_encoder"].fillna(False).astype(bool)
    enc &= ~df["dataset"].astype(str).str.endswith(" (output encoder)")  # labelled once
    return df.assign(dataset=np.where(enc, df["dataset"] + " (output encoder)", df["dataset"]))


def with_nuisance(df: pd.DataFrame | None) -> pd.DataFrame | None:
    """``df`` with the columns of a real day's evaluation where an older one lacks them:
    ``nuisance`` (``none``), and in a false-alarm table ``gear_fault_alarms`` (every alarm
    of a detector that names no fault, the per-window detectors) and ``advisories`` (0
    where the detector gives none)."""
    if df is None:
        return df
    df = df.assign(nuisance=df["nuisance"].fillna("none") if "nuisance" in df else "none")
    if "false_alarms" in df and "healthy_hours" in df:
        gf = df["gear_fault_alarms"] if "gear_fault_alarms" in df else np.nan
        adv = df["advisories"] if "advisories" in df else np.nan
        df = df.assign(gear_fault_alarms=pd.Series(gf, index=df.index).fillna(
            df["false_alarms"]), advisories=pd.Series(adv, index=df.index).fillna(0))
    return df


def summary_table(res: pd.DataFrame) -> pd.DataFrame:
    """Per dataset, nuisance, detector, fault, severity and onset: the table's figures."""
    res = with_nuisance(labelled(res))
    rows = []
    keys = ["dataset", "nuisance", "detector", "fault", "severity", "onset"]
    for k, g in res.groupby(keys, sort=False):
        det = g[g.detected.astype(bool)]
        ttd = det.time_to_detect_h * 60.0
        err = (det.severity_est - det.severity_at_alarm).abs()
        rows.append({**dict(zip(keys, k, strict=True)), "lives": len(g),
                     "detection_rate": len(det) / len(g),
                     "ttd_median_min": float(np.median(ttd)) if len(det) else np.nan,
                     "ttd_p95_min": float(np.percentile(ttd, 95)) if len(det) else np.nan,
                     "isolation_at_alarm": float((det.fault_at_alarm == det.fault).mean())
                     if len(det) else np.nan,
                     "isolation_after_1h": float((det.fault_after_1h == det.fault).mean())
                     if len(det) else np.nan,
                     "severity_error": float(err.median()) if err.notna().any() else np.nan})
    return pd.DataFrame(rows)


GEAR_TARGET_FAULTS = ("eccentric_wg", "reduced_damping", "root_tooth_crack", "tip_tooth_crack")


def targets(res: pd.DataFrame, fa: pd.DataFrame) -> pd.DataFrame:
    """The issue's targets for the monitor, per data set, on the worst held-out gear, on
    the stationary lives (``nuisance`` none; :func:`nuisance_targets` for the others).

    Rows: false alarms per 1000 h (worst gear; target 0 in 1000 h), per gear fault the
    detection rate over every severity and onset (worst gear; target 1), the median time
    to detect at the mildest step severity (worst gear; target <= 30 min), the share named
    correctly one hour after the alarm (all lives; target >= 0.99), sensor faults named
    as a gear fault (count; target 0) and with their faulty bridge (count).
    """
    res, fa = with_nuisance(labelled(res)), with_nuisance(labelled(fa))
    res, fa = res[res.nuisance == "none"], fa[fa.nuisance == "none"]
    mon = res[res.detector == "monitor"].copy()
    mon["detected"] = mon.detected.astype(bool)
    rows = []
    for ds, d in mon.groupby("dataset", sort=False):
        f = fa[(fa.dataset == ds) & (fa.detector == "monitor")]
        per_gear = f.groupby("held_out_gear").agg(h=("healthy_hours", "sum"),
                                                  n=("false_alarms", "sum"))
        worst = float((per_gear.n / per_gear.h * 1000).max())
        rows.append({"dataset": ds, "what": "false alarms per 1000 h (worst gear)",
                     "target": "0", "measured": f"{worst:.3g} ({int(per_gear.n.sum())} in "
                     f"{per_gear.h.sum():.0f} h)"})
        for fault in GEAR_TARGET_FAULTS:
            x = d[d.fault == fault]
            if x.empty:
                continue
            det = x.groupby("held_out_gear").detected.mean().min()
            mild = x[(x.onset == "step") & (x.severity.abs() == x.severity.abs().min())]
            ttd = mild[mild.detected].groupby("held_out_gear").time_to_detect_h.median().max()
            iso = (x[x.detected].fault_after_1h == fault).mean()
            rows += [{"dataset": ds, "what": f"{display(fault)}: detected (worst gear)",
                      "target": "1", "measured": f"{det:.3g}"},
                     {"dataset": ds, "what": f"{display(fault)}: median time to detect at "
                      f"{mild.severity.abs().min():g} [min] (worst gear)", "target": "<= 30",
                      "measured": f"{ttd * 60:.3g}"},
                     {"dataset": ds, "what": f"{display(fault)}: named right 1 h after the "
                      "alarm", "target": ">= 0.99", "measured": f"{iso:.3g}"}]
        sens = d[d.fault.isin(list(SENSOR_FAULTS)) & d.detected]
        wrong = int((~sens.fault_after_1h.isin(list(SENSOR_FAULTS))).sum())
        rows.append({"dataset": ds, "what": "sensor faults named as a gear fault",
                     "target": "0", "measured": f"{wrong} of {len(sens)}"})
        if "bridge_named" in sens:
            right = int((sens.bridge_named == sens.bridge).sum())
            rows.append({"dataset": ds, "what": "sensor faults: faulty bridge named",
                         "target": "-", "measured": f"{right} of {len(sens)}"})
    return pd.DataFrame(rows)


def smallest_detectable(tab: pd.DataFrame) -> pd.DataFrame:
    """Per dataset, detector and fault: the smallest step severity detected in every life
    (NaN when none is)."""
    step = tab[(tab.onset == "step") & (tab.nuisance == "none")]
    out = []
    for k, g in step.groupby(["dataset", "detector", "fault"], sort=False):
        ok = g[g.detection_rate >= 1.0].severity.abs()
        out.append({"dataset": k[0], "detector": k[1], "fault": k[2],
                    "smallest_detectable": float(ok.min()) if len(ok) else np.nan})
    return pd.DataFrame(out)


def false_alarm_table(fa: pd.DataFrame) -> pd.DataFrame:
    """Alarms per 1000 h of healthy operation per dataset, nuisance, detector and held-out
    gear (all seeds): every alarm (``per_1000_h``), the gear-fault alarms among them, the
    sensor-fault alarms (``sensor_fault_per_1000_h``: the monitor named a sensor fault of
    one bridge or the temperature sensor), the unexplained changes
    (``unexplained_per_1000_h``) and the advisories ("outside what commissioning saw"),
    counted apart. A table from before the monitor named unexplained changes (no
    ``sensor_fault_alarms`` column) counts every alarm that is not a gear fault's as a
    sensor fault's, as it was then."""
    fa = with_nuisance(labelled(fa))
    if "sensor_fault_alarms" not in fa:
        fa = fa.assign(sensor_fault_alarms=fa.false_alarms - fa.gear_fault_alarms)
    if "unexplained_changes" not in fa:
        fa = fa.assign(unexplained_changes=0)
    g = fa.fillna({"sensor_fault_alarms": 0, "unexplained_changes": 0}).groupby(
        ["dataset", "nuisance", "detector", "held_out_gear"], sort=False).agg(
        healthy_hours=("healthy_hours", "sum"), false_alarms=("false_alarms", "sum"),
        gear_fault_alarms=("gear_fault_alarms", "sum"), advisories=("advisories", "sum"),
        sensor_fault_alarms=("sensor_fault_alarms", "sum"),
        unexplained_changes=("unexplained_changes", "sum"))
    for col, n in (("per_1000_h", "false_alarms"), ("gear_fault_per_1000_h", "gear_fault_alarms"),
                   ("sensor_fault_per_1000_h", "sensor_fault_alarms"),
                   ("unexplained_per_1000_h", "unexplained_changes"),
                   ("advisories_per_1000_h", "advisories")):
        g[col] = g[n] / g.healthy_hours * 1000.0
    return g.reset_index()


def _real_day_figures(res: pd.DataFrame, fat: pd.DataFrame) -> list[tuple[str, str, float]]:
    """One data set's, detector's and nuisance's lives: (figure, target, value) on the
    worst held-out gear (:func:`nuisance_table`)."""
    out = [("gear-fault alarms per 1000 h (worst gear)", "0",
            float(fat.gear_fault_per_1000_h.max()) if len(fat) else np.nan),
           ("alarms naming a sensor fault per 1000 h (worst gear)", "0",
            float(fat.sensor_fault_per_1000_h.max()) if len(fat) else np.nan),
           ("unexplained changes per 1000 h (worst gear)", "-",
            float(fat.unexplained_per_1000_h.max()) if len(fat) else np.nan),
           ("advisories per 1000 h (worst gear)", "-",
            float(fat.advisories_per_1000_h.max()) if len(fat) else np.nan),
           ("healthy hours (all gears and seeds)", "-", float(fat.healthy_hours.sum()))]
    x = res[res.fault.isin(GEAR_TARGET_FAULTS) & (res.onset == "step")]
    if x.empty:
        return out
    x = x.assign(detected=x.detected.astype(bool))
    det = x.groupby(["fault", "held_out_gear"]).detected.mean().min()
    mild = mildest_steps(x)
    ttd = mild[mild.detected].groupby(["fault", "held_out_gear"]).time_to_detect_h.median()
    named = (x[x.detected].fault_after_1h == x[x.detected].fault).mean()
    return out + [("gear faults detected (worst fault and gear)", "1", float(det)),
                  ("median time to detect at the mildest severity [min] (worst fault "
                   "and gear)", "<= 60", float(ttd.max() * 60) if len(ttd) else np.nan),
                  ("gear faults named right 1 h after the alarm", ">= 0.99", float(named))]


def nuisance_table(res: pd.DataFrame, fa: pd.DataFrame) -> pd.DataFrame:
    """The stationary lives beside each nuisance's: per data set, detector and figure
    (:func:`_real_day_figures`) one column per nuisance, ``none`` first; empty when no
    life lived a nuisance."""
    res, fa = with_nuisance(labelled(res)), with_nuisance(labelled(fa))
    if set(fa.nuisance) <= {"none"}:
        return pd.DataFrame()
    fat = false_alarm_table(fa)
    rows = []
    for (ds, d, n), f in fat[fat.detector != "always"].groupby(
            ["dataset", "detector", "nuisance"], sort=False):
        r = res[(res.dataset == ds) & (res.detector == d) & (res.nuisance == n)]
        rows += [{"dataset": ds, "detector": d, "what": w, "target": t, "nuisance": n,
                  "value": v} for w, t, v in _real_day_figures(r, f)]
    tab = pd.DataFrame(rows)
    order = list(dict.fromkeys(["none", *tab.nuisance]))
    wide = tab.set_index(["dataset", "detector", "what", "target", "nuisance"])[
        "value"].unstack("nuisance", sort=False)
    return wide.reindex(columns=order).reset_index()


def write_table(res: pd.DataFrame, fa: pd.DataFrame, path: Path, header: str = "") -> str:
    """``table.md`` (module docstring); returns its text."""
    tab = summary_table(res)
    tab["fault"] = tab.fault.map(display)
    small = smallest_detectable(summary_table(res))
    small["fault"] = small.fault.map(display)
    seeds = res.seed.nunique() if "seed" in res else 0
    real = nuisance_table(res, fa)
    sections = [(f"## Targets (monitor; held-out gears, {seeds} seed(s))\n", targets(res, fa)),
                *[("\n## A real day: stationary lives beside each nuisance (held-out gears, "
                   "worst gear, all seeds; per-window detectors under the same nuisance)\n",
                   real)] * bool(len(real)),
                ("\n## Detection and isolation per fault and severity (held-out gears, all "
                 "seeds)\n", tab),
                ("\n## Smallest severity detected in every life (step onsets)\n", small),
                ("\n## False alarms in healthy operation\n", false_alarm_table(fa))]
    text = [header] + [x for title, t in sections for x in
                       (title, md_table(t.columns, t.itertuples(index=False), nan="-"))] + [""]
    out = "\n".join(text)
    atomic_write_bytes(path, out.encode())
    return out


def figures(res: pd.DataFrame, fa: pd.DataFrame, out_dir: Path,
            curve: pd.DataFrame | None = None) -> list[Path]:
    """Time to detect against severity per fault; false-alarm rate against time to detect:
    the monitor's rule at the design rates of ``curve`` (``tradeoff.csv``), and the
    per-window and always-alarm detectors; on the stationary lives. Then, where lives
    lived a nuisance, :func:`real_day_figure`."""
    import matplotlib

    res_all, fa_all = res, fa
    res, fa, curve = with_nuisance(labelled(res)), with_nuisance(labelled(fa)), labelled(curve)
    res, fa = res[res.nuisance == "none"], fa[fa.nuisance == "none"]  # the stationary lives
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    mon = res[(res.detector == "monitor") & (res.onset == "step")]
    faults = list(dict.fromkeys(mon.fault))
    ncol = 4
    nrow = -(-len(faults) // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(2.9 * ncol, 2.6 * nrow), squeeze=False)
    top = float(np.nanmax(mon.time_to_detect_h.to_numpy(float) * 60, initial=60.0)) * 1.5
    index = {ds: i for i, ds in enumerate(dict.fromkeys(mon.dataset))}  # one colour each
    for ax, f in zip(axes.flat, faults, strict=False):
        for ds, g in mon[mon.fault == f].groupby("dataset", sort=False):
            i = index[ds]
            det = g.detected.astype(bool)
            jit = (i - 0.5) * 0.02 * g.severity.abs().max()
            ax.plot(g.severity.abs()[det] + jit, g.time_to_detect_h[det] * 60, "o", ms=3,
                    alpha=0.5, color=f"C{i}", label=ds)
            ax.plot(g.severity.abs()[~det] + jit, np.full((~det).sum(), top), "x", ms=4,
                    color=f"C{i}")
        ax.axhline(30, color="0.5", lw=0.8, ls="--")
        ax.set_yscale("log")
        ax.set_title(display(f), fontsize=9)
        ax.set_xlabel("severity", fontsize=8)
    for ax in axes.flat[len(faults):]:
        ax.set_visible(False)
    for ax in axes[:, 0]:
        ax.set_ylabel("time to detect [min]", fontsize=8)
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("Monitor: time to detect per life, held-out gears, step onsets (dashed: 30 "
                 "min; x: not detected within the fault life)", fontsize=9)
    p = _save(fig, out_dir / "time_to_detect.png")
    paths.append(p)

    fat = false_alarm_table(fa).groupby(["dataset", "detector"]).per_1000_h.max()
    tab = summary_table(res)
    ttd = tab.groupby(["dataset", "detector"]).ttd_median_min.median()
    fig, ax = plt.subplots(figsize=(5.6, 3.8))
    floor = 0.1
    if curve is not None and len(curve):
        for i, (ds, c) in enumerate(curve.groupby("dataset", sort=False)):
            hh = c[c.life == "healthy"].groupby("design_hours")
            rate = hh.false_alarms.sum() / hh.healthy_hours.sum() * 1000
            f = c[(c.life == "fault") & c.fault.isin(GEAR_TARGET_FAULTS)]
            med = f.assign(t=f.time_to_detect_h.fillna(np.inf) * 60).groupby(
                "design_hours").t.median()
            ax.plot(np.maximum(rate, floor), med.reindex(rate.index), "o-", color=f"C{i}",
                    label=f"monitor, {ds} (design 1 per 1-1000 h)")
            ax.plot(1000 / rate.index.to_numpy(float), med.reindex(rate.index), ":",
                    color=f"C{i}", lw=0.8)
    others = [d for d in dict.fromkeys(fat.index.get_level_values(1)) if d != "monitor"]
    sets = list(dict.fromkeys(fat.index.get_level_values(0)))
    for (ds, d), v in fat.items():
        if d == "monitor":
            continue
        ax.plot(max(v, floor), ttd.get((ds, d), np.nan), "s^Dv"[sets.index(ds) % 4], ms=5,
                color=f"C{2 + others.index(d) % 8}", alpha=0.8,
                label=f"{d.replace('_', '-')}, {ds}")
    ax.set_xscale("log")
    ax.axvline(1.0, color="0.5", lw=0.8, ls="--")
    ax.set_xlabel(f"false alarms per 1000 h, measured (0 drawn at {floor})")
    ax.set_ylabel("median time to detect [min]")
    ax.set_title("False-alarm rate against time to detect (gear faults but stiffness; dotted: "
                 "at the design rate)", fontsize=8)
    ax.legend(fontsize=6)
    p = _save(fig, out_dir / "false_alarms_vs_ttd.png")
    paths.append(p)
    return paths + real_day_figure(res_all, fa_all, out_dir)


def _save(fig, path: Path) -> Path:
    """Lay out, write at 130 dpi and close a figure; its path."""
    fig.tight_layout()
    return save_figure(fig, path, 130)


def mildest_steps(res: pd.DataFrame, by: tuple[str, ...] = ("fault",)) -> pd.DataFrame:
    """The rows of the target gear faults' (:data:`GEAR_TARGET_FAULTS`) step-onset lives
    at each fault's mildest severity (the smallest magnitude per ``by`` group)."""
    x = res[res.fault.isin(GEAR_TARGET_FAULTS) & (res.onset == "step")]
    return x[x.severity.abs() == x.groupby(list(by)).severity.transform(
        lambda v: v.abs().min())]


def _mildest_detected(res: pd.DataFrame) -> pd.DataFrame:
    """Share of the monitor's step-onset lives detected at each gear fault's mildest
    severity, per data set, nuisance and fault (all held-out gears and seeds)."""
    x = mildest_steps(res[res.detector == "monitor"], ("dataset", "fault"))
    return x.assign(detected=x.detected.astype(bool)).groupby(
        ["dataset", "nuisance", "fault"], sort=False).detected.agg(["mean", "size"])


def real_day_figure(res: pd.DataFrame, fa: pd.DataFrame, out_dir: Path) -> list[Path]:
    """``real_day.png``: per data set whose monitor lived a nuisance, its gear-fault alarms
    and advisories per 1000 h (worst held-out gear) under each nuisance beside the
    stationary lives, and the share of lives in which each gear fault at its mildest
    severity was detected; ``[]`` when no life lived a nuisance."""
    import matplotlib

    res, fa = with_nuisance(labelled(res)), with_nuisance(labelled(fa))
    fa = fa[fa.detector == "monitor"]
    sets = [d for d in dict.fromkeys(fa.dataset)
            if set(fa[fa.dataset == d].nuisance) - {"none"}]
    if not sets:
        return []
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fat = false_alarm_table(fa).groupby(["dataset", "nuisance"], sort=False)[
        ["gear_fault_per_1000_h", "advisories_per_1000_h"]].max()
    det = _mildest_detected(res)
    fig, axes = plt.subplots(len(sets), 2, figsize=(11, 2.9 * len(sets)), squeeze=False)
    for (a1, a2), ds in zip(axes, sets, strict=True):
        f = fat.loc[ds]
        x = np.arange(len(f))
        for k, (col, lab) in enumerate((("gear_fault_per_1000_h", "gear-fault alarms"),
                                        ("advisories_per_1000_h", "advisories"))):
            bars = a1.bar(x + (k - 0.5) * 0.38, f[col], 0.38, label=lab,
                          color=("C3", "0.6")[k])
            a1.bar_label(bars, fmt="%.3g", fontsize=6)
        a1.set_xticks(x, f.index, fontsize=7)
        a1.tick_params(labelsize=7)
        a1.set_ylabel("per 1000 h, worst gear", fontsize=8)
        a1.set_title(f"{ds}: healthy lives (target: no gear-fault alarm)", fontsize=8)
        a1.legend(fontsize=6)
        if ds in det.index.get_level_values(0):
            d = det.loc[ds]["mean"].unstack("fault")
            d.plot.bar(ax=a2, rot=0, width=0.8, fontsize=7, legend=False)
            a2.legend(a2.get_legend_handles_labels()[0], [display(c) for c in d.columns],
                      fontsize=6, loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=4,
                      frameon=False)
            a2.axhline(1.0, color="0.5", lw=0.8, ls="--")
            a2.set_ylim(0, 1.05)
        a2.set_xlabel("")
        a2.set_ylabel("share of lives detected", fontsize=8)
        a2.set_title(f"{ds}: gear faults at their mildest severity", fontsize=8)
    fig.suptitle("The monitor through a real day: each nuisance beside the stationary "
                 "lives (none)", fontsize=9)
    p = _save(fig, out_dir / "real_day.png")
    return [p]


__all__ = ["display", "false_alarm_table", "figures", "mildest_steps", "nuisance_table",
           "real_day_figure",
           "smallest_detectable",
           "summary_table", "targets", "with_nuisance", "write_table"]
