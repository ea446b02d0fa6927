"""Ownership of output folders: a run deletes or overwrites only what it can prove it wrote.

A file's name proves nothing (a ``manifest.json`` of another tool, a user's
``report.md``). Every run therefore writes, before anything else, an *ownership stamp*
:data:`STAMP` (``.swg-owner.json``) into its output folder::

    {"writer": "swg-monitor", "version": 1, "apps": ["swgsim-calibrate"],
     "files": {"report.md": ["<sha256>"], "figures/time.png": ["<sha256>"]},
     "runs": ["<host>-<pid>", ...]}

``writer`` is this project's signature; ``files`` maps each file a run of this project
wrote (path relative to the folder) to its SHA-256 (the previous one is kept beside a
new one until the next claim, so that a run stopped between recording and renaming
still proves the file on disk); ``runs`` names the processes (``<host>-<pid>``,
:func:`swgsim.data.temp_prefix`) that may leave temporary files there. A file is *ours*
if a stamp of this project in its folder or an enclosing one (up to the folder checked)
lists it with the SHA-256 it has now; a temporary file is ours if its name carries a run
a stamp lists. Anything else, whatever its name, is *foreign*: it is never deleted nor
overwritten, and a run whose folder holds one refuses (:func:`check`), naming it, before
it touches anything, cleanup of temporary files included.

Every write into a claimed folder is recorded: :func:`swgsim.data.atomic_write_bytes`
and :func:`swgsim.data.write_shard` record the file's SHA-256 before they rename it into
place (:func:`before_replace`), and an app records what its writers wrote otherwise
(:meth:`Claim.record`). Stamp updates are serialised by an ``flock`` on the stamp and
written atomically, so that worker processes and cluster jobs can share a folder.

One helper serves every app: :func:`check` (read-only, to refuse before any work) and
:func:`claim` (check, stamp, register this process, remove our stale temporary files).
"""

from __future__ import annotations

import fcntl
import json
import logging
import os
import time
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from . import data as dsio

log = logging.getLogger(__name__)

__all__ = ["SIGNATURE", "STAMP", "Survey", "Claim", "survey", "check", "claim", "join",
           "before_replace", "sha256"]

#: This project's signature: the ``writer`` of every stamp it writes.
SIGNATURE = "swg-monitor"
#: Name of the ownership stamp in every folder a run of this project writes into.
STAMP = ".swg-owner.json"
_VERSION = 1
_CLAIMS: dict[Path, Claim] = {}   # folders this process claimed (resolved) -> claim
_HASHES: dict[tuple, str] = {}    # (path, dev, ino, size, mtime_ns, ctime_ns) -> SHA-256


def sha256(path: Path) -> str:
    """SHA-256 of a file, computed once per process while the file is unchanged (same
    inode, size, modification and change time)."""
    st = os.stat(path)
    key = (str(path), st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns)
    if key not in _HASHES:
        if len(_HASHES) > 4096:
            _HASHES.clear()
        _HASHES[key] = dsio.sha256_file(path)
    return _HASHES[key]


def _run_id() -> str:
    """This process as a stamp names it: ``<host>-<pid>``, as in its temporary files."""
    return f"{dsio.temp_host()}-{os.getpid()}"


def _read_stamp(folder: Path) -> dict | None:
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


@dataclass
class Survey:
    """What a folder holds, sorted by ownership (:func:`survey`).

    Attributes
    ----------
    folder : Path
    owned : dict of str to str
        Files proved ours: path relative to ``folder`` -> SHA-256 (stamps excluded).
    foreign : list of str
        Files (relative paths) nothing proves ours, links and special files included.
    stale : list of Path
        Our temporary files whose process (on this host) is gone.
    live : list of str
        Our temporary files of a process still running (or of another host).
    """

    folder: Path
    owned: dict[str, str] = field(default_factory=dict)
    foreign: list[str] = field(default_factory=list)
    stale: list[Path] = field(default_factory=list)
    live: list[str] = field(default_factory=list)


def _temp_owner(name: str, runs: set[str]) -> str | None:
    """``"stale"``/``"live"`` for a temporary file of a run in ``runs``, else None."""
    m = dsio.TEMP_NAME.match(name)
    if not m or f"{m['host']}-{m['pid']}" not in runs:
        return None
    if m["host"] != dsio.temp_host() or int(m["pid"]) == os.getpid():
        return "live"
    return "stale" if not dsio.pid_alive(int(m["pid"])) else "live"


def _classify(s: Survey, path: Path, rel: str, stamps: list[tuple[Path, dict]]) -> None:
    """Sort one entry of the folder into ``s`` (``stamps``: enclosing stamps, innermost
    first, with their folders)."""
    if path.is_symlink() or not path.is_file():
        s.foreign.append(rel)
        return
    if path.name == STAMP and stamps and stamps[0][0] == path.parent:
        return  # a stamp of ours
    runs = {r for _, st in stamps for r in st["runs"]}
    kind = _temp_owner(path.name, runs)
    if kind == "stale":
        s.stale.append(path)
        return
    if kind == "live":
        s.live.append(rel)
        return
    for where, st in stamps:
        hashes = st["files"].get(path.relative_to(where).as_posix())
        if isinstance(hashes, list) and hashes and sha256(path) in hashes:
            s.owned[rel] = sha256(path)
            return
    s.foreign.append(rel)


def survey(folder: str | os.PathLike, only: Iterable[str] | None = None,
           what: str = "out_dir") -> Survey:
    """Sort the files below ``folder`` into ours and foreign; read-only.

    Parameters
    ----------
    folder : path-like
        Need not exist.
    only : iterable of str, optional
        For a folder shared with others (the main job's report root): look only at these
        names (and our stamp and temporary files there); default every file below.
    what : str
        The key the folder was given as, for the message.

    Returns
    -------
    Survey

    Raises
    ------
    ValueError
        If ``folder`` exists and is not a folder.
    """
    folder = Path(folder)
    only = None if only is None else frozenset(only)
    if not folder.exists() and not folder.is_symlink():
        return Survey(folder)
    if not folder.is_dir():
        raise ValueError(f"{what} {folder} exists and is not a folder")
    s = _survey_once(folder, only)
    if s.foreign:  # a run sharing the folder may have finished a file after we read its
        again = _survey_once(folder, only)  # stamp: it is recorded before it appears
        again.foreign = [f for f in again.foreign if f in set(s.foreign)]
        s = again
    return s


def _survey_once(folder: Path, only: frozenset[str] | None) -> Survey:
    """One pass of :func:`survey` over an existing folder."""
    s = Survey(folder)
    top = _read_stamp(folder)
    if only is not None:
        stamps = [(folder, top)] if top else []
        runs = {r for _, st in stamps for r in st["runs"]}
        names = only | {STAMP}
        for p in sorted(folder.iterdir()):
            if p.name in names or _temp_owner(p.name, runs):
                _classify(s, p, p.name, stamps)
        return s
    enclosing: dict[Path, list[tuple[Path, dict]]] = {folder: [(folder, top)] if top else []}
    for dirpath, dirnames, filenames in os.walk(folder):
        here = Path(dirpath)
        stamps = enclosing[here]
        for d in sorted(dirnames):
            sub = here / d
            if sub.is_symlink():
                s.foreign.append(sub.relative_to(folder).as_posix())
                continue
            st = _read_stamp(sub)
            enclosing[sub] = ([(sub, st)] if st else []) + stamps
        dirnames[:] = [d for d in dirnames if not (here / d).is_symlink()]
        for f in sorted(filenames):
            _classify(s, here / f, (here / f).relative_to(folder).as_posix(), stamps)
    s.foreign.sort()
    return s


def check(folder: str | os.PathLike, what: str = "out_dir",
          only: Iterable[str] | None = None) -> Survey:
    """:func:`survey`, refusing a folder that holds a file nothing proves ours.

    Parameters
    ----------
    folder : path-like
    what : str
        The key the folder was given as, for the message (``out_dir``, ``report_dir``).
    only : iterable of str, optional
        See :func:`survey`.

    Returns
    -------
    Survey
        With ``foreign`` empty.

    Raises
    ------
    ValueError
        One line naming the folder and its first foreign file; nothing was touched.
    """
    s = survey(folder, only, what)
    if s.foreign:
        more = f" and {len(s.foreign) - 1} more such file(s)" if len(s.foreign) > 1 else ""
        raise ValueError(
            f"{what} {folder} holds {s.foreign[0]}{more}, which this project cannot show "
            f"it wrote (no ownership stamp {STAMP} lists it with its SHA-256); nothing was "
            f"touched: move it away or choose another {what}")
    return s


def _new_stamp(app: str) -> dict:
    """A stamp naming this process, so that its temporary files are ours from the start."""
    return {"writer": SIGNATURE, "version": _VERSION, "apps": [app], "files": {},
            "runs": [_run_id()]}


def _write_stamp(path: Path, stamp: dict) -> None:
    dsio.atomic_write_bytes(path, (json.dumps(stamp, indent=1, sort_keys=True) + "\n").encode())


def _update(folder: Path, app: str, change) -> None:
    """Apply ``change(stamp)`` to the stamp of ``folder`` under an exclusive lock and write
    it atomically; the stamp is created (exclusively) when there is none."""
    path = folder / STAMP
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o666)
    except FileExistsError:
        pass
    else:  # a new stamp: written in place (readers retry an empty one), then updated
        with os.fdopen(fd, "wb") as f:
            f.write((json.dumps(_new_stamp(app), indent=1) + "\n").encode())
            f.flush()
            os.fsync(f.fileno())
    while True:
        fd = os.open(path, os.O_RDWR | os.O_NOFOLLOW)  # write access: flock is fcntl's on NFS
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            if os.fstat(fd).st_ino != os.stat(path).st_ino:
                continue  # replaced while we waited: lock the new one
            stamp = _read_stamp(folder)
            if stamp is None:
                raise ValueError(f"{path} is not this project's ownership stamp (another "
                                 "tool's file, or damaged); nothing was touched: move it away")
            change(stamp)
            _write_stamp(path, stamp)
            return
        finally:
            os.close(fd)  # releases the lock


class Claim:
    """A folder this process writes into, stamped as ours (made by :func:`claim` or
    :func:`join`); a context manager that stops recording into it on exit.

    Attributes
    ----------
    folder : Path
    app : str
        The app that claimed it (recorded in the stamp's ``apps``).
    """

    def __init__(self, folder: Path, app: str) -> None:
        self.folder, self.app = Path(folder), app
        _CLAIMS[self.folder.resolve()] = self

    def _rel(self, path: str | os.PathLike) -> str:
        p = Path(path)
        p = p if p.is_absolute() else self.folder / p
        return p.resolve().relative_to(self.folder.resolve()).as_posix()

    def record(self, paths: Iterable[str | os.PathLike]) -> None:
        """List files this run wrote (paths absolute or relative to the folder) in the
        stamp with their SHA-256; folders, missing files and the stamp are skipped."""
        found = {}
        for p in paths:
            p = Path(p) if Path(p).is_absolute() else self.folder / p
            if p.is_file() and not p.is_symlink() and p.name != STAMP:
                found[self._rel(p)] = sha256(p)

        def add(stamp: dict) -> None:
            stamp["files"].update({rel: [h] for rel, h in found.items()})
        if found:
            _update(self.folder, self.app, add)

    def remove(self, rels: Iterable[str]) -> int:
        """Delete files of the folder proved ours (each checked against the stamp again,
        just before); return how many.

        Raises
        ------
        ValueError
            Naming a file the stamp no longer proves ours (changed since the check).
        """
        rels = sorted(rels)
        proof = survey(self.folder).owned
        for rel in rels:
            if rel not in proof:
                raise ValueError(f"{self.folder / rel} changed since it was checked and is "
                                 "no longer provably this project's; left as it is")
        for rel in rels:
            (self.folder / rel).unlink()

        def drop(stamp: dict) -> None:
            for rel in rels:
                stamp["files"].pop(rel, None)
        _update(self.folder, self.app, drop)
        return len(rels)

    def close(self) -> None:
        """Stop recording writes into the folder (the stamp stays)."""
        if _CLAIMS.get(self.folder.resolve()) is self:
            del _CLAIMS[self.folder.resolve()]

    def __enter__(self) -> Claim:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def claim(folder: str | os.PathLike, app: str, what: str = "out_dir",
          only: Iterable[str] | None = None, found: Survey | None = None) -> Claim:
    """Make ``folder`` a folder of this run: check it, stamp it, clean it.

    The folder must hold nothing foreign (:func:`check`); then it is created, our
    temporary files of dead processes are removed, its stamp written (or updated: this
    process added to ``runs``, runs of this host that are gone removed, entries of
    vanished files dropped), and every later write of this process into it recorded.

    Parameters
    ----------
    folder : path-like
    app : str
        Name of the app, recorded in the stamp.
    what : str
        The key the folder was given as, for messages.
    only : iterable of str, optional
        For a shared folder: check only these names (:func:`survey`).
    found : Survey, optional
        A survey of ``folder`` just made (saves hashing it again).

    Returns
    -------
    Claim

    Raises
    ------
    ValueError
        Naming the first foreign file, or if ``folder`` is not a folder; before anything
        is touched.
    """
    folder = Path(folder)
    found = found if found is not None else check(folder, what, only)
    folder.mkdir(parents=True, exist_ok=True)
    for f in found.stale:  # ours: a run of this project, gone, named in the stamp
        f.unlink(missing_ok=True)
        log.info("removed %s, left by a stopped run", f.name)
    me = _run_id()

    def refresh(stamp: dict) -> None:
        host = dsio.temp_host() + "-"
        stamp["runs"] = sorted({r for r in stamp["runs"] if not (
            r.startswith(host) and r[len(host):].isdigit()
            and not dsio.pid_alive(int(r[len(host):])))} | {me})
        stamp["apps"] = sorted(set(stamp.get("apps", [])) | {app})
        stamp["files"] = {rel: h for rel, h in stamp["files"].items()
                          if (folder / rel).is_file()}
    _update(folder, app, refresh)
    return Claim(folder, app)


def join(folder: str | os.PathLike, app: str = "worker") -> Claim:
    """Register this process (a worker of a run that claimed ``folder``) in its stamp, so
    that its temporary files and the files it writes are ours.

    Raises
    ------
    ValueError
        If ``folder`` holds no stamp of this project.
    """
    folder = Path(folder)
    stamp = _read_stamp(folder)
    if stamp is None:
        raise ValueError(f"{folder} was not claimed by a run of this project (no {STAMP})")
    me = _run_id()

    def add(stamp: dict) -> None:
        stamp["runs"] = sorted(set(stamp["runs"]) | {me})
    if me not in stamp["runs"]:  # a run is removed from it only once it is gone
        _update(folder, app, add)
    return Claim(folder, app)


def before_replace(path: str | os.PathLike, tmp: str | os.PathLike,
                   digest: str | None = None) -> None:
    """Record ``path`` in the stamp of the claimed folder holding it, with the SHA-256 of
    its finished temporary file ``tmp``, before ``tmp`` is renamed to ``path`` (called by
    :func:`swgsim.data.atomic_write_bytes` and :func:`swgsim.data.write_shard`); the
    hash recorded before is kept beside it. Nothing happens outside a claimed folder."""
    path = Path(path)
    if not _CLAIMS or path.name == STAMP:
        return
    where = path.parent.resolve()
    for d in (where, *where.parents):
        c = _CLAIMS.get(d)
        if c is not None:
            break
    else:
        return
    rel = (where / path.name).relative_to(d).as_posix()
    h = digest or dsio.sha256_file(tmp)

    def add(stamp: dict) -> None:
        old = stamp["files"].get(rel)
        stamp["files"][rel] = ([old[-1]] if isinstance(old, list) and old and old[-1] != h
                               else []) + [h]
    _update(c.folder, c.app, add)
