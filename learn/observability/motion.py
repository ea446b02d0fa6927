"""Observability of stiffness loss and wear: steady windows against a joint in motion.

Per output inertia J_out, three views of the same gear: ``steady`` (the ``robot_joint``
recording at :data:`STEADY_POINTS`), ``profile`` (the ``robot_joint_motion`` profile, input
angle only) and ``profile + output encoder`` (the output twist's mean and RMS added). Every
window is a gear life's (:class:`swgsim.datasets.life.LifeSimulator`); its monitor health
features (:func:`learn.inputs.health.life_features`) are z-scored against healthy
reference windows of its operating point or slot, and its *separation* is the mean square
z-score; a fault window is *beyond* above the healthy test windows' 95th percentile at its
point. The smallest detectable loss of a view: the smallest severity with at least half
its windows beyond. Views, physics and outputs: ``docs/observability.md``, "Steady windows
against a joint in motion".
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from learn.inputs.health import life_features
from swgsim.base.lazy import lazy_module
from swgsim.datasets.life import LifeSimulator
from swgsim.datasets.schedule import DutyPoint, FaultOnset, LifeConfig
from swgsim.datasets.slots import profile_slots
from swgsim.files.ownership import save_figure

pd = lazy_module("pandas")

#: Steady operating points of the ``steady`` view: (input speed [rpm], load [N m]), the
#: robot profile's cruise speed order of magnitude at a light and a medium load.
STEADY_POINTS = ((2000.0, 7.0), (2000.0, 39.0))
VIEWS = ("steady", "profile", "profile + output encoder")
COLUMNS = ("j_out_kgm2", "view", "fault", "severity", "stiffness_left", "fraction_beyond_p95",
           "median_separation", "windows")


@dataclass
class MotionMapConfig:
    """The motion study's design (``motion`` group of ``swgsim-observability``); it checks
    itself (:meth:`check`).

    Attributes
    ----------
    windows : int
        Windows per fault state and view, >= 20, spread over the operating points (steady)
        or slots (profile); healthy gets twice as many per point (reference and test
        halves: the reference's mean and spread and the test's 95th percentile per point
        rest on ``windows`` windows each).
    reduced_stiffness : list of float
        Severities of ``reduced_stiffness`` (k1 × (1 − s)), within its range [0, 0.25].
    wear : list of float
        Severities of ``wear`` (k1, k2 × (1 − 0.75 s), backlash 3 arcmin × s), in [0, 1].
    seed : int
        Life seed of the windows.
    """

    windows: int = 120
    reduced_stiffness: list[float] = field(default_factory=lambda: [0.05, 0.1, 0.15, 0.2, 0.25])
    wear: list[float] = field(default_factory=lambda: [0.0667, 0.1333, 0.2, 0.3333, 0.6667,
                                                       1.0])
    seed: int = 0

    def check(self, where: str) -> None:
        """Refuse a design outside its ranges in one line naming the key (run by
        :func:`swgsim.base.typed.check_tree`).

        Parameters
        ----------
        where : str
            Full name of the design for messages, ``motion``.

        Raises
        ------
        ValueError
            ``windows`` below 20; a severity list empty or with a severity outside
            (0, 0.25] (``reduced_stiffness``) or (0, 1] (``wear``).
        """
        if int(self.windows) < 20:
            raise ValueError(f"{where}.windows must be >= 20, got {self.windows}")
        for name, hi in (("reduced_stiffness", 0.25), ("wear", 1.0)):
            bad = [s for s in getattr(self, name) if not 0 < float(s) <= hi]
            if bad or not getattr(self, name):
                raise ValueError(f"{where}.{name} must list severities in (0, {hi}], got "
                                 f"{getattr(self, name)}")


def stiffness_left(fault: str, severity: float) -> float:
    """k1 after the fault as a fraction of nominal [-] (swgsim.gear.faults)."""
    if fault == "reduced_stiffness":
        return 1.0 - severity
    if fault == "wear":
        return 1.0 - 0.75 * severity
    return 1.0


def _windows(plan, fault: str, severity: float, n: int, seed: int, points=None):
    """Features, operating points and, for a profile, the same windows' features without
    the output encoder: n windows of one state, cycling through the steady ``points``
    ((input speed [rpm], load [N m]) pairs) or, when None, the profile's slots."""
    iv = 1.0
    duty = [DutyPoint(s, t, iv) for s, t in points] if points is not None else []
    c0 = iv / 60.0
    fo = FaultOnset(fault, c0, severity) if fault != "healthy" else FaultOnset()
    life = LifeConfig(hours=(n + 1) * c0, interval_min=iv, commissioning_h=c0, duty=duty,
                      fault=fo, life_seed=seed, severity_levels=1)
    sim = LifeSimulator(plan, 1, life)
    sig, meta = sim.windows(1, len(sim))
    pts = np.stack([meta["n_in_rpm"], meta["t_out_nm"]], axis=1)
    with_enc = life_features(plan, sig, meta)
    if points is not None:
        return {"steady": with_enc}, pts
    no_enc = life_features(plan, sig, {k: v for k, v in meta.items() if k != "phi_out_meas"})
    return {"profile + output encoder": with_enc, "profile": no_enc}, pts


def _reference(plan, windows: int, seed: int, points=None):
    """Healthy windows of each view split into reference and test halves: the reference
    (features, points), the test windows' p95 of separation per point, and the test
    windows' separations and points."""
    n_pts = len(points) if points is not None else len(profile_slots(plan).starts)
    hf, hp = _windows(plan, "healthy", 0.0, 2 * windows * n_pts, seed, points)
    half = _alternate(hp)  # reference and test halves, every point in both
    ref, thr, test = {}, {}, {}
    for v, f in hf.items():
        ref[v] = (f[half], hp[half])
        s = separations(*ref[v], f[~half], hp[~half])
        thr[v] = {tuple(p): np.percentile(s[(hp[~half] == p).all(axis=1)], 95)
                  for p in np.unique(hp, axis=0)}
        test[v] = (s, hp[~half])
    return ref, thr, test


def fault_visibility(plan, fault: str, severity: float, windows: int, seeds,
                     points=None) -> dict[str, np.ndarray]:
    """Share of a fault's windows beyond the healthy 95th percentile of their point, per
    view and fault life (each seed draws its own fault position).

    Parameters
    ----------
    plan : swgsim.datasets.plan.Plan
        A steady data set (``points`` given) or a profile data set.
    fault : str
        A class of :data:`swgsim.gear.faults.FAULTS`.
    severity : float
        Within the fault's range.
    windows : int
        Windows of each fault life, spread over the points or slots; twice as many healthy
        windows per point or slot (reference and test halves), as :class:`MotionMapConfig`.
    seeds : sequence of int
        Life seeds of the fault lives (the healthy windows use seed 0).
    points : sequence of (float, float), optional
        Steady operating points (input speed [rpm], load [N m]); None: the profile's slots.

    Returns
    -------
    dict
        View (:data:`VIEWS`: ``steady``, or ``profile`` and ``profile + output encoder``)
        -> ndarray, shape (len(seeds),) [-], 0.05 where the features cannot see the fault.
    """
    ref, thr, _ = _reference(plan, windows, 0, points)
    out = {v: [] for v in ref}
    for seed in seeds:
        ff, fp = _windows(plan, fault, severity, windows, int(seed), points)
        for v, f in ff.items():
            s = separations(*ref[v], f, fp)
            out[v].append(_beyond(s, fp, thr[v]).mean())
    return {v: np.asarray(x) for v, x in out.items()}


def separations(ref: np.ndarray, ref_pts: np.ndarray, x: np.ndarray, pts: np.ndarray
                ) -> np.ndarray:
    """Mean square z-score of windows ``x`` (n, F) against the reference windows of their
    operating point [-], shape (n,).

    Raises
    ------
    ValueError
        A window's point without reference windows.
    """
    out = np.empty(len(x))
    for p in np.unique(pts, axis=0):
        r, m = ref[(ref_pts == p).all(axis=1)], (pts == p).all(axis=1)
        if len(r) < 3:
            raise ValueError(f"operating point {tuple(p)}: {len(r)} reference windows")
        z = (x[m] - r.mean(axis=0)) / np.maximum(r.std(axis=0, ddof=1), 1e-12)
        out[m] = np.mean(z ** 2, axis=1)
    return out


def motion_map_rows(plans: dict[str, object], j_out: float, mc: MotionMapConfig
                    ) -> pd.DataFrame:
    """The map's rows at one output inertia.

    Parameters
    ----------
    plans : dict
        ``steady``: the steady data set (robot_joint at this J_out), ``profile``: the
        profile data set with an output encoder (robot_joint_motion at this J_out).
    j_out : float
        [kg m²].
    mc : MotionMapConfig

    Returns
    -------
    pandas.DataFrame
        :data:`COLUMNS`, one row per (view, fault, severity), healthy included.
    """
    rows = []
    states = [("reduced_stiffness", s) for s in mc.reduced_stiffness] + [
        ("wear", s) for s in mc.wear]
    for kind, plan in (("steady", plans["steady"]), ("profile", plans["profile"])):
        points = STEADY_POINTS if kind == "steady" else None
        ref, thr, test = _reference(plan, mc.windows, mc.seed, points)
        for v, (s, pts) in test.items():
            rows.append(_row(j_out, v, "healthy", 0.0, s, pts, thr[v]))
        for fault, sev in states:
            ff, fp = _windows(plan, fault, sev, mc.windows, mc.seed + 1, points)
            for v, f in ff.items():
                rows.append(_row(j_out, v, fault, sev, separations(*ref[v], f, fp), fp,
                                 thr[v]))
    return pd.DataFrame(rows, columns=list(COLUMNS))


def _alternate(pts: np.ndarray) -> np.ndarray:
    """True for every other window of each operating point, shape (n,)."""
    out = np.zeros(len(pts), bool)
    for p in np.unique(pts, axis=0):
        idx = np.flatnonzero((pts == p).all(axis=1))
        out[idx[::2]] = True
    return out


def _beyond(s: np.ndarray, pts: np.ndarray, thr: dict) -> np.ndarray:
    """True for each separation beyond its point's threshold, shape (n,)."""
    return np.array([si > thr[tuple(p)] for si, p in zip(s, pts, strict=True)])


def _row(j_out, view, fault, sev, s, pts, thr) -> dict:
    beyond = _beyond(s, pts, thr)
    return {"j_out_kgm2": float(j_out), "view": view, "fault": fault, "severity": float(sev),
            "stiffness_left": stiffness_left(fault, sev),
            "fraction_beyond_p95": float(beyond.mean()),
            "median_separation": float(np.median(s)), "windows": int(len(s))}


def plot_motion_map(table: pd.DataFrame, path):
    """Share of windows beyond the healthy 95th percentile against the stiffness left, one
    panel per fault, one colour per view, one line style per output inertia; returns the
    path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    faults = ["reduced_stiffness", "wear"]
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    colour = dict(zip(VIEWS, ("tab:grey", "tab:blue", "tab:red"), strict=True))
    js = sorted(table.j_out_kgm2.unique())
    styles = ["-", "--", ":", "-.", (0, (1, 4)), (0, (5, 1))]
    for ax, f in zip(axes, faults, strict=True):
        for v in VIEWS:
            for i, j in enumerate(js):
                g = table[(table.fault == f) & (table.view == v) & (table.j_out_kgm2 == j)]
                ax.plot(g.stiffness_left, 100 * g.fraction_beyond_p95, marker="o", ms=3,
                        color=colour[v], ls=styles[i % len(styles)],
                        label=f"{v}, J_out {j:.3g}" if f == faults[0] else None)
        ax.axhline(5, color="k", lw=0.6)
        ax.axhline(50, color="k", lw=0.6, ls=":")
        ax.invert_xaxis()
        ax.set(title=f.replace("_", " "), xlabel="k1 left [fraction of nominal]")
    axes[0].set_ylabel("fault windows beyond healthy p95 [%]")
    fig.legend(loc="lower center", ncol=3, fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, 0.18, 1, 1))
    save_figure(fig, path, 120)
    return path


def smallest_detectable(table: pd.DataFrame, level: float = 0.5) -> pd.DataFrame:
    """Per (J_out, view, fault): the smallest severity (and the stiffness left) with at least
    ``level`` of its windows beyond the healthy 95th percentile; NaN where none is."""
    out = []
    for (j, v, f), g in table[table.fault != "healthy"].groupby(
            ["j_out_kgm2", "view", "fault"], sort=False):
        ok = g[g.fraction_beyond_p95 >= level].sort_values("severity")
        out.append({"j_out_kgm2": j, "view": v, "fault": f,
                    "smallest_severity": float(ok.severity.iloc[0]) if len(ok) else np.nan,
                    "stiffness_left": float(ok.stiffness_left.iloc[0]) if len(ok) else np.nan})
    return pd.DataFrame(out)


__all__ = ["COLUMNS", "STEADY_POINTS", "VIEWS", "MotionMapConfig",
           "motion_map_rows", "plot_motion_map", "separations", "smallest_detectable",
           "stiffness_left"]
