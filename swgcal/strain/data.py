"""Measured strain windows for the calibration (data kind 2) and their held-out split.

:func:`strain_windows` reads the windows and their operating points from a schema-v1 data
set (``swgsim.datasets.schema``); :func:`heldout_split` assigns whole windows (or whole operating
points) to the fit, validation and test roles (:mod:`.problem`, module docstring).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from swgsim.datasets import schema as dsio

__all__ = ["StrainWindows", "strain_windows", "heldout_split", "check_bridge_scale",
           "MAX_BRIDGE_MVV"]

#: Largest |bridge output| a strain-gauge bridge on a flexspline gives [mV/V]: a full bridge
#: of gauge factor 2 at 5000 µε (about the yield strain of flexspline steel) gives
#: GF · ε = 10 mV/V [derived]; twice that as margin.
MAX_BRIDGE_MVV = 20.0
#: Below this peak |output| of every bridge a recording is taken as given in V/V, not
#: mV/V (a bench bridge's 24-bit noise alone is larger) [mV/V] [choice].
MIN_BRIDGE_MVV = 1e-4


@dataclass(frozen=True)
class StrainWindows:
    """Measured strain windows and their operating points.

    Attributes
    ----------
    y : ndarray, shape (n_windows, 5, n_t)
        Bridge outputs s0..s4 [mV/V].
    time_s : ndarray, shape (n_t,)
        Time since the window start [s], uniform.
    n_in_rpm, t_out_nm : ndarray, shape (n_windows,)
        Operating point simulated for each window (desired values, or the acting means
        where the desired ones are missing) [rpm, N m].
    n_in_mean_rpm, t_out_mean_nm : ndarray, shape (n_windows,)
        Acting mean input speed and output torque [rpm, N m].
    sample : ndarray of int, shape (n_windows,)
        Index of each window in the data set (its place in the recording sequence).
    op : ndarray of int, shape (n_windows,)
        Operating-point index into ``ops``.
    ops : tuple of (float, float)
        Distinct operating points (n_in [rpm], T_out [N m]), sorted.
    """

    y: np.ndarray
    time_s: np.ndarray
    n_in_rpm: np.ndarray
    t_out_nm: np.ndarray
    n_in_mean_rpm: np.ndarray
    t_out_mean_nm: np.ndarray
    sample: np.ndarray
    op: np.ndarray
    ops: tuple[tuple[float, float], ...]
    name: str = "strain"
    source: str | None = None

    @property
    def fs(self) -> float:
        """Sample rate [Hz]."""
        return 1.0 / float(self.time_s[1] - self.time_s[0])

    @property
    def n_windows(self) -> int:
        return int(self.y.shape[0])

    @property
    def n_t(self) -> int:
        return int(self.y.shape[2])


def strain_windows(ds: Any, select: Mapping[str, Any] | None = None,
                   max_windows: int | None = None, name: str | None = None) -> StrainWindows:
    """Measured windows from a schema-v1 data set.

    Parameters
    ----------
    ds : xarray.Dataset or path-like
        A loaded data set or its directory (``manifest.json``).
    select : mapping, optional
        Per-sample variable -> value or list of values to keep, e.g.
        ``{"disturbed": False, "gear": 1}``.
    max_windows : int, optional
        Keep at most this many windows per operating point (the first in sequence).
    name : str, optional
        Name for the report; default the data set's ``name`` attribute, else its folder.

    Raises
    ------
    ValueError
        A ``select`` key that is not a per-sample variable, no window left, non-finite
        signals, bridge outputs beyond a strain-gauge bridge's range (the unit's factor
        named, :func:`check_bridge_scale`), or an operating point with non-positive speed.
    """
    if not hasattr(ds, "data_vars"):
        source = str(ds)
        ds = dsio.load(ds)
    else:
        source = ds.attrs.get("source_path")
    keep = np.ones(ds.sizes["sample"], bool)
    for k, v in (select or {}).items():
        if k not in dsio.PER_SAMPLE:
            raise ValueError(f"select: {k!r} is not a per-sample variable; allowed: "
                             f"{sorted(dsio.PER_SAMPLE)}")
        vals = v if isinstance(v, (list, tuple)) else [v]
        keep &= np.isin(ds[k].values, vals)
    idx = np.flatnonzero(keep)
    if idx.size == 0:
        raise ValueError(f"no window left after select={dict(select or {})}")
    y = np.asarray(ds["strain_signal"].values[idx], float)
    if not np.all(np.isfinite(y)):
        raise ValueError("strain_signal has non-finite values in the selected windows")
    check_bridge_scale(y, [str(v) for v in ds["sensor"].values] if "sensor" in ds.coords
                       else [f"s{i}" for i in range(y.shape[1])])
    n_des = np.asarray(ds["n_in_rpm"].values[idx], float)
    t_des = np.asarray(ds["t_out_nm"].values[idx], float)
    n_mean = np.asarray(ds["n_in_mean_rpm"].values[idx], float)
    t_mean = np.asarray(ds["t_out_mean_nm"].values[idx], float)
    n_op = np.where(np.isfinite(n_des), n_des, np.round(n_mean, 0))
    t_op = np.where(np.isfinite(t_des), t_des, np.round(t_mean, 1))
    if np.any(~np.isfinite(n_op)) or np.any(n_op <= 0):
        raise ValueError("every window needs a positive input speed (n_in_rpm or "
                         "n_in_mean_rpm)")
    if np.any(~np.isfinite(t_op)) or np.any(t_op < 0):
        raise ValueError("every window needs a load torque >= 0 (t_out_nm or t_out_mean_nm)")
    n_mean = np.where(np.isfinite(n_mean), n_mean, n_op)
    t_mean = np.where(np.isfinite(t_mean), t_mean, t_op)
    keys = [(float(a), float(b)) for a, b in zip(n_op, t_op, strict=True)]
    ops = tuple(sorted(set(keys)))
    op = np.array([ops.index(k) for k in keys])
    sel = np.arange(idx.size)
    if max_windows is not None:
        if int(max_windows) < 1:
            raise ValueError(f"max_windows must be >= 1, got {max_windows}")
        sel = np.sort(np.concatenate([np.flatnonzero(op == i)[:int(max_windows)]
                                      for i in range(len(ops))]))
    t = np.asarray(ds["time"].values, float)
    nm = name or str(ds.attrs.get("name") or (Path(source).name if source else "strain"))
    return StrainWindows(y=y[sel], time_s=t, n_in_rpm=n_op[sel], t_out_nm=t_op[sel],
                         n_in_mean_rpm=n_mean[sel], t_out_mean_nm=t_mean[sel],
                         sample=idx[sel], op=op[sel], ops=ops, name=nm, source=source)


def check_bridge_scale(y: np.ndarray, names: Sequence[str]) -> None:
    """Refuse bridge outputs no strain-gauge bridge gives, naming the factor when the unit
    is off by one (µV/V or V/V for mV/V).

    Parameters
    ----------
    y : ndarray, shape (n_windows, n_bridges, n_t)
        Bridge outputs as recorded [mV/V].
    names : sequence of str
        The bridges' names (``s0``..``s4``).

    Raises
    ------
    ValueError
        ``strain_signal: bridge s2 peaks at 1850 mV/V, beyond any strain-gauge bridge
        (allowed |s| <= 20 mV/V); 1000 times too large: it looks like µV/V ...``.
    """
    peak = np.abs(y).max(axis=(0, 2)) if y.size else np.zeros(0)
    big = np.flatnonzero(peak > MAX_BRIDGE_MVV)
    if big.size:
        i = int(big[np.argmax(peak[big])])
        unit = ("1000 times too large: it looks like µV/V; divide strain_signal by 1000"
                if peak[i] / 1000 <= MAX_BRIDGE_MVV else "check that it is in mV/V")
        raise ValueError(f"strain_signal: bridge {names[i]} peaks at {peak[i]:.4g} mV/V, "
                         f"beyond any strain-gauge bridge (allowed |s| <= {MAX_BRIDGE_MVV:g} "
                         f"mV/V); {unit}")
    if peak.size and np.all(peak < MIN_BRIDGE_MVV) and np.any(peak > 0):
        raise ValueError(f"strain_signal: every bridge peaks below {MIN_BRIDGE_MVV:g} mV/V "
                         f"(largest {peak.max():.3g} mV/V), below a bridge's own noise; "
                         "1000 times too small: it looks like V/V; multiply strain_signal by "
                         "1000")


def heldout_split(win: StrainWindows, heldout: str, validation: Sequence[int] | None,
                   test: Sequence[int] | None) -> tuple[np.ndarray, str]:
    """Roles of whole windows (0 fit, 1 validation, 2 test) and the description text."""
    n_w = win.n_windows
    role = np.zeros(n_w, int)
    if heldout == "windows":
        if validation is not None or test is not None:
            if validation is None or test is None:
                raise ValueError("give both validation and test (data-set sample indices) or "
                                 "neither")
            for what, lst, r in (("validation", validation, 1), ("test", test, 2)):
                bad = [s for s in lst if s not in set(win.sample.tolist())]
                if bad:
                    raise ValueError(f"{what} samples {bad} are not among the selected windows")
                role[np.isin(win.sample, list(lst))] = r
            how = "given lists"
        else:
            for i in range(len(win.ops)):
                w = np.flatnonzero(win.op == i)
                w = w[np.argsort(win.sample[w])]
                if w.size < 3:
                    raise ValueError(
                        f"heldout='windows' needs >= 3 windows per operating point (fit, "
                        f"validation, test); operating point {win.ops[i]} has {w.size}")
                role[w[-1]] = 2
                role[w[(w.size - 1) // 2]] = 1
            how = ("per operating point, the last window of the sequence is a test window "
                   "(drift must extrapolate) and the middle one a validation window")
        text = (f"Whole windows held out by metadata ({how}): validation samples "
                f"{win.sample[role == 1].tolist()}, test samples {win.sample[role == 2].tolist()}, "
                f"fit samples {win.sample[role == 0].tolist()}. Every window's WG angle is "
                "aligned on that window's own data with the nominal chain only (no effect "
                "parameter), so held-out windows are treated exactly like fit windows.")
    elif heldout == "operating_points":
        n_op = len(win.ops)
        if n_op < 3:
            raise ValueError(f"heldout='operating_points' needs >= 3 operating points, "
                             f"got {n_op}; use heldout='windows'")
        v = list(validation) if validation is not None else [n_op // 2]
        te = list(test) if test is not None else [n_op - 1]
        for what, lst in (("validation", v), ("test", te)):
            bad = [i for i in lst if not 0 <= int(i) < n_op]
            if bad:
                raise ValueError(f"{what} operating-point indices {bad} outside [0, {n_op})")
        if set(v) & set(te):
            raise ValueError(f"operating points {sorted(set(v) & set(te))} are both "
                             "validation and test")
        role[np.isin(win.op, v)] = 1
        role[np.isin(win.op, te)] = 2
        text = ("Whole operating points held out: validation "
                f"{[win.ops[i] for i in v]}, test {[win.ops[i] for i in te]} "
                "((n_in [rpm], T_out [N m])); the model must extrapolate to them.")
    else:
        raise ValueError(f"heldout must be 'windows' or 'operating_points', got {heldout!r}")
    if not (role == 0).any():
        raise ValueError("no fit windows left after holding out validation and test windows")
    return role, text
