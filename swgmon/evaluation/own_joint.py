"""Task ``own_joint`` (``swgsim-train experiment=own_joint``): a diagnosis model for one
acquisition in minutes, saved with its card, for ``swgsim-monitor`` on one's own joint.

The acquisition - sample rate, window length, operating points - is taken from an imported
stream (``own_joint.stream``, written by ``swgsim-import``) or named (``own_joint.
sample_rate_hz``, ``own_joint.window_s``, ``own_joint.n_in_rpm``, ``own_joint.t_out_nm``);
the physics (chain,
converter, load, gears) from a data-set preset (``own_joint.dataset``: ``bench`` or
``robot_joint``). The model is trained on every gear of that preset with the monitor
evaluation's training (:func:`.training.train_model`), at the quick design of
``conf/experiment/own_joint.yaml`` (fewer and shorter training lives than the evaluation's;
a model of the evaluation's design: ``swgsim-train experiment=monitor``). Nothing is
evaluated: the model's names and severities are as good as its training, which
``docs/OWN_JOINT.md`` discusses. Files: ``out`` (``.skops``) and its ``.card.json``, an
MLflow run (experiment ``monitor/own_joint``).
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from learn.tasks.config import typed_app
from learn.tracking import log_run
from learn.tracking.store import check_tracking
from swgmon.assessment.model_io import MODEL_SUFFIX, save_model
from swgmon.evaluation.evaluate import banks_of
from swgmon.evaluation.study import MonitorStudyConfig
from swgmon.evaluation.training import train_model
from swgsim.base.typed import allowed, check_tree, plain
from swgsim.datasets.config import DatasetConfig
from swgsim.datasets.plan import DatasetPlan, plan
from swgsim.datasets.schema import DataSetError, load
from swgsim.files import ownership
from swgsim.files.inputs import absolute_path


@dataclass
class OwnJointExperiment:
    """``own_joint`` group of ``swgsim-train``; checks itself (:meth:`check`).

    Attributes
    ----------
    stream : str or None
        An imported stream (``swgsim-import``) whose sample rate, window length and
        operating points the model takes; None: they are named below or the preset's.
    dataset : str
        Key of ``datasets``: the preset whose physics the training lives have [choice].
    datasets : dict of str to DatasetConfig
        The presets offered (``conf/experiment/own_joint.yaml``: bench, robot_joint).
    sample_rate_hz : float or None
        The acquisition's sample rate [Hz]; None: the stream's, else the preset's.
    window_s : float or None
        The window's length [s]; None: the stream's, else the preset's.
    n_in_rpm, t_out_nm : list of float
        The operating points' input speeds [rpm] and output torques [N m]; empty: the
        stream's, else the preset's. The training lives run at every pair of them (a grid,
        :class:`~swgsim.datasets.config.OperatingPointsConfig`, which checks them).
    study : MonitorStudyConfig
        The training's design (its ``train_*``, ``commissioning_h``, ``faults``,
        ``normal`` keys are read).
    out : str
        The model file (``.skops`` added where missing; its card beside it).
    """

    stream: str | None = None
    dataset: str = "bench"
    datasets: dict[str, DatasetConfig] = field(default_factory=dict)
    sample_rate_hz: float | None = field(default=None, metadata=allowed(
        100.0, 1e6, unit="Hz"))
    window_s: float | None = field(default=None, metadata=allowed(
        0.0, 10.0, lo_open=True, unit="s"))
    n_in_rpm: list[float] = field(default_factory=list)
    t_out_nm: list[float] = field(default_factory=list)
    study: MonitorStudyConfig = field(default_factory=MonitorStudyConfig)
    out: str = "reports/own_joint/model.skops"

    def check(self, where: str) -> None:
        """Refuse a ``dataset`` not among ``datasets``, naming the key, before any work.

        Raises
        ------
        ValueError
        """
        if self.dataset not in self.datasets:
            raise ValueError(f"{where}.dataset={self.dataset!r}; allowed: "
                             f"{sorted(self.datasets)}")


def acquisition(exp: OwnJointExperiment) -> dict:
    """The acquisition the model is made for: the stream's where one is given, then the
    named keys over it.

    Returns
    -------
    dict
        ``sample_rate_hz``, ``window_s`` (None: the preset's), ``n_in_rpm`` and
        ``t_out_nm`` (sorted, distinct; empty: the preset's).

    Raises
    ------
    DataSetError
        ``stream`` not a data set (:func:`swgsim.datasets.schema.load`).
    ValueError
        A stream recorded with an output encoder (windows with twist need a model trained
        on motion: ``swgsim-train experiment=monitor``, data set ``robot_joint_motion``).
    """
    acq = {"sample_rate_hz": None, "window_s": None, "n_in_rpm": [], "t_out_nm": []}
    if exp.stream is not None:
        try:
            ds = load(absolute_path(exp.stream))
        except DataSetError as e:
            raise DataSetError(f"own_joint.stream: {e}") from None
        if "phi_out_meas" in ds:
            raise ValueError(f"own_joint.stream={exp.stream}: recorded with an output "
                             "encoder; a model for its twist is trained on motion: "
                             "swgsim-train experiment=monitor (robot_joint_motion's models)")
        fs = float(ds.attrs["sample_rate_hz"])
        acq = {"sample_rate_hz": fs, "window_s": ds.sizes["time"] / fs,
               **{k: np.unique(ds[k].values.astype(float)).tolist()
                  for k in ("n_in_rpm", "t_out_nm")}}
    named = {k: getattr(exp, k) for k in acq}
    return {k: v if (v is not None and v != []) else acq[k] for k, v in named.items()}


def model_plan(exp: OwnJointExperiment, acq: dict) -> DatasetPlan:
    """The preset with the acquisition put in, planned (its checks name the key).

    Raises
    ------
    ValueError
        The acquisition outside what the simulator takes (``own_joint.<key>: ...``): a
        point beyond the size-20 catalogue's speed or torque, a window shorter than one
        wave-generator turn at the slowest point, a rate the integrator cannot follow.
    """
    cfg = exp.datasets[exp.dataset]
    chain = cfg.chain
    for k in ("sample_rate_hz", "window_s"):
        if acq[k] is not None:
            chain = dataclasses.replace(chain, **{k: float(acq[k])})
    points = cfg.operating_points
    for k in ("n_in_rpm", "t_out_nm"):
        if acq[k]:
            points = dataclasses.replace(points, **{k: sorted(set(map(float, acq[k])))})
    try:
        return plan(dataclasses.replace(cfg, chain=chain, operating_points=points))
    except ValueError as e:
        raise ValueError(f"own_joint: the acquisition {acq} on preset {exp.dataset!r}: "
                         f"{e}") from None


def run_own_joint(cfg) -> dict:
    """Make the model (module docstring); return its path, card and wall time.

    Raises
    ------
    ValueError
        Before any work: a key out of range (named), a stream that is not a data set or
        has an output encoder, an acquisition the simulator refuses, an unwritable MLflow
        store, or ``out``'s folder holding a file this project cannot show it wrote.
    """
    app = typed_app(cfg)
    exp: OwnJointExperiment = app.own_joint
    check_tree(exp, "own_joint")
    acq = acquisition(exp)
    p = model_plan(exp, acq)
    if app.logger is not None:
        check_tracking(app.logger.tracking_uri, "logger.tracking_uri")
    path = Path(absolute_path(exp.out))
    path = path if path.suffix == MODEL_SUFFIX else path.with_name(path.name + MODEL_SUFFIX)
    ownership.check(path.parent, "own_joint.out", app="own_joint")
    gears = [int(g.id) for g in p.config.gears]
    t0 = time.perf_counter()
    fs, win = p.config.chain.sample_rate_hz, p.config.chain.window_s
    op = p.config.operating_points
    print(f"training a diagnosis model on gears {gears} of {exp.dataset}: {fs:g} Hz, windows "
          f"of {win:g} s, {len(op.n_in_rpm) * len(op.t_out_nm)} operating point(s) ...",
          flush=True)
    model = train_model(p, banks_of(p), gears, exp.study)
    wall = time.perf_counter() - t0
    training = [{"name": exp.dataset, "config_hash": p.config_hash, "gears": gears,
                 "simulated": "training lives of swgmon.evaluation.training",
                 "acquisition": acq, "stream": exp.stream, "train_s": round(wall, 1)}]
    with ownership.claim(path.parent, "own_joint", "own_joint.out", strict=True) as claim:
        saved = save_model(model, path, training)
        card = saved.with_name(saved.name.removesuffix(MODEL_SUFFIX) + ".card.json")
        claim.record([saved, card])
    if app.logger is not None:
        with log_run(app.logger.experiment, app.logger.run_name,
                     tracking_uri=app.logger.tracking_uri,
                     params={"dataset": exp.dataset, "stream": exp.stream,
                             "sample_rate_hz": model.sample_rate_hz,
                             "window_s": model.window_s, "n_in_rpm": str(acq["n_in_rpm"]),
                             "t_out_nm": str(acq["t_out_nm"]),
                             "config_hash": p.config_hash},
                     config=plain(app)) as run:
            run.log_metrics({"wall_s": wall, "n_classes": len(model.classes)})
            run.log_artifact(card)
    print(f"model: {saved} (card {card.name}), trained in {wall:.0f} s\n"
          f"use it: swgsim-monitor stream={exp.stream or '<your stream>'} "
          f"diagnosis_model={saved}")
    return {"model": str(saved), "card": str(card), "wall_s": wall,
            "classes": list(model.classes), "acquisition": acq}


__all__ = ["OwnJointExperiment", "acquisition", "model_plan", "run_own_joint"]
