"""Typed schemas of the four apps, registered as Hydra structured configs.

Each app's primary config (``conf/<app>.yaml``) starts from its schema here
(:class:`GenerateApp`, :class:`PaperApp`, :class:`TrainApp`; the calibration app's,
``CalibrateApp``, lives in :mod:`swgcli.calibrate`, which loads the calibration stack), so
Hydra refuses unknown keys, missing mandatory values and values of the wrong type while
composing; :func:`validate` repeats the key check after composition, because Hydra's
``+key=value`` adds a key even to a typed config. Ranges are checked where they are
decided (:func:`swgsim.datasets.plan.plan`, the learners, the calibration).

The config groups whose defaults live in Python are generated here from their one
source, not written twice as YAML:

==============  =====================================================================
group           source
==============  =====================================================================
``protocol``    :data:`learn.studies.protocols.PROTOCOLS` (the paper's four protocols)
``model``       :data:`learn.learners.models.MODELS` (Table VI); deep models stay YAML
``features``    :data:`learn.inputs.features.SELECTIONS` (Table III selections)
``experiment``  ``table_vii`` .. ``table_x`` from :data:`learn.paper.tables.PAPER_TABLES`
``dataset``     :class:`swgsim.datasets.config.DatasetConfig` (the paper preset is its defaults)
==============  =====================================================================
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

from hydra.core.config_store import ConfigStore
from omegaconf import MISSING, DictConfig, OmegaConf

from learn.inputs.features import SELECTIONS, FeatureSettings
from learn.observability.motion import MotionMapConfig
from learn.paper.study import StudyTracking
from learn.paper.tables import StudyOptions
from learn.studies.protocols import PROTOCOLS, ProtocolConfig
from learn.tracking.config import LoggerConfig
from learn.transfer.study import TransferConfig
from swgmon.assessment.gear_monitor import MaintenanceEvent
from swgmon.assessment.sensor_check import NamingConfig
from swgmon.detection.normal import NormalConfig
from swgmon.detection.rule import RuleConfig
from swgmon.evaluation.benchmark_task import BenchmarkExperiment
from swgmon.evaluation.own_joint import OwnJointExperiment
from swgmon.evaluation.prognosis_task import PrognosisExperiment
from swgmon.evaluation.task import MonitorExperiment
from swgmon.prognosis.stream import StreamPrognosis
from swgsim.base.typed import allowed, check_keys
from swgsim.datasets.config import DatasetConfig
from swgsim.gear.thermal import THERMAL_PRESETS

#: Experiments of ``swgsim-train`` (conf/experiment/) whose tracking is a ``logger`` group
#: option of their name, selected in their defaults (``~logger`` then switches it off like
#: every other app's): option -> MLflow experiment (the naming scheme, docs/apps.md,
#: "MLflow experiments and runs"); the run is named after the option.
EXPERIMENT_LOGGERS = {"benchmark": "monitor/benchmark", "monitor": "monitor/evaluation",
                      "own_joint": "monitor/own_joint", "prognosis": "monitor/prognosis",
                      "transfer": "transfer"}
#: ``n_jobs`` of every app: worker processes, one or more (0 or a negative count is
#: refused with the keys, before any work)
N_JOBS = allowed(1, None, "worker processes")


@dataclass
class GenerateApp:
    """``swgsim-generate``: simulate a data set."""

    OUT_DIRS: ClassVar[tuple[str, ...]] = ("out_dir",)  # folders written (app.check_out_dirs)

    dataset: DatasetConfig = field(default_factory=DatasetConfig)
    out_dir: str = "data/${dataset.name}"   # relative: from the directory you start in
    n_jobs: int = field(default=2, metadata=N_JOBS)  # worker processes (joblib); 1: in-process
    overwrite: bool = False                 # replace a data set of another config
    shard: int | None = None                # compute only this shard (cluster array jobs)
    progress: bool = True


@dataclass
class PaperApp:
    """``swgsim-paper``: the main job."""

    datasets: dict[str, DatasetConfig] = field(default_factory=dict)
    run_on: list[str] = field(default_factory=lambda: ["paper", "bench"])  # keys of datasets
    OUT_DIRS: ClassVar[tuple[str, ...]] = ("data_root", "report_root")

    data_root: str = "data"
    report_root: str = "reports"
    n_jobs: int = field(default=2, metadata=N_JOBS)
    tracking_uri: str | None = None
    log_models: bool = StudyTracking.log_models  # each job's last-split model (no refit)
    seed: int = 0
    study: StudyOptions = field(default_factory=StudyOptions)


@dataclass
class ObservabilityApp:
    """``swgsim-observability``: the observability map over the output inertia."""

    OUT_DIRS: ClassVar[tuple[str, ...]] = ("data_root", "report_dir")

    dataset: DatasetConfig = field(default_factory=DatasetConfig)  # preset observability
    j_out_kgm2: list[float] | None = None   # null: n_j_out log-spaced, bench to robot link
    n_j_out: int = 6
    data_root: str = "data/observability"   # data sets in <data_root>/j_out_<value>
    report_dir: str = "reports/observability"
    n_jobs: int = field(default=2, metadata=N_JOBS)
    harmonics: int = 8                       # harmonics of the WG angle in the separation
    plot_only: bool = False                  # redraw the figure from observability.csv
    progress: bool = True
    map: str = "steady"                      # steady: the map above; motion: stiffness and
    #                                          wear, steady windows against a joint in motion
    motion: MotionMapConfig = field(default_factory=MotionMapConfig)  # design of map=motion
    motion_steady: DatasetConfig = field(default_factory=DatasetConfig)   # preset robot_joint
    motion_profile: DatasetConfig = field(default_factory=DatasetConfig)  # robot_joint_motion


@dataclass
class MonitorApp:
    """``swgsim-monitor``: one gear's stream through the condition monitor."""

    OUT_DIRS: ClassVar[tuple[str, ...]] = ("out_dir",)

    stream: str = MISSING                    # a life data set (swgsim-generate, dataset.life)
    diagnosis_model: str = MISSING           # a .skops of experiment=monitor (models/), card beside
    # open a legacy .joblib pickle: it runs any code it names when opened (your own files only)
    trust_pickle: bool = False
    gear: int | None = None                  # the gear to monitor when the stream holds several
    out_dir: str = "reports/monitor_run"
    rule: RuleConfig = field(default_factory=RuleConfig)
    normal: NormalConfig = field(default_factory=NormalConfig)  # conditions (temperature, ...)
    naming: NamingConfig = field(default_factory=NamingConfig)  # the naming's tuned numbers
    confirm_h: float = field(default=1.0, metadata=allowed(  # hours after an alarm that name
        0.0, 1000.0, "hours after an alarm whose windows name the fault",  # the fault
        lo_open=True, unit="h"))
    # the joint's maintenance log: [{hour: 40.0, kind: regrease}, ...]; kinds regrease,
    # tool_change, repair (swgmon/assessment/gear_monitor.py MaintenanceEvent)
    maintenance: list[MaintenanceEvent] = field(default_factory=list)
    # after a gear-fault alarm the hours to failure: prognosis.enabled=true; a planned duty
    # prognosis.planned=[{minutes: 60, n_in_rpm: 2500, t_acting_nm: 40, temp_c: 30}]
    # (swgmon/prognosis/stream.py StreamPrognosis)
    prognosis: StreamPrognosis = field(default_factory=StreamPrognosis)
    seed: int = 0                            # the p-values' smoothing draws
    logger: LoggerConfig | None = None


@dataclass
class StoredDataset:
    """A data set already on disk, to read (``conf/stored/<name>.yaml``); the group
    ``dataset`` is the config of a data set to simulate."""

    name: str = "paper"
    path: str = "${paths.data_dir}/paper"


@dataclass
class PathsConfig:
    """Every path the apps read or write; relative paths are from the working directory."""

    root_dir: str = "${oc.env:SWG_ROOT,.}"
    data_dir: str = "${paths.root_dir}/data"
    report_dir: str = "${paths.root_dir}/reports"


@dataclass
class TrainApp:
    """``swgsim-train``: one study job, a sweep, or a task of :data:`swgcli.tasks.TASKS`."""

    OUT_DIRS: ClassVar[tuple[str, ...]] = ("paths.report_dir", "monitor.report_dir",
                                           "prognosis.report_dir", "benchmark.report_dir",
                                           "transfer.report_dir", "transfer.data_root")

    task: str = "study"
    seed: int = 0
    n_jobs: int = field(default=1, metadata=N_JOBS)
    stored: StoredDataset = field(default_factory=StoredDataset)
    features: FeatureSettings = field(default_factory=FeatureSettings)
    input: str | None = None  # null: features; a learn.inputs.signals.INPUTS kind (raw, diff)
    model: Any = MISSING
    protocol: ProtocolConfig = field(default_factory=ProtocolConfig)
    logger: LoggerConfig | None = None
    paths: PathsConfig = field(default_factory=PathsConfig)
    study: StudyOptions = field(default_factory=StudyOptions)
    transfer: TransferConfig | None = None
    monitor: MonitorExperiment | None = None
    prognosis: PrognosisExperiment | None = None
    benchmark: BenchmarkExperiment | None = None
    own_joint: OwnJointExperiment | None = None


#: Keys and groups renamed, per app: old name -> the new one and why. An override that
#: uses an old name is refused naming the new one (:func:`check_renamed`).
_STUDY_RENAMED = {
    "study.baselines": "study.detectors (the per-window detectors beside the monitor; "
                       "'baseline' named three things)",
    "study.baseline_hours": "study.detector_hours",
    "rule.min_baseline": "rule.min_normal_windows (windows per operating point that fit the "
                         "gear's normal behaviour)",
}
_FRICTION_RENAMED = {
    "friction_effects.baseline": "friction_effects.base_model (the calibration's paper-law "
                                 "parameters)",
}
#: Keys renamed, per app: old dotted key (matched at any depth, e.g. ``monitor.study.
#: baselines``) -> the new key and why. Refused in one line naming the new key.
RENAMED: dict[str, dict[str, str]] = {
    "train": {"data": "stored (a data set already on disk, to read; the group 'dataset' "
                      "is the config of a data set to simulate)",
              **_STUDY_RENAMED, **_FRICTION_RENAMED},
    "paper": {"protocols": "run_on (the data sets to run, keys of datasets; 'protocol' "
                           "names only an evaluation protocol, a data set's way of "
                           "acquisition is its acquisition)", **_FRICTION_RENAMED},
    "generate": dict(_FRICTION_RENAMED),
    "observability": dict(_FRICTION_RENAMED),
    "export": dict(_FRICTION_RENAMED),
    "monitor": {"rule.min_baseline": _STUDY_RENAMED["rule.min_baseline"]},
    "calibrate": {"baseline": "base_model (the paper-law model the calibration starts from)"},
}


def check_renamed(overrides: list[str], app: str) -> None:
    """Refuse command-line overrides that use a key or group renamed in ``app``.

    An old key matches an override's key whole, or a whole run of its dotted parts
    (``monitor.study.baselines=...`` matches ``study.baselines``).

    Raises
    ------
    ValueError
        ``<old>: renamed <new> (why)``, for the first override naming an old key.
    """
    renamed = RENAMED.get(app, {})
    for o in overrides:
        key = o.lstrip("+~").split("=", 1)[0].split("@", 1)[0]
        parts = key.split(".")
        for old, new in renamed.items():
            n = len(old.split("."))
            runs = [".".join(parts[i:i + n]) for i in range(len(parts) - n + 1)]
            if old in runs:
                raise ValueError(f"{key.split(old)[0]}{old}: renamed "
                                 f"{key.split(old)[0]}{new}")


def register() -> None:
    """Register the schemas and the generated config groups in Hydra's ConfigStore."""
    from learn.learners.models import MODELS, model_config
    from learn.paper.tables import PAPER_TABLES

    cs = ConfigStore.instance()
    cs.store(name="generate_schema", node=GenerateApp)
    cs.store(name="paper_schema", node=PaperApp)
    cs.store(name="train_schema", node=TrainApp)
    cs.store(name="observability_schema", node=ObservabilityApp)
    cs.store(name="monitor_schema", node=MonitorApp)
    for name in PROTOCOLS:
        cs.store(group="protocol", name=name,
                 node=ProtocolConfig.paper(name, random_state="${seed}"))
    for name in MODELS:  # the paper's (Table VI) and any registered in learn.learners
        cs.store(group="model", name=name, node=model_config(name))
    for k, name in SELECTIONS.items():
        cs.store(group="features", name=name, node=FeatureSettings(name=name, selection=k))
    for name, changes in THERMAL_PRESETS.items():  # the fields each joint changes
        cs.store(group="thermal", name=name, node=dict(changes))
    cs.store(group="paths", name="default", node=PathsConfig)
    cs.store(group="logger", name="mlflow", node=LoggerConfig)
    # swgsim-monitor's tracking as a group option, so that `~logger` removes all of it
    cs.store(group="logger", name="monitor_stream",
             node=LoggerConfig(experiment="monitor/stream", run_name="monitor"))
    # an experiment's tracking as a group option it selects (conf/experiment/*.yaml):
    # keys an experiment set directly would bring a logger back after `~logger`
    for name, experiment in EXPERIMENT_LOGGERS.items():
        cs.store(group="logger", name=name, node=LoggerConfig(experiment=experiment,
                                                              run_name=name))
    for table, spec in PAPER_TABLES.items():
        cs.store(group="experiment", name=f"table_{table.lower()}", package="_global_", node={
            "defaults": [{"override /protocol": spec.protocol}],
            "hydra": {"sweeper": {"params": {
                "features": ",".join(spec.selection_names),
                "model": ",".join(spec.models)}}}})


def validate(cfg: DictConfig, schema: type) -> None:
    """Check a composed app config against its schema before any work.

    Hydra's ``+key=value`` adds a key even to a typed config, so a misspelled key would
    otherwise be ignored silently; mandatory values left at ``???`` are refused too.

    Raises
    ------
    ValueError
        One line: ``<full key>: unknown key; allowed: ...``, ``... missing value``, or a
        value of the wrong type.
    """
    container = OmegaConf.to_container(cfg, resolve=True, throw_on_missing=False)
    container.pop("hydra", None)
    check_keys(container, schema, "")
    if isinstance(container.get("model"), dict):
        check_target(container["model"], "model")
    models = (container.get("transfer") or {}).get("models") if isinstance(
        container.get("transfer"), dict) else None
    for name, m in (models or {}).items():
        check_target(m, f"transfer.models.{name}")
    if isinstance(container.get("monitor"), dict):
        check_monitor_choices(container["monitor"])


def check_monitor_choices(monitor: dict) -> None:
    """Refuse ``monitor.study.faults`` and ``monitor.study.gears`` that a data set of
    ``monitor.run_on`` does not have (they would fail deep in a worker otherwise).

    Raises
    ------
    ValueError
        ``monitor.study.faults: ['x'] not in monitor.datasets.bench; allowed: ...``.
    """
    from swgsim.sensing.sensor_faults import SENSOR_FAULTS

    study = monitor.get("study") or {}
    for name in monitor.get("run_on") or []:
        ds = (monitor.get("datasets") or {}).get(name)
        if not isinstance(ds, dict):
            continue  # refused by the task, naming monitor.run_on
        faults = [f for f in (ds.get("variants") or {}) if f != "healthy"]
        faults += list(SENSOR_FAULTS)
        bad = [f for f in study.get("faults") or [] if f not in faults]
        if bad:
            raise ValueError(f"monitor.study.faults: {bad} not in monitor.datasets.{name}; "
                             f"allowed: its gear faults and the sensor faults {faults}")
        gears = [g.get("id") for g in ds.get("gears") or [] if isinstance(g, dict)]
        bad = [g for g in study.get("gears") or [] if g not in gears]
        if bad:
            raise ValueError(f"monitor.study.gears: {bad} not in monitor.datasets.{name}; "
                             f"allowed: {gears} (empty: every gear)")


def check_target(node: Any, where: str) -> None:
    """Refuse keys of a ``_target_`` config that its target does not take.

    Hydra would only fail when instantiating, with a TypeError that names no key; this
    checks each ``{_target_: path, **kwargs}`` mapping (recursively) against the
    signature of its target.

    Raises
    ------
    ValueError
        ``<where>.<key>: not a parameter of <target>; allowed: ...``, or a ``_target_``
        that cannot be imported.
    """
    import importlib
    import inspect

    if isinstance(node, list):
        for i, v in enumerate(node):
            check_target(v, f"{where}[{i}]")
        return
    if not isinstance(node, dict):
        return
    target = node.get("_target_")
    if target is not None:
        module, _, name = str(target).rpartition(".")
        try:
            obj = getattr(importlib.import_module(module), name)
        except (ImportError, AttributeError, ValueError):
            raise ValueError(f"{where}._target_: cannot import {target!r}") from None
        params = inspect.signature(obj).parameters
        if not any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values()):
            bad = [k for k in node if not k.startswith("_") and k not in params]
            if bad:
                raise ValueError(f"{where}.{bad[0]}: not a parameter of {target}; allowed: "
                                 f"{', '.join(k for k in params if k != 'self')}")
    for k, v in node.items():
        if not k.startswith("_"):
            check_target(v, f"{where}.{k}")


register()
