"""``swgsim-calibrate``: Hydra app around :func:`run_calibrate`.

Measured data in (a friction CSV, kind 1, a schema-v1 data-set directory, kind 2, or a
robot's joint log, kind 3, recognised automatically), a report out: ``out_dir/report.md``,
``summary.json``, the accepted effects as a simulation option (``friction_effects.yaml``,
``sensor_effects.yaml`` or ``joint_thermal.yaml``) and ``figures/*.png``; the run is
logged to MLflow. The app only parses, calls the kind-independent API of :mod:`swgcal`
and writes.

Examples
--------
::

    swgsim-calibrate measured=/work/shared/data/joint_friction/franka_joint2_slow.csv \\
        out_dir=reports/calibration/franka_joint2_slow
    swgsim-calibrate measured=my.csv out_dir=out ~logger figures=false
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import field
from pathlib import Path
from typing import Any

from hydra.core.config_store import ConfigStore
from omegaconf import MISSING, DictConfig, OmegaConf

from learn.tracking.config import LoggerConfig
from swgcal import (
    KINDS,
    SelectionConfig,
    build_problem,
    calibrate,
    detect_kind,
    kind_module,
    options_from_config,
    write_outputs,
)
from swgcli.app import hydra_app
from swgsim.base.typed import schema_of
from swgsim.files import ownership

log = logging.getLogger(__name__)


def kind_option_fields() -> list[tuple[str, Any, Any]]:
    """Schema fields of every kind's problem options (``OPTIONS`` of each kind
    subpackage), in the order the kinds declare them; a key shared by kinds once."""
    out, seen = [], set()
    for kind in KINDS:
        schema = schema_of(kind_module(kind).OPTIONS)
        for f in dataclasses.fields(schema):
            if f.name not in seen:
                seen.add(f.name)
                out.append((f.name, f.type, field(default=f.default,
                                                  default_factory=f.default_factory)))
    return out


#: The ``selection`` group: the keys of :class:`swgcal.SelectionConfig`.
SelectionOptions = schema_of(SelectionConfig, "SelectionOptions")

CalibrateApp = dataclasses.make_dataclass("CalibrateApp", [
    ("measured", str, field(default=MISSING)),
    ("out_dir", str, field(default=MISSING)),
    *kind_option_fields(),
    ("selection", SelectionOptions, field(default_factory=SelectionOptions)),
    ("figures", bool, field(default=True)),
    ("logger", LoggerConfig | None, field(default=None)),
])
CalibrateApp.__module__ = __name__
CalibrateApp.OUT_DIRS = ("out_dir",)  # folders written (swgcli.app.check_out_dirs)
CalibrateApp.__doc__ = """``swgsim-calibrate``: calibrate the model against measured data.

``measured``: a friction CSV (kind 1) or a schema-v1 data-set directory (kind 2);
``out_dir``: created if absent; the keys of every kind's problem options with the
library's defaults and ranges (friction: :class:`swgcal.friction.FrictionOptions`:
``base model``, ``gear_ratio``, ``accel_window``, ``split``); ``selection``:
:class:`swgcal.SelectionConfig`; ``figures``; ``logger`` (MLflow, the one tracking config
of every app, :class:`learn.tracking.config.LoggerConfig`: experiment ``calibration``, the
run named after the measured data; ``~logger``: no tracking).
"""

ConfigStore.instance().store(name="calibrate_schema", node=CalibrateApp)
# the tracking as a group option, so that `~logger` removes all of it (as swgsim-monitor's)
ConfigStore.instance().store(group="logger", name="calibration",
                             node=LoggerConfig(experiment="calibration", run_name=""))


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
        metrics = {k: summary[k] for k in ("rmse_before", "rmse_after", "rmse_ratio")
                   if summary.get(k) is not None}  # None: not scored (an unphysical base)
        metrics.update({"n_effects_added": float(len(summary["effects_added"])),
                        "unexplained": float(summary["unexplained"])})
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


def check_inputs(cfg: DictConfig) -> tuple[Path, Path, str]:
    """What ``swgsim-calibrate`` reads and writes, checked before any work and before its
    libraries are imported (:func:`swgcli.app.hydra_app`'s ``inputs``).

    Parameters
    ----------
    cfg : DictConfig
        Composed ``conf/calibrate.yaml`` (``measured``, ``out_dir``).

    Returns
    -------
    measured : Path
    out_dir : Path
    kind : str
        ``"friction"``, ``"thermal"`` or ``"strain"`` (:func:`swgcal.detect_kind`).

    Raises
    ------
    swgcal.MeasuredDataError
        ``measured`` is missing or of no known kind (named).
    ValueError
        ``out_dir`` holds a file this project cannot show it wrote
        (:func:`swgsim.files.ownership.check`).
    """
    measured = Path(cfg.measured).expanduser()
    out_dir = Path(cfg.out_dir).expanduser()
    ownership.check(out_dir, "out_dir", app="swgsim-calibrate")
    return measured, out_dir, detect_kind(measured)


def run_calibrate(cfg: DictConfig) -> dict[str, Any]:
    """Calibrate the model against measured data (the task behind ``swgsim-calibrate``).

    Parameters
    ----------
    cfg : DictConfig
        Composed ``conf/calibrate.yaml`` (:class:`CalibrateApp`); the steps are
        :func:`swgcal.build_problem`, :func:`swgcal.calibrate`, :func:`swgcal.write_outputs`.

    Returns
    -------
    dict
        The summary written to ``out_dir/summary.json`` plus ``out_dir`` and
        ``mlflow_run_id`` (None when logging is disabled).

    Raises
    ------
    swgcal.MeasuredDataError, ValueError
        Before any work, as :func:`check_inputs`; the app's own earlier output is replaced.
    """
    measured, out_dir, kind = check_inputs(cfg)
    options, selection = options_from_config(
        kind, OmegaConf.to_container(cfg, resolve=True), measured)
    if cfg.get("logger") is not None:
        from learn.tracking.store import check_tracking

        check_tracking(cfg.logger.tracking_uri, "logger.tracking_uri")
    log.info("measured data %s: kind %s", measured, kind)
    problem = build_problem(measured, **options)
    result = calibrate(problem, selection)
    with ownership.claim(out_dir, "swgsim-calibrate", strict=True, fresh=True) as claim:
        summary = write_outputs(result, out_dir, source=str(measured),
                                figures=bool(cfg.figures))
        claim.record([*summary["files"], *summary["figures"].values()])
    run_id = _log_mlflow(cfg, summary, out_dir) if cfg.get("logger") is not None else None
    scored = summary.get("rmse_after") is not None
    log.info("%s: test RMSE %s %s, added %s, unexplained %s; report %s", summary["name"],
             f"{summary['rmse_before']:.4g} -> {summary['rmse_after']:.4g}" if scored else
             f"not scored ({summary.get('not_scored', 'no errors')})", summary["units"],
             [e["name"] for e in summary["effects_added"]], summary["unexplained"],
             out_dir / "report.md")
    return {**summary, "out_dir": str(out_dir), "mlflow_run_id": run_id}


#: The libraries its runs import, resolved before any work
#: (:func:`learn.tracking.preflight.check_imports`).
NEEDS = ("numpy", "scipy", "pandas", "sklearn", "yaml", "matplotlib", "mlflow")


main = hydra_app("calibrate", CalibrateApp, "swgsim-calibrate", NEEDS,
                 inputs=check_inputs)(run_calibrate)

if __name__ == "__main__":
    main()
