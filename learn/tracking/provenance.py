"""Provenance of an MLflow run: git state, data-set identity, how a model is stored.

Used by :func:`learn.tracking.log_run`, which attaches all of it to every run:

* :func:`git_tags` - the commit of the checkout and whether its work tree is dirty;
  :func:`provenance_tags` - those and the versions of numpy, scipy, scikit-learn, torch;
* :func:`dataset_ref` - a data set's name, absolute path and content hash, read from its
  ``manifest.json`` (schema v1, ``docs/DATASET.md``) rather than re-hashing gigabytes of
  shards;
* :func:`sklearn_only`, :func:`model_requirements` - the serialization format and pip
  requirements of a logged model.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from pathlib import Path

from swgsim.datasets.schema import MANIFEST, DataSetError, read_manifest
from swgsim.files.digest import sha256_file
from swgsim.files.provenance import library_versions

#: Run tag of the git commit (MLflow's own key, shown in its UI) and of the dirty flag.
GIT_COMMIT_TAG = "mlflow.source.git.commit"
GIT_DIRTY_TAG = "git_dirty"
#: Hex characters of a data set's SHA-256 kept as MLflow's dataset digest (MLflow: <= 36).
DIGEST_CHARS = 32


@functools.lru_cache(maxsize=8)
def _git_state(root: str) -> tuple[str, str]:
    import subprocess

    def git(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run(["git", *args], cwd=root, capture_output=True, text=True,
                              timeout=20)

    try:
        head = git("rev-parse", "HEAD")
        if head.returncode != 0:
            return "unknown", "unknown"
        status = git("status", "--porcelain")
    except (OSError, subprocess.SubprocessError):
        return "unknown", "unknown"
    dirty = "unknown" if status.returncode else str(bool(status.stdout.strip())).lower()
    return head.stdout.strip(), dirty


def repo_root() -> Path:
    """Root of the source checkout.

    Returns
    -------
    Path
        The parent of the ``learn`` package if it holds ``pyproject.toml`` (a source
        checkout or editable install), otherwise the current working directory.
    """
    here = Path(__file__).resolve().parents[2]
    return here if (here / "pyproject.toml").is_file() else Path.cwd()


#: Prefix of the run tags that record a library's version (``library.numpy``, ...).
LIBRARY_TAG = "library."


def provenance_tags(root: str | Path | None = None) -> dict[str, str]:
    """Every run's provenance tags: the git state (:func:`git_tags`) and the versions of
    the numerical libraries (:func:`swgsim.files.provenance.library_versions`, tagged
    ``library.<name>``).

    Returns
    -------
    dict of str to str
    """
    return {**git_tags(root),
            **{LIBRARY_TAG + k: v for k, v in library_versions().items()}}


def git_tags(root: str | Path | None = None) -> dict[str, str]:
    """Git commit of a checkout and whether its work tree differs from it, as run tags.

    Read once per process and folder (cached), so a study of hundreds of runs asks git
    once; the state recorded is the one when the first run was logged.

    Parameters
    ----------
    root : path-like, optional
        Folder inside the checkout; default :func:`repo_root`.

    Returns
    -------
    dict of str to str
        ``{GIT_COMMIT_TAG: 40 hex digits, GIT_DIRTY_TAG: "true" | "false"}``: dirty when
        ``git status --porcelain`` lists anything (changed or untracked, not ignored
        files). Both ``"unknown"`` where git is missing or ``root`` is not in a checkout;
        never raises.
    """
    commit, dirty = _git_state(str(Path(root or repo_root()).resolve()))
    return {GIT_COMMIT_TAG: commit, GIT_DIRTY_TAG: dirty}


@dataclass(frozen=True)
class DatasetRef:
    """A data set on disk as logged to MLflow: name, absolute path, content hash.

    Attributes
    ----------
    name : str
        Folder or file name, unless given.
    path : str
        Absolute path.
    sha256 : str
        64 hex digits, of what ``digest_of`` says.
    digest_of : {"content_sha256", "shard_sha256", "file_sha256"}
        ``content_sha256``: the manifest's hash over every shard's signals and per-window
        metadata (independent of the file encoding); ``shard_sha256``: SHA-256 over the
        shard names and file hashes listed in the manifest (manifests without
        ``content_sha256``); ``file_sha256``: the file's bytes.
    n_samples, n_shards : int or None
        From the manifest, where it says.
    config_hash : str or None
        The generator's config hash, from the manifest.
    """

    name: str
    path: str
    sha256: str
    digest_of: str
    n_samples: int | None = None
    n_shards: int | None = None
    config_hash: str | None = None

    @property
    def digest(self) -> str:
        """The first :data:`DIGEST_CHARS` hex digits of ``sha256`` (MLflow's digest)."""
        return self.sha256[:DIGEST_CHARS]


@functools.lru_cache(maxsize=64)
def _dataset_ref(path: str, name: str, stamp: tuple[int, int]) -> DatasetRef:
    import hashlib

    p = Path(path)
    if p.is_file():
        return DatasetRef(name, path, sha256_file(p), "file_sha256")
    m = read_manifest(p)
    shards = m.get("shards") or {}
    if m.get("content_sha256"):
        sha, of = str(m["content_sha256"]), "content_sha256"
    else:
        listed = "".join(f"{k}:{(v or {}).get('sha256', '')}\n" for k, v in sorted(shards.items()))
        sha, of = hashlib.sha256(listed.encode()).hexdigest(), "shard_sha256"
    n = m.get("n_samples")
    if n is None and shards and all("n_samples" in (v or {}) for v in shards.values()):
        n = sum(int(v["n_samples"]) for v in shards.values())
    return DatasetRef(name, path, sha, of, None if n is None else int(n), len(shards),
                      m.get("config_hash"))


def dataset_ref(path: str | os.PathLike, name: str | None = None) -> DatasetRef:
    """Name, path and content hash of a data set, read from its manifest (nothing hashed).

    Parameters
    ----------
    path : path-like
        A schema-v1 data-set folder (``manifest.json`` and shards, ``docs/DATASET.md``)
        or a file (e.g. a friction recording, CSV), hashed whole.
    name : str, optional
        Default the folder or file name.

    Returns
    -------
    DatasetRef
        Cached per path and manifest (or file) modification time and size.

    Raises
    ------
    ValueError
        ``dataset=<path>: ...`` where the path is neither a file nor a folder with a
        readable schema-v1 manifest (:class:`swgsim.datasets.schema.DataSetError`).
    """
    p = Path(path).expanduser().resolve()
    probe = p if p.is_file() else p / MANIFEST
    if not probe.is_file():
        raise ValueError(f"dataset={p}: neither a file nor a data-set folder with {MANIFEST}")
    st = probe.stat()
    if name is None:
        name = p.stem if p.is_file() else p.name
    try:
        return _dataset_ref(str(p), name, (st.st_mtime_ns, st.st_size))
    except DataSetError as e:
        raise ValueError(f"dataset={p}: {e}") from None


def sklearn_only(model) -> bool:
    """Whether ``model`` and every estimator in its parameters are scikit-learn classes.

    Models that are not (the torch nets of :mod:`learn.learners.nets`, MiniRocket of
    :mod:`learn.learners.rocket`) need this package importable where they are loaded, so their
    requirements pin it (:func:`model_requirements`).
    """
    objs = [model]
    if hasattr(model, "get_params"):
        objs += [v for v in model.get_params(deep=True).values() if hasattr(v, "get_params")]
    return all(type(o).__module__.split(".")[0] == "sklearn" for o in objs)


def model_requirements(fmt: str, own_classes: bool) -> list[str]:
    """Pip requirements of a model saved by ``mlflow.sklearn`` (given, not inferred).

    Parameters
    ----------
    fmt : {"skops", "cloudpickle"}
        Serialization format.
    own_classes : bool
        The model holds classes of this package (``swg-monitor``), which is then pinned.

    Returns
    -------
    list of str
        scikit-learn (and skops or cloudpickle) pinned to the installed versions.
    """
    return list(_requirements(fmt, own_classes))


@functools.cache
def _requirements(fmt: str, own_classes: bool) -> tuple[str, ...]:
    """:func:`model_requirements`, read once per process and format (reading the installed
    distributions' metadata costs milliseconds, and a study logs a model per job)."""
    import importlib.metadata

    import mlflow.sklearn

    reqs = mlflow.sklearn.get_default_pip_requirements(
        include_cloudpickle=fmt == "cloudpickle", include_skops=fmt == "skops")
    if own_classes:
        try:
            reqs.append(f"swg-monitor=={importlib.metadata.version('swg-monitor')}")
        except importlib.metadata.PackageNotFoundError:
            pass
    return tuple(reqs)
