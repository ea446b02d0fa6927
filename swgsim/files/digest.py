"""SHA-256 digests of files and of plain configs."""

from __future__ import annotations

import hashlib
import json
import os
from typing import Any

__all__ = ["config_digest", "sha256_cached", "sha256_file"]

_HASHES: dict[tuple, str] = {}    # (path, dev, ino, size, mtime_ns, ctime_ns) -> SHA-256


def config_digest(plain: Any) -> str:
    """First 16 hex digits of the SHA-256 of the canonical JSON of a plain config.

    Parameters
    ----------
    plain : JSON-serialisable
        Nested dicts, lists and scalars (keys sorted before hashing).

    Returns
    -------
    str
        16 hex digits (the ``config_hash`` of a data set,
        :func:`swgsim.datasets.plan.config_hash`).
    """
    return hashlib.sha256(json.dumps(plain, sort_keys=True).encode()).hexdigest()[:16]


def sha256_file(path: str | os.PathLike) -> str:
    """SHA-256 hex digest of a file's bytes, read in blocks of 1 MiB.

    Raises
    ------
    OSError
        If the file cannot be read.
    """
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def sha256_cached(path: str | os.PathLike) -> str:
    """SHA-256 of a file, computed once per process while the file is unchanged (same
    inode, size, modification and change time).

    Raises
    ------
    OSError
        If the file cannot be read.
    """
    st = os.stat(path)
    key = (str(path), st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns)
    if key not in _HASHES:
        if len(_HASHES) > 4096:
            _HASHES.clear()
        _HASHES[key] = sha256_file(path)
    return _HASHES[key]
