"""Data set on disk, schema v1.

A data set is a directory of NetCDF4/HDF5 shards (xarray + h5netcdf), whole windows along
``sample``, plus a ``manifest.json`` holding every shard's SHA-256. :func:`write_shard`
writes a shard atomically and refuses non-finite signals; :func:`load` joins the shards,
checking each against the manifest and, with ``check=True``, its content against the
schema (:func:`check_shard`), each failure in one line naming the file and the variable.
Variables, reference windows, attributes, manifest and checks: docs/DATASET.md,
"Variables" and "Integrity checks".
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from swgsim.files.digest import config_digest, sha256_file
from swgsim.files.inputs import available_memory, check_input_file
from swgsim.files.ownership import atomic_write_bytes
from swgsim.gear.faults import FAULTS
from swgsim.gear.sensors import SENSORS
from swgsim.sensing.sensor_faults import SENSOR_FAULTS

SCHEMA_VERSION = 1
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
#: The joint temperatures a stream's ``temperature_c`` may hold [degC]: a robot joint's
#: grease and gauges stay well inside (industrial joints run at about 20-65 degC); a value
#: outside is a fault of the sensor, kelvin or degF. The importer and the monitor refuse
#: a window outside.
TEMPERATURE_RANGE_C = (-40.0, 150.0)
#: Largest manifest read [bytes]: 64 MiB (a paper data set's is tens of kB) [choice].
MAX_MANIFEST_BYTES = 64 * 2**20
#: The signal variables: every value finite and within ±:data:`MAX_BRIDGE_MVV` (refused on
#: write and on load).
SIGNALS = ("strain_signal",)
#: Largest bridge output accepted [mV/V]: a full-bridge of gauges of factor 2 at 5000
#: µm/m gives 10 mV/V, beyond a flexspline's elastic strain (the paper's bridges stay
#: under 1 mV/V); a larger value is raw counts or another unit.
MAX_BRIDGE_MVV = 10.0
#: Memory a data set's load holds per byte of its shards [-]: the shards read, then
#: joined (xarray's concatenation copies them once) [derived].
LOAD_BYTES_PER_FILE_BYTE = 2
#: Fault labels of the schema besides the registered classes: measured data's unknown state.
EXTRA_LABELS = ("unknown",)
_DIMS = {"strain_signal": ("sample", "sensor", "time"), **{k: ("sample",) for k in PER_SAMPLE}}
_KINDS = {"float32": "f", "float64": "fiu", "int64": "iu", "bool": "biu", "str": "UOS"}
_CHUNK = 1 << 22  # values per finiteness test (bounded memory)


class DataSetError(ValueError):
    """A data set on disk is missing, incomplete, altered or of another schema."""


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
        Every per-sample variable of the schema (docs/DATASET.md, "Variables").
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
        Target file; written to a temporary name in the same folder, then renamed (in a
        folder this process claimed, listed in its ownership stamp first,
        :mod:`swgsim.files.ownership`).

    Returns
    -------
    str
        SHA-256 hex digest of the file written.

    Raises
    ------
    DataSetError
        Before anything is written, if a signal variable holds NaN or infinity
        (:func:`check_signals`).
    swgsim.files.atomic.DiskFullError
        If the disk is full; nothing is left behind.
    """
    path = Path(path)
    check_signals(ds, f"shard {path}", "refused before writing")
    # encoded in memory, then written as plain bytes: a full disk fails in that write,
    # never inside the HDF5 library, which kept the half-written file open after the
    # error (touched again by the next HDF5 call or at exit: a segmentation fault)
    data = ds.to_netcdf(engine="h5netcdf", invalid_netcdf=False)
    digest = hashlib.sha256(data).hexdigest()
    atomic_write_bytes(path, data, digest)
    return digest


def read_manifest(path: str | os.PathLike) -> dict:
    """Read ``manifest.json`` of a data-set directory.

    Raises
    ------
    DataSetError
        If the directory or its manifest is missing or not schema v1, or the manifest
        lacks its shard list or a shard's SHA-256 (naming the file and the entry).
    """
    path = Path(path)
    mf = path / MANIFEST
    if not mf.is_file():
        if mf.exists():  # a FIFO, a device: never read
            raise DataSetError(f"{mf} is not a regular file; nothing was read")
        raise DataSetError(f"{path} is not a data set: {MANIFEST} is missing")
    try:
        check_input_file(mf, "manifest", MAX_MANIFEST_BYTES)
    except ValueError as e:
        raise DataSetError(str(e)) from None
    try:
        manifest = json.loads(mf.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise DataSetError(f"{mf} is not valid JSON: {e}") from e
    if not isinstance(manifest, dict):
        raise DataSetError(f"{mf}: not a JSON object (schema v1, docs/DATASET.md)")
    if manifest.get("schema_version") != SCHEMA_VERSION:
        raise DataSetError(
            f"{mf}: schema_version {manifest.get('schema_version')!r}, expected {SCHEMA_VERSION}"
        )
    shards = manifest.get("shards")
    if not isinstance(shards, dict):
        raise DataSetError(f"{mf}: shards is {'missing' if shards is None else 'not a mapping'}"
                           " (schema v1: shard file name -> its sha256 and n_samples)")
    for name, entry in shards.items():
        if not (name == Path(name).name and name not in ("", ".", "..")
                and "\\" not in name and name.endswith(".nc")):
            raise DataSetError(f"{mf}: shard {name!r} is not a file name in its folder "
                               "(a path, '..' or not *.nc); a manifest names only the shards "
                               "beside it")
        sha = entry.get("sha256") if isinstance(entry, dict) else None
        if not (isinstance(sha, str) and len(sha) == 64):
            raise DataSetError(f"{mf}: shards.{name}.sha256 is "
                               f"{'missing' if sha is None else repr(sha)}: the shard cannot "
                               "be verified (a hand-made or truncated manifest; regenerate it)")
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
            if f.exists():  # a FIFO, a device, a folder: never read
                raise DataSetError(f"shard {f} is not a regular file")
            raise DataSetError(f"shard {f} is missing")
        if sha256_file(f) != entries[name]["sha256"]:
            raise DataSetError(
                f"shard {f} is truncated or altered: its SHA-256 differs from {MANIFEST}"
            )
        files.append(f)
    return files


# ------------------------------------------------------------------ content checks
def _n_nonfinite(values: np.ndarray) -> int:
    """Number of NaN or infinite values of an array, tested in chunks (bounded memory)."""
    flat = np.asarray(values).reshape(-1)
    if flat.dtype.kind not in "fc":
        return 0
    return sum(int(chunk.size - np.count_nonzero(np.isfinite(chunk)))
               for chunk in (flat[i:i + _CHUNK] for i in range(0, flat.size, _CHUNK)))


def check_signals(ds, where: str, what: str = "") -> None:
    """Refuse NaN or infinity in the signal variables (:data:`SIGNALS`) and in ``time``,
    and a signal beyond ±:data:`MAX_BRIDGE_MVV`.

    Parameters
    ----------
    ds : xarray.Dataset
        A shard, in memory.
    where : str
        What ``ds`` is, for the message, e.g. ``"shard data/x/gear1_n2000rpm.nc"``.
    what : str, optional
        Appended to the message, e.g. ``"refused before writing"``.

    Raises
    ------
    DataSetError
        Naming ``where``, the variable and how many of its values are not finite, or the
        first sample beyond the bridges' range.
    """
    for name in (*SIGNALS, "time"):
        if name in ds.variables:
            values = ds[name].values
            bad = _n_nonfinite(values)
            if bad:
                raise DataSetError(f"{where}: {name} holds {bad} non-finite value(s) (NaN or "
                                   f"infinity) of {values.size}{'; ' + what if what else ''}")
    for name in SIGNALS:
        if name in ds.variables:
            values = ds[name].values  # (sample, sensor, time)
            peak = np.abs(values).reshape(values.shape[0], -1).max(axis=1) if values.size \
                else np.zeros(0)
            far = np.flatnonzero(peak > MAX_BRIDGE_MVV)
            if far.size:
                i = int(far[0])
                raise DataSetError(
                    f"{where}: {name} of sample {i} reaches {peak[i]:.4g} mV/V, beyond any "
                    f"strain-gauge bridge (allowed |s| <= {MAX_BRIDGE_MVV:g} mV/V: raw counts "
                    f"or another unit?){'; ' + what if what else ''}")


def fault_labels(manifest: dict) -> frozenset[str]:
    """The fault labels a data set may hold: the schema's classes.

    The registered gear faults (:data:`swgsim.gear.faults.FAULTS`, ``healthy`` first), the
    sensor faults (:data:`swgsim.sensing.sensor_faults.SENSOR_FAULTS`), :data:`EXTRA_LABELS`
    (``unknown``, measured data), and the classes the manifest's config names
    (``variants``, ``life.fault.fault``): a class registered by the user who generated the
    data set need not be registered where it is read.
    """
    labels = {"healthy", *FAULTS, *SENSOR_FAULTS, *EXTRA_LABELS}
    cfg = manifest.get("config")
    if isinstance(cfg, dict):
        if isinstance(cfg.get("variants"), dict):
            labels.update(str(k) for k in cfg["variants"])
        life = cfg.get("life")
        if isinstance(life, dict) and isinstance(life.get("fault"), dict):
            labels.add(str(life["fault"].get("fault")))
    return frozenset(labels)


def check_manifest(path: Path, manifest: dict) -> None:
    """Refuse a manifest whose ``config_hash`` contradicts its own ``config`` (an edit).

    Raises
    ------
    DataSetError
        Naming the manifest file and both hashes.
    """
    cfg, rec = manifest.get("config"), manifest.get("config_hash")
    if isinstance(cfg, dict) and rec is not None and config_digest(cfg) != rec:
        raise DataSetError(f"{path / MANIFEST}: config_hash {rec} contradicts its config "
                           f"(hash {config_digest(cfg)}): the config was edited")


def _check_variables(ds, where: str) -> None:
    """Every variable of the schema present with its dims and dtype, sensors s0..s4."""
    for name, dims in _DIMS.items():
        if name not in ds.variables:
            raise DataSetError(f"{where}: variable {name} is missing (schema v1 requires "
                               f"{', '.join(_DIMS)})")
        var = ds[name]
        if var.dims != dims:
            raise DataSetError(f"{where}: variable {name} has dims {var.dims}, schema v1 "
                               f"says {dims}")
        dtype = "float32" if name == "strain_signal" else PER_SAMPLE[name][0]
        if var.dtype.kind not in _KINDS[dtype]:
            raise DataSetError(f"{where}: variable {name} has dtype {var.dtype}, schema v1 "
                               f"says {dtype}")
    if "sensor" not in ds.coords or list(ds["sensor"].values) != list(SENSORS):
        got = list(ds["sensor"].values) if "sensor" in ds.coords else None
        raise DataSetError(f"{where}: coordinate sensor must be {list(SENSORS)}, got {got}")
    if "time" not in ds.coords:
        raise DataSetError(f"{where}: coordinate time is missing")


def _check_labels(ds, where: str, labels: frozenset[str]) -> None:
    """Every fault label a class of the schema (:func:`fault_labels`)."""
    found, count = np.unique(ds["fault"].values.astype(str), return_counts=True)
    bad = [(str(v), int(c)) for v, c in zip(found, count, strict=True) if v not in labels]
    if bad:
        allowed = ", ".join(sorted(labels))
        raise DataSetError(f"{where}: variable fault holds label {bad[0][0]!r} ({bad[0][1]} "
                           f"sample(s)), not a class of the schema; allowed: {allowed}")


def _check_against_manifest(ds, where: str, name: str, entry: dict, manifest: dict) -> None:
    """The shard's attributes and time axis agree with its manifest entry and config."""
    attrs, mf = ds.attrs, MANIFEST
    if attrs.get("schema_version", SCHEMA_VERSION) != SCHEMA_VERSION:
        raise DataSetError(f"{where}: attribute schema_version={attrs['schema_version']}, "
                           f"{mf} says {SCHEMA_VERSION}")
    for key, rec in (("shard", name), ("content_sha256", entry.get("content_sha256")),
                     ("seed", manifest.get("seed"))):
        if rec is not None and key in attrs and attrs[key] != rec:
            raise DataSetError(f"{where}: attribute {key}={attrs[key]!r} contradicts {mf} "
                               f"({rec!r})")
    t = ds["time"].values
    fs = attrs.get("sample_rate_hz")
    if fs is not None and not (isinstance(fs, (int, float, np.integer, np.floating))
                               and not isinstance(fs, bool) and np.isfinite(fs) and fs > 0):
        shown = repr(fs) if isinstance(fs, (str, bytes)) else fs
        raise DataSetError(f"{where}: attribute sample_rate_hz={shown} is not a sample rate "
                           "(a positive number of Hz)")
    if fs is not None and t.size > 1 and not np.isclose(1.0 / (t[1] - t[0]), fs, rtol=1e-6):
        raise DataSetError(f"{where}: variable time is sampled at {1.0 / (t[1] - t[0]):g} Hz, "
                           f"its attribute sample_rate_hz says {fs:g} Hz")
    cfg = manifest.get("config")
    if not isinstance(cfg, dict):
        return
    chain = cfg.get("chain")
    if (isinstance(chain, dict) and fs is not None
            and isinstance(chain.get("sample_rate_hz"), (int, float))):
        if not np.isclose(chain["sample_rate_hz"], fs, rtol=1e-9):
            raise DataSetError(f"{where}: attribute sample_rate_hz={fs:g} Hz contradicts "
                               f"{mf} (config.chain.sample_rate_hz={chain['sample_rate_hz']:g})")
        win = chain.get("window_s")
        if isinstance(win, (int, float)) and round(win * fs) != ds.sizes["time"]:
            raise DataSetError(f"{where}: variable time holds {ds.sizes['time']} samples, "
                               f"{mf} says {round(win * fs)} (config.chain.window_s="
                               f"{win:g} s at {fs:g} Hz)")
    if isinstance(attrs.get("config"), str) and "config_hash" in manifest:
        try:
            same = json.loads(attrs["config"]) == cfg
        except json.JSONDecodeError:
            same = False
        if not same:
            raise DataSetError(f"{where}: attribute config contradicts {mf}'s config "
                               "(a shard of another data set)")


def check_shard(ds, path: Path, entry: dict, manifest: dict, labels: frozenset[str]) -> None:
    """Check a loaded shard against the schema and its manifest.

    Parameters
    ----------
    ds : xarray.Dataset
        The shard, in memory.
    path : Path
        Its file, named in the messages.
    entry : dict
        Its entry in the manifest's ``shards``.
    manifest : dict
        The data set's manifest.
    labels : frozenset of str
        Allowed fault labels (:func:`fault_labels`).

    Raises
    ------
    DataSetError
        One line naming the file and the variable or attribute: a variable of the schema
        missing or of the wrong dims or dtype, the sensors not s0..s4, a non-finite signal
        or time, a fault label not of the schema, or an attribute, sample count, sample
        rate or window length that contradicts the manifest.
    """
    where = f"shard {path}"
    _check_variables(ds, where)
    want = entry.get("n_samples")
    if want is not None and ds.sizes["sample"] != want:
        raise DataSetError(f"{where} holds {ds.sizes['sample']} samples, {MANIFEST} says {want}")
    check_signals(ds, where)
    _check_labels(ds, where, labels)
    _check_against_manifest(ds, where, path.name, entry, manifest)


def _check_same_time(ds, path: Path, first, first_path: Path) -> None:
    """The shard's time axis and ``sample_rate_hz`` those of the data set's first shard
    (joined along ``sample``, shards of another rate would be padded with NaN)."""
    if ds is first:
        return
    t, t0 = ds["time"].values, first["time"].values
    fs, fs0 = ds.attrs.get("sample_rate_hz"), first.attrs.get("sample_rate_hz")
    if fs != fs0 or t.shape != t0.shape or not np.allclose(t, t0, rtol=1e-9, atol=0.0):
        raise DataSetError(f"shard {path}: attribute sample_rate_hz={fs} Hz and its time axis "
                           f"({t.size} samples) disagree with shard {first_path} "
                           f"(sample_rate_hz={fs0} Hz, {t0.size} samples): the shards of a "
                           "data set share one time axis")


def _check_load_memory(path: Path, files: list[Path]) -> None:
    """Refuse a data set whose load cannot fit in the memory available, before a shard is
    read (:data:`LOAD_BYTES_PER_FILE_BYTE`; no check where the memory is not known)."""
    avail = available_memory()
    size = sum(f.stat().st_size for f in files if f.is_file())
    need = LOAD_BYTES_PER_FILE_BYTE * size
    if avail is not None and need > avail:
        gib = float(1 << 30)
        raise DataSetError(f"{path}: loading its {len(files)} shard(s) ({size / gib:.3g} GiB) "
                           f"needs about {need / gib:.3g} GiB of memory, {avail / gib:.3g} GiB "
                           "available; nothing was read")


def load(path: str | os.PathLike, check: bool = True):
    """Load a schema-v1 data set directory as one ``xarray.Dataset``.

    Parameters
    ----------
    path : path-like
        Data-set directory holding ``manifest.json`` and the shards.
    check : bool, default True
        Verify the manifest and every shard's SHA-256 first (:func:`verify`,
        :func:`check_manifest`), then each shard's content as it is read
        (:func:`check_shard`: variables, finite signals, fault labels, agreement with the
        manifest). False: only the sample counts.

    Returns
    -------
    xarray.Dataset
        All shards joined along ``sample`` (in manifest order), loaded into memory.

    Raises
    ------
    DataSetError
        One line naming the file: the directory is not a complete schema-v1 data set, a
        shard is altered, its load would not fit in the memory available, or its content
        fails :func:`check_shard`.
    """
    import xarray as xr

    path = Path(path)
    files = verify(path) if check else [path / n for n in read_manifest(path)["shards"]]
    _check_load_memory(path, files)
    manifest = read_manifest(path)
    entries = manifest["shards"]
    if check:
        check_manifest(path, manifest)
        labels = fault_labels(manifest)
    parts = []
    for f in files:
        try:
            with xr.open_dataset(f, engine="h5netcdf") as ds:
                parts.append(ds.load())
        except OSError as e:
            raise DataSetError(f"shard {f} cannot be read: {e}") from e
        if check:
            check_shard(parts[-1], f, entries.get(f.name, {}), manifest, labels)
            _check_same_time(parts[-1], f, parts[0], files[0])
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
