"""Resumable parts of an evaluation, saved as each ends, grouped for job arrays: a part's
key (:func:`part_key`, the hash of what made it), the parts of one (data set, held-out
gear) run in one worker, in order (:func:`run_parts`, :func:`run_group`), resumed from
``parts/`` when their key matches (:func:`finished_parts`), each data set's design part
before its lives' (:meth:`EvaluationExperiment.run_stages`), and one (data set, held-out
gear) alone as a job of a cluster array (:func:`group_jobs`, :func:`run_one_group`); the
options an evaluation's group of ``swgsim-train`` shares (:class:`EvaluationExperiment`);
what reports write alike (:func:`write_csvs`). Used by the
monitor's, the prognosis's and the benchmark's evaluations (:mod:`swgmon.evaluation`) and
the transfer comparison (:mod:`learn.transfer.task`)."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tqdm.auto import tqdm

from learn.tracking.store import check_tracking
from swgsim.base.lazy import lazy_module
from swgsim.base.registry import travelling
from swgsim.base.typed import allowed
from swgsim.datasets.config import DatasetConfig
from swgsim.datasets.plan import DatasetPlan, plan
from swgsim.files import ownership
from swgsim.files.ownership import atomic_write_json, write_owned

joblib = lazy_module("joblib")

log = logging.getLogger(__name__)


#: A data set's design part in a staged evaluation (:meth:`EvaluationExperiment.run_stages`).
DESIGN = "design"


@dataclass(frozen=True)
class Job:
    """One resumable part: the monitor (``detector`` None) or one per-window detector on
    one held-out gear of one data set; of a staged evaluation
    (:meth:`EvaluationExperiment.run_stages`), a data set's design part (``gear`` 0,
    ``detector`` :data:`DESIGN`) or its lives on one held-out gear (``detector`` None, or
    the family they live)."""

    dataset: str
    gear: int
    detector: str | None
    key: str

    @property
    def file(self) -> str:
        """Its part's file name in ``parts/``."""
        return (f"{self.dataset}{f'_gear{self.gear}' if self.gear else ''}"
                f"{'_' + self.detector if self.detector else ''}.json")

    @property
    def held_out(self) -> str:
        """What it scores, in messages."""
        return "its design" if self.detector == DESIGN else f"held-out gear {self.gear}"


@dataclass(kw_only=True)
class EvaluationExperiment:
    """What the ``monitor`` and ``prognosis`` groups of ``swgsim-train`` share
    (:class:`swgmon.evaluation.task.MonitorExperiment`,
    :class:`swgmon.evaluation.prognosis_task.PrognosisExperiment` add their study's
    type and default, their ``report_dir`` default and what only they have).

    Attributes
    ----------
    run_on : list of str
        Keys of ``datasets`` to evaluate, in order; default the bench and the robot joint
        [choice].
    datasets : dict of str to DatasetConfig
        Data-set presets whose gears live (their chain, acquisition, gears, Table V grid).
    study : dataclass
        The evaluation's design (its type and default: the evaluation's).
    report_dir : str
        The report's folder (its default: the evaluation's).
    n_jobs : int
        Worker processes, one part each (a data set and held-out gear; the monitor's: and
        one detector); default 2 [choice].
    progress : bool
    group : int or None
        Evaluate only the (data set, held-out gear) of this index, in the order of
        ``run_on`` and the gears (a job of a cluster array: ``monitor.group=range(0,N)``
        with a submitit launcher, docs/scale_out.md), writing its parts to ``parts/`` and
        no report; the jobs of one evaluation share ``report_dir``. None: every one still
        to do, then the report.
    """

    run_on: list[str] = field(default_factory=lambda: ["bench", "robot_joint"])
    datasets: dict[str, DatasetConfig] = field(default_factory=dict)
    study: Any
    report_dir: str
    n_jobs: int = field(default=2, metadata=allowed(1, None, "worker processes"))
    progress: bool = True
    group: int | None = field(default=None, metadata=allowed(0, None, "group index"))

    def plans(self, where: str) -> dict[str, DatasetPlan]:
        """The shared keys checked and each data set of ``run_on`` planned
        (:func:`swgsim.datasets.plan.plan`, which checks its config), before any work.

        Parameters
        ----------
        where : str
            The group's name in messages (``monitor``, ``prognosis``).

        Returns
        -------
        dict of str to DatasetPlan
            Per key of ``run_on``, in its order.

        Raises
        ------
        ValueError
            ``run_on`` empty or naming a key not in ``datasets``, ``n_jobs`` < 1, or a
            data set's config out of its ranges (``<where>.datasets.<name>: ...``).
        """
        unknown = [d for d in self.run_on if d not in self.datasets]
        if unknown or not self.run_on:
            raise ValueError(f"{where}.run_on: {unknown or 'empty'}; allowed: keys of "
                             f"{where}.datasets {sorted(self.datasets)}")
        if self.n_jobs < 1:
            raise ValueError(f"{where}.n_jobs must be >= 1, got {self.n_jobs}")
        return plan_datasets(self.datasets, self.run_on, where)

    @contextmanager
    def claimed_report(self, where: str, plans: dict[str, DatasetPlan], logger
                       ) -> Iterator[tuple[Path, Any]]:
        """The report folder checked and claimed for this evaluation, before any work: the
        MLflow store (``logger``, where not a job of an array), then ``report_dir``
        (:func:`swgsim.files.ownership.check`, ``claim``), shared by the jobs of one
        evaluation (:func:`share_key`: the same data sets and design).

        Yields
        ------
        out : Path
            ``report_dir``.
        claim
            The claim (:func:`swgsim.files.ownership.claim`).

        Raises
        ------
        ValueError
            An unwritable MLflow store, or a ``report_dir`` holding a file this project
            cannot show it wrote (named ``<where>.report_dir``).
        """
        if logger is not None and self.group is None:
            check_tracking(logger.tracking_uri, "logger.tracking_uri")
        out = Path(self.report_dir)
        share = share_key(plans, self.study)
        ownership.check(out, f"{where}.report_dir", share=share, app=where)
        with ownership.claim(out, where, f"{where}.report_dir", share=share,
                             strict=True) as claim:
            yield out, claim

    def run_stages(self, where: str, plans: dict[str, DatasetPlan], logger,
                   design_jobs: list[Job], life_jobs: list[Job], design: Callable,
                   lives: Callable, report: Callable[..., dict]) -> dict:
        """An evaluation in two stages, in its claimed report folder (:meth:`claimed_report`;
        ``parts/`` and ``models/`` made): each data set's design part (:data:`DESIGN`, by
        ``design(plan, jobs, study, out)``: its model, trained once, written by the part),
        then the lives' parts (per data set and held-out gear, by ``lives(plan, jobs,
        study, out, design part)``), both by :func:`run_parts` (progress lines ``<where>
        design``, ``<where> lives``; the workers return :func:`run_group`'s pairs); then
        ``report(out, claim, design parts, lives' parts, wall time [s], parts resumed)``'s
        summary. With ``group``, that group's parts alone (a job of an array, option
        ``<where>.group``; :func:`run_one_group`), no report: its summary with ``task`` =
        ``where``.

        Raises
        ------
        ValueError
            ``group`` beyond the groups (:func:`group_jobs`), a lives group before its
            data set's design part (naming the group to run first), or as
            :meth:`claimed_report`; before any work.
        """
        key = f"{where}.group"
        jobs = group_jobs(design_jobs + life_jobs, self.group, key)
        with self.claimed_report(where, plans, logger) as (out, claim):
            (out / "parts").mkdir(parents=True, exist_ok=True)
            (out / "models").mkdir(exist_ok=True)
            by: dict[str, dict] = {}  # data set -> its design part, for its lives

            def run_design(js: list[Job]):
                return joblib.delayed(design)(plans[js[0].dataset], js, self.study, str(out))

            def run_lives(js: list[Job]):
                return joblib.delayed(lives)(plans[js[0].dataset], js, self.study, str(out),
                                             by[js[0].dataset])
            if self.group is not None:  # its lives read their design part from parts/
                first = [j for j in design_jobs if j.dataset == jobs[0].dataset]
                done, _ = finished_parts(out, first)
                if jobs[0].detector != DESIGN and not done:
                    raise ValueError(f"{key}={self.group} lives {jobs[0].dataset}'s held-out "
                                     f"instance {jobs[0].gear} and needs its design part "
                                     f"first: run {key}={design_jobs.index(first[0])} before")
                by.update({d["dataset"]: d for d in done})
                run = run_design if jobs[0].detector == DESIGN else run_lives
                return {"task": where, **run_one_group(out, jobs, run, where, self.progress,
                                                       self.n_jobs, key, self.group)}
            t0 = time.perf_counter()
            designs, r0 = run_parts(out, design_jobs, run_design, f"{where} design",
                                    self.progress, self.n_jobs)
            by.update({d["dataset"]: d for d in designs})
            parts, r1 = run_parts(out, life_jobs, run_lives, f"{where} lives", self.progress,
                                  self.n_jobs)
            return report(out, claim, designs, parts, time.perf_counter() - t0, r0 + r1)


def plan_datasets(datasets: dict[str, DatasetConfig], names: list[str], where: str
                  ) -> dict[str, DatasetPlan]:
    """Each data set of ``names`` planned (:func:`swgsim.datasets.plan.plan`, which checks
    its config), in their order.

    Raises
    ------
    ValueError
        A data set's config out of its ranges, named ``<where>.datasets.<name>: ...``.
    """
    plans = {}
    for name in names:
        try:
            plans[name] = plan(datasets[name])
        except ValueError as e:
            raise ValueError(f"{where}.datasets.{name}: {e}") from None
    return plans


def part_key(obj: object) -> str:
    """The key of a part: the first 16 hex digits of the SHA-256 of ``obj`` as sorted JSON
    (what made it: the data set's config hash, the gear, the study)."""
    return hashlib.sha256(json.dumps(obj, sort_keys=True, default=str).encode()).hexdigest()[:16]


def share_key(plans: dict[str, DatasetPlan], study: object) -> str:
    """What the jobs of one evaluation share their report folder by
    (:func:`swgsim.files.ownership.claim`'s ``share``): its data sets' config hashes and
    its design."""
    return part_key([p.config_hash for p in plans.values()] + [dataclasses.asdict(study)])


def group_jobs(jobs: list[Job], group: int | None, key: str = "monitor.group"
               ) -> list[Job]:
    """The jobs of the (data set, held-out gear) of index ``group`` (in the jobs' order),
    or all of them for None; ``key``: the option's name in messages.

    Raises
    ------
    ValueError
        ``group`` beyond the evaluation's (data set, held-out gear) pairs, naming them.
    """
    if group is None:
        return jobs
    keys = list(dict.fromkeys((j.dataset, j.gear) for j in jobs))
    if not 0 <= group < len(keys):
        pairs = ", ".join(f"{k}: {d}" + (f" gear {g}" if g else "")
                          for k, (d, g) in enumerate(keys))
        raise ValueError(f"{key} must lie in [0, {len(keys) - 1}] ({pairs}), got {group}")
    return [j for j in jobs if (j.dataset, j.gear) == keys[group]]


def run_one_group(out: Path, jobs: list[Job], delayed: Callable, desc: str, progress: bool,
                  n_jobs: int, key: str, group: int) -> dict:
    """One (data set, held-out gear)'s parts into ``out/parts`` (a job of an array, option
    ``key`` = ``group``; :func:`run_parts`), no report; returns its summary."""
    (out / "parts").mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    parts, resumed = run_parts(out, jobs, delayed, desc, progress, n_jobs)
    wall = time.perf_counter() - t0
    if progress:
        print(f"{key} {group} ({jobs[0].dataset}, {jobs[0].held_out}): "
              f"{len(parts)} part(s) in {out}/parts ({resumed} already there), "
              f"{wall / 60:.1f} min; the report: the same command without {key}")
    return {"report_dir": str(out), "group": group, "parts": [j.file for j in jobs],
            "wall_s": wall}


def finished_parts(out: Path, jobs: list[Job]) -> tuple[list[dict], list[Job]]:
    """Parts already done in ``out/parts`` (their key matches) and the jobs left."""
    done, todo = [], []
    for j in jobs:
        f = out / "parts" / j.file
        try:
            part = json.loads(f.read_text()) if f.is_file() else None
        except (json.JSONDecodeError, UnicodeDecodeError):
            part = None
        if part is not None and part.get("key") == j.key:
            done.append(part)
        else:
            todo.append(j)
    return done, todo


def save_part(out: Path, job: Job, part: dict) -> None:
    """Write a finished part to ``parts/`` in its keys' order (not sorted), so that the
    tables of a resumed run, read back by :func:`finished_parts`, keep a fresh run's columns."""
    atomic_write_json(out / "parts" / job.file, part, sort_keys=False)


def run_parts(out: Path, jobs: list[Job], delayed: Callable, desc: str, progress: bool,
              n_jobs: int) -> tuple[list[dict], int]:
    """Each part, resumed from ``out/parts`` when its key matches (:func:`finished_parts`),
    the others run by ``n_jobs`` workers, those of one (data set, held-out gear) in one
    worker, in order, so that they share its gears' records (simulated once instead of once
    per part); each part is saved as it ends (:func:`save_part`, by the worker); one
    progress line over all of them and a log line per finished group.

    Parameters
    ----------
    out : Path
        The report folder.
    jobs : list of Job
    delayed : callable
        A list of jobs (one data set, one held-out gear) -> the ``joblib.delayed`` call
        that runs them in order, saves each part as it ends and returns the list of
        ``(part, job)``.
    desc : str
        The progress line's label.
    progress : bool
    n_jobs : int

    Returns
    -------
    (list of dict, int)
        The parts in the jobs' order, and how many were resumed.
    """
    done, todo = finished_parts(out, jobs)
    resumed = len(done)
    if done:
        log.info("resuming: %d of %d part(s) already done", len(done), len(jobs))
    groups: dict[tuple, list[Job]] = {}
    for j in todo:
        groups.setdefault((j.dataset, j.gear), []).append(j)
    bar = tqdm(total=len(todo), desc=desc, unit="part", disable=not progress)
    par = joblib.Parallel(n_jobs=min(n_jobs, max(1, len(groups))),
                          return_as="generator_unordered")
    t0 = time.perf_counter()
    # each group's call, with this process's registries (a user's detectors, faults, ...)
    calls = (delayed(g) for g in groups.values())  # (function, args, kwargs)
    for finished in par((travelling(f), a, kw) for f, a, kw in calls):
        done += [part for part, _ in finished]
        bar.update(len(finished))
        log.info("part(s) %s done (%d of %d left, %.1f min so far)",
                 ", ".join(job.file for _, job in finished), bar.total - bar.n, bar.total,
                 (time.perf_counter() - t0) / 60)
    bar.close()
    order = {j.key: i for i, j in enumerate(jobs)}
    return sorted(done, key=lambda p: order[p["key"]]), resumed


def run_group(out: str | Path, jobs: list[Job], run_one: Callable[[Job], dict]
              ) -> list[tuple[dict, Job]]:
    """In a worker: each job's part by ``run_one``, in order, its key set, made plain JSON
    and saved as it ends (:func:`save_part`); returns the ``(part, job)`` pairs
    (:func:`run_parts`'s ``delayed``)."""
    finished = []
    for job in jobs:
        part = run_one(job)
        part["key"] = job.key
        part = json.loads(json.dumps(part, default=float))
        save_part(Path(out), job, part)
        finished.append((part, job))
    return finished


def resumed_note(resumed: int, n_parts: int) -> str:
    """What follows an evaluation's wall time when its run of ``n_parts`` parts resumed
    ``resumed`` of them from ``parts/`` (:func:`run_parts`): their time was spent by an
    earlier run, not in this one's wall time; empty when none was."""
    return (f" ({resumed} of {n_parts} parts resumed from parts/, not timed here)"
            if resumed else "")


def write_csvs(out: Path, tables: dict[str, Any]) -> list[Path]:
    """Each table of ``tables`` (file name -> DataFrame) into ``out`` as CSV without its
    index, in their order, as a run writes its files
    (:func:`swgsim.files.ownership.write_owned`); returns their paths (the claim's record)."""
    for name, table in tables.items():
        write_owned(out / name, lambda tmp, t=table: t.to_csv(tmp, index=False))
    return [out / name for name in tables]


__all__ = ["DESIGN", "EvaluationExperiment", "Job", "finished_parts", "group_jobs", "part_key",
           "plan_datasets", "resumed_note", "run_group", "run_one_group", "run_parts",
           "save_part", "share_key", "write_csvs"]
