"""Hand-crafted features of the paper, Table III and eq. (7)-(9).

Every feature of a window is normalised by the same quantity of its *reference window*,
the commissioning recording of the same gear, operating point and ``disturbed`` flag
(schema v1, :mod:`swgsim.datasets.schema`): reference windows only ever serve as
denominators. :func:`extract_features` (and :func:`iter_features`, in chunks) gives
Selections 1-3 of Table III; :func:`order_spectrum` the DFT at orders of the input rotation.
Design (the selections' table, the DFT, the DFT_rel floor, our choice):
docs/paper_study.md, "The paper's features".
"""

from __future__ import annotations

import logging
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from swgsim.base.lazy import lazy_module

pd = lazy_module("pandas")

log = logging.getLogger(__name__)

#: The paper's feature selections (Table III), the one registry of them: number -> config
#: name (``features=<name>`` of the apps, the ``selection`` column of results).
SELECTIONS: dict[int, str] = {k: f"selection{k}" for k in (1, 2, 3)}
META_COLUMNS = ("gear", "fault", "variant", "n_in_rpm", "t_out_nm", "disturbed")
REFERENCE_KEYS = ("gear", "n_in_rpm", "t_out_nm", "disturbed")
N_SENSORS = 5


@dataclass
class FeatureSettings:
    """Settings of the paper's features (Table III), the one place of their defaults.

    Attributes
    ----------
    name : str
        Config name, ``selection1`` .. ``selection3``.
    selection : int
        Paper Table III selection, 1, 2 or 3.
    max_order : float
        Highest DFT order of the input rotation [-] (paper Fig. 7 shows orders up to 8).
    order_step : float
        Spacing and lowest DFT order [-].
    floor_rel : float
        DFT_rel floor, fraction of the reference spectrum's maximum [-].
    """

    name: str = "selection1"
    selection: int = 1
    max_order: float = 8.0
    order_step: float = 0.25
    floor_rel: float = 1e-3

    def kwargs(self) -> dict:
        """``orders`` and ``floor_rel`` for :func:`extract_features`."""
        return {"orders": paper_orders(self.max_order, self.order_step),
                "floor_rel": self.floor_rel}


class Features(NamedTuple):
    """Feature matrix of the non-reference windows of a data set.

    Attributes
    ----------
    X : ndarray, shape (n_samples, n_features)
        Features (dimensionless ratios), float64.
    names : list of str, length n_features
        Feature names, e.g. ``m_rel_s0``, ``dft_rel_ds13_o1.00``, ``eta2_rel``.
    meta : pandas.DataFrame, n_samples rows
        Per-sample metadata: ``sample`` (index into the data set) and
        :data:`META_COLUMNS`, with a fresh 0..n-1 index aligned with the rows of ``X``.
    """

    X: np.ndarray
    names: list[str]
    meta: pd.DataFrame


def paper_orders(max_order: float = FeatureSettings.max_order,
                 order_step: float = FeatureSettings.order_step) -> np.ndarray:
    """Orders of the input rotation used for the DFT features.

    Parameters
    ----------
    max_order : float, default 8.0
        Highest order (inclusive) [-].
    order_step : float, default 0.25
        Spacing and lowest order [-].

    Returns
    -------
    ndarray, shape (n_orders,)
        ``order_step, 2 * order_step, ..., max_order``; 32 values by default (paper Fig. 7
        shows orders up to 8).

    Raises
    ------
    ValueError
        If ``order_step`` or ``max_order`` is not positive.
    """
    if not (order_step > 0 and max_order >= order_step):
        raise ValueError(
            f"order_step must be > 0 and max_order >= order_step, got order_step={order_step}, "
            f"max_order={max_order}"
        )
    n = int(np.floor(max_order / order_step + 1e-9))
    return order_step * np.arange(1, n + 1, dtype=np.float64)


def order_spectrum(
    x: np.ndarray,
    time_s: np.ndarray,
    f_in_hz: np.ndarray,
    orders: np.ndarray,
    chunk_elements: int = 1 << 22,
) -> np.ndarray:
    """Amplitude spectrum of zero-mean, Hann-windowed signals at orders of the input speed.

    ``A_k = 2 / sum(w) * | sum_t w(t) (x(t) - mean(x)) exp(-i 2 pi k f_in t) |``, with the
    periodic Hann window ``w``. A sinusoid of amplitude ``a`` at order ``k`` gives
    ``A_k ~= a`` (exactly for an integer number of its periods in the window).

    The sum is evaluated in blocks of L ≈ sqrt(n_time) samples, t = t_a + τ_b:
    ``exp(-i ω (t_a + τ_b)) = exp(-i ω t_a) exp(-i ω τ_b)``, so each window needs the
    trigonometric functions at about 2 sqrt(n_time) points per order instead of n_time,
    and the rest is one batched matrix product; the same sums as
    the term-by-term sums to round-off (tested against them,
    ``tests/learn/test_learn_features.py``).

    Parameters
    ----------
    x : ndarray, shape (n_samples, n_signals, n_time)
        Signals [mV/V].
    time_s : ndarray, shape (n_time,)
        Time since window start [s], uniformly spaced.
    f_in_hz : ndarray, shape (n_samples,)
        Input rotation frequency of each window [Hz] (``n_in_mean_rpm / 60``).
    orders : ndarray, shape (n_orders,)
        Orders of the input rotation [-].
    chunk_elements : int, default 2**22
        Bounds the size of per-chunk temporaries (samples x signals x time); windows are
        processed in chunks.

    Returns
    -------
    ndarray, shape (n_samples, n_signals, n_orders)
        Amplitudes [mV/V], float64.

    Raises
    ------
    ValueError
        If shapes disagree or the time axis is not uniform.
    """
    x, time_s, f_in_hz, orders = _spectrum_args(x, time_s, f_in_hz, orders)
    n, c, n_time = x.shape
    w = 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(n_time) / n_time)  # periodic Hann
    scale = 2.0 / w.sum()
    dt = float(time_s[1] - time_s[0]) if n_time > 1 else 1.0
    blk = max(1, int(round(np.sqrt(n_time))))
    n_blk = -(-n_time // blk)
    pad = n_blk * blk - n_time
    tau = np.arange(blk) * dt  # (L,) within a block
    t_a = time_s[0] + np.arange(n_blk) * blk * dt  # (A,) block starts
    out = np.empty((n, c, orders.size))
    step = max(1, int(chunk_elements // max(1, c * n_time)))
    for start in range(0, n, step):  # chunks of windows
        sl = slice(start, start + step)
        xw = (x[sl] - x[sl].mean(axis=-1, keepdims=True)) * w  # (B, C, T)
        if pad:
            xw = np.concatenate([xw, np.zeros(xw.shape[:-1] + (pad,))], axis=-1)
        xb = xw.reshape(xw.shape[0], c * n_blk, blk)  # (B, C A, L)
        om = (2.0 * np.pi) * f_in_hz[sl, None] * orders[None, :]  # (B, K)
        ph_in = om[:, None, :] * tau[None, :, None]  # (B, L, K)
        re = np.matmul(xb, np.cos(ph_in))  # (B, C A, K)
        im = np.matmul(xb, np.sin(ph_in))
        re = re.reshape(-1, c, n_blk, orders.size)  # (B, C, A, K)
        im = im.reshape(-1, c, n_blk, orders.size)
        ph_out = om[:, None, :] * t_a[None, :, None]  # (B, A, K)
        co, si = np.cos(ph_out)[:, None], np.sin(ph_out)[:, None]  # (B, 1, A, K)
        # Σ_a (re + i im)(cos + i sin) of exp(+i ω t): the modulus equals that of exp(-i ω t)
        sum_re = (re * co - im * si).sum(axis=2)
        sum_im = (re * si + im * co).sum(axis=2)
        out[sl] = np.hypot(sum_re, sum_im) * scale
    return out


def _spectrum_args(x, time_s, f_in_hz, orders):
    x = np.asarray(x, dtype=np.float64)
    if x.ndim != 3:
        raise ValueError(f"x must have shape (n_samples, n_signals, n_time), got {x.shape}")
    n, _, n_time = x.shape
    time_s = np.asarray(time_s, dtype=np.float64)
    f_in_hz = np.asarray(f_in_hz, dtype=np.float64)
    orders = np.asarray(orders, dtype=np.float64)
    if time_s.shape != (n_time,):
        raise ValueError(f"time_s must have shape ({n_time},), got {time_s.shape}")
    if f_in_hz.shape != (n,):
        raise ValueError(f"f_in_hz must have shape ({n},), got {f_in_hz.shape}")
    if n_time > 2 and not np.allclose(np.diff(time_s), time_s[1] - time_s[0], rtol=1e-6,
                                      atol=0.0):
        raise ValueError("time_s must be uniformly spaced")
    return x, time_s, f_in_hz, orders


def _selection_id(selection: int | str) -> int:
    """Map 1, "1", "selection1" to 1 (etc.); raise naming the allowed values."""
    s = str(selection).strip().lower().removeprefix("selection")
    if not s.isdigit() or int(s) not in SELECTIONS:
        raise ValueError(f"selection must be one of {', '.join(map(str, SELECTIONS))} or "
                         f"{', '.join(SELECTIONS.values())}; got {selection!r}")
    return int(s)


def selection_name(selection: int | str) -> str:
    """Config name of a selection of :data:`SELECTIONS` (``3`` -> ``"selection3"``).

    Raises
    ------
    ValueError
        For a selection that is not registered.
    """
    return SELECTIONS[_selection_id(selection)]


def feature_names(selection: int | str, orders: Sequence[float] | None = None) -> list[str]:
    """Names of the features of a selection, in column order of :func:`extract_features`.

    Parameters
    ----------
    selection : {1, 2, 3, "selection1", "selection2", "selection3"}
        Paper Table III.
    orders : sequence of float, optional
        DFT orders; default :func:`paper_orders`.

    Returns
    -------
    list of str
    """
    sel = _selection_id(selection)
    orders = paper_orders() if orders is None else np.asarray(orders, dtype=np.float64)
    sensors = [f"s{i}" for i in range(N_SENSORS)]

    def dft(sig: str) -> list[str]:
        return [f"dft_rel_{sig}_o{k:.2f}" for k in orders]

    stats = [f"m_rel_{s}" for s in sensors] + [f"var_rel_{s}" for s in sensors] + ["eta_rel"]
    if sel == 1:
        return stats
    if sel == 2:
        return stats + [name for s in sensors for name in dft(s)]
    return dft("ds13") + dft("ds24") + ["eta2_rel"]


def check_orders(ds, orders: Sequence[float]) -> None:
    """Refuse DFT orders that a data set cannot carry.

    The highest order must lie below the Nyquist frequency at the highest input speed,
    and the lowest order (and the spacing) must be resolved by the window, i.e. the window
    must hold at least 1 / order input revolutions at the lowest speed.

    Parameters
    ----------
    ds : xarray.Dataset
        Schema-v1 data set (``sample_rate_hz`` attribute, ``time``, ``n_in_rpm``).
    orders : sequence of float
        Orders of the input rotation [-].

    Raises
    ------
    ValueError
        Naming ``features.max_order`` / ``features.order_step``, the value, the limit and
        the data set.
    """
    orders = np.asarray(orders, dtype=np.float64)
    t = np.asarray(ds["time"].values, dtype=np.float64)
    fs = float(ds.attrs.get("sample_rate_hz", 0.0)) or 1.0 / float(t[1] - t[0])
    n_in = np.asarray(ds["n_in_rpm"].values, dtype=np.float64)
    src = ds.attrs.get("source_path", "the data set")
    f_hi = orders.max() * n_in.max() / 60.0
    if f_hi >= fs / 2:
        raise ValueError(
            f"features.max_order={orders.max():g} is {f_hi:.0f} Hz at {n_in.max():g} rpm, at or "
            f"above the Nyquist frequency {fs / 2:g} Hz of {src}; allowed: max_order < "
            f"{fs / 2 * 60 / n_in.max():.4g}")
    rev = t.size / fs * n_in.min() / 60.0  # input revolutions per window at the lowest speed
    step = float(np.min(np.diff(np.concatenate([[0.0], np.sort(orders)]))))
    if step * rev < 1.0 - 1e-6:
        raise ValueError(
            f"features.order_step={step:g} needs windows of at least {1 / step:g} input "
            f"revolutions; {src} holds {rev:.3g} at {n_in.min():g} rpm; allowed: order_step "
            f">= {1 / rev:.3g}")


def reference_index(ds) -> tuple[np.ndarray, np.ndarray]:
    """Pair every non-reference window with its reference window.

    Parameters
    ----------
    ds : xarray.Dataset
        Schema-v1 data set (:func:`swgsim.datasets.schema.load`).

    Returns
    -------
    samples : ndarray of int, shape (n,)
        Indices of the non-reference windows, in data-set order.
    refs : ndarray of int, shape (n,)
        Index of the reference window of the same gear, ``n_in_rpm``, ``t_out_nm`` and
        ``disturbed`` flag, for each of ``samples``.

    Raises
    ------
    ValueError
        If the data set has no ``reference`` variable or no reference windows, if a key
        has more than one reference window, or if a window has no reference window
        (naming the first missing keys).
    """
    if "reference" not in ds:
        raise ValueError(
            "the data set has no 'reference' variable: features are normalised by the "
            "reference (commissioning) windows of schema v1 (paper eq. 7)"
        )
    fast = _reference_pairs(ds)
    return fast if fast is not None else _reference_index_frame(ds)


def _reference_pairs(ds) -> tuple[np.ndarray, np.ndarray] | None:
    """:func:`reference_index` by the windows' keys coded as integers (a data set of 2,166
    windows: 0.4 ms, against 6.6 ms for the table merge); None where a key is NaN or a
    window lacks its one reference window: then the merge says what is wrong."""
    cols = [np.asarray(ds[k].values) for k in REFERENCE_KEYS]
    cols[-1] = cols[-1].astype(bool)
    if any(c.dtype.kind == "f" and np.isnan(c).any() for c in cols):
        return None
    is_ref = np.asarray(ds["reference"].values).astype(bool)
    inv = np.zeros(is_ref.size, dtype=np.int64)
    for c in cols:  # one integer per distinct key, column by column (each below n**2)
        values, c_inv = np.unique(c, return_inverse=True)
        inv = np.unique(inv * values.size + c_inv.ravel(), return_inverse=True)[1].ravel()
    ref_rows = np.flatnonzero(is_ref)
    ref_of = np.full(int(inv.max(initial=-1)) + 1, -1, dtype=np.int64)
    if ref_rows.size == 0 or np.bincount(inv[ref_rows], minlength=ref_of.size).max() > 1:
        return None
    ref_of[inv[ref_rows]] = ref_rows
    samples = np.flatnonzero(~is_ref).astype(np.int64)
    refs = ref_of[inv[samples]]
    return None if (refs < 0).any() else (samples, refs)


def _reference_index_frame(ds) -> tuple[np.ndarray, np.ndarray]:
    """:func:`reference_index` by a table merge, with its errors (the slow reference path
    of :func:`_reference_pairs`)."""
    df = pd.DataFrame({k: np.asarray(ds[k].values) for k in (*REFERENCE_KEYS, "reference")})
    df["reference"] = df["reference"].astype(bool)
    df["disturbed"] = df["disturbed"].astype(bool)
    df["idx"] = np.arange(len(df))
    ref = df[df["reference"]]
    if ref.empty:
        raise ValueError(
            "the data set has no reference windows (reference == True): features need one "
            "healthy commissioning window per gear x operating point x disturbed flag"
        )
    dup = ref.duplicated(list(REFERENCE_KEYS), keep=False)
    if dup.any():
        keys = ref.loc[dup, list(REFERENCE_KEYS)].drop_duplicates().head(3).to_dict("records")
        raise ValueError(f"more than one reference window for {keys}")
    smp = df[~df["reference"]]
    merged = smp.merge(
        ref[[*REFERENCE_KEYS, "idx"]], on=list(REFERENCE_KEYS), how="left",
        suffixes=("", "_ref"), validate="many_to_one",
    )
    missing = merged["idx_ref"].isna()
    if missing.any():
        keys = merged.loc[missing, list(REFERENCE_KEYS)].drop_duplicates()
        raise ValueError(
            f"{int(missing.sum())} windows have no reference window; first missing keys "
            f"(gear, n_in_rpm, t_out_nm, disturbed): {keys.head(5).to_dict('records')}"
        )
    return merged["idx"].to_numpy(np.int64), merged["idx_ref"].to_numpy(np.int64)


def extract_features(
    ds,
    selection: int | str,
    orders: Sequence[float] | None = None,
    floor_rel: float = FeatureSettings.floor_rel,
) -> Features:
    """Features of paper Table III for every non-reference window of a data set.

    Parameters
    ----------
    ds : xarray.Dataset
        Schema-v1 data set with reference windows (:func:`swgsim.datasets.schema.load`).
        ``strain_signal`` (sample, sensor=5, time) [mV/V].
    selection : {1, 2, 3, "selection1", "selection2", "selection3"}
        Paper Table III (docs/paper_study.md, "The paper's features").
    orders : sequence of float, optional
        Orders of the input rotation for the DFT features [-]; default
        :func:`paper_orders` (0.25, 0.5, ..., 8).
    floor_rel : float, default 1e-3
        Floor of DFT_rel as a fraction of the reference spectrum's maximum
        (docs/paper_study.md, "The paper's features").

    Returns
    -------
    Features
        ``(X, names, meta)``: X of shape (n_samples, n_features), float64, for the
        ``n_samples`` non-reference windows in data-set order.

    Raises
    ------
    ValueError
        For an unknown selection, a data set without (or with ambiguous) reference
        windows, a bad ``floor_rel``, or non-finite features (e.g. a reference mean of
        exactly zero in eq. (7)).
    """
    return next(iter_features(ds, [selection], orders, floor_rel))


def iter_features(
    ds,
    selections: Sequence[int | str],
    orders: Sequence[float] | None = None,
    floor_rel: float = FeatureSettings.floor_rel,
) -> Iterator[Features]:
    """:func:`extract_features` of several selections, in order, reading what they share
    once: the pairing with the reference windows, the windows' signals as float64 and the
    relative means and variances (Selections 1 and 2). The same features as one call of
    :func:`extract_features` per selection.

    Parameters
    ----------
    ds : xarray.Dataset
        See :func:`extract_features`.
    selections : sequence of {1, 2, 3, "selection1", "selection2", "selection3"}
    orders, floor_rel
        See :func:`extract_features`.

    Yields
    ------
    Features
        One per selection, in the order of ``selections``.

    Raises
    ------
    ValueError
        See :func:`extract_features` (every argument checked before the first is made).
    """
    sels = [_selection_id(s) for s in selections]
    if not floor_rel >= 0:
        raise ValueError(f"floor_rel must be >= 0, got {floor_rel}")
    orders = paper_orders() if orders is None else np.asarray(orders, dtype=np.float64)
    names = [feature_names(sel, orders) for sel in sels]
    samples, refs = reference_index(ds)
    used = np.unique(np.concatenate([samples, refs]))  # windows whose raw values we need
    pos = np.full(ds.sizes["sample"], -1, dtype=np.int64)
    pos[used] = np.arange(used.size)
    i_s, i_r = pos[samples], pos[refs]  # rows into the `used` arrays

    if any(sel in (2, 3) for sel in sels):
        check_orders(ds, orders)
    s = np.asarray(ds["strain_signal"].values[used], dtype=np.float64)  # (U, 5, T)
    if s.shape[1] != N_SENSORS:
        raise ValueError(f"strain_signal must have {N_SENSORS} sensors, got {s.shape[1]}")
    eta = np.asarray(ds["efficiency"].values[used], dtype=np.float64)  # (U,)
    eta_rel = eta[i_s] / eta[i_r]  # (n,)
    moments: list[np.ndarray] = []  # m_rel, var_rel: Selections 1 and 2
    for sel, sel_names in zip(sels, names, strict=True):
        cols: list[np.ndarray] = []
        if sel in (1, 2):
            if not moments:
                m = s.mean(axis=-1)  # (U, 5)
                v = s.var(axis=-1)  # (U, 5)
                moments = [m[i_s] / m[i_r], v[i_s] / v[i_r]]
            cols += [*moments, eta_rel[:, None]]
        if sel in (2, 3):
            rel = _dft_rel(ds, s, used, i_s, i_r, sel, orders, floor_rel)  # (n, C, K)
            cols.append(rel.reshape(rel.shape[0], -1))  # (n, C*K), signal-major
        if sel == 3:
            cols.append(np.abs(1.0 - eta_rel)[:, None] ** 0.25)  # eq. (9)
        X = np.concatenate(cols, axis=1)
        assert X.shape[1] == len(sel_names), (X.shape, len(sel_names))
        _check_finite(X, sel_names)
        log.info("selection %d: %d windows x %d features", sel, X.shape[0], X.shape[1])
        yield Features(X, sel_names, meta_table(ds, samples))


def _dft_rel(ds, s: np.ndarray, used: np.ndarray, i_s: np.ndarray, i_r: np.ndarray,
             sel: int, orders: np.ndarray, floor_rel: float) -> np.ndarray:
    """DFT_rel of eq. (8) of every window against its reference, shape (n, C, K): all
    five signals (Selection 2) or the differences s1 - s3, s2 - s4 (Selection 3); ``s``
    holds the ``used`` windows, shape (U, 5, T), ``i_s``/``i_r`` index it."""
    n_in = np.asarray(ds["n_in_mean_rpm"].values[used], dtype=np.float64)
    n_des = np.asarray(ds["n_in_rpm"].values[used], dtype=np.float64)
    f_in = np.where(np.isfinite(n_in), n_in, n_des) / 60.0  # (U,) [Hz]
    time_s = np.asarray(ds["time"].values, dtype=np.float64)
    if sel == 2:
        sig = s  # (U, 5, T)
    else:
        sig = np.stack([s[:, 1] - s[:, 3], s[:, 2] - s[:, 4]], axis=1)  # (U, 2, T)
    a = order_spectrum(sig, time_s, f_in, orders)  # (U, C, K)
    eps = floor_rel * a.max(axis=-1, keepdims=True)  # (U, C, 1)
    return (a[i_s] + eps[i_r]) / (a[i_r] + eps[i_r])  # (n, C, K)


def _check_finite(X: np.ndarray, names: list[str]) -> None:
    bad = ~np.isfinite(X)
    if bad.any():
        cols_bad = [names[j] for j in np.flatnonzero(bad.any(axis=0))[:5]]
        raise ValueError(
            f"{int(bad.sum())} non-finite feature values (e.g. in {cols_bad}); a reference "
            "window has a mean, variance or efficiency of zero"
        )


def meta_table(ds, samples: np.ndarray, columns: Sequence[str] = META_COLUMNS
               ) -> pd.DataFrame:
    """Metadata of the windows ``samples``: ``sample`` and ``columns`` (fault as str,
    disturbed as bool), one row per window."""
    meta = pd.DataFrame({"sample": samples})
    for k in columns:
        meta[k] = np.asarray(ds[k].values)[samples]
    meta["fault"] = meta["fault"].astype(str)
    meta["disturbed"] = meta["disturbed"].astype(bool)
    return meta


def feature_spread(feats: Features) -> pd.DataFrame:
    """Spread of every feature per class, and how far each class lies from healthy.

    Parameters
    ----------
    feats : Features
        Output of :func:`extract_features`.

    Returns
    -------
    pandas.DataFrame
        One row per (fault, feature), over the class's clean (undisturbed) windows of
        every gear and operating point: ``fault``, ``feature``, ``median``, ``std``,
        ``shift`` (median over the windows of ``|x − median|`` of the healthy windows) and
        ``n`` (windows). A healthy ``std`` of 0 means every healthy window has the same
        value (phase-locked, noise-free windows). Empty without healthy windows.
    """
    clean = ~feats.meta["disturbed"].to_numpy(bool)
    fault = feats.meta["fault"].to_numpy().astype(str)
    healthy = feats.X[clean & (fault == "healthy")]
    if len(healthy) == 0:
        return pd.DataFrame(columns=["fault", "feature", "median", "std", "shift", "n"])
    ref = np.median(healthy, axis=0)
    rows = []
    for f in np.unique(fault[clean]):
        x = feats.X[clean & (fault == f)]  # (n, F)
        med, std = np.median(x, axis=0), x.std(axis=0)
        shift = np.median(np.abs(x - ref), axis=0)
        rows += [(f, name, float(m), float(s), float(d), len(x))
                 for name, m, s, d in zip(feats.names, med, std, shift, strict=True)]
    return pd.DataFrame(rows, columns=["fault", "feature", "median", "std", "shift", "n"])
