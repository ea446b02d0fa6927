"""A recording's table: bounded reading, checks over its rows, segments and windows.

The array work behind :mod:`swgsim.datasets.recordings`, which calls these functions with
the mapping's fields (:mod:`swgsim.datasets.recording_mapping`); nothing here knows the
mapping's classes. A
table is CSV (UTF-8, a byte-order mark accepted, comma-separated, one header line) or
Parquet (pandas with pyarrow), one row per sample. Every refusal is one ``ValueError``
line naming the file, the column (with the mapping key it was given as) and the row:
rows are counted from 0, the header not counted (row ``i`` of a CSV is its line
``i + 2``, given beside it).

**Windows.** Each segment (:mod:`swgsim.datasets.recording_checks`) is cut from its first
row into consecutive windows of ``n_t`` samples; a segment's tail shorter than a window is
left out. Per window the mean, minimum
or maximum of a column comes from :func:`window_reduce`, and :func:`thin` takes one
window every interval of operation.
"""

from __future__ import annotations

import hashlib
import io
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from swgsim.files.inputs import check_input_file

__all__ = ["MAX_READ_BYTES", "MAX_TABLE_BYTES", "MAX_TABLE_CELLS", "MIN_WINDOW_SAMPLES",
           "TABLE_FORMATS", "assign_points", "check_file", "check_limit", "column_name",
           "content_hash", "datetime_seconds", "numeric", "read_table", "row_name",
           "stream_table", "thin", "window_reduce", "window_starts"]

#: Largest table read [bytes] (1 GiB): a CSV of about 10 columns at 10 kHz holds some
#: 1.5 h; pandas holds it in about 2-3 times its size of memory. Longer recordings: one
#: file per day, or Parquet (compressed, typically 3-5 times smaller).
MAX_TABLE_BYTES = 1 << 30
#: Largest ``max_bytes`` a run may ask for (``swgsim-import max_file_mb``) [bytes]: 4 GiB.
#: Reading holds the file's bytes (hashed and parsed from the one copy, issue 43) and
#: parses them: measured (growth of the largest resident size over :func:`read_table` and
#: :func:`numeric` on its columns, a synthetic CSV of 14 numeric columns, 209 bytes a row)
#: 1.97 and 2.30 times the file at 523 MB (3 and 14 columns mapped), 3.3 and 3.8 times at
#: 104 MB (the parser's chunk of :data:`_CHUNK_ROWS` rows then holds the whole file). A
#: file at the bound needs about 9-10 GiB [choice: what a workstation of 16 GiB holds
#: beside the rest; issue 82 found ``max_file_mb=65536`` allowed]. A longer recording:
#: one file per day, or Parquet.
MAX_READ_BYTES = 4 << 30
#: Most cells (data rows times mapped columns) read from a table: 2**27, 1 GiB as float64,
#: what a 1 GiB CSV of 8-character cells holds. The file's size alone does not bound it: a
#: Parquet file compresses a constant column to almost nothing (a 50 MiB file ran out of
#: 4 GB of memory, issue 43).
MAX_TABLE_CELLS = 1 << 27
#: The formats read, by file suffix.
TABLE_FORMATS = {".csv": "csv", ".txt": "csv", ".parquet": "parquet", ".pq": "parquet"}
#: Fewest samples in a window: the monitor's least-squares series in the wave-generator
#: angle has 31 coefficients per bridge (offset, 12 harmonics and 3 sub-harmonic orders,
#: as cosine and sine; learn/inputs/health.py), so a window needs at least twice as many
#: samples [choice].
MIN_WINDOW_SAMPLES = 64
_CHUNK_ROWS = 1_000_000  # CSV rows read at a time (the progress bar's step)


def row_name(i: int, fmt: str) -> str:
    """How messages name row ``i`` (0-based, header not counted): ``row 12 (line 14)``
    for a CSV, whose line numbers count the header."""
    return f"row {i} (line {i + 2})" if fmt == "csv" else f"row {i}"


def column_name(column: str, key: str) -> str:
    """How messages name a column: ``column 'x' (key)``, with the mapping key it was
    given as."""
    return f"column {column!r} ({key})"


def check_file(path: str | os.PathLike, what: str, max_bytes: int) -> Path:
    """Refuse a path that is not a regular, non-empty file of at most ``max_bytes``.

    Parameters
    ----------
    path : path-like
    what : str
        The key the file was given as, for the message (``recording``, ``mapping``).
    max_bytes : int
        Largest size read [bytes].

    Returns
    -------
    Path

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    ValueError
        If it is a folder, larger than ``max_bytes``, not a regular file or a sparse one
        (:func:`swgsim.files.inputs.check_input_file`, every input file's checks), or
        empty.
    """
    p = Path(path).expanduser()
    if not p.exists():
        raise FileNotFoundError(2, f"no {what} file", str(p))
    if p.is_dir():
        raise ValueError(f"{what} {p}: is a folder; give a file")
    size = p.stat().st_size
    if size > max_bytes:
        raise ValueError(f"{what} {p}: {size / 2**20:.1f} MiB, more than the "
                         f"{max_bytes / 2**20:g} MiB read; split it or write it as Parquet")
    check_input_file(p, what, max_bytes)
    if size == 0:
        raise ValueError(f"{what} {p}: the file is empty (0 bytes)")
    return p


def _header(p: Path, data: bytes, fmt: str, sep: str = ",") -> tuple[list[str], int]:
    """The column names of a table held in ``data`` (the bytes of ``p``; a CSV's fields
    separated by ``sep``) and its number of data rows (Parquet: from its metadata; CSV:
    line ends after the header, an upper bound where a quoted field holds one), refusing
    bytes that are not a table."""
    import pandas as pd

    try:
        if fmt == "parquet":
            import pyarrow.parquet as pq

            pf = pq.ParquetFile(io.BytesIO(data))
            return [str(c) for c in pf.schema_arrow.names], int(pf.metadata.num_rows)
        names = [str(c) for c in pd.read_csv(io.BytesIO(data), nrows=0, sep=sep,
                                             encoding="utf-8-sig").columns]
        return names, data.count(b"\n") - (1 if data.endswith(b"\n") else 0)
    except ImportError as e:
        raise ValueError(f"recording {p}: reading Parquet needs pyarrow ({e})") from None
    except (UnicodeDecodeError, pd.errors.ParserError, pd.errors.EmptyDataError) as e:
        raise ValueError(f"recording {p}: not a CSV table (UTF-8 text, one header line, "
                         f"comma-separated): {str(e).splitlines()[0]}") from None
    except Exception as e:  # noqa: BLE001 - pyarrow's errors for a file that is not Parquet
        raise ValueError(f"recording {p}: not a Parquet table ({type(e).__name__}: "
                         f"{str(e).splitlines()[0] if str(e) else ''})") from None


def _read_bytes(p: Path, max_bytes: int) -> bytes:
    """The bytes of ``p``, read once and at most ``max_bytes`` of them (the file may have
    grown since :func:`check_file`).

    The buffer is the file's size (plus one byte, to see it grow), not ``max_bytes``:
    ``read(max_bytes + 1)`` asks for all of it at once, a MemoryError for any file, even
    a small one, once ``max_bytes`` passes the machine's memory (issue 82:
    ``max_file_mb=65536`` on a machine of 24 GiB)."""
    with open(p, "rb") as f:
        size = min(os.fstat(f.fileno()).st_size, max_bytes)
        data = f.read(size + 1)
    if len(data) > max_bytes:
        raise ValueError(f"recording {p}: grew beyond the {max_bytes / 2**20:g} MiB read "
                         "while it was read; import a finished file")
    if len(data) > size:
        raise ValueError(f"recording {p}: grew while it was read (past the {size} bytes it "
                         "had); import a finished file")
    if not data:
        raise ValueError(f"recording {p}: the file is empty (0 bytes)")
    return data


def _read_csv_chunks(data: bytes, use: list[str], name: str, progress: bool, sep: str,
                     decimal: str):
    """The columns ``use`` of a CSV's bytes, parsed in chunks of :data:`_CHUNK_ROWS` rows
    (a progress bar over them named ``name``, shown when reading takes > 2 s); an empty
    frame of those columns when there is no data row. Raises pandas' parser errors."""
    import pandas as pd
    from tqdm.auto import tqdm

    parts = []
    with tqdm(desc=f"read {name}", unit="row", unit_scale=True, delay=2.0,
              disable=not progress) as bar:
        for chunk in pd.read_csv(io.BytesIO(data), usecols=use, encoding="utf-8-sig",
                                 sep=sep, decimal=decimal, chunksize=_CHUNK_ROWS,
                                 low_memory=False, float_precision="round_trip"):
            parts.append(chunk)
            bar.update(len(chunk))
    return pd.concat(parts, ignore_index=True) if parts else pd.DataFrame(columns=use)


def read_table(path: str | os.PathLike, columns: dict[str, str],
               max_bytes: int = MAX_TABLE_BYTES, progress: bool = False,
               max_cells: int | None = None, sep: str = ",", decimal: str = "."):
    """Read the mapped columns of a recording's table, bounded and checked.

    The file is read once into memory and everything comes from those bytes: its
    SHA-256, its header and row count, and the table parsed from them; a file replaced or
    appended to meanwhile changes neither (issue 43, cause 8). What the table expands to
    (data rows times mapped columns) is checked against ``max_cells`` before it is parsed:
    a Parquet file compresses a long constant column to almost nothing (issue 43, cause 7).

    Parameters
    ----------
    path : path-like
        A CSV (``.csv``, ``.txt``) or Parquet (``.parquet``, ``.pq``) file.
    columns : dict of str to str
        Column name -> the mapping key it was given as (for messages).
    max_bytes : int
        Largest file read (:func:`check_file`) [bytes].
    progress : bool
        A progress bar over the CSV's rows.
    max_cells : int, optional
        Most cells (rows times mapped columns) parsed; default :data:`MAX_TABLE_CELLS`.
    sep, decimal : str
        A CSV's field separator and decimal mark (``,`` and ``.``; a controller's log
        written for a European locale: ``;`` and ``,``, :mod:`swgsim.datasets.joint_log`).

    Returns
    -------
    (pandas.DataFrame, str, str)
        The mapped columns only, the format (``csv`` or ``parquet``) and the SHA-256 of
        the bytes parsed.

    Raises
    ------
    FileNotFoundError, ValueError
        One line naming the file: not a regular file, empty, too large (as a file, or as
        the cells it holds), of another suffix, not a table, a mapped column missing
        (named with its key and the columns the table has), or no data row.
    """
    import pandas as pd

    max_cells = MAX_TABLE_CELLS if max_cells is None else max_cells
    p = check_file(path, "recording", max_bytes)
    fmt = TABLE_FORMATS.get(p.suffix.lower())
    if fmt is None:
        raise ValueError(f"recording {p}: suffix {p.suffix or '(none)'!r}; a table is read "
                         f"from {', '.join(TABLE_FORMATS)}")
    data = _read_bytes(p, max_bytes)
    digest = hashlib.sha256(data).hexdigest()
    have, rows = _header(p, data, fmt, sep)
    for col, key in columns.items():
        if col not in have:
            hint = ("; the header is one field: is the file separated by ';' or tabs? "
                    "Write it comma-separated") if len(have) == 1 and len(columns) > 1 else ""
            shown = ", ".join(have[:20]) + (", ..." if len(have) > 20 else "")
            raise ValueError(f"recording {p}: column {col!r} ({key}) is missing; the table "
                             f"has {shown}{hint}")
    use = list(columns)
    if rows * len(use) > max_cells:
        raise ValueError(f"recording {p}: {rows} rows of {len(use)} mapped columns are "
                         f"{rows * len(use)} values, more than the {max_cells} read (at 8 "
                         f"bytes each {max_cells * 8 / 2**30:g} GiB); split the recording")
    try:
        if fmt == "parquet":
            df = pd.read_parquet(io.BytesIO(data), columns=use)
        else:
            df = _read_csv_chunks(data, use, p.name, progress, sep, decimal)
    except (UnicodeDecodeError, pd.errors.ParserError) as e:
        raise ValueError(f"recording {p}: not a table: {str(e).splitlines()[0]}") from None
    if len(df) == 0:
        raise ValueError(f"recording {p}: the table has a header but no data row")
    return df, fmt, digest


def numeric(df, column: str, key: str, fmt: str, missing: bool = False,
            decimal: str = ".") -> np.ndarray:
    """A column as finite float64, refusing the first cell that is not.

    Parameters
    ----------
    df : pandas.DataFrame
    column : str
    key : str
        The mapping key the column was given as.
    fmt : str
        ``csv`` or ``parquet`` (how rows are named, :func:`row_name`).
    missing : bool
        An empty cell is a missing reading, NaN (default False: refused); text that is
        not a number and infinities are refused either way.
    decimal : str
        The decimal mark of cells read as text (a column that holds one cell not a
        number stays text in pandas, its numbers too).

    Returns
    -------
    ndarray, shape (n_rows,)

    Raises
    ------
    ValueError
        ``column 'x' (key), row i: 'abc' is not a number`` or ``... nan is not finite``.
    """
    import pandas as pd

    s = df[column]
    if s.dtype.kind == "b":
        raise ValueError(f"column {column!r} ({key}): holds true/false, not numbers")
    if s.dtype.kind in "fiu":
        v = s.to_numpy(dtype=np.float64)
    else:
        text = s.astype(str).str.replace(decimal, ".", regex=False) if decimal != "." else s
        num = pd.to_numeric(text.where(s.notna()), errors="coerce")
        bad = np.flatnonzero(num.isna().to_numpy() & s.notna().to_numpy())
        if bad.size:
            raise ValueError(f"column {column!r} ({key}), {row_name(int(bad[0]), fmt)}: "
                             f"{s.iloc[bad[0]]!r} is not a number")
        v = num.to_numpy(dtype=np.float64)
    bad = np.flatnonzero(np.isinf(v) if missing else ~np.isfinite(v))
    if bad.size:
        raise ValueError(f"column {column!r} ({key}), {row_name(int(bad[0]), fmt)}: "
                         f"{v[bad[0]]} is not a finite number (an empty cell, NaN or "
                         f"infinity; {bad.size} such row(s))")
    return v


#: Texts of an event flag's cells, case-insensitive (the UR3 CobotOps log writes True and
#: False) [choice].
FLAG_TEXTS = {"true": True, "false": False, "1": True, "0": False}


def flag(df, column: str, key: str, fmt: str, missing: bool | None = None) -> np.ndarray:
    """An event flag column as booleans: true/false (booleans or their text,
    :data:`FLAG_TEXTS`) or finite numbers, nonzero true.

    Parameters
    ----------
    df : pandas.DataFrame
        The table read (:func:`read_table`).
    column : str
        The flag's column.
    key : str
        The column's field, named in a refusal.
    fmt : str
        The table's format (``csv`` or ``parquet``), for the row's name in a refusal.
    missing : bool or None
        What an empty cell reads as; None (default) refuses it (a controller's log that
        leaves a flag empty where it logged nothing passes False).

    Returns
    -------
    ndarray of bool, shape (n_rows,)

    Raises
    ------
    ValueError
        ``column 'x' (key), row i: 'abc' is not a flag (true/false or a number)``; an
        empty cell likewise unless ``missing`` is given.
    """
    import pandas as pd

    s = df[column]
    if s.dtype.kind == "b":
        return s.to_numpy(dtype=bool)
    empty = s.isna().to_numpy()
    if s.dtype.kind in "fiu":
        v = s.to_numpy(dtype=np.float64)
    else:
        text = s.astype(str).str.strip().str.lower()
        v = pd.to_numeric(text, errors="coerce").to_numpy(dtype=np.float64)
        named = text.map(FLAG_TEXTS)
        v = np.where(named.notna(), named.fillna(False).astype(float), v)
    ok = np.isfinite(v) & ~empty
    if missing is not None:
        ok |= empty
        v = np.where(empty, float(missing), v)
    bad = np.flatnonzero(~ok)
    if bad.size:
        i = int(bad[0])
        cell = ("an empty cell" if pd.isna(s.iloc[i]) else repr(s.iloc[i])
                ) if s.dtype.kind == "O" else f"{v[i]:g}"
        raise ValueError(f"column {column!r} ({key}), {row_name(i, fmt)}: {cell} is not a "
                         "flag (true/false or a number)")
    return v != 0


def datetime_seconds(df, column: str, key: str, fmt: str) -> np.ndarray:
    """A wall-clock column (ISO 8601 text or datetime values) as seconds since its first
    row, float64, shape (n_rows,).

    Raises
    ------
    ValueError
        Naming the column and the first row that is not a time stamp.
    """
    import pandas as pd

    s = df[column]
    try:
        ts = pd.to_datetime(s, errors="coerce", utc=True, format="ISO8601") \
            if s.dtype.kind not in "M" else pd.to_datetime(s, utc=True)
    except (ValueError, TypeError) as e:
        raise ValueError(f"column {column!r} ({key}): not time stamps ({e})") from None
    bad = np.flatnonzero(ts.isna().to_numpy())
    if bad.size:
        raise ValueError(f"column {column!r} ({key}), {row_name(int(bad[0]), fmt)}: "
                         f"{s.iloc[bad[0]]!r} is not a time stamp (ISO 8601, e.g. "
                         "2025-03-01T12:00:00.0001)")
    ns = ts.to_numpy(dtype="datetime64[ns]").astype(np.int64)
    return (ns - ns[0]).astype(np.float64) * 1e-9


def check_limit(values: np.ndarray, lo: float, hi: float, column: str, key: str, unit: str,
                fmt: str, why: str, row: Callable[[int], str] | None = None) -> None:
    """Refuse the first value outside [lo, hi], naming the column, the row and ``why``
    (what a value there means, e.g. a unit mistaken).

    Parameters
    ----------
    values : ndarray, shape (n_rows,)
        The column (NaN passes: a missing reading is the caller's to refuse or keep).
    lo, hi : float
        The range, in ``unit``.
    column, key : str
        The column and what it was given as (:func:`column_name`).
    unit : str
    fmt : str
        ``csv`` or ``parquet`` (how rows are named, :func:`row_name`).
    why : str
        What a value outside means.
    row : callable, optional
        How the message names row ``i`` where a reader knows better than
        :func:`row_name` (a CSV with blank lines or quoted line breaks).

    Raises
    ------
    ValueError
    """
    bad = np.flatnonzero((values < lo) | (values > hi))
    if bad.size:
        i = int(bad[0])
        where = row_name(i, fmt) if row is None else row(i)
        raise ValueError(f"column {column!r} ({key}), {where}: {values[i]:g} {unit} "
                         f"outside [{lo:g}, {hi:g}] {unit}: {why}")


def window_starts(starts: np.ndarray, n: int, n_t: int) -> tuple[np.ndarray, np.ndarray]:
    """First rows of the whole windows of every segment, cut from its first row.

    Returns
    -------
    (ndarray of int, ndarray of int), each shape (n_windows,)
        The windows' first rows, increasing, and their segments.
    """
    ends = np.append(starts[1:], n)
    k = (ends - starts) // n_t
    seg = np.repeat(np.arange(starts.size), k)
    within = np.arange(int(k.sum())) - np.repeat(np.cumsum(k) - k, k)
    return starts[seg] + within * n_t, seg


def window_reduce(x: np.ndarray, w0: np.ndarray, n_t: int, how: str = "mean") -> np.ndarray:
    """Mean, minimum or maximum of ``x`` (shape (n,)) over each window [w0, w0 + n_t),
    shape (n_windows,)."""
    ufunc = {"mean": np.add, "min": np.minimum, "max": np.maximum}[how]
    if w0.size == 0:
        return np.empty(0)
    idx = np.ravel(np.column_stack([w0, w0 + n_t]))
    r = ufunc.reduceat(np.append(x, 0.0), idx)[::2]
    return r / n_t if how == "mean" else r


def thin(hours: np.ndarray, interval_h: float, tolerance_h: float) -> np.ndarray:
    """Indices of the windows taken: the first, then each first one at least
    ``interval_h - tolerance_h`` after the last taken (``hours`` increasing).

    Returns
    -------
    ndarray of int
    """
    if interval_h <= 0:
        return np.arange(hours.size)
    taken, i = [], 0
    while i < hours.size:
        taken.append(i)
        i = max(i + 1, int(np.searchsorted(hours, hours[i] + interval_h - tolerance_h)))
    return np.asarray(taken, dtype=np.int64)


def assign_points(mean_rpm: np.ndarray, lo_rpm: np.ndarray, hi_rpm: np.ndarray,
                  mean_nm: np.ndarray, points: np.ndarray, tol_rpm: float, tol_nm: float
                  ) -> np.ndarray:
    """Each window's declared operating point, or -1 (outside every one).

    A window is at point (n, T) when its mean speed and mean torque lie within the
    tolerances of it and its lowest and highest speed within the speed tolerance (a
    steady window); the points' tolerance boxes do not overlap (checked with the mapping).

    Parameters
    ----------
    mean_rpm, lo_rpm, hi_rpm : ndarray, shape (n_windows,)
        Mean, lowest and highest input speed of each window [rpm].
    mean_nm : ndarray, shape (n_windows,)
        Mean output torque [N m].
    points : ndarray, shape (P, 2)
        Declared (n_in_rpm, t_out_nm).
    tol_rpm, tol_nm : float
        Tolerances [rpm], [N m].

    Returns
    -------
    ndarray of int, shape (n_windows,)
    """
    out = np.full(mean_rpm.size, -1, dtype=np.int64)
    for k, (n, t) in enumerate(points):
        at = ((np.abs(mean_rpm - n) <= tol_rpm) & (np.abs(mean_nm - t) <= tol_nm)
              & (np.abs(lo_rpm - n) <= tol_rpm) & (np.abs(hi_rpm - n) <= tol_rpm))
        out[at] = k
    return out


def content_hash(ds) -> str:
    """SHA-256 of a shard's float32 signals and its other variables in sorted order (as a
    life shard's, :func:`swgsim.datasets.life.simulate_life_shard`)."""
    h = hashlib.sha256(ds["strain_signal"].values.tobytes())
    for k in sorted(v for v in ds.data_vars if v != "strain_signal"):
        v = ds[k].values
        h.update(np.ascontiguousarray(v.astype(str) if v.dtype.kind in "OU" else v).tobytes())
    return h.hexdigest()


def stream_table(ds) -> tuple[Any, dict]:
    """The table a burst logger would record of a stream, and the mapping that imports it
    back (:func:`swgsim.datasets.recordings.import_recording`): an example of the format,
    and the round trip's test.

    Each window is a burst of its samples: ``time_s`` [s] the window's hour in seconds
    plus the time in it, ``hours`` the window's hour (constant in the burst, the clock),
    the bridges ``s0``..``s4`` [mV/V], ``n_in_rpm`` and ``t_out_nm`` the window's acting
    means, ``p_in_w`` (100 W) and ``p_out_w`` (100 W times the efficiency; only where
    every efficiency is finite), the angles ``phi_in`` and ``phi_out`` [rad] and
    ``temperature_c`` where the stream has them.

    Parameters
    ----------
    ds : xarray.Dataset
        A stream of one gear (a life: ``hour``, ``commissioning``).

    Returns
    -------
    (pandas.DataFrame, dict)
        The table, one row per sample, and the mapping as plain data: the stream's
        operating points, commissioning period, window, interval, sample rate and gear.
    """
    import json

    import pandas as pd

    from swgsim.datasets.schema import SENSORS
    from swgsim.sensing.angles import InputAngleSensor

    sig = ds["strain_signal"].values  # (n_w, 5, n_t)
    n_w, _, n_t = sig.shape
    fs = float(ds.attrs["sample_rate_hz"])
    hour = ds["hour"].values.astype(float)

    def rep(v) -> np.ndarray:
        return np.repeat(np.asarray(v), n_t)

    cols = {"time_s": (hour[:, None] * 3600.0 + np.arange(n_t) / fs).ravel(),
            "hours": rep(hour), **{s: sig[:, i, :].ravel() for i, s in enumerate(SENSORS)},
            "n_in_rpm": rep(ds["n_in_mean_rpm"].values),
            "t_out_nm": rep(ds["t_out_mean_nm"].values)}
    comm = ds["commissioning"].values.astype(bool)
    pts = np.unique(np.stack([ds["n_in_rpm"].values, ds["t_out_nm"].values], axis=1), axis=0)
    mapping: dict[str, Any] = {
        "time": "time_s", "clock": {"column": "hours", "unit": "h"},
        "operating_points": {"points": pts.tolist()},
        "commissioning_h": float((hour[~comm][0] if (~comm).any() else hour[-1] + 1.0) - hour[0]),
        "gear": int(ds["gear"].values[0]), "window_s": n_t / fs, "sample_rate_hz": fs,
        "interval_min": float(np.median(np.diff(hour)) * 60.0) if n_w > 1 else 0.0}
    eff = ds["efficiency"].values
    if np.isfinite(eff).all():
        cols.update(p_in_w=np.full(n_w * n_t, 100.0), p_out_w=rep(100.0 * eff))
        mapping["power"] = {"input": "p_in_w", "output": "p_out_w"}
    angles = (json.loads(ds.attrs.get("config", "{}")).get("profile") or {}).get("angles") or {}
    if "phi_in_meas" in ds:
        cols["phi_in"] = ds["phi_in_meas"].values.ravel()
        mapping["input_angle"] = {"column": "phi_in", "counts_per_rev": int(
            angles.get("input_counts_per_rev") or InputAngleSensor().counts_per_rev)}
    if "phi_out_meas" in ds:
        cols["phi_out"] = ds["phi_out_meas"].values.ravel()
        mapping["output_angle"] = {"column": "phi_out",
                                   "counts_per_rev": 2 ** int(angles["output_encoder_bits"])}
    if "temperature_c" in ds:
        cols["temperature_c"] = rep(ds["temperature_c"].values)
        mapping["temperature"] = "temperature_c"
    return pd.DataFrame(cols), mapping
