"""Data set on disk, schema v1 (see ``docs/DATASET.md``).

A data set is a directory of NetCDF4/HDF5 shards written through xarray + h5netcdf plus a
``manifest.json``. Every shard holds whole windows along the ``sample`` dimension; the
loader joins them. Writes are atomic (temporary name, then ``os.replace``) and every shard's
SHA-256 is recorded in the manifest and checked on load, so a truncated or altered shard
is reported with its file name instead of silently giving wrong data.

Variables (dims, dtype, units):

=====================  ======================  =======  ======  ==========================
name                   dims                    dtype    units   meaning
=====================  ======================  =======  ======  ==========================
strain_signal          (sample, sensor, time)  float32  mV/V    bridge outputs s0..s4
sensor                 (sensor)                str              "s0".."s4"
time                   (time)                  float64  s       time since window start
gear                   (sample)                int64            SWG model 1, 2, 3
fault                  (sample)                str              class name or "unknown"
variant                (sample)                int64            0..59 (-1: reference)
severity               (sample)                float64          0 = healthy
position_deg           (sample)                float64  deg     fault position (NaN: none)
n_in_rpm               (sample)                float64  rpm     desired input speed
t_out_nm               (sample)                float64  N m     desired load torque
disturbed              (sample)                bool             eq. (10) applied
reference              (sample)                bool             commissioning window
efficiency             (sample)                float64          mean P_out / mean P_in
n_in_mean_rpm          (sample)                float64  rpm     acting input speed
t_out_mean_nm          (sample)                float64  N m     acting output torque
=====================  ======================  =======  ======  ==========================

``reference`` marks the commissioning windows: one recording of each gear while known to
be healthy, per operating point and per clean/disturbed, taken before the gear is put into
service. Features are normalised by them (paper eq. 7); they are never training or test
samples. This is how a gear that was never seen in training gets its healthy reference.
"""

from __future__ import annotations

import errno
import hashlib
import json
import logging
import os
import re
import socket
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

log = logging.getLogger(__name__)

SCHEMA_VERSION = 1
SENSORS = ("s0", "s1", "s2", "s3", "s4")
PER_SAMPLE = {
    "gear": ("int64", ""),
    "fault": ("str", ""),
    "variant": ("int64", ""),
    "severity": ("float64", ""),
    "position_deg": ("float64", "deg"),
    "n_in_rpm": ("float64", "rpm"),
    "t_out_nm": ("float64", "N m"),
    "disturbed": ("bool", ""),
    "reference": ("bool", ""),
    "efficiency": ("float64", ""),
    "n_in_mean_rpm": ("float64", "rpm"),
    "t_out_mean_nm": ("float64", "N m"),
}
MANIFEST = "manifest.json"


class DataSetError(ValueError):
    """A data set on disk is missing, incomplete, altered or of another schema."""


def sha256_file(path: str | os.PathLike) -> str:
    """SHA-256 hex digest of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _umask_mode() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def _host() -> str:
    return re.sub(r"[^A-Za-z0-9_-]", "_", socket.gethostname()) or "host"


def temp_prefix(path: Path) -> str:
    """Prefix of this process's temporary files for ``path``: ``.<name>.<host>-<pid>.``,
    so that a later run can tell the leftovers of a dead process (:func:`stale_temp_files`).
    """
    return f".{path.name}.{_host()}-{os.getpid()}."


_TEMP = re.compile(r"^\.(?P<name>.+)\.(?P<host>[A-Za-z0-9_-]+)-(?P<pid>\d+)\..+\.tmp$")


def stale_temp_files(folder: str | os.PathLike) -> list[Path]:
    """Temporary files in ``folder`` left by processes of this host that no longer run.

    A write in progress by a live process (on this host or another one) is never listed.
    """
    out = []
    folder = Path(folder)
    if not folder.is_dir():
        return out
    for p in folder.iterdir():
        m = _TEMP.match(p.name)
        if not m or m["host"] != _host() or int(m["pid"]) == os.getpid():
            continue
        try:
            os.kill(int(m["pid"]), 0)
        except ProcessLookupError:
            out.append(p)
        except PermissionError:  # alive, another user's
            pass
    return sorted(out)


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (temporary file in the same folder, rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=temp_prefix(path), suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, _umask_mode())
        os.replace(tmp, path)
    except BaseException as e:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(e, OSError) and e.errno == errno.ENOSPC:
            raise DataSetError(f"disk full while writing {path} (folder {path.parent})") from e
        raise


def atomic_write_json(path: str | os.PathLike, obj: Any) -> None:
    """Write ``obj`` as indented JSON to ``path`` atomically."""
    atomic_write_bytes(path, (json.dumps(obj, indent=2, sort_keys=True) + "\n").encode())


def make_dataset(
    strain_signal: np.ndarray,
    time_s: np.ndarray,
    meta: dict[str, np.ndarray],
    attrs: dict[str, Any] | None = None,
):
    """Assemble an ``xarray.Dataset`` of schema v1 from arrays.

    Parameters
    ----------
    strain_signal : ndarray, shape (n_sample, 5, n_time)
        Bridge outputs s0..s4 [mV/V].
    time_s : ndarray, shape (n_time,)
        Time since window start [s], uniformly spaced.
    meta : dict of ndarray, each shape (n_sample,)
        Every per-sample variable of the schema (see module docstring).
    attrs : dict, optional
        Extra global attributes (config, seed, ...); non-scalar values are stored as JSON.

    Returns
    -------
    xarray.Dataset

    Raises
    ------
    ValueError
        If a per-sample variable is missing or shapes disagree.
    """
    import xarray as xr

    strain_signal = np.asarray(strain_signal, dtype=np.float32)
    if strain_signal.ndim != 3 or strain_signal.shape[1] != len(SENSORS):
        raise ValueError(
            f"strain_signal must have shape (n_sample, {len(SENSORS)}, n_time), "
            f"got {strain_signal.shape}"
        )
    n = strain_signal.shape[0]
    time_s = np.asarray(time_s, dtype=np.float64)
    if time_s.shape != (strain_signal.shape[2],):
        raise ValueError(f"time_s must have shape ({strain_signal.shape[2]},), got {time_s.shape}")
    missing = set(PER_SAMPLE) - set(meta)
    if missing:
        raise ValueError(f"meta lacks per-sample variables {sorted(missing)}")
    data_vars = {
        "strain_signal": (("sample", "sensor", "time"), strain_signal, {"units": "mV/V"}),
    }
    for name, (dtype, units) in PER_SAMPLE.items():
        v = np.asarray(meta[name])
        if v.shape != (n,):
            raise ValueError(f"meta[{name!r}] must have shape ({n},), got {v.shape}")
        v = v.astype(str) if dtype == "str" else v.astype(dtype)
        data_vars[name] = (("sample",), v, {"units": units} if units else {})
    dt = float(time_s[1] - time_s[0]) if time_s.size > 1 else float("nan")
    all_attrs: dict[str, Any] = {"schema_version": SCHEMA_VERSION, "sample_rate_hz": 1.0 / dt}
    for k, v in (attrs or {}).items():
        all_attrs[k] = v if isinstance(v, (str, int, float, bool)) else json.dumps(v)
    return xr.Dataset(
        data_vars,
        coords={"sensor": list(SENSORS), "time": ("time", time_s, {"units": "s"})},
        attrs=all_attrs,
    )


def write_shard(ds, path: str | os.PathLike) -> str:
    """Write one shard atomically as NetCDF4 (h5netcdf engine); return its SHA-256.

    Parameters
    ----------
    ds : xarray.Dataset
        A schema-v1 data set (see :func:`make_dataset`).
    path : path-like
        Target file; written to a temporary name in the same folder, then renamed.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=temp_prefix(path), suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        ds.to_netcdf(tmp, engine="h5netcdf", invalid_netcdf=False)
        digest = sha256_file(tmp)
        os.chmod(tmp, _umask_mode())
        os.replace(tmp, path)
    except BaseException as e:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(e, OSError) and e.errno == errno.ENOSPC:
            raise DataSetError(f"disk full while writing {path} (folder {path.parent})") from e
        raise
    return digest


def read_manifest(path: str | os.PathLike) -> dict:
    """Read ``manifest.json`` of a data-set directory.

    Raises
    ------
    DataSetError
        If the directory or its manifest is missing or not schema v1.
    """
    path = Path(path)
    mf = path / MANIFEST
    if not mf.is_file():
        raise DataSetError(f"{path} is not a data set: {MANIFEST} is missing")
    try:
        manifest = json.loads(mf.read_text())
    except json.JSONDecodeError as e:
        raise DataSetError(f"{mf} is not valid JSON: {e}") from e
    if manifest.get("schema_version") != SCHEMA_VERSION:
        raise DataSetError(
            f"{mf}: schema_version {manifest.get('schema_version')!r}, expected {SCHEMA_VERSION}"
        )
    return manifest


def verify(path: str | os.PathLike, shards: Iterable[str] | None = None) -> list[Path]:
    """Check a data set's files against its manifest.

    Every shard the manifest lists must exist with its SHA-256; no shard file may exist
    that the manifest does not list; the manifest's shard count and sample total must
    agree with its entries.

    Returns
    -------
    list of Path
        The shard files, in manifest order.

    Raises
    ------
    DataSetError
        Naming what is missing, extra, truncated or altered, or if the manifest says the
        data set is incomplete or contradicts itself.
    """
    path = Path(path)
    manifest = read_manifest(path)
    if not manifest.get("complete", False):
        raise DataSetError(f"{path}: the data set is incomplete (generation did not finish)")
    entries = manifest["shards"]
    if "n_shards" in manifest and manifest["n_shards"] != len(entries):
        raise DataSetError(f"{path / MANIFEST}: lists {len(entries)} shards but records "
                           f"n_shards={manifest['n_shards']}: an entry was removed or added")
    total = sum(int(e.get("n_samples", 0)) for e in entries.values())
    if "n_samples" in manifest and manifest["n_samples"] != total:
        raise DataSetError(f"{path / MANIFEST}: its shards hold {total} samples but it "
                           f"records n_samples={manifest['n_samples']}")
    extra = sorted(p.name for p in path.glob("*.nc") if p.name not in entries)
    if extra:
        raise DataSetError(f"{path}: shard file(s) {extra} are not in {MANIFEST} (a removed "
                           "entry, or files of another data set)")
    names = list(entries) if shards is None else list(shards)
    files = []
    for name in names:
        f = path / name
        if not f.is_file():
            raise DataSetError(f"shard {f} is missing")
        if sha256_file(f) != entries[name]["sha256"]:
            raise DataSetError(
                f"shard {f} is truncated or altered: its SHA-256 differs from {MANIFEST}"
            )
        files.append(f)
    return files


def load(path: str | os.PathLike, check: bool = True):
    """Load a schema-v1 data set directory as one ``xarray.Dataset``.

    Parameters
    ----------
    path : path-like
        Data-set directory holding ``manifest.json`` and the shards.
    check : bool, default True
        Verify every shard's SHA-256 against the manifest first.

    Returns
    -------
    xarray.Dataset
        All shards joined along ``sample`` (in manifest order), loaded into memory.

    Raises
    ------
    DataSetError
        If the directory is not a complete schema-v1 data set or a shard is altered.
    """
    import xarray as xr

    path = Path(path)
    files = verify(path) if check else [path / n for n in read_manifest(path)["shards"]]
    entries = read_manifest(path)["shards"]
    parts = []
    for f in files:
        try:
            with xr.open_dataset(f, engine="h5netcdf") as ds:
                parts.append(ds.load())
        except OSError as e:
            raise DataSetError(f"shard {f} cannot be read: {e}") from e
        want = entries.get(f.name, {}).get("n_samples")
        if want is not None and parts[-1].sizes.get("sample") != want:
            raise DataSetError(f"shard {f} holds {parts[-1].sizes.get('sample')} samples, "
                               f"{MANIFEST} says {want}")
    if not parts:
        raise DataSetError(f"{path}: the data set has no shards")
    out = xr.concat(parts, dim="sample", data_vars="minimal", coords="minimal",
                    compat="override", combine_attrs="override")
    out.attrs["source_path"] = str(path)
    return out
