"""The observability map's task, behind ``swgsim-observability`` (:mod:`swgcli.observability`).

For each output inertia (``j_out_kgm2``, default ``n_j_out`` log-spaced from the bench's
to a robot link's, :mod:`learn.observability.study`) :func:`run_observability` generates
the data set ``<data_root>/j_out_<value>`` from the ``dataset`` preset with that inertia (a
valid one already there is kept; the settling time is raised where the torsional mode
rings longer), measures each window's separation from the healthy windows of its gear and
operating point (clean windows), and writes ``<report_dir>/observability.csv``
(:data:`learn.observability.study.COLUMNS` and more), ``torsional_modes.csv`` and
``observability.png``; ``map=motion`` runs the motion map instead
(:func:`run_motion_map`, :mod:`learn.observability.motion`). Config:
``conf/observability.yaml``.
"""

from __future__ import annotations

import copy
import logging
import math
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from omegaconf import DictConfig, OmegaConf

from learn.observability.motion import (
    motion_map_rows,
    plot_motion_map,
    smallest_detectable,
)
from learn.observability.study import (
    j_out_grid,
    observability_table,
    plot_observability,
    torsional_modes,
)
from learn.studies.separability import separation_records
from swgsim.base.lazy import lazy_module
from swgsim.base.typed import check_tree
from swgsim.datasets.config import min_settle_s
from swgsim.datasets.generate import generate
from swgsim.datasets.plan import plan
from swgsim.datasets.schema import load
from swgsim.files import ownership
from swgsim.files.inputs import absolute_path
from swgsim.files.ownership import atomic_write_bytes

if TYPE_CHECKING:
    from swgsim.datasets.plan import DatasetPlan

pd = lazy_module("pandas")

log = logging.getLogger(__name__)

#: The files each map writes into ``report_dir``: a run of one map renews its own and keeps
#: the other's whole (:func:`swgsim.files.ownership.claim`'s ``fresh``).
STEADY_FILES = ("observability.csv", "observability.png", "torsional_modes.csv")
MOTION_FILES = ("observability_motion.csv", "observability_motion.png",
                "smallest_detectable.csv")


def j_out_values(cfg: DictConfig) -> list[float]:
    """The map's output inertias [kg m²]: ``j_out_kgm2``, or ``n_j_out`` log-spaced from
    the bench's to a robot link's.

    Raises
    ------
    ValueError
        ``n_j_out`` outside [2, 50] or ``j_out_kgm2`` not distinct values.
    """
    if cfg.j_out_kgm2 is None:
        if not 2 <= int(cfg.n_j_out) <= 50:
            raise ValueError(f"n_j_out: must be in [2, 50], got {cfg.n_j_out}")
        return [float(v) for v in j_out_grid(int(cfg.n_j_out))]
    values = [float(v) for v in cfg.j_out_kgm2]
    if not values or len(set(values)) != len(values):
        raise ValueError(f"j_out_kgm2: must list distinct values, got {values}")
    return values


def data_set_configs(cfg: DictConfig) -> dict[float, DatasetPlan]:
    """The data set of every output inertia, checked once, before any work.

    Returns
    -------
    dict
        J_out [kg m²] -> the checked data set (:class:`swgsim.datasets.plan.DatasetPlan`;
        ``load.j_out_kgm2`` set, ``chain.settle_s`` raised to
        :func:`swgsim.datasets.config.min_settle_s` rounded up to 10 ms).

    Raises
    ------
    ValueError
        Naming the key: ``j_out_kgm2`` / ``n_j_out`` out of range, or a data-set key.
    """
    values = j_out_values(cfg)
    for key in ("n_jobs", "harmonics"):
        if int(cfg[key]) < 1:
            raise ValueError(f"{key}: must be >= 1, got {cfg[key]}")
    base = OmegaConf.to_object(cfg.dataset)  # the typed DatasetConfig
    out = {}
    for j in values:
        if not 1e-4 <= j <= 100.0:
            raise ValueError(f"j_out_kgm2: {j} outside the allowed range [1e-4, 100] kg m²")
        c = copy.deepcopy(base)
        c.load.j_out_kgm2 = j
        c.name = f"{base.name}_j_out_{j:.4g}"
        need = math.ceil(min_settle_s(c) * 100 - 1e-9) / 100
        c.chain.settle_s = max(float(c.chain.settle_s), need)
        try:
            out[j] = plan(c)
        except ValueError as e:
            raise ValueError(f"{e} (data set of j_out_kgm2={j:.4g})") from None
    return out


def run_observability(cfg: DictConfig) -> dict:
    """Run the map (task function, no Hydra needed).

    Returns
    -------
    dict
        ``table`` (DataFrame), ``files``, ``data_sets`` (J_out -> folder), ``wall_s``.

    Raises
    ------
    ValueError
        ``report_dir`` or a data-set folder holds a file this project cannot show it
        wrote (named; the report folder before any work, :func:`swgsim.files.ownership.check`).
    """
    rep = Path(absolute_path(str(cfg.report_dir)))
    csv = rep / "observability.csv"
    if cfg.map not in ("steady", "motion"):
        raise ValueError(f"map: must be one of ['steady', 'motion'], got {cfg.map!r}")
    ownership.check(rep, "report_dir", app="swgsim-observability")  # before any work
    if cfg.map == "motion":
        return run_motion_map(cfg, rep)
    if bool(cfg.plot_only):
        if not csv.is_file():
            raise FileNotFoundError(2, "no map to redraw (run without plot_only first)",
                                    str(csv))
        table = pd.read_csv(csv)
        loads = sorted(set(table["t_out_nm"]))
        modes = torsional_modes(sorted(set(table["j_out_kgm2"])), loads)
        with ownership.claim(rep, "swgsim-observability", "report_dir", strict=True) as claim:
            fig = plot_observability(table, rep / "observability.png", modes)
            claim.record([fig])
        return {"table": table, "files": {"figure": str(fig)}, "data_sets": {}, "wall_s": 0.0}
    configs = data_set_configs(cfg)
    root = Path(absolute_path(str(cfg.data_root)))
    t0 = time.perf_counter()
    parts, folders = [], {}
    for n, (j, c) in enumerate(configs.items(), 1):
        folder = root / f"j_out_{j:.4g}"
        g = generate(c, folder, n_jobs=int(cfg.n_jobs), overwrite=True,
                     progress=bool(cfg.progress))
        state = (f"{len(g['computed'])} shard(s) simulated" if g["computed"]
                 else "already there and valid")
        print(f"[{n}/{len(configs)}] J_out = {j:.4g} kg m² (settle {c.config.chain.settle_s:g}"
              f" s): {g['windows']} windows in {folder} ({state})", flush=True)
        rec = separation_records(load(folder), disturbed=False, n_harmonics=int(cfg.harmonics),
                                 ratio=100.0)
        parts.append(observability_table(rec, j))
        folders[j] = str(folder)
    table = pd.concat(parts, ignore_index=True)
    loads = [float(t) for t in cfg.dataset.operating_points.t_out_nm]
    modes = torsional_modes(list(configs), loads)
    with ownership.claim(rep, "swgsim-observability", "report_dir", strict=True,
                         fresh=STEADY_FILES) as claim:
        atomic_write_bytes(csv, table.to_csv(index=False, float_format="%.6g").encode())
        atomic_write_bytes(rep / "torsional_modes.csv",
                           modes.to_csv(index=False, float_format="%.6g").encode())
        fig = plot_observability(table, rep / "observability.png", modes)
        claim.record([fig])
    wall = time.perf_counter() - t0
    return {"table": table, "files": {"csv": str(csv), "figure": str(fig),
                                      "modes": str(rep / "torsional_modes.csv")},
            "data_sets": folders, "wall_s": wall}


def motion_plans(cfg: DictConfig) -> dict[float, dict[str, DatasetPlan]]:
    """The steady (``motion_steady``, preset ``robot_joint``) and profile
    (``motion_profile``, preset ``robot_joint_motion``) data sets of every output inertia
    of the map, checked before any work.

    Raises
    ------
    ValueError
        Naming the key (``j_out_kgm2``, ``n_j_out``, ``motion.*`` or a data-set key).
    """
    check_tree(OmegaConf.to_object(cfg.motion), "motion")  # MotionMapConfig.check
    out = {}
    for j in j_out_values(cfg):
        if not 1e-4 <= j <= 100.0:
            raise ValueError(f"j_out_kgm2: {j} outside the allowed range [1e-4, 100] kg m²")
        out[j] = {}
        for k in ("steady", "profile"):
            c = copy.deepcopy(OmegaConf.to_object(cfg[f"motion_{k}"]))
            c.load.j_out_kgm2 = j
            # as the steady map: settled where the mode rings longer (a profile's windows
            # then tile from the later start)
            need = math.ceil(min_settle_s(c) * 100 - 1e-9) / 100
            c.chain.settle_s = max(float(c.chain.settle_s), need)
            try:
                out[j][k] = plan(c)
            except ValueError as e:
                m = str(e)
                m = f"motion_{k}.{m[8:]}" if m.startswith("dataset.") else f"motion_{k}: {m}"
                raise ValueError(f"{m} (data set of j_out_kgm2={j:.4g})") from None
    return out


def run_motion_map(cfg: DictConfig, rep: Path) -> dict:
    """``map=motion``: steady windows against the joint in motion, with and without the
    output encoder (:mod:`learn.observability.motion`); writes
    ``observability_motion.csv``, ``smallest_detectable.csv`` and
    ``observability_motion.png`` into ``rep``."""
    from tqdm.auto import tqdm

    plans = motion_plans(cfg)
    mc = OmegaConf.to_object(cfg.motion)
    t0 = time.perf_counter()
    parts = [motion_map_rows(p, j, mc) for j, p in tqdm(plans.items(), desc="motion map",
                                                         unit="J_out",
                                                         disable=not cfg.progress)]
    table = pd.concat(parts, ignore_index=True)
    small = smallest_detectable(table)
    with ownership.claim(rep, "swgsim-observability", "report_dir", strict=True,
                         fresh=MOTION_FILES) as claim:
        files = {"csv": rep / "observability_motion.csv",
                 "smallest": rep / "smallest_detectable.csv"}
        atomic_write_bytes(files["csv"], table.to_csv(index=False, float_format="%.6g").encode())
        atomic_write_bytes(files["smallest"], small.to_csv(index=False,
                                                           float_format="%.6g").encode())
        files["figure"] = plot_motion_map(table, rep / "observability_motion.png")
        claim.record([files["figure"]])
    return {"table": table, "smallest": small, "files": {k: str(v) for k, v in files.items()},
            "data_sets": {}, "wall_s": time.perf_counter() - t0}


def run_observability_app(cfg: DictConfig) -> dict:
    """Run the map (:func:`run_observability`) and print where it went and the share
    per fault and inertia: what ``swgsim-observability`` runs."""
    out = run_observability(cfg)
    t = out["table"]
    if "smallest" in out:
        print("\nsmallest severity with half its windows beyond the healthy 95th percentile "
              "(k1 left in brackets; '-': none up to the largest):")
        s = out["smallest"].assign(cell=lambda d: [
            "-" if np.isnan(a) else f"{a:g} ({b:.2f})"
            for a, b in zip(d.smallest_severity, d.stiffness_left, strict=True)])
        print(s.pivot_table(index=["fault", "view"], columns="j_out_kgm2", values="cell",
                            aggfunc="first").to_string())
    elif len(t):
        piv = (t[t["fault"] != "healthy"].groupby(["fault", "j_out_kgm2"])
               ["fraction_beyond_p95"].mean().unstack() * 100)
        print("\nshare of fault windows beyond the healthy 95th percentile [%], mean over "
              "speeds and loads (columns: J_out [kg m²]):")
        print(piv.to_string(float_format=lambda v: f"{v:.1f}"))
    for k, v in out["files"].items():
        print(f"{k}: {v}")
    if out["wall_s"]:
        print(f"wall time {out['wall_s']:.1f} s")
    return out
