"""Which app, and which kind of output, wrote each file of a folder.

The ownership stamp (:mod:`swgsim.files.ownership`) proves that a run of this project wrote
a file; its ``writers`` say which app, and what kind of output the file belongs to (a data
set, a monitor report, a calibration, ...)::

    "writers": {"report.md": {"app": "swgsim-monitor", "kind": "monitor report"}}

An app replaces only its own kind of output (docs/DATASET.md, "Files"); a file of another
kind, or of an unknown app (a stamp of version 1), is refused in one line naming the file
and its writer (:func:`refuse_others`), before any work.

:data:`WRITERS` is the one list of the apps, by the tag they claim a folder with.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

__all__ = ["Writer", "WRITERS", "writer_of", "entry", "read_entry", "others",
           "refuse_others"]


@dataclass(frozen=True)
class Writer:
    """Who wrote a file.

    Attributes
    ----------
    app : str
        The program, as the user runs it (``swgsim-monitor``, ``swgsim-train
        experiment=monitor``).
    kind : str
        The kind of output (``data set``, ``monitor report``, ...): an app replaces only
        files of its own kind.
    parts : str
        Glob (relative to the folder) of the finished parts a stopped run leaves for a
        rerun to resume from (shards, the evaluation's parts); empty: none.
    part : str
        What one part is called (``shard``).
    resume : str
        What a rerun of the same command reuses, for the line a stop ends with.
    """

    app: str
    kind: str
    parts: str = ""   # glob (relative) of its finished parts kept by a stop, "" for none
    part: str = ""    # what one part is called
    resume: str = ""  # what a rerun of the same command reuses (with parts)


#: The tag an app claims a folder with (:func:`swgsim.files.ownership.claim`) -> the program
#: and its kind of output. A tag not listed is its own program and kind (a test's).
WRITERS: dict[str, Writer] = {
    "swgsim-generate": Writer(
        "swgsim-generate", "data set", "*.nc", "shard",
        "it reuses each shard whose SHA-256 its sidecar and the ownership stamp prove "
        "complete, and simulates the rest"),
    "swgsim-calibrate": Writer("swgsim-calibrate", "calibration"),
    "swgsim-monitor": Writer("swgsim-monitor", "monitor report"),
    "swgsim-export": Writer("swgsim-export", "export"),
    "swgsim-import": Writer("swgsim-import", "imported stream"),
    "swgsim-observability": Writer("swgsim-observability", "observability"),
    "swgsim-paper": Writer("swgsim-paper", "paper study"),
    "paper-study": Writer("swgsim-paper or swgsim-train task=paper_study", "paper study"),
    "transfer": Writer("swgsim-train experiment=transfer", "transfer report"),
    "monitor": Writer(
        "swgsim-train experiment=monitor", "monitor evaluation", "parts/*.json", "part",
        "it reuses each part in parts/ whose SHA-256 the ownership stamp and whose key the "
        "config prove complete, and runs the rest"),
    "monitor-families": Writer(
        "scripts/monitor_families.py", "monitor families", "*_part.json", "family",
        "it reuses each family whose rows the ownership stamp and whose key in "
        "<family>_part.json prove complete, and runs the rest"),
    "prognosis": Writer(
        "swgsim-train experiment=prognosis", "prognosis evaluation", "parts/*.json", "part",
        "it reuses each part in parts/ whose SHA-256 the ownership stamp and whose key the "
        "config prove complete, and runs the rest"),
}


def writer_of(tag: str) -> Writer:
    """The program and kind of output of the app that claims with ``tag``."""
    return WRITERS.get(tag, Writer(tag, tag))


def entry(tag: str) -> dict[str, str]:
    """The stamp's ``writers`` entry of a file written by the app ``tag``."""
    return {"app": tag, "kind": writer_of(tag).kind}


def read_entry(value: object) -> Writer | None:
    """The writer a stamp's ``writers`` entry names (program as the user knows it), or None
    when it names none (a stamp of an earlier version, or a damaged entry)."""
    if not (isinstance(value, dict) and isinstance(value.get("app"), str)
            and isinstance(value.get("kind"), str)):
        return None
    return Writer(writer_of(value["app"]).app, value["kind"])


def others(writers: dict[str, Writer | None], tag: str) -> list[tuple[str, Writer | None]]:
    """The files (relative paths, sorted) of ``writers`` not written as the app ``tag``'s
    kind of output, with their writer (None: unknown)."""
    kind = writer_of(tag).kind
    return [(rel, w) for rel, w in sorted(writers.items()) if w is None or w.kind != kind]


def refuse_others(folder: str | Path, what: str, writers: dict[str, Writer | None],
                  tag: str, overwrite: str | None = None) -> None:
    """Refuse a folder holding a file of another kind of output than the app ``tag``'s.

    Parameters
    ----------
    folder : path-like
    what : str
        The key the folder was given as (``out_dir``), for the message.
    writers : dict of str to Writer or None
        Files proved ours and their writers (:attr:`swgsim.files.ownership.Survey.writers`).
    tag : str
        The app about to write (a key of :data:`WRITERS`).
    overwrite : str, optional
        The key that lets the app replace files of an unknown app (``overwrite``); None:
        the app has none.

    Raises
    ------
    ValueError
        One line naming the first such file and its writer; nothing was touched.
    """
    found = others(writers, tag)
    if not found:
        return
    me = writer_of(tag)
    rel, w = next(((r, w) for r, w in found if w is not None), found[0])
    more = f" and {len(found) - 1} more such file(s)" if len(found) > 1 else ""
    if w is None:
        hint = f", or pass {overwrite}=true to replace it" if overwrite else ""
        raise ValueError(
            f"{what} {folder} holds {rel}{more}, written by a run of this project whose "
            f"ownership stamp (an earlier version's) does not say which app wrote it; "
            f"nothing was touched: move it away or choose another {what}{hint}")
    raise ValueError(
        f"{what} {folder} holds {rel}{more}, written by {w.app} (a {w.kind}); {me.app} "
        f"replaces only its own earlier output ({me.kind}); nothing was touched: choose "
        f"another {what} or move it away")
