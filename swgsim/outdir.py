"""The output folder of a data set: what a run may replace, disk space, finished shards,
the manifest.

A run never deletes what it did not create: a folder is replaced only when it holds
nothing but this project's data-set files (:data:`DATASET_FILE`), and every write is
atomic (:func:`swgsim.data.atomic_write_json`). Used by :func:`swgsim.generate.generate`;
takes the checked :class:`swgsim.plan.DatasetPlan`.
"""

from __future__ import annotations

import hashlib
import json
import logging
import re
import shutil
import subprocess
from pathlib import Path
from typing import TYPE_CHECKING

from . import data as dsio

if TYPE_CHECKING:
    from .plan import DatasetPlan, ShardSpec

log = logging.getLogger(__name__)

__all__ = ["package_version", "git_revision", "shard_done", "DATASET_FILE",
           "foreign_entries", "prepare_out_dir", "check_disk_space", "finalize"]


def package_version() -> str:
    """Installed version of this package, ``"unknown"`` when not installed."""
    try:
        from importlib.metadata import version

        return version("swg-monitor")
    except Exception:  # noqa: BLE001 - not installed
        return "unknown"


def git_revision() -> str:
    """Short git commit of the source tree, ``"unknown"`` without git."""
    try:
        out = subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], capture_output=True,
                             text=True, cwd=Path(__file__).parent, timeout=10)
        return out.stdout.strip() or "unknown"
    except Exception:  # noqa: BLE001 - no git
        return "unknown"


def shard_done(out_dir: Path, shard: ShardSpec, chash: str) -> bool:
    """Whether a shard's file is there and matches its sidecar (and this config)."""
    f = out_dir / shard.name
    side = f.with_suffix(".json")
    if not (f.is_file() and side.is_file()):
        return False
    try:
        meta = json.loads(side.read_text())
    except json.JSONDecodeError:
        return False
    return meta.get("config_hash") == chash and dsio.sha256_file(f) == meta.get("sha256")


#: Names of the files a data set of this project consists of: its manifest, the config
#: stamp, the shards and their sidecars, and temporary files of an interrupted write.
DATASET_FILE = re.compile(
    r"manifest\.json|\.config\.json|gear\d+_(n\d+rpm|life)\.(nc|json)|\..+\.tmp")


def foreign_entries(out_dir: Path) -> list[str]:
    """Names of the entries of ``out_dir`` that are not files of this project's data set
    (:data:`DATASET_FILE`); folders and links always count as foreign."""
    return sorted(p.name for p in Path(out_dir).iterdir()
                  if p.is_symlink() or not p.is_file() or not DATASET_FILE.fullmatch(p.name))


def prepare_out_dir(out_dir: Path, plan: DatasetPlan, overwrite: bool) -> str | None:
    """Create ``out_dir``, or check that it holds (part of) a data set of this config.

    Temporary files that dead processes of this host left behind are removed. A folder
    holding an *unfinished* data set of another config (no manifest: a run that failed or
    was stopped) is replaced, so that it never blocks a corrected rerun; a *finished* one
    only with ``overwrite``. Either way the folder must hold nothing but this project's
    data-set files (:func:`foreign_entries`), which are deleted one by one; the folder
    itself is kept.

    Returns
    -------
    str or None
        What was replaced, or None.

    Raises
    ------
    ValueError
        Naming the folder, if ``out_dir`` is not a folder, holds a finished data set of
        another config without ``overwrite``, holds anything else, or another run is
        writing into it; nothing is touched then.
    """
    chash = plan.config_hash
    mf = out_dir / dsio.MANIFEST
    stamp = out_dir / ".config.json"
    replaced = None
    if out_dir.exists() and not out_dir.is_dir():
        raise ValueError(f"out_dir {out_dir} exists and is not a folder")
    if out_dir.exists():
        for f in dsio.stale_temp_files(out_dir):  # left by a killed run
            f.unlink(missing_ok=True)
            log.info("removed %s, left by a stopped run", f.name)
    if out_dir.exists() and any(out_dir.iterdir()):
        old = None
        for f in (mf, stamp):
            if f.is_file():
                try:
                    old = json.loads(f.read_text()).get("config_hash")
                except (json.JSONDecodeError, UnicodeDecodeError, AttributeError):
                    old = "unreadable"
                break
        if old != chash:
            foreign = foreign_entries(out_dir)
            finished = mf.is_file()
            if foreign:
                what = ("holds no data set" if old is None else
                        f"holds a data set of another config (hash {old}, this one {chash})")
                raise ValueError(
                    f"out_dir {out_dir} {what} and {len(foreign)} entr"
                    f"{'y' if len(foreign) == 1 else 'ies'} that are not this project's "
                    f"data set (e.g. {', '.join(foreign[:3])}); nothing was touched: "
                    "choose another out_dir")
            live = [p.name for p in out_dir.iterdir() if p.name.endswith(".tmp")]
            if live:
                raise ValueError(f"out_dir {out_dir}: another run is writing into it "
                                 f"({live[0]}); wait for it or choose another out_dir")
            if finished and not overwrite:
                raise ValueError(
                    f"out_dir {out_dir} holds a data set made with another config (config "
                    f"hash {old}, this one {chash}); choose another out_dir or pass "
                    "overwrite=true to replace it")
            files = sorted(out_dir.iterdir())
            for f in files:
                f.unlink()
            replaced = (f"replaced the {'data set' if finished else 'unfinished data set'} "
                        f"in {out_dir} (config hash {old} -> {chash}, {len(files)} files)")
            log.info("%s", replaced)  # the caller reports it (summary["replaced"])
    out_dir.mkdir(parents=True, exist_ok=True)
    if not stamp.is_file():
        dsio.atomic_write_json(stamp, {"config_hash": chash, "config": plan.as_dict()})
    return replaced


def check_disk_space(out_dir: Path, shards: list[ShardSpec], plan: DatasetPlan) -> None:
    """Refuse to start when the disk of ``out_dir`` cannot hold the shards to write.

    Raises
    ------
    ValueError
        Naming the folder, the space needed and the space free.
    """
    n_t = int(round(plan.config.chain.window_s * plan.config.chain.sample_rate_hz))
    windows = sum(s.n_windows for s in shards)
    need = int(1.1 * windows * (5 * n_t * 4 + 200)) + (1 << 20)  # float32 signals + metadata
    probe = out_dir
    while not probe.exists():
        probe = probe.parent
    free = shutil.disk_usage(probe).free
    if free < need:
        raise ValueError(f"out_dir {out_dir}: the data set needs about {need / 2**20:.0f} MiB, "
                         f"the disk holding {probe} has {free / 2**20:.0f} MiB free")


def finalize(out_dir: Path, plan: DatasetPlan) -> dict:
    """Write the manifest once every shard is present and verified; return it."""
    shards = plan.shards
    entries = {}
    for s in shards:
        meta = json.loads((out_dir / s.name).with_suffix(".json").read_text())
        entries[s.name] = {"sha256": meta["sha256"], "n_samples": meta["n_samples"],
                           "content_sha256": meta["content_sha256"]}
    content = hashlib.sha256("".join(entries[s.name]["content_sha256"]
                                     for s in shards).encode()).hexdigest()
    manifest = {"schema_version": dsio.SCHEMA_VERSION, "complete": True,
                "config_hash": plan.config_hash, "config": plan.as_dict(),
                "seed": int(plan.config.seed),
                "n_shards": len(shards),
                "shards": entries, "content_sha256": content, "package_version": package_version(),
                "git_revision": git_revision(),
                "n_samples": int(sum(e["n_samples"] for e in entries.values()))}
    dsio.atomic_write_json(out_dir / dsio.MANIFEST, manifest)
    return manifest
