"""The output folder of a data set: what a run may replace, disk space, finished shards,
the manifest.

A run never deletes nor overwrites what it cannot prove it wrote: the folder is claimed
through its ownership stamp (:mod:`swgsim.files.ownership`); every write is atomic
(:func:`swgsim.files.ownership.atomic_write_json`). Used by
:func:`swgsim.datasets.generate.generate`; takes the checked
:class:`swgsim.datasets.plan.DatasetPlan`.
"""

from __future__ import annotations

import hashlib
import json
import logging
import shutil
from pathlib import Path

from swgsim.datasets.plan import DatasetPlan, ShardSpec
from swgsim.datasets.schema import MANIFEST, SCHEMA_VERSION
from swgsim.files import ownership
from swgsim.files.ownership import atomic_write_json
from swgsim.files.provenance import git_revision, library_versions, package_version
from swgsim.files.writers import others, refuse_others

log = logging.getLogger(__name__)

#: The tag generation claims a folder with (:data:`swgsim.files.writers.WRITERS`).
APP = "swgsim-generate"

__all__ = ["APP", "shard_done", "finished", "prepare_out_dir",
           "check_disk_space", "finalize"]


def shard_done(out_dir: Path, shard: ShardSpec, chash: str) -> bool:
    """Whether a shard's file is there and matches its sidecar (and this config)."""
    f = out_dir / shard.name
    side = f.with_suffix(".json")
    if not (f.is_file() and side.is_file()):
        return False
    try:
        meta = json.loads(side.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError):
        return False
    return (isinstance(meta, dict) and meta.get("config_hash") == chash
            and ownership.sha256(f) == meta.get("sha256"))


def finished(out_dir: Path, plan: DatasetPlan) -> dict | None:
    """The manifest of a finished data set of this config in ``out_dir``, every shard
    present with the SHA-256 it lists; None otherwise. Read-only: such a folder is used
    as it is, whoever wrote it, since nothing needs to be written."""
    if not (out_dir / MANIFEST).is_file():  # a FIFO or a device is never read
        return None
    try:
        manifest = json.loads((out_dir / MANIFEST).read_text())
    except (OSError, ValueError):
        return None
    if not (isinstance(manifest, dict) and manifest.get("complete") is True
            and manifest.get("config_hash") == plan.config_hash
            and isinstance(manifest.get("shards"), dict)
            and set(manifest["shards"]) == {s.name for s in plan.shards}):
        return None
    for name, entry in manifest["shards"].items():
        f = out_dir / name
        if not (isinstance(entry, dict) and f.is_file()
                and ownership.sha256(f) == entry.get("sha256")):
            return None
    return manifest


def _config_of(out_dir: Path, found: ownership.Survey) -> str | None:
    """Config hash of our data set in ``out_dir`` (its manifest, else its config stamp);
    ``"unknown"`` for our files without either; None for a folder without our files."""
    for name in (MANIFEST, ".config.json"):
        if name in found.owned:
            try:
                return str(json.loads((out_dir / name).read_text())["config_hash"])
            except (ValueError, KeyError, TypeError):
                return "unreadable"
    return "unknown" if found.owned else None


def prepare_out_dir(out_dir: Path, plan: DatasetPlan,
                    overwrite: bool) -> tuple[str | None, ownership.Claim]:
    """Claim ``out_dir`` for this data set: create it, or check that it holds (part of) a
    data set of this project.

    The folder must hold nothing but files a run of this project can be shown to have
    written (:func:`swgsim.files.ownership.check`: listed with their SHA-256 in its ownership
    stamp), whatever their names, and written as a data set by a generation run (the
    stamp's writers, :mod:`swgsim.files.writers`: a monitor report, a calibration or any
    other app's output is never replaced); this is checked before anything is touched.
    Then the folder is claimed (:func:`swgsim.files.ownership.claim`: stamped, our temporary
    files of dead processes removed). Our *unfinished* data set of another config (no
    manifest: a run that failed or was stopped) is replaced, so that it never blocks a
    corrected rerun; our *finished* one only with ``overwrite``, and so are files whose
    stamp (an earlier version's) does not say which app wrote them: deleted one by one,
    each checked against the stamp again; the folder itself is kept.

    Returns
    -------
    replaced : str or None
        What was replaced, or None.
    claim : swgsim.files.ownership.Claim
        The claimed folder; the caller closes it.

    Raises
    ------
    ValueError
        Naming the folder: ``out_dir`` is not a folder, holds a file not provably ours
        (named), a file of another app (named with its writer), a finished data set of
        another config or files of an unknown app without ``overwrite``, or another run is
        writing our data set of another config into it; nothing is touched then.
    """
    chash = plan.config_hash
    found = ownership.check(out_dir, "out_dir", share=chash)  # jobs of one data set share it
    other = others(found.writers, APP)
    known = {rel: w for rel, w in other if w is not None}
    if known:  # another app's output: never ours to replace, with or without overwrite
        refuse_others(out_dir, "out_dir", known, APP)
    old = _config_of(out_dir, found)
    replaced = None
    if old not in (None, chash):
        done = MANIFEST in found.owned
        if found.live:
            raise ValueError(f"out_dir {out_dir}: another run is writing into it "
                             f"({found.live[0]}); wait for it or choose another out_dir")
        if other and not overwrite:
            refuse_others(out_dir, "out_dir", dict(other), APP, overwrite="overwrite")
        if done and not overwrite:
            raise ValueError(
                f"out_dir {out_dir} holds a data set made with another config (config "
                f"hash {old}, this one {chash}); choose another out_dir or pass "
                "overwrite=true to replace it")
        replaced = f"{'data set' if done else 'unfinished data set'} in {out_dir} " \
                   f"(config hash {old} -> {chash}"
    claim = ownership.claim(out_dir, APP, found=found, share=chash)
    try:
        if replaced:
            n = claim.remove(found.owned)
            replaced = f"replaced the {replaced}, {n} files)"
            log.info("%s", replaced)  # the caller reports it (summary["replaced"])
        if not (out_dir / ".config.json").is_file():
            atomic_write_json(out_dir / ".config.json",
                                   {"config_hash": chash, "config": plan.plain})
    except BaseException:
        claim.close()
        raise
    return replaced, claim


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
    manifest = {"schema_version": SCHEMA_VERSION, "complete": True,
                "config_hash": plan.config_hash, "config": plan.plain,
                "seed": int(plan.config.seed),
                "n_shards": len(shards),
                "shards": entries, "content_sha256": content, "package_version": package_version(),
                "git_revision": git_revision(), "library_versions": library_versions(),
                "n_samples": int(sum(e["n_samples"] for e in entries.values()))}
    atomic_write_json(out_dir / MANIFEST, manifest)
    return manifest
