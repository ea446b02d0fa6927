"""``swgsim-calibrate``: Hydra app around :func:`run_calibrate`.

Measured data in (a friction CSV, kind 1, or a schema-v1 data-set directory, kind 2,
recognised automatically), a report out: ``out_dir/report.md``, ``summary.json``,
``friction_effects.yaml`` (the accepted effects as a simulation option) and
``figures/*.png``; the run is logged to MLflow.

Examples
--------
::

    swgsim-calibrate measured=/work/shared/data/joint_friction/franka_joint2_slow.csv \\
        out_dir=reports/calibration/franka_joint2_slow
    swgsim-calibrate measured=my.csv out_dir=out logger.enabled=false figures=false
"""

from __future__ import annotations

import json
import logging
from pathlib import Path
from typing import Any

from omegaconf import DictConfig, OmegaConf

from swgcli.app import hydra_app
from swgcli.schema import CalibrateApp

log = logging.getLogger(__name__)


def _as_list(x: Any) -> list | None:
    if x is None:
        return None
    return list(OmegaConf.to_container(x, resolve=True)) if OmegaConf.is_config(x) else list(x)


def write_outputs(result, out_dir: str | Path, source: str | None = None,
                  figures: bool = True) -> dict[str, Any]:
    """Write report.md, summary.json, friction_effects.yaml and figures of a result.

    Parameters
    ----------
    result : swgsim.calibration.CalibrationResult
    out_dir : str or Path
        Created if absent.
    source : str, optional
        Path of the measured data (recorded in the summary).
    figures : bool, default True

    Returns
    -------
    dict
        The summary (see :func:`swgsim.calibration.summarize`).
    """
    import yaml

    from swgsim.calibration import render_report, summarize

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    summary = summarize(result, source=source)
    figs = {}
    if figures:
        from swgcli.calibrate_figures import make_figures

        figs = make_figures(result, out)
    summary["figures"] = figs
    (out / "summary.json").write_text(json.dumps(summary, indent=1, allow_nan=False))
    (out / "report.md").write_text(render_report(result, summary, figs))
    sim = summary.get("simulation") or {}
    if summary["kind"] == "friction":
        fx = {"v_s": sim.get("v_s_rad_s"), "t0_s": sim.get("t0_s"),
              "baseline": sim.get("baseline"), "effects": summary["friction_effects"]}
        (out / "friction_effects.yaml").write_text(
            f"# accepted friction effects of {summary['name']} (swgsim-calibrate); a config "
            "option for conf/friction_effects/\n" + yaml.safe_dump(fx, sort_keys=False))
    return summary


def _log_mlflow(cfg: DictConfig, summary: dict[str, Any], out_dir: Path) -> str:
    """One MLflow run: flattened config, metrics, the output directory as artifacts."""
    import mlflow
    from mlflow.entities import Metric, Param, RunTag

    from learn.tracking import default_tracking_uri, flatten_config, get_experiment_id

    lg = cfg.logger
    client = mlflow.MlflowClient(lg.tracking_uri or default_tracking_uri())
    exp_id = get_experiment_id(client, lg.experiment)
    run = client.create_run(exp_id, run_name=lg.run_name or summary["name"],
                            tags={"kind": summary["kind"], "data": summary["name"]})
    run_id = run.info.run_id
    status = "FAILED"
    try:
        ts = run.info.start_time
        metrics = [Metric("rmse_before", summary["rmse_before"], ts, 0),
                   Metric("rmse_after", summary["rmse_after"], ts, 0),
                   Metric("rmse_ratio", summary["rmse_ratio"], ts, 0),
                   Metric("n_effects_added", float(len(summary["effects_added"])), ts, 0),
                   Metric("unexplained", float(summary["unexplained"]), ts, 0)]
        for split, v in summary["rmse"].items():
            for when in ("before", "after"):
                if v[when] is not None:
                    metrics.append(Metric(f"{split}/rmse_{when}", v[when], ts, 0))
        for it in summary["iterations"]:
            metrics.append(Metric("validation_rmse", it["val_rmse"], ts, it["index"]))
        params = flatten_config(OmegaConf.to_container(cfg, resolve=True))
        flat = sorted(params.items())
        tags = [RunTag("effects_added",
                       ",".join(e["name"] for e in summary["effects_added"]) or "none"),
                RunTag("unexplained", str(summary["unexplained"]))]
        for start in range(0, max(len(flat), 1), 100):
            client.log_batch(run_id, metrics=metrics if start == 0 else [],
                             params=[Param(k, v) for k, v in flat[start:start + 100]],
                             tags=tags if start == 0 else [])
        for f in ("report.md", "summary.json", "friction_effects.yaml"):
            if (out_dir / f).is_file():
                client.log_artifact(run_id, str(out_dir / f))
        if (out_dir / "figures").is_dir():
            client.log_artifacts(run_id, str(out_dir / "figures"), "figures")
        status = "FINISHED"
    finally:
        client.set_terminated(run_id, status=status)
    log.info("MLflow run %s (%s)", run_id, lg.experiment)
    return run_id


def run_calibrate(cfg: DictConfig) -> dict[str, Any]:
    """Calibrate the model against measured data (the task behind ``swgsim-calibrate``).

    Parameters
    ----------
    cfg : DictConfig
        Composed ``conf/calibrate.yaml``: ``measured`` (a friction CSV, kind 1, or a
        schema-v1 strain data-set directory, kind 2, dispatched to
        :func:`swgsim.calibration.strain.calibrate_strain`), ``out_dir``, ``baseline``,
        ``accel_window``, ``split``, ``selection``, ``figures``, ``logger``.

    Returns
    -------
    dict
        The summary written to ``out_dir/summary.json`` plus ``out_dir`` and
        ``mlflow_run_id`` (None when logging is disabled).

    Raises
    ------
    swgsim.calibration.MeasuredDataError
        ``measured`` is neither a friction CSV nor a data-set directory.
    """
    from swgsim.calibration import SelectionConfig, build_problem, calibrate, detect_kind

    measured = Path(cfg.measured).expanduser()
    out_dir = Path(cfg.out_dir).expanduser()
    kind = detect_kind(measured)
    log.info("measured data %s: kind %s", measured, kind)
    if kind == "strain":
        from swgsim.calibration.strain import calibrate_strain

        summary = calibrate_strain(measured, out_dir, figures=bool(cfg.figures))
        summary.pop("_result", None)
        run_id = _log_mlflow(cfg, summary, out_dir) if cfg.logger.enabled else None
        log.info("%s: held-out RMSE %.4g -> %.4g mV/V, added %s, unexplained %s; report %s",
                 summary.get("name"), summary["rmse_before"], summary["rmse_after"],
                 [e["name"] for e in summary["effects_added"]], summary["unexplained"],
                 out_dir / "report.md")
        return {**summary, "out_dir": str(out_dir), "mlflow_run_id": run_id}
    sel = cfg.selection
    problem = build_problem(
        measured, v_s=cfg.baseline.v_s, v_s_rel=cfg.baseline.v_s_rel,
        n_blocks=cfg.split.n_blocks, validation_blocks=_as_list(cfg.split.validation_blocks),
        test_blocks=_as_list(cfg.split.test_blocks), guard_frac=cfg.split.guard_frac,
        candidates=_as_list(sel.candidates), accel_window=cfg.accel_window)
    config = SelectionConfig(
        min_rel_improvement=sel.min_rel_improvement, max_delta_bic=sel.max_delta_bic,
        max_iter=sel.max_iter, candidates=_as_list(sel.candidates),
        structure_threshold=sel.structure_threshold, max_rel_se=sel.max_rel_se,
        max_abs_corr=sel.max_abs_corr, max_starts=sel.max_starts,
        effective_bic=sel.effective_bic, pair_candidates=sel.pair_candidates)
    result = calibrate(problem, config)
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
