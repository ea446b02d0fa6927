"""The task of ``swgsim-monitor``: one gear's stream through the condition monitor.

Reads a stream (a gear's life: a schema-v1 data set with ``hour`` and ``commissioning``,
e.g. ``swgsim-generate dataset=tiny_life``) and a diagnosis model trained on simulated
gears (``models/*.skops`` of ``swgsim-train experiment=monitor``), checks that they fit
before any work, runs the stream through the monitor (:func:`.stream.monitor_stream`) and
writes ``summary.json``, ``report.md``, ``health.png`` and an MLflow run; with
``prognosis.enabled=true`` the prognosis after each gear-fault alarm
(:mod:`swgmon.prognosis.stream`) and ``prognosis.png``. The app around it:
:mod:`swgcli.monitor`; config: ``conf/monitor.yaml``.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from learn.tasks.config import typed_app
from learn.tracking import log_run
from learn.tracking.store import check_tracking
from swgmon.advisories.report import write_outputs
from swgmon.advisories.stream import monitor_stream, select_gear
from swgmon.assessment.hypotheses import registered
from swgmon.assessment.model_io import load_model
from swgmon.prognosis.stream import trained_duty
from swgsim.base.typed import check_tree
from swgsim.datasets.schema import load, read_manifest
from swgsim.files import ownership
from swgsim.files.inputs import absolute_path


def check_inputs(cfg):
    """The options, the output folder and the stream checked before any work and before
    the libraries are imported (:func:`swgcli.app.hydra_app`'s ``inputs``).

    Parameters
    ----------
    cfg : omegaconf.DictConfig or swgcli.schema.MonitorApp
        Composed ``conf/monitor.yaml``.

    Returns
    -------
    swgcli.schema.MonitorApp
        The typed config.

    Raises
    ------
    ValueError
        A rule, normal-behaviour, maintenance or prognosis option or ``confirm_h`` out of
        range (named), a hypothesis that does not import (``naming.hypotheses``),
        ``out_dir`` holding a file this project cannot show it wrote
        (:func:`swgsim.files.ownership.check`), or a ``stream`` that is not a data set.
    """
    app = typed_app(cfg)
    # every part's ranges and check (the rule, the normal behaviour, each maintenance
    # event, the prognosis; its planned duty against the model's once it is loaded)
    check_tree(app, "")
    registered(app.naming)  # each hypothesis named imports, before any work
    ownership.check(Path(absolute_path(app.out_dir)), "out_dir", app="swgsim-monitor")
    read_manifest(absolute_path(app.stream))
    return app


def run_monitor_app(cfg) -> dict:
    """Run the monitor on the stream (task function); return the summary.

    Raises
    ------
    ValueError
        Before any work: a rule option or ``confirm_h`` out of range
        (:meth:`swgmon.detection.rule.RuleConfig.check`), an unwritable MLflow store, ``out_dir``
        holding a file this project cannot show it wrote (named,
        :func:`swgsim.files.ownership.check`), a model or stream that is unfit, or a
        prognosis option out of range (a planned duty outside the model's operating
        points or the data sets' temperatures: ``prognosis.planned.<quantity>``).
    """
    app = check_inputs(cfg)
    if app.logger is not None:
        check_tracking(app.logger.tracking_uri, "logger.tracking_uri")
    out = Path(absolute_path(app.out_dir))
    model = load_model(absolute_path(app.diagnosis_model), "diagnosis_model",
                       trust_pickle=app.trust_pickle)
    if app.prognosis.enabled:
        app.prognosis.check(trained=trained_duty(model))
    src = absolute_path(app.stream)
    ds = select_gear(load(src), app.gear)
    res = monitor_stream(ds, model, app.rule, seed=app.seed, confirm_h=app.confirm_h,
                         source=str(src), normal=app.normal, maintenance=app.maintenance,
                         prognosis=app.prognosis, naming=app.naming)
    with ownership.claim(out, "swgsim-monitor", strict=True, fresh=True) as claim:
        files = write_outputs(res, out, str(src))
        claim.record(files.values())
    if app.logger is not None:
        params = {"stream": str(src), "diagnosis_model": app.diagnosis_model,
                  "gear": app.gear, "rule": dataclasses.asdict(app.rule),
                  "naming": dataclasses.asdict(app.naming),
                  "normal": dataclasses.asdict(app.normal), "confirm_h": app.confirm_h}
        with log_run(app.logger.experiment, app.logger.run_name,
                     tracking_uri=app.logger.tracking_uri, params=params,
                     config=dataclasses.asdict(app), dataset=src) as run:
            run.log_metrics({"alarms": len(res.alarms), "threshold": res.threshold})
            for f in files.values():
                run.log_artifact(f)
    return {"alarms": [a.as_dict() for a in res.alarms], "events": res.events(),
            "prognosis": None if res.prognosis is None else res.prognosis.events,
            "threshold": res.threshold, "files": {k: str(v) for k, v in files.items()}}


__all__ = ["check_inputs", "run_monitor_app"]
