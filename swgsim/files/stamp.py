"""The ownership stamp ``.swg-owner.json`` as a file: its names, reading it, and its
updates (serialised by a file lock, written atomically); the lock files' names.

What the stamp proves and how runs use it: :mod:`swgsim.files.ownership`; the writers it
records: :mod:`swgsim.files.writers`.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from collections.abc import Callable
from pathlib import Path

from filelock import FileLock

from swgsim.files.atomic import temp_host, write_atomically

__all__ = ["SIGNATURE", "STAMP", "LOCK", "STAMP_LOCK", "LOCKS", "EMPTY", "VERSION", "run_id",
           "read_stamp", "slot", "is_lock", "lock_file", "writers_of", "update"]

#: This project's signature: the ``writer`` of every stamp it writes.
SIGNATURE = "swg-monitor"
#: Name of the ownership stamp in every folder a run of this project writes into.
STAMP = ".swg-owner.json"
#: Name of the gate of a folder: runs are admitted to it under this lock
#: (:func:`swgsim.files.ownership.claim`).
LOCK = ".swg-owner.lock"
#: Name of the lock that serialises updates of the stamp.
STAMP_LOCK = ".swg-owner.json.lock"
#: The lock files every stamp lists from the start.
LOCKS = (LOCK, STAMP_LOCK)
EMPTY = hashlib.sha256(b"").hexdigest()  # the SHA-256 of a lock file (always empty)
VERSION = 2  # 2: files carry their writers (1: without; their app is unknown)


def run_id() -> str:
    """This process as a stamp names it: ``<host>-<pid>``, as in its temporary files."""
    return f"{temp_host()}-{os.getpid()}"


def read_stamp(folder: Path) -> dict | None:
    """The stamp in ``folder`` if it is this project's, else None (absent, unreadable or
    another tool's). An empty or half-created stamp is read again a few times."""
    path = folder / STAMP
    for attempt in range(4):
        if not path.is_file() or path.is_symlink():
            return None
        try:
            stamp = json.loads(path.read_bytes())
        except (json.JSONDecodeError, UnicodeDecodeError):
            time.sleep(0.05 * (attempt + 1))  # another process may be creating it
            continue
        except OSError:
            return None
        ok = (isinstance(stamp, dict) and stamp.get("writer") == SIGNATURE
              and isinstance(stamp.get("files"), dict) and isinstance(stamp.get("runs"), list))
        return stamp if ok else None
    return None


def slot(run: str) -> str:
    """Name of the run lock of run ``run`` (``<host>-<pid>``) in a folder it claimed."""
    return f".swg-owner.{run}.lock"


def is_lock(name: str) -> bool:
    """Whether ``name`` is named as a lock file of this module (proof comes from a stamp)."""
    return name.startswith(".swg-owner.") and name.endswith(".lock")


def lock_file(folder: Path, name: str) -> str:
    """Absolute path of the lock file ``name`` of ``folder``, which is absent or an empty
    plain file (ours are empty: a lock is never opened on anything else)."""
    path = folder / name
    if path.is_symlink() or (path.exists() and (not path.is_file() or path.stat().st_size)):
        raise ValueError(f"{path} is not this project's lock file (not an empty file); "
                         "nothing was touched: move it away")
    return os.path.abspath(path)


def writers_of(stamp: dict) -> dict:
    """The stamp's ``writers`` (created; an earlier version's stamp has none)."""
    if not isinstance(stamp.get("writers"), dict):
        stamp["writers"] = {}
    return stamp["writers"]


def update(folder: Path, app: str, change: Callable[[dict], None]) -> None:
    """Apply ``change(stamp)`` to the stamp of ``folder`` under an exclusive lock and write
    it atomically; the stamp is created when there is none, like every other file
    (:func:`swgsim.files.atomic.write_atomically`, exclusively): a full disk or a kill
    leaves no stamp at all, never an empty one that would make every rerun refuse the
    folder.

    Raises
    ------
    swgsim.files.atomic.DiskFullError
        The disk filled up while the stamp was created or updated; nothing left behind.
    ValueError
        The stamp there is not this project's.
    """
    path = folder / STAMP
    if not os.path.lexists(path):
        # a new stamp names this process (its temporary files ours from the start) and
        # lists the lock files (empty) before they are created
        new = {"writer": SIGNATURE, "version": VERSION, "apps": [app],
               "files": {name: [EMPTY] for name in LOCKS}, "runs": [run_id()]}
        data = (json.dumps(new, indent=1) + "\n").encode()
        try:
            write_atomically(path, lambda tmp: tmp.write_bytes(data), exclusive=True)
        except FileExistsError:
            pass  # another run created it first
    with FileLock(lock_file(folder, STAMP_LOCK), thread_local=False):
        stamp = read_stamp(folder)
        if stamp is None:
            raise ValueError(f"{path} is not this project's ownership stamp (another "
                             "tool's file, or damaged); nothing was touched: move it away")
        change(stamp)
        stamp["version"] = max(VERSION, int(stamp.get("version", 1) or 1))
        stamp["files"][STAMP_LOCK] = [EMPTY]  # held, so an empty plain file: ours
        data = (json.dumps(stamp, indent=1, sort_keys=True) + "\n").encode()
        write_atomically(path, lambda tmp: tmp.write_bytes(data))
