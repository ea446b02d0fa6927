"""Task ``transfer`` (``swgsim-train -m experiment=transfer``): the transfer comparison
(:func:`learn.transfer.study.run_comparison`) on every data set of ``transfer.run_on``
(generated when missing), the separability of its classes, and its report
(:mod:`learn.transfer.report`) and MLflow runs. Files in ``report_dir``: see
:mod:`learn.transfer.study`."""

from __future__ import annotations

import dataclasses
import json
import logging
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from learn.studies.runs import net_device_settings
from learn.tasks.config import typed_app
from learn.tasks.parts import part_key, plan_datasets, write_csvs
from learn.transfer.study import TransferConfig, run_comparisons
from swgsim.base.lazy import lazy_module
from swgsim.base.typed import check_tree, plain
from swgsim.datasets.schema import read_manifest
from swgsim.files.inputs import absolute_path
from swgsim.files.ownership import atomic_write_json

pd = lazy_module("pandas")

log = logging.getLogger(__name__)


@dataclass
class _Collected:
    """What the comparison gathered over the data sets."""

    results: list = field(default_factory=list)
    confusion: list = field(default_factory=list)
    run_s: list = field(default_factory=list)
    latency: pd.DataFrame | None = None
    separability: dict = field(default_factory=dict)
    files: dict = field(default_factory=dict)
    input_s: float = 0.0


def _hashes(app, tc: TransferConfig) -> tuple[dict[str, str], dict]:
    """The config hash of every data set of the comparison (``run_on``'s plans, checked
    here once before any work, or the stored data set's manifest) and the plans."""
    if not tc.run_on:
        name = str(app.stored.name or Path(app.stored.path).name)
        return {name: str(read_manifest(app.stored.path).get("config_hash"))}, {}
    plans = plan_datasets(tc.datasets, tc.run_on, "transfer")
    return {n: p.config_hash for n, p in plans.items()}, plans


def _content(tc: TransferConfig) -> dict:
    """What a cell's result depends on beside its data set, split and seed."""
    keep = ("k_shots", "adapt_windows", "aux", "residual", "finetune", "runs", "models")
    return {k: v for k, v in dataclasses.asdict(tc).items() if k in keep}


@dataclass
class CellParts:
    """The comparison's finished cells on disk (:func:`learn.transfer.study.run_comparisons`'s
    ``parts``): ``<folder>/<data set>/<protocol>_<split>_seed<seed>.json`` with a cell's
    result rows and run times, and ``latency.json``; read back only where its key, what
    made it (the data set's config hash, the runs and models, the features, the split
    seed), is the data set's in ``keys``."""

    folder: Path
    keys: dict[str, str]
    _cache: dict = field(default_factory=dict, repr=False)

    def _read(self, path: Path, name: str) -> dict | None:
        try:
            part = json.loads(path.read_text()) if path.is_file() else None
        except (json.JSONDecodeError, UnicodeDecodeError):
            part = None
        ok = isinstance(part, dict) and part.get("key") == self.keys.get(name)
        return part if ok else None

    def _file(self, name: str, c: tuple) -> Path:
        return self.folder / name / f"{c[0]}_{c[1].name}_seed{int(c[2])}.json"

    def load(self, name: str, c: tuple) -> tuple[list, dict] | None:
        """The rows and run seconds of cell ``c`` = (protocol, split, seed), or None."""
        f = self._file(name, c)
        if f not in self._cache:
            part = self._read(f, name)
            self._cache[f] = None if part is None else (
                part["rows"], {k: tuple(v) for k, v in part["seconds"].items()})
        return self._cache[f]

    def save(self, name: str, c: tuple, rows: list, seconds: dict) -> tuple[list, dict]:
        """Write a finished cell (atomically); return it as :meth:`load` reads it back, so
        that a fresh and a resumed run gather the same values."""
        f = self._file(name, c)
        _write_plain(f, {"key": self.keys[name], "rows": rows, "seconds": seconds})
        self._cache.pop(f, None)
        return self.load(name, c)

    def latency(self, name: str):
        """The latency table measured on data set ``name``, or None."""
        part = self._read(self.folder / name / "latency.json", name)
        return None if part is None else pd.DataFrame(part["rows"])

    def save_latency(self, name: str, table) -> None:
        """Keep the latency table measured on data set ``name``."""
        _write_plain(self.folder / name / "latency.json",
                     {"key": self.keys[name], "rows": table.to_dict("records")})


def _write_plain(path: Path, obj: dict) -> None:
    """``obj`` as plain JSON (numpy scalars and arrays as numbers and lists), written
    atomically in its keys' order."""
    atomic_write_json(path, json.loads(json.dumps(obj, default=lambda x: x.tolist()
                                                  if hasattr(x, "tolist") else str(x))),
                      sort_keys=False)


def _data_sets(app, tc: TransferConfig, plans: dict, names: list[str]
               ) -> tuple[list[tuple[str, str]], float]:
    """(name, path) of the data sets ``names``, generating the missing ones."""
    from swgsim.datasets.generate import generate

    if not tc.run_on:
        return [(str(app.stored.name or Path(app.stored.path).name), str(app.stored.path))], 0.0
    root = absolute_path(str(tc.data_root))
    out, t0 = [], time.perf_counter()
    for name in names:
        path = f"{root}/{name}"
        g = generate(plans[name], path, n_jobs=int(tc.n_jobs), overwrite=True,
                     progress=tc.progress)
        if g["computed"]:
            log.info("data set %s: %d shard(s) simulated in %s", name, len(g["computed"]),
                     path)
        out.append((name, path))
    return out, time.perf_counter() - t0


def print_summary(headline: list[str], targets: pd.DataFrame, report_dir: Path,
                  wall_s: float, device: str) -> None:
    """Print the headline (the primary run first, the best beside it chosen afterwards),
    the targets (reached, observable) and where the report went."""
    if headline:
        print("\nresult (worst split, mean over seeds; the declared primary run first):")
        for line in headline:
            print(f"  {line}")
    if len(targets):
        print("\ntargets (worst split, mean over seeds; k labelled target windows per "
              "class):")
        for r in targets.itertuples():
            obs = "" if np.isnan(r.observable) else f", observable {100 * r.observable:.1f} %"
            reached = ("      —  " if r.met is None else f"{100 * r.reached:6.2f} %")
            run = f"{r.run}, {r.split}" if r.run else "—"
            print(f"  {r.dataset:<12s} {r.condition:<44s} target {100 * r.target:5.1f} %  "
                  f"reached {reached} ({r.who}: {run}){obs}")
    print(f"report: {report_dir}/table.md (+ results.csv, confusion.csv, figures); "
          f"{wall_s / 60:.1f} min on {device}")


def net_devices(tc: TransferConfig) -> dict[str, str | int | bool]:
    """Where the comparison's torch nets run on this machine, checked before any work.

    Every model of ``transfer.runs`` with a ``device`` parameter (the torch nets) has it
    resolved (:func:`learn.learners.devices.resolve_device`; the jobs' worker processes
    resolve it alike on this machine).

    Returns
    -------
    dict
        :func:`learn.learners.devices.device_record` of the nets' device (``device`` names
        each, joined by " and ", when they differ); ``{"device": "none (no torch net)",
        "deterministic": True}`` without a net.

    Raises
    ------
    ValueError
        As :func:`learn.studies.runs.net_device_settings`.
    """
    from learn.learners.devices import device_record

    records = {str(dev): device_record(dev)
               for dev in net_device_settings(tc.runs, tc.models).values()}
    if not records:
        return {"device": "none (no torch net)", "deterministic": True}
    out = dict(next(iter(records.values())))
    out["device"] = " and ".join(r["device"] for r in records.values())
    out["deterministic"] = all(r["deterministic"] for r in records.values())
    return out


def _separability(ds, name: str, tc: TransferConfig, report_dir: Path, got: _Collected) -> None:
    """Class separability of the clean and the disturbed windows of one data set."""
    from learn.studies.separability import plot_separability, separations, summary_table

    got.separability[name] = {}
    for kind in ("clean", "disturbed"):
        if not (ds["disturbed"].values.astype(bool) == (kind == "disturbed")).any():
            continue
        sep = separations(ds, disturbed=kind == "disturbed", ratio=float(tc.residual.ratio))
        if "healthy" not in sep:
            continue
        got.separability[name][kind] = summary_table(sep)
        got.files[f"separability_{name}_{kind}"] = plot_separability(
            sep, report_dir / f"separability_{name}_{kind}.png",
            f"Class separability, data set {name} ({kind} windows)")


def _compare(app, tc: TransferConfig, data_sets, report_dir: Path, parts: CellParts
             ) -> _Collected:
    """The comparison and the separability on every data set, one pool of workers for
    all of them (:func:`learn.transfer.study.run_comparisons`); one data set in memory
    at a time, its separability computed when it is loaded."""
    from functools import partial

    from swgsim.datasets.schema import load

    got = _Collected()

    def loaded(name: str, ds) -> None:
        log.info("transfer: %s, %d windows, %d runs", name, ds.sizes["sample"], len(tc.runs))
        _separability(ds, name, tc, report_dir, got)

    outs = run_comparisons([(name, partial(load, path)) for name, path in data_sets], tc,
                           feature_kwargs=app.features.kwargs(), split_seed=app.seed,
                           checked=True, on_load=loaded, parts=parts)
    for out in outs.values():
        got.results.append(out["results"])
        got.confusion.append(out["confusion"])
        got.run_s.append(out["run_s"])
        got.input_s += out["input_s"]
        if len(out["latency"]):
            got.latency = out["latency"]
    return got


def _timings(tc: TransferConfig, wall: float, input_s: float, generate_s: float,
             nets: dict) -> dict:
    threads = (f"{tc.n_jobs} process(es) x {tc.threads_per_job or 'default'} torch thread(s)"
               if tc.n_jobs > 1 else f"1 process x {tc.n_threads} torch thread(s)")
    det = "deterministic" if nets["deterministic"] else "not deterministic"
    return {"wall_s": wall, "input_s": input_s, "generate_s": generate_s, "threads": threads,
            "cpus": os.cpu_count(), "device": f"{nets['device']} (the nets; {det})",
            "nets": nets}


def _write(res, conf, got: _Collected, tc: TransferConfig, report_dir: Path, timings) -> dict:
    """results.csv, confusion.csv, run_times.csv, latency.csv, table.md and
    accuracy_vs_k.png."""
    from learn.transfer.figure import plot_accuracy_vs_k
    from learn.transfer.report import write_table

    files = dict(got.files)
    run_s = pd.concat(got.run_s, ignore_index=True) if got.run_s else None
    latency = got.latency if got.latency is not None and len(got.latency) else None
    tables = {"results": res, "confusion": conf, "run_times": run_s, "latency": latency}
    written = write_csvs(report_dir, {f"{key}.csv": table for key, table in tables.items()
                                      if table is not None})
    files.update({path.stem: path for path in written})
    targets = {d: t for d, t in tc.targets.items() if d in set(res["dataset"])}
    files["table"] = write_table(res, conf, report_dir / "table.md", targets=targets,
                                 primary=tc.primary, separability=got.separability,
                                 latency=got.latency, timings=timings,
                                 adapt_windows=int(tc.adapt_windows), run_times=run_s)
    files["figure"] = plot_accuracy_vs_k(res, report_dir / "accuracy_vs_k.png",
                                         targets=targets, separability=got.separability)
    return files


def _group_done(tc: TransferConfig, name: str, report_dir: Path, wall: float) -> dict:
    """One data set's cells done (a job of an array): said, and returned."""
    if tc.progress:
        print(f"transfer.group {tc.group} ({name}): its cells in {report_dir}/parts/{name}, "
              f"{wall / 60:.1f} min; the report: the same command without transfer.group")
    return {"task": "transfer", "report_dir": str(report_dir), "group": tc.group,
            "dataset": name, "wall_s": wall}


def run_transfer(cfg) -> dict:
    """Task ``transfer``: the whole comparison over the data sets, report and MLflow.

    Reads ``transfer`` (:class:`learn.transfer.study.TransferConfig`,
    ``conf/experiment/transfer.yaml``), ``stored`` (when ``transfer.run_on`` is empty),
    ``features`` (orders, floor), ``logger`` (:class:`learn.tracking.config.LoggerConfig`;
    None: no tracking) and ``seed`` (CV folds).

    Parameters
    ----------
    cfg : swgcli.schema.TrainApp or omegaconf.DictConfig
        The typed app config (:func:`learn.tasks.config.typed_app`).

    Returns
    -------
    dict
        ``report_dir``, ``files``, ``wall_s``, ``n_runs``, ``worst_split`` (per data set,
        ood_disturbed worst-split mean accuracy per model/input/k), ``headline`` (rows of
        :func:`learn.transfer.picks.headline_table`: the primary run first, the
        best beside it), ``targets`` (rows of
        :func:`learn.transfer.report.target_table`), ``run_id`` (parent MLflow run).

    Raises
    ------
    ValueError
        A missing ``transfer`` config, a bad ``transfer`` key (a net's device that this
        machine does not have among them, :func:`net_devices`), or a ``report_dir``
        holding a file this project cannot show it wrote (named); before any work.
    """
    import torch

    from learn.transfer.runs import log_transfer
    from swgsim.files import ownership

    app = typed_app(cfg)
    tc = app.transfer
    if tc is None:
        raise ValueError("transfer: missing; the task needs experiment=transfer (or a "
                         "transfer group of its own)")
    check_tree(tc, "transfer")  # its data sets, then TransferConfig.check
    report_dir = Path(tc.report_dir or Path(app.paths.report_dir) / "transfer")
    nets = net_devices(tc)  # a CUDA device asked for on a machine without one: refused
    hashes, plans = _hashes(app, tc)
    # the jobs of one comparison (its data sets and runs) may write into it together
    share = part_key([sorted(hashes.items()), _content(tc)])
    ownership.check(report_dir, "transfer.report_dir", share=share,
                    app="transfer")  # before any work
    if tc.n_threads:
        torch.set_num_threads(int(tc.n_threads))
    t_all = time.perf_counter()
    names = list(hashes) if tc.group is None else [list(hashes)[tc.group]]
    data_sets, generate_s = _data_sets(app, tc, plans, names)
    keys = {n: part_key([h, _content(tc), app.features.kwargs(), app.seed])
            for n, h in hashes.items()}
    with ownership.claim(report_dir, "transfer", "transfer.report_dir", share=share,
                         strict=True) as claim:
        got = _compare(app, tc, data_sets, report_dir, CellParts(report_dir / "parts", keys))
        if tc.group is not None:
            return _group_done(tc, names[0], report_dir, time.perf_counter() - t_all)
        res = pd.concat(got.results, ignore_index=True)
        conf = pd.concat(got.confusion, ignore_index=True)
        wall = time.perf_counter() - t_all
        timings = _timings(tc, wall, got.input_s, generate_s, nets)
        files = _write(res, conf, got, tc, report_dir, timings)
        claim.record(files.values())
    run_id = None if app.logger is None else log_transfer(
        res, files, app.logger, tc, data_sets, timings, got.latency, config=plain(app))
    log.info("transfer report in %s (%.1f min)", report_dir, wall / 60)
    return {"task": "transfer", "report_dir": str(report_dir),
            "files": {k: str(v) for k, v in files.items()}, "wall_s": wall,
            "n_runs": len(res), "run_id": run_id,
            **_summary(res, conf, got, tc, report_dir, wall, timings["device"])}


def _summary(res, conf, got: _Collected, tc: TransferConfig, report_dir: Path, wall: float,
             device: str) -> dict:
    """The worst split per run, the headline and the targets (printed with
    :func:`print_summary` when ``tc.progress``)."""
    from learn.transfer.picks import headline_lines, headline_table
    from learn.transfer.report import class_recall, row_label, summarise, target_table

    summ = summarise(res)
    w = summ[(summ["protocol"] == "ood_disturbed") & (summ["split"] == "worst")]
    worst = {f"{r.dataset}/{r.model}/{r.input}/k{int(r.k_shot)}": float(r.mean)
             for r in w.itertuples()}
    targets = {d: t for d, t in tc.targets.items() if d in set(res["dataset"])}
    tt = (target_table(summ, class_recall(conf, summ), targets, tc.primary, got.separability)
          if len(conf) else pd.DataFrame())
    head = headline_table(summ, tc.primary)
    if tc.progress:  # the console's summary (the log holds every cell)
        print_summary(headline_lines(head, row_label), tt, report_dir, wall, device)
    return {"worst_split": worst, "headline": head.to_dict("records"),
            "targets": tt.to_dict("records")}
