"""``swgsim-calibrate``: Hydra app around :func:`run_calibrate`.

Measured data in (a friction CSV, kind 1, or a schema-v1 data-set directory, kind 2,
recognised automatically), a report out: ``out_dir/report.md``, ``summary.json``, the
accepted effects as a simulation option (``friction_effects.yaml`` or
``sensor_effects.yaml``) and ``figures/*.png``; the run is logged to MLflow. The app only
parses, calls the kind-independent API of :mod:`swgcal` and writes.

Examples
--------
::

    swgsim-calibrate measured=/work/shared/data/joint_friction/franka_joint2_slow.csv \\
        out_dir=reports/calibration/franka_joint2_slow
    swgsim-calibrate measured=my.csv out_dir=out logger.enabled=false figures=false
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hydra.core.config_store import ConfigStore
from omegaconf import MISSING, DictConfig, OmegaConf

from swgcli.app import hydra_app

log = logging.getLogger(__name__)


def _arg(func, name: str):
    """Default of a library function's argument: the one place of that default."""
    import inspect

    value = inspect.signature(func).parameters[name].default
    return list(value) if isinstance(value, tuple) else value


# the friction calibration's defaults live in swgcal; the app takes them

def _friction_default(name: str):
    from swgcal.friction import friction_problem

    return _arg(friction_problem, name)


def _friction_builder():
    from swgcal.friction import build_problem

    return build_problem


def _selection_default(name: str):
    from swgcal import SelectionConfig

    return getattr(SelectionConfig, name)


@dataclass
class BaselineOptions:
    """Smooth sign of the paper's friction law."""

    v_s: float | None = None     # tanh(dq / v_s) [rad/s]; null: v_s_rel * p99(|dq|)
    v_s_rel: float = _friction_default("v_s_rel")


@dataclass
class SplitOptions:
    """Held-out time blocks of a friction recording; the other blocks are fit blocks."""

    n_blocks: int = _friction_default("n_blocks")
    validation_blocks: list[int] = field(  # choose the effects
        default_factory=lambda: _friction_default("validation_blocks"))
    test_blocks: list[int] = field(  # errors before/after only; the last block extrapolates
        default_factory=lambda: _friction_default("test_blocks"))
    guard_frac: float = _friction_default("guard_frac")  # dropped at role boundaries [blocks]


@dataclass
class SelectionOptions:
    """Which effects a calibration accepts (swgcal.SelectionConfig)."""

    candidates: list[str] | None = None  # null: the whole library; or effect names
    min_rel_improvement: float = _selection_default("min_rel_improvement")
    min_heldout_evidence: float = _selection_default("min_heldout_evidence")
    max_delta_bic: float = _selection_default("max_delta_bic")
    effective_bic: bool = _selection_default("effective_bic")
    max_rel_se: float = _selection_default("max_rel_se")
    max_abs_corr: float = _selection_default("max_abs_corr")
    max_iter: int = _selection_default("max_iter")
    pair_candidates: int = _selection_default("pair_candidates")
    max_starts: int = _selection_default("max_starts")
    structure_threshold: float = _selection_default("structure_threshold")


@dataclass
class CalibrateLogger:
    """MLflow tracking of ``swgsim-calibrate``."""

    enabled: bool = True
    tracking_uri: str | None = None
    experiment: str = "calibration"
    run_name: str | None = None


@dataclass
class CalibrateApp:
    """``swgsim-calibrate``: calibrate the model against measured data."""

    measured: str = MISSING   # friction CSV (kind 1) or schema-v1 data-set directory (kind 2)
    out_dir: str = MISSING    # created if absent
    baseline: BaselineOptions = field(default_factory=BaselineOptions)
    gear_ratio: float | None = None  # N (WG turns per output turn) if known: ripple orders
    accel_window: int = field(  # samples of the Savitzky-Golay estimate of ddq
        default_factory=lambda: _arg(_friction_builder(), "accel_window"))
    split: SplitOptions = field(default_factory=SplitOptions)
    selection: SelectionOptions = field(default_factory=SelectionOptions)
    figures: bool = True
    logger: CalibrateLogger = field(default_factory=CalibrateLogger)


ConfigStore.instance().store(name="calibrate_schema", node=CalibrateApp)


def _as_list(x: Any) -> list | None:
    if x is None:
        return None
    return list(OmegaConf.to_container(x, resolve=True)) if OmegaConf.is_config(x) else list(x)


def _log_mlflow(cfg: DictConfig, summary: dict[str, Any], out_dir: Path) -> str:
    """One MLflow run through :func:`learn.tracking.log_run`: the git commit, the measured
    data (file or data-set folder) as dataset input, the flattened config and
    ``config.yaml``, metrics, the files the calibration wrote as artifacts. The calibrated
    model is the simulation option (``friction_effects.yaml`` or ``sensor_effects.yaml``),
    stored as an artifact."""
    from learn.tracking import log_run

    lg = cfg.logger
    resolved = OmegaConf.to_container(cfg, resolve=True)
    tags = {"kind": summary["kind"], "data": summary["name"],
            "effects_added": ",".join(e["name"] for e in summary["effects_added"]) or "none",
            "unexplained": str(summary["unexplained"])}
    with log_run(lg.experiment, lg.run_name or summary["name"], tracking_uri=lg.tracking_uri,
                 params=resolved, config=resolved, dataset=Path(cfg.measured).expanduser(),
                 tags=tags) as run:
        metrics = {"rmse_before": summary["rmse_before"], "rmse_after": summary["rmse_after"],
                   "rmse_ratio": summary["rmse_ratio"],
                   "n_effects_added": float(len(summary["effects_added"])),
                   "unexplained": float(summary["unexplained"])}
        for split, v in summary["rmse"].items():
            for when in ("before", "after"):
                if v[when] is not None:
                    metrics[f"{split}/rmse_{when}"] = v[when]
        run.log_metrics(metrics)
        for it in summary["iterations"]:  # step: the selection's iteration
            run.log_metrics({"validation_rmse": it["val_rmse"]}, step=it["index"])
        for f in summary["files"]:
            run.log_artifact(out_dir / f)
        if (out_dir / "figures").is_dir():
            run.log_artifact(out_dir / "figures", "figures")
    log.info("MLflow run %s (%s)", run.run_id, lg.experiment)
    return run.run_id


#: Options that only the friction calibration (kind 1) reads.
FRICTION_ONLY = ("baseline", "gear_ratio", "accel_window", "split")


def check_options(cfg: DictConfig, kind: str, measured: Path) -> None:
    """Check the calibration options before any work.

    Ranges of the friction options; and for a strain data set (kind 2), which takes none
    of :data:`FRICTION_ONLY`, any of them set away from its default is refused rather
    than ignored.

    Raises
    ------
    ValueError
        Naming the key, the value and the allowed range (or the data kind it needs).
    """
    defaults = OmegaConf.to_container(OmegaConf.structured(CalibrateApp), resolve=False)
    given = OmegaConf.to_container(cfg, resolve=True)
    if kind == "strain":
        for group in FRICTION_ONLY:
            d, g = defaults[group], given[group]
            changed = ([f"{group}.{k}={g[k]}" for k in g if g[k] != d[k]]
                       if isinstance(g, dict) else ([f"{group}={g}"] if g != d else []))
            if changed:
                names = ", ".join(f"{x}.*" if isinstance(defaults[x], dict) else x
                                  for x in FRICTION_ONLY)
                raise ValueError(
                    f"{changed[0]} applies to friction recordings (kind 1); {measured} is a "
                    f"strain data set (kind 2), whose calibration takes none of {names}")
    se = given["selection"]
    for key, lo, hi in (("min_rel_improvement", 0.0, 1.0), ("max_rel_se", 0.0, 10.0),
                        ("min_heldout_evidence", 0.0, 1e6),
                        ("max_abs_corr", 0.0, 1.0), ("structure_threshold", 0.0, 1.0)):
        if not lo <= se[key] <= hi:
            raise ValueError(f"selection.{key} must lie in [{lo:g}, {hi:g}], got {se[key]}")
    for key, lo, hi in (("max_iter", 0, 100), ("pair_candidates", 0, 50), ("max_starts", 1, 50)):
        if not lo <= se[key] <= hi:
            raise ValueError(f"selection.{key} must lie in [{lo}, {hi}], got {se[key]}")
    if not se["max_delta_bic"] <= 0:
        raise ValueError(f"selection.max_delta_bic must be <= 0, got {se['max_delta_bic']}")
    if kind == "strain":
        return
    b, sp = given["baseline"], given["split"]
    aw = given["accel_window"]
    if not (5 <= aw <= 1001 and aw % 2 == 1):
        raise ValueError(f"accel_window must be an odd integer in [5, 1001], got {aw}")
    if b["v_s"] is not None and not b["v_s"] > 0:
        raise ValueError(f"baseline.v_s must be > 0 rad/s or null, got {b['v_s']}")
    gr = given["gear_ratio"]
    if gr is not None and not 1 < gr <= 10_000:
        raise ValueError(f"gear_ratio must lie in (1, 10000] (wave-generator turns per output "
                         f"turn) or be null, got {gr}")
    if not 0 < b["v_s_rel"] <= 1:
        raise ValueError(f"baseline.v_s_rel must lie in (0, 1], got {b['v_s_rel']}")
    n = sp["n_blocks"]
    if not 3 <= n <= 1000:
        raise ValueError(f"split.n_blocks must lie in [3, 1000], got {n}")
    for key in ("validation_blocks", "test_blocks"):
        bad = [x for x in sp[key] if not -n <= x < n]
        if bad or not sp[key]:
            raise ValueError(f"split.{key} must list blocks in [{-n}, {n - 1}], got {sp[key]}")
    if not 0 <= sp["guard_frac"] <= 0.45:
        raise ValueError(f"split.guard_frac must lie in [0, 0.45], got {sp['guard_frac']}")


def problem_options(cfg: DictConfig, kind: str) -> dict[str, Any]:
    """The options of the kind's problem builder from the app's config.

    Friction: baseline, split, accel_window, gear_ratio and ``selection.candidates``
    (:func:`swgcal.friction.build_problem`); strain:
    ``selection.candidates`` (:func:`swgcal.strain.build_problem`).
    """
    cand = _as_list(cfg.selection.candidates)
    if kind == "strain":
        return {"candidates": cand} if cand is not None else {}
    return dict(v_s=cfg.baseline.v_s, v_s_rel=cfg.baseline.v_s_rel,
                n_blocks=cfg.split.n_blocks,
                validation_blocks=_as_list(cfg.split.validation_blocks),
                test_blocks=_as_list(cfg.split.test_blocks), guard_frac=cfg.split.guard_frac,
                candidates=cand, accel_window=cfg.accel_window, gear_ratio=cfg.gear_ratio)


def selection_config(cfg: DictConfig):
    """:class:`swgcal.SelectionConfig` from the app's ``selection`` group."""
    from swgcal import SelectionConfig

    sel = OmegaConf.to_container(cfg.selection, resolve=True)
    return SelectionConfig(**{k: (list(v) if isinstance(v, list) else v)
                              for k, v in sel.items()})


def run_calibrate(cfg: DictConfig) -> dict[str, Any]:
    """Calibrate the model against measured data (the task behind ``swgsim-calibrate``).

    Parameters
    ----------
    cfg : DictConfig
        Composed ``conf/calibrate.yaml``: ``measured`` (a friction CSV, kind 1, or a
        schema-v1 strain data-set directory, kind 2), ``out_dir``, ``baseline``,
        ``gear_ratio``, ``accel_window``, ``split`` (friction only), ``selection``,
        ``figures``, ``logger``. Parses them, calls :func:`swgcal.build_problem`,
        :func:`swgcal.calibrate` and :func:`swgcal.write_outputs`,
        and logs the run.

    Returns
    -------
    dict
        The summary written to ``out_dir/summary.json`` plus ``out_dir`` and
        ``mlflow_run_id`` (None when logging is disabled).

    Raises
    ------
    swgcal.MeasuredDataError
        ``measured`` is neither a friction CSV nor a data-set directory.
    """
    from swgcal import build_problem, calibrate, detect_kind, write_outputs

    measured = Path(cfg.measured).expanduser()
    out_dir = Path(cfg.out_dir).expanduser()
    kind = detect_kind(measured)
    check_options(cfg, kind, measured)
    if cfg.logger.enabled:
        from learn.tracking import check_tracking

        check_tracking(cfg.logger.tracking_uri, "logger.tracking_uri")
    log.info("measured data %s: kind %s", measured, kind)
    problem = build_problem(measured, **problem_options(cfg, kind))
    result = calibrate(problem, selection_config(cfg))
    summary = write_outputs(result, out_dir, source=str(measured), figures=bool(cfg.figures))
    run_id = _log_mlflow(cfg, summary, out_dir) if cfg.logger.enabled else None
    log.info("%s: test RMSE %.4g -> %.4g %s, added %s, unexplained %s; report %s",
             summary["name"], summary["rmse_before"], summary["rmse_after"], summary["units"],
             [e["name"] for e in summary["effects_added"]], summary["unexplained"],
             out_dir / "report.md")
    return {**summary, "out_dir": str(out_dir), "mlflow_run_id": run_id}


main = hydra_app("calibrate", CalibrateApp, "swgsim-calibrate")(run_calibrate)

if __name__ == "__main__":
    main()
