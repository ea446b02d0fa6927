"""Observability map: which faults a flexspline-gauge monitor can see, and where.

For data sets that differ only in the output inertia J_out (the bench's flange and
coupling up to a robot link), each fault window's separation from the healthy windows of
its gear and operating point (:func:`learn.studies.separability.separation_records`) is compared
with what healthy windows reach by chance: the share of a fault's windows beyond the
95th percentile of the healthy windows' leave-one-out separations, per (J_out, speed,
load). A fault at 5 % is indistinguishable from a healthy gear in these windows; at
100 % every window shows it.

Why J_out matters (the torsional mode, :func:`torsional_modes`): ``docs/observability.md``.

The runner is ``swgsim-observability`` (:mod:`learn.observability.task`); the end points of
J_out are :data:`J_OUT_BENCH` and :data:`J_OUT_ROBOT`.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from swgsim.base.lazy import lazy_module
from swgsim.files.ownership import save_figure

pd = lazy_module("pandas")

#: The bench's output inertia: flange and load coupling [kg m²]
#: (:attr:`swgsim.gear.dynamics.GearParams.j_out_kgm2`, from a public simulation script of the
#: same model structure).
J_OUT_BENCH = 8.8e-3
#: A robot link's: the shoulder (joint 2) of a Universal Robots UR3e carrying links 2-6
#: stretched out, Σ m r² from the masses and centres of mass Universal Robots publishes
#: ("DH parameters for calculations of kinematics and dynamics"); see
#: ``conf/dataset/robot_joint.yaml`` [kg m²].
J_OUT_ROBOT = 0.69
COLUMNS = ("j_out_kgm2", "n_in_rpm", "t_out_nm", "fault", "fraction_beyond_p95")


def j_out_grid(n: int = 6, lo: float = J_OUT_BENCH, hi: float = J_OUT_ROBOT) -> np.ndarray:
    """``n`` log-spaced output inertias from ``lo`` to ``hi`` [kg m²].

    Raises
    ------
    ValueError
        ``n`` < 2 or not 0 < lo < hi.
    """
    if int(n) < 2 or not 0 < lo < hi:
        raise ValueError(f"need n >= 2 and 0 < lo < hi, got n={n}, lo={lo}, hi={hi}")
    return np.geomspace(lo, hi, int(n))


def observability_table(records: pd.DataFrame, j_out: float,
                        percentile: float = 95.0) -> pd.DataFrame:
    """Share of each fault's windows beyond the healthy percentile, per operating point.

    Parameters
    ----------
    records : pandas.DataFrame
        :func:`learn.studies.separability.separation_records` of one data set.
    j_out : float
        Its output inertia [kg m²] (written to the table).
    percentile : float
        Of the healthy windows' leave-one-out separations at the same operating point,
        pooled over gears.

    Returns
    -------
    pandas.DataFrame
        :data:`COLUMNS` plus ``median_separation`` [healthy spreads], ``windows`` and
        ``healthy_threshold``; one row per (n_in_rpm, t_out_nm, fault), healthy
        included (its share is 1 - percentile / 100 by construction).

    Raises
    ------
    ValueError
        If the records hold no healthy windows at some operating point.
    """
    rows = []
    for (n, t), g in records.groupby(["n_in_rpm", "t_out_nm"]):
        h = g.loc[g["fault"] == "healthy", "z"].to_numpy()
        if h.size == 0:
            raise ValueError(f"no healthy windows at {n} rpm, {t} N m")
        thr = float(np.percentile(h, percentile))
        for f, gf in g.groupby("fault"):
            z = gf["z"].to_numpy()
            rows.append({"j_out_kgm2": float(j_out), "n_in_rpm": float(n),
                         "t_out_nm": float(t), "fault": str(f),
                         "fraction_beyond_p95": float(np.mean(z > thr)),
                         "median_separation": float(np.median(z)), "windows": int(z.size),
                         "healthy_threshold": thr})
    return pd.DataFrame(rows)


def torsional_modes(j_values: Sequence[float], loads: Sequence[float],
                    n_in_rpm: float = 2000.0) -> pd.DataFrame:
    """Torsional mode of the nominal gear per output inertia and load.

    Parameters
    ----------
    j_values : sequence of float
        Output inertias [kg m²].
    loads : sequence of float
        Load torques [N m].
    n_in_rpm : float
        Input speed of the linearisation [rpm] (the mode barely depends on it).

    Returns
    -------
    pandas.DataFrame
        Columns j_out_kgm2, t_out_nm, f_hz, decay_s (:func:`swgsim.gear.modes.torsional_mode`).
    """
    import dataclasses

    from swgsim.gear.dynamics import rt1_size20
    from swgsim.gear.modes import torsional_mode

    p = rt1_size20()
    rows = []
    for j in j_values:
        for t in loads:
            f, d = torsional_mode(dataclasses.replace(p, j_out_kgm2=float(j)), n_in_rpm,
                                  float(t))
            rows.append({"j_out_kgm2": float(j), "t_out_nm": float(t), "f_hz": f,
                         "decay_s": d})
    return pd.DataFrame(rows)


def plot_observability(table: pd.DataFrame, path: str | Path,
                       modes: pd.DataFrame | None = None) -> Path:
    """Figure: share of fault windows beyond the healthy p95 against J_out.

    One column per fault, one row per load; one line per input speed. With ``modes``
    (:func:`torsional_modes`), a last row shows the torsional mode's frequency against
    J_out per load, with the frequencies of the kinematic error's orders 1, 2 and 4 at
    each speed: where one crosses the mode, the gear is excited at resonance.
    """
    from matplotlib import colormaps
    from matplotlib.figure import Figure

    from swgsim.gear.faults import fault_classes

    present = set(table["fault"])  # one column per faulty class, in the registry's order
    faults = [f for f in fault_classes() if f != "healthy" and f in present]
    loads = sorted(set(table["t_out_nm"]))
    speeds = sorted(set(table["n_in_rpm"]))
    cmap = colormaps["viridis"]
    colour = {n: cmap(i / max(1, len(speeds) - 1) * 0.9) for i, n in enumerate(speeds)}
    nrow = len(loads) + (modes is not None)
    fig = Figure(figsize=(2.9 * len(faults), 2.3 * len(loads) + 3.2 * (modes is not None)
                          + 0.6), layout="constrained")
    gs = fig.add_gridspec(nrow, len(faults), height_ratios=[1.0] * len(loads)
                          + [1.4] * (modes is not None))
    first = _fault_panels(fig, gs, table, faults, loads, colour)
    handles, labels = first.get_legend_handles_labels()
    if modes is not None:
        _mode_panel(fig.add_subplot(gs[-1, :]), modes, colour)
    fig.legend(handles, labels, loc="outside lower center", ncol=len(speeds), fontsize=8,
               frameon=False)
    fig.suptitle("Which faults the flexspline gauges show: share of fault windows beyond "
                 "the healthy 95th percentile (dotted: 5 %, chance)", fontsize=10)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return save_figure(fig, path, 130)


def _fault_panels(fig, gs, table: pd.DataFrame, faults: list[str], loads: list[float],
                  colour: dict):
    """One panel per (load, fault): the share beyond the healthy p95 against J_out, one
    line per input speed; returns the first panel (its legend is the figure's)."""
    from swgsim.gear.faults import display_name

    first = None
    for r, t in enumerate(loads):
        for c, f in enumerate(faults):
            ax = fig.add_subplot(gs[r, c], sharex=first)
            first = first or ax
            for n in colour:
                g = table[(table["fault"] == f) & (table["t_out_nm"] == t)
                          & (table["n_in_rpm"] == n)].sort_values("j_out_kgm2")
                ax.plot(g["j_out_kgm2"], 100 * g["fraction_beyond_p95"], "o-", ms=3,
                        color=colour[n], label=f"{n:g} rpm")
            ax.axhline(5.0, color="0.5", ls=":", lw=1)
            ax.set_xscale("log")
            ax.set_ylim(-3, 103)
            ax.grid(alpha=0.3)
            if r == 0:
                ax.set_title(display_name(f))
            if c == 0:
                ax.set_ylabel(f"{t:g} N m\nbeyond healthy p95 [%]")
            if r == len(loads) - 1:
                ax.set_xlabel("output inertia J_out [kg m²]")
    return first


def _mode_panel(ax, modes: pd.DataFrame, colour: dict) -> None:
    """The torsional mode's frequency against J_out per load, and the kinematic error's
    orders 1, 2 and 4 at each speed (the keys of ``colour``)."""
    for t, g in modes.groupby("t_out_nm"):
        g = g.sort_values("j_out_kgm2")
        ax.plot(g["j_out_kgm2"], g["f_hz"], "k-", lw=1.6)
        ax.annotate(f"mode, {t:g} N m", (g["j_out_kgm2"].iloc[-1], g["f_hz"].iloc[-1]),
                    fontsize=7, xytext=(3, 0), textcoords="offset points", va="center")
    styles = {1: ":", 2: "--", 4: "-."}
    for n in colour:
        for order, ls in styles.items():
            ax.axhline(order * n / 60.0, color=colour[n], ls=ls, lw=1)
    lo, hi = modes["f_hz"].min() / 1.5, modes["f_hz"].max() * 1.5
    ax.set_ylim(lo, hi)
    ax.set_xlim(modes["j_out_kgm2"].min() / 1.2, modes["j_out_kgm2"].max() * 1.8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("output inertia J_out [kg m²]")
    ax.set_ylabel("frequency [Hz]")
    ax.set_title("Why: the torsional mode (black; output inertia on the gear stiffness) "
                 "and the kinematic error's orders 1 (dotted), 2 (dashed) and 4 "
                 "(dash-dot) at each speed. Reduced stiffness shows where an order "
                 "crosses the mode.", fontsize=9)
    ax.grid(alpha=0.3, which="both")
