"""Ownership of output folders: a run deletes or overwrites only what it can prove it wrote.

The rule, the *ownership stamp* :data:`STAMP` (``.swg-owner.json``) a run writes into its
output folder before anything else, its fields (``writer``, ``files``, ``writers``,
``runs``, ``holders``), the locks and what is *ours* or *foreign*: docs/DATASET.md,
"Files" ("What a run may delete or overwrite"). ``files`` keeps a file's previous SHA-256
beside a new one until the next claim, so that a run stopped between recording and
renaming still proves the file on disk. A foreign file is never deleted nor overwritten,
and a run whose folder holds one refuses (:func:`check`), naming it, before it touches
anything.

Every write into a claimed folder is recorded before its rename (:func:`before_replace`,
called by :func:`atomic_write_bytes` and :func:`swgsim.datasets.schema.write_shard`), or
by the app (:meth:`Claim.record`). Stamp updates are serialised by a file lock
(``filelock``) on :data:`STAMP_LOCK` and written atomically, so that worker processes and
cluster jobs can share a folder.

One run at a time: :func:`claim` admits a run under the folder's gate :data:`LOCK` (held
for milliseconds) and the run then holds its own run lock until the claim is closed;
another process claiming the folder meanwhile (a run's workers, :func:`join`, take no
lock) is refused unless both passed the same ``share``. A killed run leaves a free run
lock, removed by the next admission. A lock file is opened only if it is an empty plain
file (no link); like the stamp, it is neither foreign nor ``owned``, and no run deletes it
as output (the gate and :data:`STAMP_LOCK` stay: removing a lock file others wait on
would split them).
"""

from __future__ import annotations

import fnmatch
import json
import logging
import os
import sys
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from filelock import FileLock, Timeout

from swgsim.files.atomic import TEMP_NAME, pid_alive, temp_host, write_atomically
from swgsim.files.digest import sha256_cached as sha256
from swgsim.files.digest import sha256_file
from swgsim.files.stamp import (
    EMPTY,
    LOCK,
    LOCKS,
    SIGNATURE,
    STAMP,
    STAMP_LOCK,
    is_lock,
    lock_file,
    read_stamp,
    run_id,
    slot,
    update,
    writers_of,
)
from swgsim.files.writers import Writer, entry, read_entry, refuse_others, writer_of

log = logging.getLogger(__name__)

__all__ = ["SIGNATURE", "STAMP", "LOCK", "STAMP_LOCK", "Survey", "Claim", "survey", "check",
           "claim", "join", "before_replace", "sha256", "atomic_write_bytes",
           "atomic_write_json", "write_owned", "save_figure", "stop_note", "forget_stops"]

_CLAIMS: dict[Path, Claim] = {}   # folders this process claimed (resolved) -> claim
_HELD: dict[Path, list] = {}  # run locks held: resolved folder -> [lock, count, pid, folder]
_STOPPED: list[tuple[Path, str]] = []  # claims a stop (Ctrl-C, SIGTERM) ended: folder, app
_FINISHED: list[Path] = []  # claims of this run that ended without a stop, before one
_GATE_S = 30.0  # how long a run waits for the gate (held for milliseconds by others)


@dataclass
class Survey:
    """What a folder holds, sorted by ownership (:func:`survey`).

    Attributes
    ----------
    folder : Path
    owned : dict of str to str
        Files proved ours: path relative to ``folder`` -> SHA-256 (stamps excluded).
    writers : dict of str to Writer or None
        The same files -> the app and kind of output that wrote them (None: the stamp does
        not say, an earlier version's; :mod:`swgsim.files.writers`).
    foreign : list of str
        Files (relative paths) nothing proves ours, links and special files included.
    stale : list of Path
        Our temporary files whose process (on this host) is gone.
    live : list of str
        Our temporary files of a process still running (or of another host).
    """

    folder: Path
    owned: dict[str, str] = field(default_factory=dict)
    writers: dict[str, Writer | None] = field(default_factory=dict)
    foreign: list[str] = field(default_factory=list)
    stale: list[Path] = field(default_factory=list)
    live: list[str] = field(default_factory=list)


def _temp_owner(name: str, runs: set[str]) -> str | None:
    """``"stale"``/``"live"`` for a temporary file of a run in ``runs``, else None."""
    m = TEMP_NAME.match(name)
    if not m or f"{m['host']}-{m['pid']}" not in runs:
        return None
    if m["host"] != temp_host() or int(m["pid"]) == os.getpid():
        return "live"
    return "stale" if not pid_alive(int(m["pid"])) else "live"


def _joining(path: Path) -> set[str]:
    """The run that wrote ``path``, a temporary copy of the stamp beside it, where the
    copy's own content lists that run (the run named by the file's name): a worker killed
    while it joined (:func:`join`) leaves one, whose run the stamp on disk does not list
    yet; else nothing."""
    m = TEMP_NAME.match(path.name)
    if not m or m["name"] != STAMP or path.is_symlink() or path.stat().st_size > 2**24:
        return set()
    try:
        copy = json.loads(path.read_bytes())
    except (OSError, ValueError):
        return set()
    me = f"{m['host']}-{m['pid']}"
    ok = (isinstance(copy, dict) and copy.get("writer") == SIGNATURE
          and isinstance(copy.get("runs"), list) and me in copy["runs"])
    return {me} if ok else set()


def _listed(stamp: dict, rel: str, path: Path) -> bool:
    """Whether ``stamp`` lists ``rel`` with the SHA-256 ``path`` has now."""
    hashes = stamp["files"].get(rel)
    return isinstance(hashes, list) and sha256(path) in hashes


def _classify(s: Survey, path: Path, rel: str, stamps: list[tuple[Path, dict]]) -> None:
    """Sort one entry of the folder into ``s`` (``stamps``: enclosing stamps, innermost
    first, with their folders)."""
    if path.is_symlink() or not path.is_file():
        s.foreign.append(rel)
        return
    if path.name == STAMP and stamps and stamps[0][0] == path.parent:
        return  # a stamp of ours
    if is_lock(path.name) and stamps and stamps[0][0] == path.parent \
            and _listed(stamps[0][1], path.name, path):
        return  # a lock file of ours, listed by the stamp beside it: kept, as the stamp
    runs = {r for _, st in stamps for r in st["runs"]}
    if stamps and stamps[0][0] == path.parent:
        runs |= _joining(path)
    kind = _temp_owner(path.name, runs)
    if kind == "stale":
        s.stale.append(path)
        return
    if kind == "live":
        s.live.append(rel)
        return
    for where, st in stamps:
        inner = path.relative_to(where).as_posix()
        if _listed(st, inner, path):
            s.owned[rel] = sha256(path)
            w = st.get("writers")
            s.writers[rel] = read_entry(w.get(inner)) if isinstance(w, dict) else None
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
    top = read_stamp(folder)
    if only is not None:
        stamps = [(folder, top)] if top else []
        runs = {r for _, st in stamps for r in st["runs"]}
        names = only | {STAMP, *LOCKS}
        for p in sorted(folder.iterdir()):
            if p.name in names or is_lock(p.name) or _temp_owner(p.name, runs):
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
            st = read_stamp(sub)
            enclosing[sub] = ([(sub, st)] if st else []) + stamps
        dirnames[:] = [d for d in dirnames if not (here / d).is_symlink()]
        for f in sorted(filenames):
            _classify(s, here / f, (here / f).relative_to(folder).as_posix(), stamps)
    s.foreign.sort()
    return s


def check(folder: str | os.PathLike, what: str = "out_dir",
          only: Iterable[str] | None = None, share: str | None = None,
          app: str | None = None) -> Survey:
    """:func:`survey`, refusing a folder that holds a file nothing proves ours (or, given
    ``app``, one of another kind of output).

    Parameters
    ----------
    folder : path-like
    what : str
        The key the folder was given as, for the message (``out_dir``, ``report_dir``).
    only : iterable of str, optional
        See :func:`survey`.
    share : str, optional
        See :func:`claim`: a run of another process holding the folder with the same
        ``share`` is no reason to refuse.
    app : str, optional
        The app about to write (a tag of :data:`swgsim.files.writers.WRITERS`): a file of
        ours of another kind of output, or of an unknown app, is refused too
        (:func:`swgsim.files.writers.refuse_others`). None: any file of ours is accepted.

    Returns
    -------
    Survey
        With ``foreign`` empty.

    Raises
    ------
    ValueError
        One line naming the folder and its first foreign file (or file of another app,
        and its writer), or the run of another process holding its run lock
        (:func:`claim`); nothing was touched.
    """
    s = survey(folder, only, what)
    if s.foreign:
        more = f" and {len(s.foreign) - 1} more such file(s)" if len(s.foreign) > 1 else ""
        raise ValueError(
            f"{what} {folder} holds {s.foreign[0]}{more}, which this project cannot show "
            f"it wrote (no ownership stamp {STAMP} lists it with its SHA-256); nothing was "
            f"touched: move it away or choose another {what}")
    if app is not None:
        refuse_others(folder, what, s.writers, app)
    _probe(Path(folder), what, share)
    return s


@contextmanager
def _gate(folder: Path) -> Iterator[None]:
    """Hold the gate :data:`LOCK` of ``folder``, under which runs are admitted and leave
    (held for milliseconds; waited for up to :data:`_GATE_S`)."""
    lock = FileLock(lock_file(folder, LOCK), thread_local=False)
    try:
        lock.acquire(timeout=_GATE_S)
    except Timeout:
        raise ValueError(f"{folder / LOCK} has been held by another process for over "
                         f"{_GATE_S:g} s; try again, or stop that process") from None
    try:
        yield
    finally:
        lock.release()


def _holders(folder: Path, stamp: dict) -> tuple[dict, list[str]]:
    """Under the gate: the runs of the stamp's ``holders`` whose run lock is held (run ->
    what the stamp says of it), and those whose lock is free (gone)."""
    live, gone = {}, []
    held = stamp.get("holders")
    for run, info in sorted(held.items() if isinstance(held, dict) else []):
        path = folder / slot(run)
        if run == run_id() or path.is_symlink() or not path.is_file():
            gone.append(run)
            continue
        lock = FileLock(lock_file(folder, slot(run)), thread_local=False)
        try:
            lock.acquire(timeout=0)
        except Timeout:
            live[run] = info if isinstance(info, dict) else {}
            continue
        lock.release()
        gone.append(run)
    return live, gone


def _conflict(folder: Path, what: str, live: dict, share: str | None) -> None:
    """Refuse ``folder`` if a run in ``live`` does not share it with this one."""
    for run, info in live.items():
        if share is None or info.get("share") != share:
            raise ValueError(
                f"{what}={folder}: another run ({run}, {info.get('app', '?')}) is writing "
                f"into it; wait for it to finish or choose another {what}")


def _held_here(folder: Path) -> list | None:
    """The entry of :data:`_HELD` if this process holds the run lock of ``folder``."""
    held = _HELD.get(folder.resolve())
    return held if held is not None and held[2] == os.getpid() else None


def _probe(folder: Path, what: str, share: str | None) -> None:
    """Refuse ``folder`` if a run of another process holds it (and does not share it)."""
    stamp = read_stamp(folder)
    if _held_here(folder) or not stamp or not stamp.get("holders") \
            or not (folder / LOCK).is_file():
        return
    with _gate(folder):
        _conflict(folder, what, _holders(folder, read_stamp(folder) or stamp)[0], share)


def _hold(folder: Path, what: str, app: str, share: str | None) -> None:
    """Admit this run to ``folder`` under the gate and take its run lock (again, if this
    process holds it: counted)."""
    held = _held_here(folder)
    if held is not None:
        held[1] += 1
        return
    me, mine = run_id(), slot(run_id())
    with _gate(folder):
        live, gone = _holders(folder, read_stamp(folder) or {})
        _conflict(folder, what, live, share)
        for run in gone:  # their process is gone: its lock file goes before its entry
            if os.path.exists(lock_file(folder, slot(run))) and run != me:
                os.unlink(folder / slot(run))

        def admit(stamp: dict) -> None:
            held = stamp["holders"] = {r: h for r, h in (stamp.get("holders") or {}).items()
                                       if r not in gone}
            held[me] = {"app": app, "share": share}
            for run in gone:
                stamp["files"].pop(slot(run), None)
            stamp["files"][mine] = [EMPTY]  # listed before it appears
        update(folder, app, admit)
        lock = FileLock(lock_file(folder, mine), thread_local=False)
        lock.acquire(timeout=0)  # this process's own lock: nobody else takes it
    _HELD[folder.resolve()] = [lock, 1, os.getpid(), folder]


def _let_go(key: Path) -> None:
    """Drop one hold of the run lock of the (resolved) folder ``key``; at the last, the
    lock is released and its file and entry removed (what fails is left to the next
    run's admission). A forked child never releases its parent's lock."""
    held = _HELD.get(key)
    if held is None or held[2] != os.getpid():
        return
    held[1] -= 1
    if held[1] > 0:
        return
    del _HELD[key]
    lock, folder, me = held[0], held[3], run_id()

    def leave(stamp: dict) -> None:
        if isinstance(stamp.get("holders"), dict):
            stamp["holders"].pop(me, None)
        stamp["files"].pop(slot(me), None)
    try:
        with _gate(folder):
            lock.release()
            os.unlink(folder / slot(me))
            if read_stamp(folder) is not None:
                update(folder, "", leave)
    except (OSError, ValueError):
        lock.release()


class Claim:
    """A folder this process writes into, stamped as ours (made by :func:`claim` or
    :func:`join`); a context manager that stops recording into it on exit.

    Attributes
    ----------
    folder : Path
    app : str
        The app that claimed it (recorded in the stamp's ``apps``, and as the writer of
        each file it records, :mod:`swgsim.files.writers`).
    """

    def __init__(self, folder: Path, app: str) -> None:
        self.folder, self.app = Path(folder), app
        self.written: list[str] = []  # files this process recorded (relative), in order
        self._key = self.folder.resolve()
        self._locked = False  # holds (a count of) the run lock: set by claim()
        _CLAIMS[self._key] = self

    def record(self, paths: Iterable[str | os.PathLike]) -> None:
        """List files this run wrote in the stamp with their SHA-256; folders, missing
        files and the stamp are skipped. A path is absolute, relative to the folder (a
        name inside it), or else relative to the current directory, as the folder itself
        may be given (``Path(report_dir) / "results.csv"``).

        Raises
        ------
        ValueError
            A path outside the folder.
        """
        found = {}
        for p in paths:
            p = Path(p)
            p = p if p.is_absolute() or not (self.folder / p).is_file() else self.folder / p
            if p.is_file() and not p.is_symlink() and p.name != STAMP \
                    and not is_lock(p.name):
                found[p.resolve().relative_to(self.folder.resolve()).as_posix()] = sha256(p)

        def add(stamp: dict) -> None:
            stamp["files"].update({rel: [h] for rel, h in found.items()})
            writers_of(stamp).update({rel: entry(self.app) for rel in found})
        if found:
            update(self.folder, self.app, add)
            self.written.extend(r for r in found if r not in self.written)

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
                writers_of(stamp).pop(rel, None)
        update(self.folder, self.app, drop)
        return len(rels)

    def close(self) -> None:
        """Stop recording writes into the folder and let go of its run lock (the stamp and
        the lock files stay)."""
        if _CLAIMS.get(self._key) is self:
            del _CLAIMS[self._key]
        if self._locked:
            self._locked = False
            _let_go(self._key)

    def __enter__(self) -> Claim:
        return self

    def __exit__(self, exc_type, *exc) -> None:
        if exc_type is not None and issubclass(exc_type, KeyboardInterrupt):
            _STOPPED.append((self.folder, self.app))  # for the line the app ends with
        elif exc_type is None and self.folder not in _FINISHED:
            _FINISHED.append(self.folder)  # written whole before a later stop
        self.close()


def claim(folder: str | os.PathLike, app: str, what: str = "out_dir",
          only: Iterable[str] | None = None, found: Survey | None = None,
          share: str | None = None, strict: bool = False,
          fresh: bool | tuple[str, ...] = False) -> Claim:
    """Make ``folder`` a folder of this run: check it, stamp it, clean it.

    After :func:`check`, the folder is created, the run admitted under its gate
    :data:`LOCK` and its run lock taken until the claim is closed (a process may claim a
    folder it holds again); our temporary files of dead processes are removed, the stamp
    updated (this process added to ``runs`` and ``holders``, gone runs of this host and
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
    share : str, optional
        Runs claiming the folder with the same ``share`` may write into it together (e.g.
        the cluster jobs of one data set, each computing some of its shards: its config
        hash); default None: this run alone.
    strict : bool
        Refuse files of another kind of output than ``app``'s too (:func:`check` with
        ``app``): what every report app passes.
    fresh : bool or tuple of str
        Remove what the earlier runs of ``app`` wrote there (the files the stamp proves
        ``app``'s), once admitted and before any write: an app whose every run writes
        its whole output leaves the folder this run's alone, never a mix with an earlier
        run's files it does not write this time (a monitor run without the prognosis after
        one with it, a thermal calibration after a friction one). A tuple of glob patterns
        (relative to the folder) removes only ``app``'s files matching one: an app with
        two outputs of its own in one folder (the observability's steady and motion
        maps) renews one and keeps the other whole. An app that resumes from its earlier
        parts does not pass it.

    Returns
    -------
    Claim

    Raises
    ------
    ValueError
        Naming the first foreign file, or the run of another process that holds the
        folder's run lock, or if ``folder`` is not a folder; before anything is touched.
    """
    folder = Path(folder)
    found = found if found is not None else check(folder, what, only, share,
                                                  app if strict else None)
    folder.mkdir(parents=True, exist_ok=True)
    stamp = read_stamp(folder)
    if stamp is None or stamp["files"].get(LOCK) != [EMPTY]:  # listed before it appears

        def list_lock(stamp: dict) -> None:
            stamp["files"][LOCK] = [EMPTY]
        update(folder, app, list_lock)
    _hold(folder, what, app, share)
    try:
        c = _stamp_claim(folder, app, found)
        if fresh:
            gone = _outputs_of(folder, app)
            if not isinstance(fresh, bool):
                gone = [f for f in gone if any(fnmatch.fnmatch(f, p) for p in fresh)]
            c.remove(gone)
    except BaseException:
        _let_go(folder.resolve())
        raise
    c._locked = True
    return c


def _outputs_of(folder: Path, app: str) -> list[str]:
    """The files the stamp of ``folder`` lists as written by ``app`` (its earlier runs'
    outputs; the stamp and the lock files are no outputs)."""
    stamp = read_stamp(folder) or {"files": {}}
    me = entry(app)
    return sorted(rel for rel, w in writers_of(stamp).items()
                  if w == me and rel in stamp["files"] and (folder / rel).is_file())


def _stamp_claim(folder: Path, app: str, found: Survey) -> Claim:
    """The part of :func:`claim` done under the run lock: clean, stamp, register."""
    for f in found.stale:  # ours: a run of this project, gone, named in the stamp
        f.unlink(missing_ok=True)
        log.info("removed %s, left by a stopped run", f.name)
    me = run_id()

    def refresh(stamp: dict) -> None:
        host = temp_host() + "-"
        stamp["runs"] = sorted({r for r in stamp["runs"] if not (
            r.startswith(host) and r[len(host):].isdigit()
            and not pid_alive(int(r[len(host):])))} | {me})
        stamp["apps"] = sorted(set(stamp.get("apps", [])) | {app})
        stamp["files"] = {rel: h for rel, h in stamp["files"].items()
                          if (folder / rel).is_file()}
        stamp["writers"] = {rel: w for rel, w in writers_of(stamp).items()
                            if rel in stamp["files"]}
    update(folder, app, refresh)
    return Claim(folder, app)


def join(folder: str | os.PathLike, app: str | None = None) -> Claim:
    """Register this process (a worker of a run that claimed ``folder``) in its stamp, so
    that its temporary files and the files it writes are ours, written by ``app`` (default:
    the app of the runs holding the folder, when they agree; else ``worker``).

    Raises
    ------
    ValueError
        If ``folder`` holds no stamp of this project.
    """
    folder = Path(folder)
    stamp = read_stamp(folder)
    if stamp is None:
        raise ValueError(f"{folder} was not claimed by a run of this project (no {STAMP})")
    me = run_id()
    held = stamp.get("holders") if isinstance(stamp.get("holders"), dict) else {}
    tags = {h.get("app") for h in held.values() if isinstance(h, dict)}
    app = app or (tags.pop() if len(tags) == 1 and isinstance(next(iter(tags)), str)
                  else "worker")

    def add(stamp: dict) -> None:
        stamp["runs"] = sorted(set(stamp["runs"]) | {me})
    if me not in stamp["runs"]:  # a run is removed from it only once it is gone
        update(folder, app, add)
    return Claim(folder, app)


def before_replace(path: str | os.PathLike, tmp: str | os.PathLike,
                   digest: str | None = None) -> None:
    """Record ``path`` in the stamp of the claimed folder holding it, with the SHA-256 of
    its finished temporary file ``tmp``, before ``tmp`` is renamed to ``path`` (called by
    :func:`atomic_write_bytes` and :func:`swgsim.datasets.schema.write_shard`); the
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
    h = digest or sha256_file(tmp)

    def add(stamp: dict) -> None:
        old = stamp["files"].get(rel)
        stamp["files"][rel] = ([old[-1]] if isinstance(old, list) and old and old[-1] != h
                               else []) + [h]
        writers_of(stamp)[rel] = entry(c.app)
    update(c.folder, c.app, add)
    if rel not in c.written:
        c.written.append(rel)


def atomic_write_bytes(path: str | os.PathLike, data: bytes | memoryview,
                       digest: str | None = None) -> None:
    """:func:`write_owned` of ``data`` (``digest``: its SHA-256, when the caller has it).

    Raises
    ------
    swgsim.files.atomic.DiskFullError
        If the disk is full (naming the file and its folder); nothing is left behind.
    """
    write_owned(path, lambda tmp: tmp.write_bytes(data), digest)


def write_owned(path: str | os.PathLike, write: Callable[[Path], object],
                digest: str | None = None) -> None:
    """The one way a file of a run is written: ``write(tmp)`` writes it whole to a
    temporary file beside ``path`` (a figure: :func:`save_figure`), which is
    flushed, listed in the stamp of the claimed folder holding it (:func:`before_replace`)
    and renamed into place (:func:`swgsim.files.atomic.write_atomically`). A kill or a
    full disk at any point leaves the old file (still proved ours) or the new one whole
    and stamped, and at most a temporary file the next claim removes.

    Raises
    ------
    swgsim.files.atomic.DiskFullError
        If the disk is full (naming the file and its folder); nothing is left behind.
    """
    write_atomically(path, write, lambda p, tmp: before_replace(p, tmp, digest))


def save_figure(fig: Any, path: str | os.PathLike, dpi: int,
                bbox_inches: str | None = None) -> Path:
    """Write a matplotlib figure to ``path`` as :func:`write_owned` writes a file, in the
    format its suffix names (``.png``, ``.pdf``, ``.svg``); a figure pyplot made is then
    closed (pyplot would hold it until the process ends), a ``Figure`` made without pyplot
    is left as it is.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure, drawn.
    path : str or os.PathLike
        The file; its suffix names the format.
    dpi : int
        Resolution [dots per inch].
    bbox_inches : str, optional
        ``"tight"``: the saved area shrunk to the figure's content (matplotlib's
        ``savefig``); None: the figure's size.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        If matplotlib has no writer for the suffix.
    swgsim.files.atomic.DiskFullError
        If the disk is full (naming the file and its folder); nothing is left behind.
    """
    path = Path(path)
    write_owned(path, lambda tmp: fig.savefig(tmp, format=path.suffix[1:], dpi=dpi,
                                              bbox_inches=bbox_inches))
    if fig.canvas.manager is not None:  # a figure pyplot made, so pyplot is imported
        sys.modules["matplotlib.pyplot"].close(fig)
    return path


def atomic_write_json(path: str | os.PathLike, obj: Any, sort_keys: bool = True) -> None:
    """Write ``obj`` as indented JSON (keys sorted unless ``sort_keys`` is False: a record
    read back as a table keeps its columns' order) to ``path`` atomically, recorded as
    :func:`atomic_write_bytes` records it."""
    atomic_write_bytes(path, (json.dumps(obj, indent=2, sort_keys=sort_keys) + "\n").encode())


def stop_note() -> str:
    """What the claims a stop (Ctrl-C, SIGTERM) ended keep, and what a rerun reuses: one
    clause per folder (:class:`swgsim.files.writers.Writer`: its finished parts, proved by
    the stamp), after the folders this run finished before the stop, for the one line an
    app ends with; empty if the run wrote into no folder. Called
    once the workers are gone: the temporary files they left half-written (a worker killed
    while it wrote) are removed here, as the next claim would."""
    notes, seen = [], set()
    for folder, app in _STOPPED:
        if folder in seen:
            continue
        seen.add(folder)
        w = writer_of(app)
        try:
            found = survey(folder)
        except (OSError, ValueError):
            continue
        for f in found.stale:  # ours, of a process now gone
            f.unlink(missing_ok=True)
        kept = sorted(r for r, by in found.writers.items() if w.parts and by is not None
                      and by.kind == w.kind and fnmatch.fnmatch(r, w.parts))
        names = ", ".join(kept[:2]) + (", ..." if len(kept) > 2 else "")
        if w.parts:
            what = (f"{len(kept)} finished {w.part}(s) of the {w.kind} kept ({names})"
                    if kept else f"no {w.part} of the {w.kind} finished yet")
            notes.append(f"{folder}: {what}; rerun the same command to resume: {w.resume}")
        else:
            n = sum(1 for by in found.writers.values() if by is not None and by.kind == w.kind)
            notes.append(f"{folder}: {n} file(s) of the {w.kind} written whole, none "
                         "half-written; rerun the same command")
    done = [str(f) for f in _FINISHED if f not in seen]
    if done:  # written whole earlier in this run: kept, a rerun reuses what it can
        notes = [f"finished before the stop and kept: {', '.join(done)}",
                 *(notes or ["rerun the same command to go on"])]
    _STOPPED.clear()
    _FINISHED.clear()
    return "; ".join(notes)


def forget_stops() -> None:
    """Forget the claims earlier stops ended and earlier runs finished (a run starting in
    this process: its :func:`stop_note` names its own)."""
    _STOPPED.clear()
    _FINISHED.clear()
