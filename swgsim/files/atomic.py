"""Atomic replacement of a file, and the names of this process's temporary files.

A file is written to a temporary name in its own folder, flushed to disk and renamed over
its target (``os.replace``): a reader sees the old file or the new one, never half of
one. The temporary name carries the host and process (:func:`temp_prefix`), so that a
later run can tell a stale temporary file of a finished process from a live one
(:func:`pid_alive`); whether it may remove one is decided by the folder's ownership stamp
(:mod:`swgsim.files.ownership`), never by the name alone.
"""

from __future__ import annotations

import errno
import os
import re
import socket
import tempfile
from collections.abc import Callable
from pathlib import Path

__all__ = ["DiskFullError", "TEMP_NAME", "pid_alive", "temp_host", "temp_prefix",
           "write_atomically"]


class DiskFullError(ValueError):
    """The disk filled up while a file was written; nothing was left behind."""


def _umask_mode() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def temp_host() -> str:
    """This host's name as temporary files carry it (letters, digits, ``_`` and ``-``)."""
    return re.sub(r"[^A-Za-z0-9_-]", "_", socket.gethostname()) or "host"


def temp_prefix(path: Path) -> str:
    """Prefix of this process's temporary files for ``path``: ``.<name>.<host>-<pid>.``.

    The name alone proves nothing: a temporary file is this project's only if the
    ownership stamp of its folder names its ``<host>-<pid>`` (:mod:`swgsim.files.ownership`),
    and only then may a later run remove it once that process is gone.
    """
    return f".{path.name}.{temp_host()}-{os.getpid()}."


#: Names :func:`temp_prefix` gives (``.<name>.<host>-<pid>.<random>.tmp``).
TEMP_NAME = re.compile(r"^\.(?P<name>.+)\.(?P<host>[A-Za-z0-9_-]+)-(?P<pid>\d+)\..+\.tmp$")


def pid_alive(pid: int) -> bool:
    """Whether process ``pid`` of this host runs (another user's counts as running).

    A zombie, a process that has exited and waits for its parent to collect it, does
    not run: a worker killed while its pool is still being shut down is one, and the
    signal test alone (``os.kill(pid, 0)``) counts it alive. Its state is read from
    ``/proc/<pid>/stat`` (proc(5); elsewhere the signal test alone decides)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's: alive unless a zombie
        pass
    return not _zombie(pid)


def _zombie(pid: int) -> bool:
    """Whether ``pid`` is a zombie (state ``Z`` after the name in ``/proc/<pid>/stat``);
    False where /proc cannot be read."""
    try:
        stat = Path(f"/proc/{int(pid)}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rfind(")") + 2:].startswith("Z")


def write_atomically(path: str | os.PathLike, write: Callable[[Path], object],
                     before_replace: Callable[[Path, str], None] | None = None,
                     exclusive: bool = False) -> None:
    """Have ``write`` write a file at a temporary path in the folder of ``path``, flush it
    to disk, then rename it over ``path``: a reader, or a run after a kill or a full disk
    at any point, sees the old file or the new one whole, never half of one.

    With ``exclusive`` the file is created, never replaced: the temporary file is linked
    to ``path`` (``os.link`` fails on an existing name), so two runs creating it at once
    leave one whole file, the first's.

    Parameters
    ----------
    path : path-like
        The target; its folder is created if needed.
    write : callable
        ``write(tmp)`` writes the whole file at ``tmp`` (a :class:`~pathlib.Path` ending
        ``.tmp``: a figure is saved with an explicit ``format``); its return is ignored.
    before_replace : callable, optional
        ``before_replace(path, tmp)`` runs between the flush and the rename (the
        ownership stamp records the file there, :func:`swgsim.files.ownership.write_owned`).
    exclusive : bool
        Create ``path``; a file already there is left as it is.

    Raises
    ------
    FileExistsError
        With ``exclusive``, if ``path`` exists; nothing is left behind.
    DiskFullError
        If the disk is full, naming the file and its folder; nothing is left behind.
    Exception
        Whatever ``write`` raises; the temporary file is removed and ``path`` untouched.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=temp_prefix(path), suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        write(Path(tmp))
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
        os.chmod(tmp, _umask_mode())
        if before_replace is not None:
            before_replace(path, tmp)
        if exclusive:
            os.link(tmp, path)  # whole or not at all, and never over another's file
            Path(tmp).unlink()
        else:
            os.replace(tmp, path)
    except BaseException as e:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(e, OSError) and e.errno == errno.ENOSPC:
            raise DiskFullError(f"disk full while writing {path} (folder {path.parent})") from e
        raise
