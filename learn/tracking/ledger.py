"""Scored seeds and the ledger of scored runs (issue 83): a headline is the run declared
before it ran, and every run of a scored seed is on record.

* Seeds from :data:`SCORED_SEED_MIN` up are *scored* seeds: :func:`check_seeds` refuses
  them in any run not declared a scored run, and refuses design seeds in a scored run.
  Development, tests and diagnosis use the seeds below (design seeds).
* A scored run appends one row to the ledger in the repository (:data:`LEDGER`,
  :func:`append_scored_run`): the date, the commit and whether its tree was clean, the
  command, the seeds and the SHA-256 of its results. A scored seed run twice shows twice.
"""

from __future__ import annotations

import csv
import hashlib
import io
import sys
import time
from collections.abc import Iterable, Sequence
from pathlib import Path

from filelock import FileLock

from learn.tracking.provenance import GIT_COMMIT_TAG, GIT_DIRTY_TAG, git_tags, repo_root
from swgsim.files.digest import sha256_file
from swgsim.files.ownership import atomic_write_bytes

__all__ = ["LEDGER", "LEDGER_COLUMNS", "SCORED_SEED_MIN", "append_scored_run", "check_seeds",
           "read_ledger", "results_digest"]

#: The lowest scored seed: the seeds below are design seeds [choice: every seed the
#: project's evaluations ran before issue 83 lies below it].
SCORED_SEED_MIN = 1000
#: The ledger of scored runs, relative to the repository's root.
LEDGER = "docs/results/ledger.csv"
#: Its columns.
LEDGER_COLUMNS = ("date_utc", "commit", "tree", "command", "seeds", "results_sha256",
                  "results")


def check_seeds(seeds: Iterable[int], scored_run: bool, key: str) -> None:
    """Refuse scored seeds outside a declared scored run, and design seeds inside one.

    Parameters
    ----------
    seeds : iterable of int
        Every seed the run will draw lives or families from.
    scored_run : bool
        Whether the run is declared a scored run (it then enters the ledger).
    key : str
        The option that declares it, for the message (e.g. ``monitor.study.scored_run``).

    Raises
    ------
    ValueError
        One line naming the seeds and ``key``.
    """
    seeds = sorted({int(s) for s in seeds})
    scored = [s for s in seeds if s >= SCORED_SEED_MIN]
    design = [s for s in seeds if s < SCORED_SEED_MIN]
    if scored and not scored_run:
        raise ValueError(f"seeds {scored} are scored seeds (>= {SCORED_SEED_MIN}): they run "
                         f"only in a declared scored run ({key}=true), which enters the "
                         f"ledger {LEDGER}; design, tests and diagnosis use seeds below "
                         f"{SCORED_SEED_MIN}")
    if scored_run and design:
        raise ValueError(f"{key}=true: a scored run draws scored seeds (>= "
                         f"{SCORED_SEED_MIN}) only, got design seeds {design}")


def results_digest(files: Sequence[str | Path]) -> str:
    """SHA-256 over the results' names and SHA-256s, sorted by name (hex).

    Raises
    ------
    FileNotFoundError
        A file that does not exist.
    """
    lines = sorted(f"{Path(f).name} {sha256_file(f)}\n" for f in files)
    return hashlib.sha256("".join(lines).encode()).hexdigest()


def append_scored_run(seeds: Iterable[int], results: Sequence[str | Path],
                      command: str | None = None, ledger: str | Path | None = None) -> dict:
    """Append a scored run to the ledger (atomic; runs on one machine take turns) and say
    so on the console.

    Parameters
    ----------
    seeds : iterable of int
        The scored seeds the run drew.
    results : sequence of path-like
        The files its figures come from (e.g. ``results.csv``, ``false_alarms.csv``).
    command : str, optional
        The command it ran (default this process's command line).
    ledger : path-like, optional
        The ledger (default :data:`LEDGER` in the repository; the tests pass their own).

    Returns
    -------
    dict
        The row appended (:data:`LEDGER_COLUMNS`).
    """
    path = Path(ledger) if ledger is not None else repo_root() / LEDGER
    tags = git_tags()
    commit, dirty = tags[GIT_COMMIT_TAG], tags[GIT_DIRTY_TAG]
    row = {"date_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "commit": commit, "tree": {"false": "clean", "true": "dirty"}.get(dirty, dirty),
           "command": command or " ".join(sys.argv),
           "seeds": " ".join(str(s) for s in sorted({int(s) for s in seeds})),
           "results_sha256": results_digest(results),
           "results": " ".join(sorted(Path(f).name for f in results))}
    path.parent.mkdir(parents=True, exist_ok=True)
    with FileLock(str(path) + ".lock"):
        rows = read_ledger(path)
        buf = io.StringIO()
        w = csv.DictWriter(buf, fieldnames=LEDGER_COLUMNS, lineterminator="\n")
        w.writeheader()
        w.writerows([*rows, row])
        atomic_write_bytes(path, buf.getvalue().encode())
    print(f"scored run entered in the ledger {path}: {row['date_utc']}, commit "
          f"{commit[:12]} ({row['tree']}), results {row['results_sha256'][:16]}")
    return row


def read_ledger(path: str | Path | None = None) -> list[dict]:
    """The ledger's rows, oldest first (none where there is no ledger yet)."""
    path = Path(path) if path is not None else repo_root() / LEDGER
    if not path.is_file():
        return []
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))

