"""Input files the user names (a measured recording, a diagnosis model, a manifest): a
regular file under a stated size, read with a bounded header, refused in one line before
anything is read.

``/dev/zero``, a FIFO, a folder, a device or a sparse file of gigabytes would otherwise be
read until memory runs out (a CSV reader looking for the end of its first line) or hang.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

__all__ = ["MAX_INPUT_BYTES", "HEADER_BYTES", "absolute_path", "check_input_file",
           "available_memory", "check_text_file", "read_head"]

#: Largest input file read [bytes]: 2 GiB. A measured recording, a data set's manifest or
#: a diagnosis model of this project is far smaller (the Franka friction CSVs are a few
#: MB; a diagnosis model tens of MB) [choice].
MAX_INPUT_BYTES = 2 * 2**30
#: Most bytes read to find a text file's header line [bytes]: 64 KiB [choice].
HEADER_BYTES = 64 * 2**10
#: A file longer than this whose blocks on disk hold under an eighth of its length is
#: sparse (mostly holes: never written, not a recording) [bytes] [choice].
_SPARSE_MIN = 2**20

_KINDS = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def _size(n: int) -> str:
    return f"{n / 2**30:.2f} GiB" if n >= 2**30 else f"{n / 2**20:.1f} MiB"


def check_input_file(path: str | os.PathLike, what: str,
                     max_bytes: int = MAX_INPUT_BYTES) -> Path:
    """Refuse anything but a regular file of at most ``max_bytes``, before reading it.

    Parameters
    ----------
    path : path-like
        The file (a link to a regular file is followed).
    what : str
        The key or role it was given as (``measured``, ``diagnosis_model``), for the
        message: ``<what> <path>: is a FIFO (named pipe), not a regular file; ...``.
    max_bytes : int
        Largest size accepted [bytes]; default :data:`MAX_INPUT_BYTES` (2 GiB).

    Returns
    -------
    Path

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    ValueError
        One line naming the key, the path and what it is instead: a folder, a FIFO, a
        device, a socket, a file over ``max_bytes``, or a sparse file (mostly holes).
    """
    p = Path(path)
    st = os.stat(p)  # FileNotFoundError names the path
    if stat.S_ISDIR(st.st_mode):
        raise ValueError(f"{what} {p}: is a folder, not a file")
    for test, kind in _KINDS:
        if test(st.st_mode):
            raise ValueError(f"{what} {p}: is {kind}, not a regular file; nothing was read")
    if not stat.S_ISREG(st.st_mode):
        raise ValueError(f"{what} {p}: not a regular file; nothing was read")
    if st.st_size > max_bytes:
        raise ValueError(f"{what} {p}: {_size(st.st_size)}, over the {_size(max_bytes)} an "
                         "input file may have; nothing was read")
    on_disk = getattr(st, "st_blocks", None)
    if on_disk is not None and st.st_size > _SPARSE_MIN and on_disk * 512 < st.st_size / 8:
        raise ValueError(f"{what} {p}: a sparse file ({_size(st.st_size)} long, "
                         f"{_size(on_disk * 512)} on disk: mostly holes never written), not a "
                         "recording; nothing was read")
    return p


def check_text_file(path: str | os.PathLike, what: str,
                    max_bytes: int = MAX_INPUT_BYTES) -> bytes:
    """:func:`check_input_file`, then the head of a text table: no NUL byte and a line
    end within :data:`HEADER_BYTES`; return that head (a bounded read).

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    ValueError
        As :func:`check_input_file`; or ``<what> <path>: not a text file (...)``: a binary
        file (NUL bytes) or no header line in its first 64 KiB.
    """
    p = check_input_file(path, what, max_bytes)
    head = read_head(p)
    if b"\0" in head:
        raise ValueError(f"{what} {p}: not a text file (it holds NUL bytes: a binary file); "
                         "nothing else was read")
    if len(head) == HEADER_BYTES and head.find(b"\n") < 0 and head.find(b"\r") < 0:
        raise ValueError(f"{what} {p}: not a text file (no line end in its first "
                         f"{HEADER_BYTES // 1024} KiB: no header line)")
    return head


def read_head(path: str | os.PathLike, n: int = HEADER_BYTES) -> bytes:
    """The first ``n`` bytes of a file (fewer if it is shorter): a bounded read.

    Raises
    ------
    OSError
        If the file cannot be read.
    """
    with open(path, "rb") as f:
        return f.read(n)


def available_memory() -> int | None:
    """Memory available to new allocations [bytes]: ``MemAvailable`` of /proc/meminfo
    (Linux), else the free physical pages (``os.sysconf``); None where neither is known."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def absolute_path(path: str) -> str:
    """A path the user named, relative to the directory the app was started in (a Hydra
    app runs in its own run folder: :func:`hydra.utils.to_absolute_path`); unchanged
    outside a Hydra run (a task called directly, as the tests do).

    Parameters
    ----------
    path : str
        As given in the config.

    Returns
    -------
    str
    """
    from hydra.utils import to_absolute_path  # hydra only where an app resolves a path

    try:
        return to_absolute_path(path)
    except ValueError:  # outside a Hydra run
        return path
