"""How far each fault class lies from the healthy gear in the simulated signals.

For every gear and operating point, each window is reduced to phase-invariant numbers:
the amplitudes ``|c_h|`` of the harmonics h = 0..H of the wave-generator angle in every
bridge (:func:`learn.inputs.signals.harmonic_coefficients`; for disturbed windows the
disturbance's sub-harmonics fitted and dropped) and the efficiency η. A window's
separation is the largest ``|x - mean| / spread`` over the numbers, mean and spread of
the healthy windows of its gear and operating point; healthy windows are scored
leave-one-out, which gives the separation they reach by chance. Used by the transfer
report and the observability map (:func:`separation_records`).

    python -m learn.studies.separability                      # data/paper, clean windows
    python -m learn.studies.separability --disturbed --out reports/transfer

prints, per class, the share of windows beyond the healthy windows' 95th and 99th
percentile and the median separation, and, with ``--out``, writes ``separability.png``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from learn.inputs.signals import ResidualSettings, harmonic_coefficients
from swgsim.base.lazy import lazy_module
from swgsim.files.ownership import save_figure

pd = lazy_module("pandas")


def separation_records(ds, disturbed: bool = False, n_harmonics: int = 8,
                       ratio: float = 100.0) -> pd.DataFrame:
    """Separation of every window from the healthy windows of its gear and operating point.

    Parameters
    ----------
    ds : xarray.Dataset
        Schema v1 (``strain_signal``, ``time``, ``n_in_mean_rpm``, ``efficiency`` and
        the window labels).
    disturbed : bool
        Use the disturbed (True) or clean (False) non-reference windows. For disturbed
        windows the sub-harmonics of eq. (10) (orders 1/4, 1/3, 1/2, 1) are fitted and
        dropped; clean windows hold none, so none are fitted.
    n_harmonics : int
        Harmonics H of the wave-generator angle, >= 1.
    ratio : float
        Gear ratio N (the WG angle turns at 1 + 1/N per input revolution).

    Returns
    -------
    pandas.DataFrame
        One row per window of a (gear, operating point) with at least three healthy
        windows: ``sample``, ``gear``, ``fault``, ``variant``, ``severity``, ``n_in_rpm``,
        ``t_out_nm`` and ``z``, the max over the (5 (H + 1) + 1) numbers of
        ``|x - mean_healthy| / std_healthy`` [-]; healthy windows leave-one-out.

    Raises
    ------
    ValueError
        ``n_harmonics`` < 1.
    """
    if int(n_harmonics) < 1:
        raise ValueError(f"n_harmonics must be >= 1, got {n_harmonics}")
    keys = ("gear", "fault", "variant", "severity", "n_in_rpm", "t_out_nm", "disturbed",
            "reference")
    m = {k: ds[k].values for k in keys}
    sig = ds["strain_signal"].values
    t = np.asarray(ds["time"].values, float)
    f_in = np.asarray(ds["n_in_mean_rpm"].values, float) / 60.0
    eff = ds["efficiency"].values
    nuisance = tuple(ResidualSettings().nuisance_orders) if disturbed else ()
    parts = []
    use = (m["disturbed"] == disturbed) & ~m["reference"]
    for g in np.unique(m["gear"]):
        for n in np.unique(m["n_in_rpm"]):
            for tq in np.unique(m["t_out_nm"]):
                idx = np.flatnonzero(use & (m["gear"] == g) & (m["n_in_rpm"] == n)
                                     & (m["t_out_nm"] == tq))
                if (m["fault"][idx] == "healthy").sum() < 3:
                    continue
                c = harmonic_coefficients(sig[idx].astype(float), t, f_in[idx],
                                          1.0 + 1.0 / ratio, n_harmonics,
                                          nuisance_orders=nuisance)
                x = np.concatenate([np.abs(c).reshape(len(idx), -1), eff[idx, None]], axis=1)
                h = np.flatnonzero(m["fault"][idx] == "healthy")
                z = _zmax(x, x[h])
                # leave-one-out: a healthy window against the other healthy windows
                z[h] = [_zmax(x[i:i + 1], x[h[h != i]])[0] for i in h]
                parts.append(pd.DataFrame({"sample": idx, "z": z,
                                           **{k: m[k][idx] for k in keys[:6]}}))
    cols = ["sample", "gear", "fault", "variant", "severity", "n_in_rpm", "t_out_nm", "z"]
    if not parts:
        return pd.DataFrame(columns=cols)
    out = pd.concat(parts, ignore_index=True)[cols]
    out["fault"] = out["fault"].astype(str)
    return out


def separations(ds, disturbed: bool = False, n_harmonics: int = 8,
                ratio: float = 100.0) -> dict[str, np.ndarray]:
    """Separations of :func:`separation_records` grouped by fault class.

    Returns
    -------
    dict
        Fault class -> ndarray, shape (n_windows,) [healthy spreads]. Groups with fewer
        than three healthy windows are skipped.
    """
    rec = separation_records(ds, disturbed, n_harmonics, ratio)
    return {f: g["z"].to_numpy() for f, g in rec.groupby("fault")}


def _zmax(x: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Max over columns of |x - mean(ref)| / std(ref), shape (len(x),); std floored."""
    mu, sd = ref.mean(axis=0), ref.std(axis=0, ddof=1)
    sd = np.maximum(sd, 1e-9 * np.maximum(np.abs(mu), 1e-12))
    return np.max(np.abs(x - mu) / sd, axis=1)


def summary_table(sep: dict[str, np.ndarray]) -> pd.DataFrame:
    """Per class: windows, share beyond the healthy 95th / 99th percentile, median.

    Parameters
    ----------
    sep : dict
        Output of :func:`separations` (must hold ``healthy``).

    Returns
    -------
    pandas.DataFrame
        Columns ``fault``, ``windows``, ``beyond_p95``, ``beyond_p99`` (fractions),
        ``median`` [healthy spreads]; attrs ``p95``, ``p99``.
    """
    if "healthy" not in sep or sep["healthy"].size == 0:
        raise ValueError("separations hold no healthy windows")
    p95, p99 = np.percentile(sep["healthy"], [95, 99])
    df = pd.DataFrame([{"fault": f, "windows": z.size, "beyond_p95": float(np.mean(z > p95)),
                        "beyond_p99": float(np.mean(z > p99)),
                        "median": float(np.median(z))} for f, z in sorted(sep.items())])
    df.attrs.update(p95=float(p95), p99=float(p99))
    return df


def plot_separability(sep: dict[str, np.ndarray], path: str | Path,
                      title: str = "Class separability in the simulated signals") -> Path:
    """Box plot (5-95 % whiskers, log axis) of the separation per class; writes ``path``."""
    from matplotlib.figure import Figure

    from swgsim.gear.faults import display_name

    p95 = float(np.percentile(sep["healthy"], 95))
    names = sorted(sep, key=lambda f: np.median(sep[f]))
    fig = Figure(figsize=(7, 3.6), layout="constrained")
    ax = fig.add_subplot()
    ax.boxplot([np.maximum(sep[f], 1e-2) for f in names], orientation="horizontal",
               whis=(5, 95), showfliers=False)
    ax.set_yticks(range(1, len(names) + 1), [display_name(f) for f in names])
    ax.set_xscale("log")
    ax.axvline(p95, color="k", ls="--", lw=0.8, label="healthy 95th percentile")
    ax.legend(loc="lower right", fontsize=8)
    ax.set_xlabel("separation from healthy windows of the same gear and operating point\n"
                  "[healthy spreads, max over |harmonic| of 5 bridges and η]")
    ax.set_title(title)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return save_figure(fig, path, 130)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", default="data/paper", help="schema-v1 data set [data/paper]")
    ap.add_argument("--disturbed", action="store_true", help="use the disturbed windows")
    ap.add_argument("--harmonics", type=int, default=8, help="harmonics H of the WG angle [8]")
    ap.add_argument("--out", default=None, help="folder for separability.png")
    a = ap.parse_args(argv)
    if a.harmonics < 1:
        ap.error(f"--harmonics must be >= 1, got {a.harmonics}")
    from swgsim.datasets.schema import load

    sep = separations(load(a.data), a.disturbed, a.harmonics)
    kind = "disturbed" if a.disturbed else "clean"
    tab = summary_table(sep)
    print(f"separation from the healthy cloud ({kind} windows, {a.data}), in healthy spreads")
    print(f"healthy (leave-one-out) 95th / 99th percentile: {tab.attrs['p95']:.3g} / "
          f"{tab.attrs['p99']:.3g}")
    print(tab.to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    if a.out:
        path = plot_separability(sep, Path(a.out) / "separability.png",
                                 f"Class separability in the simulated signals ({kind})")
        print(f"figure: {path}")


if __name__ == "__main__":
    main()
