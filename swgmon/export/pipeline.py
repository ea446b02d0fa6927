"""The export: train the exported classifier, write the C, check it, measure it.

Steps (:func:`run_export`): the training gears' windows through the stage's Python
reference (:mod:`.data`), a random forest on them sized by the flash budget
(:mod:`.forest`); the held-out gear's normal behaviour from its commissioning and its labelled
windows; the C files (:mod:`.cgen`); the C compiled for the host and run on every
held-out window (:mod:`.host`: classes against the Python pipeline's, features against
the reference's); with the cross tools, flash, RAM and cycles on a Cortex-M4F
(:mod:`.target`). Beside them, for honesty, the per-window accuracy on the same held-out
windows of the full monitor's classifier (its histogram gradient boosting on its own
least-squares features, trained on the same training gears) and the reference features'
error against the monitor's.
"""

from __future__ import annotations

import dataclasses
import logging
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from swgmon.evaluation.study import MonitorStudyConfig
from swgmon.evaluation.training import classes
from swgmon.export import cgen, forest, host, target
from swgmon.export import reference as ref
from swgmon.export.data import base_tables, gear_windows, nominal_phi, plan_points, with_normal
from swgsim.base.typed import allowed
from swgsim.sensing.sensor_faults import SENSOR_FAULTS

log = logging.getLogger(__name__)


@dataclass
class ExportOptions:
    """What the export trains and measures.

    Attributes
    ----------
    held_out_gear : int
        The gear whose normal behaviour the C holds and on whose windows it is judged.
    n_trees : int
        Trees of the forest.
    forest_bytes : int
        Flash for the forest's decision nodes [bytes] (sets ``max_leaf_nodes``).
    commissioning_h, train_healthy_h, train_fault_h : float
        Hours of each gear's commissioning, healthy life after it, and fault lives
        (:class:`swgmon.evaluation.study.MonitorStudyConfig`).
    train_variants : int
        Fault positions per gear fault and severity.
    faults : list of str
        Classes besides healthy; empty: every gear fault of the data set and every
        sensor fault.
    full_model : bool
        Also train the full monitor's classifier and report its accuracy beside.
    seed : int
    """

    held_out_gear: int = 3
    n_trees: int = field(default=10, metadata=allowed(1, 255, "trees"))
    forest_bytes: int = field(default=12288, metadata=allowed(16, 1 << 20, "bytes"))
    commissioning_h: float = field(default=8.0, metadata=allowed(0.1, None, "hours"))
    train_healthy_h: float = field(default=2.0, metadata=allowed(0.1, None, "hours"))
    train_fault_h: float = field(default=0.5, metadata=allowed(0.05, None, "hours"))
    train_variants: int = field(default=3, metadata=allowed(1, 60, "positions"))
    faults: list[str] = field(default_factory=list)
    full_model: bool = True
    seed: int = 0

    def study(self) -> MonitorStudyConfig:
        """The lives' design as the monitor's study config."""
        return MonitorStudyConfig(commissioning_h=self.commissioning_h,
                                  train_healthy_h=self.train_healthy_h,
                                  train_fault_h=self.train_fault_h,
                                  train_variants=self.train_variants,
                                  faults=list(self.faults), detectors=[])


def feature_error(feats32: np.ndarray, feats64: np.ndarray, n_harmonics: int) -> dict:
    """Largest ``|reference − monitor least squares|`` per feature kind (offset and
    amplitudes [mV/V], log10 residual RMS [-], efficiency)."""
    d = np.abs(feats32.astype(float) - feats64)
    k = np.arange(d.shape[1] - 1) % (n_harmonics + 2)
    pick = {"offset_mvv": k == 0, "amplitude_mvv": (k >= 1) & (k <= n_harmonics),
            "log10_rest": k == n_harmonics + 1}
    out = {n: float(d[:, :-1][:, m].max()) if len(d) else 0.0 for n, m in pick.items()}
    out["efficiency"] = float(d[:, -1].max()) if len(d) else 0.0
    return out


def check_gears(plan, opts: ExportOptions) -> tuple[list[int], int]:
    """Training gears and the held-out one.

    Raises
    ------
    ValueError
        If ``held_out_gear`` is not a gear of the data set, no training gear is left, or
        ``faults`` names a class the data set does not have.
    """
    gears = [int(g.id) for g in plan.config.gears]
    if opts.held_out_gear not in gears:
        raise ValueError(f"export.held_out_gear={opts.held_out_gear}: not a gear of the data "
                         f"set; allowed: {gears}")
    train = [g for g in gears if g != opts.held_out_gear]
    if not train:
        raise ValueError("the data set has no gear to train on besides the held-out one")
    allowed_faults = [f for f in plan.config.variants if f != "healthy"] + list(SENSOR_FAULTS)
    unknown = [f for f in opts.faults if f not in allowed_faults]
    if unknown:
        raise ValueError(f"export.faults: {unknown} not among the data set's gear faults "
                         f"and the sensor faults; allowed: {allowed_faults}")
    return train, opts.held_out_gear


def train_stage(plan, opts: ExportOptions):
    """Tables, the forest, the held-out gear's windows and the training gears' ones."""
    train, g_out = check_gears(plan, opts)
    tables0 = base_tables(plan)
    study = opts.study()
    tr = [gear_windows(plan, g, study, tables0) for g in train]
    x = np.concatenate([ref.design_rows(w.feats, with_normal(tables0, w), w.op) for w in tr])
    y = np.concatenate([w.y for w in tr])
    missing = sorted(set(range(len(classes(plan, study)))) - set(y.tolist()))
    if missing:
        raise ValueError(f"the training gears have no windows of classes {missing}")
    rf = forest.fit_forest(x, y, opts.n_trees, opts.forest_bytes, opts.seed)
    held = gear_windows(plan, g_out, study, tables0, keep=True)
    return with_normal(tables0, held), rf, held, tr


def full_model_accuracy(plan, tr, held, seed: int) -> float:
    """Per-window accuracy on the held-out windows of the monitor's own classifier (its
    histogram gradient boosting, as swgmon.assessment.model, on its float64 least-squares
    features z-scored against each gear's normal behaviour), trained on the training gears."""
    from sklearn.ensemble import HistGradientBoostingClassifier

    def rows(w):
        z = (w.feats64 - w.mean64[w.op]) * w.inv_std64[w.op]
        return np.concatenate([z, plan_points(plan)[w.op]], axis=1)

    x = np.concatenate([rows(w) for w in tr])
    y = np.concatenate([w.y for w in tr])
    clf = HistGradientBoostingClassifier(max_iter=200, learning_rate=0.1,
                                         early_stopping=False, random_state=seed).fit(x, y)
    return float(np.mean(clf.predict(rows(held)) == held.y))


def host_check(out: Path, tables: ref.StageTables, held, py_cls, py_ph) -> dict:
    """The C compiled for the host on every held-out window against the Python
    pipeline (classes, P(healthy), features)."""
    if host.find_cc() is None:
        return {"host_c": "not checked: no C compiler (cc) on PATH"}
    with tempfile.TemporaryDirectory(prefix="swg_host_") as tmp:
        try:
            lib = host.build(out, Path(tmp) / "libswg.so")
        except RuntimeError as e:  # the compiler failed: reported, the run goes on
            return {"host_c": f"not checked: {e}", "failed": str(e)}
        cls, ph, feats = host.HostStage(lib, tables.n_features).run(
            held.signals, nominal_phi(tables, held.op), held.op, held.efficiency)
    d = np.abs(feats.astype(float) - held.feats.astype(float))
    return {"windows": int(len(cls)), "classes_equal": int(np.sum(cls == py_cls)),
            "p_healthy_max_abs_diff": float(np.max(np.abs(ph - py_ph))) if len(ph) else 0.0,
            "features_max_abs_diff": float(d.max()) if d.size else 0.0,
            "features_bit_equal_share": float(np.mean(feats == held.feats)) if d.size else 1.0,
            "accuracy_c": float(np.mean(cls == held.y)), "c_classes": cls}


def run_export(plan, dataset: str, opts: ExportOptions, out: Path, cross: bool = True,
               app: str = "swgsim-export") -> dict:
    """Train, write, check and measure the embedded stage (module docstring).

    Parameters
    ----------
    plan : DatasetPlan
        The checked data set whose gears live.
    dataset : str
        Its name (for the header and the summary).
    opts : ExportOptions
    out : Path
        Output folder: claimed (:func:`swgsim.files.ownership.claim`; refused before any work
        if it holds a file this project cannot show it wrote), then the C files,
        ``summary.json`` and ``size.json``.
    cross : bool
        Measure on the Cortex-M4F when the cross tools are there.
    app : str
        Name recorded in the folder's ownership stamp.

    Returns
    -------
    dict
        The summary (also ``out/summary.json``); ``size`` the content of ``size.json``;
        ``failed`` the external tools that failed, one line each (the host compiler, a
        cross tool: the figures they give are reported as not measured, with why).

    Raises
    ------
    ValueError
        Bad options, a foreign file in ``out``, or a model the C cannot represent.
    """
    from swgsim.files import ownership
    from swgsim.files.ownership import atomic_write_json

    out = Path(out)
    ownership.check(out, "out_dir", app=app)
    tables, rf, held, tr = train_stage(plan, opts)
    code, info = forest.to_c(rf)
    xh = ref.design_rows(held.feats, tables, held.op)
    py_cls, py_ph = forest.predict(rf, xh)
    cls = classes(plan, opts.study())
    train_gears = [w.gear for w in tr]
    summary = {"dataset": dataset, "held_out_gear": held.gear, "train_gears": train_gears,
               "classes": cls, "options": dataclasses.asdict(opts), "forest": info,
               "accuracy_python": float(np.mean(py_cls == held.y)),
               "accuracy_sklearn_soft_vote": float(np.mean(
                   rf.predict(xh.astype(float)) == held.y)),
               "features_vs_monitor_least_squares": feature_error(
                   held.feats, held.feats64, tables.n_harmonics),
               "windows": {"train": int(sum(len(w.y) for w in tr)), "held_out": len(held.y)}}
    if opts.full_model:
        summary["accuracy_full_monitor_model"] = full_model_accuracy(plan, tr, held, opts.seed)
    with ownership.claim(out, app, strict=True, fresh=True) as claim:
        files = cgen.write_sources(out, tables, cls, code, {
            "dataset": dataset, "gear": held.gear,
            "train_gears": ", ".join(map(str, train_gears))})
        chk = host_check(out, tables, held, py_cls, py_ph)
        c_cls = chk.pop("c_classes", None)
        summary["host_c"] = chk
        summary["target"] = target_figures(out, tables, held, c_cls, cross)
        summary["failed"] = [x["failed"] for x in (chk, summary["target"]) if "failed" in x]
        summary["size"] = size_record(summary)
        atomic_write_json(out / "size.json", summary["size"])
        atomic_write_json(out / "summary.json", summary)
        claim.record([*files, out / "size.json", out / "summary.json"])
    summary["files"] = [str(p) for p in files]
    return summary


def target_figures(out: Path, tables: ref.StageTables, held, c_cls, cross: bool) -> dict:
    """Cortex-M4F figures on the first held-out window, or why there are none."""
    why = target.missing_tools() if cross else "not asked (cross=false)"
    if why:
        return {"measured": False, "why": why}
    i = 0
    try:
        res = target.measure(out, held.signals[i], nominal_phi(tables, held.op[i:i + 1])[0],
                             int(held.op[i]), float(held.efficiency[i]))
    except target.ToolError as e:  # reported in size.json and summary.json, not raised
        return {"measured": False, "why": str(e), "failed": str(e)}
    bits = [f"{v:08x}" for v in held.feats[i].view(np.uint32)]
    res["target_features_equal_reference"] = res.pop("target_feature_bits") == bits
    res["target_class_equal_host"] = c_cls is None or res["target_class"] == int(c_cls[i])
    return {"measured": True, **res}


def size_record(summary: dict) -> dict:
    """``size.json``: the issue's five figures first, then the rest that explains them."""
    t = summary["target"]
    c = summary["host_c"]
    rec = {"flash_bytes": t.get("flash_bytes"), "ram_bytes": t.get("ram_bytes"),
           "cycles_per_window": t.get("cycles_per_window"),
           "accuracy_python": summary["accuracy_python"],
           "accuracy_c": c.get("accuracy_c")}
    rec |= {k: v for k, v in t.items() if k not in rec and k not in ("measured", "failed")}
    if not t.get("measured"):
        rec["target"] = f"not measured ({t['why']})"
    rec["accuracy_full_monitor_model"] = summary.get("accuracy_full_monitor_model")
    rec["held_out_windows"] = summary["windows"]["held_out"]
    rec["dataset"], rec["held_out_gear"] = summary["dataset"], summary["held_out_gear"]
    return rec
