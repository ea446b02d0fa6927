"""Data-set generation: the paper grid (Sec. III-B, Tables IV-V) in resumable shards.

A data-set config (a plain dict; the Hydra presets are ``conf/dataset/paper.yaml`` and
``tiny.yaml``) names the gears, the variants of each class, the operating points, the
chain settings, the disturbance of eq. (10) and the seed. :func:`plan` validates all of it
before any work. One shard holds every window of one gear at one input speed (all
classes, variants and load torques, clean and disturbed, plus the commissioning reference
windows). Each shard draws its randomness from ``SeedSequence(seed, spawn_key=(gear,
speed index))``, so the content does not depend on the number of workers or on the order
in which shards run.

Resumable and atomic: a shard file is written to a temporary name and renamed, then a
sidecar ``<shard>.json`` records its SHA-256; a rerun skips shards whose file matches its
sidecar. The manifest is written last, when every shard is there.
"""

from __future__ import annotations

import dataclasses
import hashlib
import logging
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from . import data as dsio
from . import dynamics
from .acquisition import acquire, parse_acquisition, start_angles
from .chain import ChainSettings, SimulationChain
from .config import dataset_config
from .disturbance import DisturbanceSpec, disturb
from .dynamics import gear_with_ke, rt1_size20, torsional_mode
from .faults import FAULTS, NO_ROOT_CRACK, ChainParams, apply_fault, get_fault
from .flexspline import FlexsplineGeometry, Mesh, TrussModel
from .friction import friction_effects_from_config
from .influence import Influence, InfluenceSolver
from .measurement import apply_sensor_effects, parse_sensor_effects
from .outdir import (  # noqa: F401 - re-exported: the data-set folder API
    DATASET_FILE,
    check_disk_space,
    config_hash,
    finalize,
    foreign_entries,
    git_revision,
    package_version,
    prepare_out_dir,
    shard_done,
)
from .sensors import SensorLayout, default_signals, signal_rows

log = logging.getLogger(__name__)

@dataclass(frozen=True)
class WindowSpec:
    """One window to simulate: gear, class, variant and operating point."""

    gear: int
    fault: str
    variant: int
    severity: float
    position_deg: float
    t_out_nm: float
    reference: bool


@dataclass(frozen=True)
class ShardSpec:
    """One shard: all windows of one gear at one input speed."""

    name: str
    gear: int
    speed_index: int
    n_in_rpm: float
    windows: tuple[WindowSpec, ...]


def _req(cond: bool, msg: str):
    if not cond:
        raise ValueError(msg)


def _in(value, lo, hi, key: str, unit: str = "", *, lo_open: bool = False,
        hi_open: bool = False, why: str = "") -> None:
    """Refuse ``value`` outside [lo, hi] (or the open ends) naming key, value and range."""
    v = float(value)
    ok = np.isfinite(v) and (v > lo if lo_open else v >= lo) and (v < hi if hi_open else v <= hi)
    if not ok:
        rng = f"{'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
        raise ValueError(f"{key} must lie in {rng}{' ' + unit if unit else ''}"
                         f"{' (' + why + ')' if why else ''}, got {value}")


def variant_list(name: str, spec: dict) -> list[tuple[float, float]]:
    """(severity, position_deg) of every variant of a class, in variant order.

    Raises
    ------
    ValueError
        Unknown fault, severity outside its range, or a non-positive variant count.
    """
    f = get_fault(name)
    lo, hi = f.severity_range
    lin, given = spec.get("severity_linspace"), spec.get("severities")
    _req((lin is None) != (given is None), f"dataset.variants.{name}: give either severities "
                                           "or severity_linspace [first, last, count]")
    if lin is not None:
        _req(len(lin) == 3, f"dataset.variants.{name}.severity_linspace must be [first, last, "
                            f"count], got {lin}")
        a, b, n = lin
        _req(int(n) >= 1 and n == int(n), f"dataset.variants.{name}.severity_linspace: count "
                                          f"must be an integer >= 1, got {n}")
        sev = list(np.linspace(float(a), float(b), int(n)))
    else:
        sev = [float(s) for s in given]
        _req(len(sev) >= 1, f"dataset.variants.{name}.severities must list at least one "
                            "severity")
    for s in sev:
        _req(lo <= s <= hi, f"dataset.variants.{name}: severity {s} outside the allowed "
                            f"range [{lo}, {hi}]")
    repeat = int(spec.get("repeat", 1))
    _req(repeat >= 1, f"dataset.variants.{name}.repeat must be >= 1, got {repeat}")
    if f.uses_position:
        n_pos = int(spec.get("n_positions", 1))
        _req(n_pos >= 1, f"dataset.variants.{name}.n_positions must be >= 1, got {n_pos}")
        pos = [360.0 * k / n_pos for k in range(n_pos)]
        out = [(s, p) for s in sev for p in pos]
    else:
        out = [(s, float("nan")) for s in sev]
    return [v for v in out for _ in range(repeat)]


def layout_for(cfg: dict, gear: dict) -> SensorLayout:
    """The sensor layout of one gear, with its placement and gain tolerances."""
    s = cfg["sensors"]
    sig = default_signals(s["r_torque_mm"] * 1e-3, s["r_pairs_mm"] * 1e-3)
    length = s["grid_length_mm"] * 1e-3
    sig = tuple(dataclasses.replace(x, grids=tuple(dataclasses.replace(g, length_m=length)
                                                   for g in x.grids)) for x in sig)
    lay = SensorLayout(signals=sig, gauge_factor=float(s["gauge_factor"]))
    t = cfg["tolerances"]
    rng = np.random.default_rng(int(gear["tolerance_seed"]))
    return lay.perturbed(rng, t["sd_theta_deg"], t["sd_r_mm"] * 1e-3, t["sd_beta_deg"],
                         t["sd_gain"])


def plan(cfg: dict) -> list[ShardSpec]:
    """Validate a data-set config and list its shards, before any simulation.

    Raises
    ------
    ValueError
        With the parameter's name and allowed range: unknown fault, severity outside its
        range, non-positive speed, negative torque or variant count, a gauge off the
        collar, a truss too coarse for the gauge layout, bad chain settings.
    """
    cfg = dataset_config(cfg)
    _in(cfg["seed"], 0, 2**32 - 1, "dataset.seed")
    _req(bool(cfg["name"]) and "/" not in cfg["name"] and cfg["name"] not in (".", ".."),
         f"dataset.name must be a non-empty folder name, got {cfg['name']!r}")
    ops = cfg["operating_points"]
    for key, lo, hi, unit, why in (
            ("n_in_rpm", 0.0, 6500.0, "rpm", "catalogue max input speed of size 20"),
            ("t_out_nm", 0.0, 107.0, "N m", "repeated peak torque of size 20")):
        vals = ops[key]
        _req(len(vals) >= 1 and len(set(vals)) == len(vals),
             f"dataset.operating_points.{key} must list distinct values, got {vals}")
        for v in vals:
            _in(v, lo, hi, f"dataset.operating_points.{key}", unit, lo_open=key == "n_in_rpm",
                why=why)
    n_theta = int(cfg["mesh"]["n_theta"])
    _req(n_theta % 20 == 0 and 20 <= n_theta <= 2000, "dataset.mesh.n_theta must be a "
         f"multiple of 20 in [20, 2000], got {cfg['mesh']['n_theta']}")
    ch = cfg["chain"]
    _in(ch["sample_rate_hz"], 0.0, 1e6, "dataset.chain.sample_rate_hz", "Hz", lo_open=True)
    _in(ch["window_s"], 0.0, 10.0, "dataset.chain.window_s", "s", lo_open=True)
    _in(ch["settle_s"], 0.0, 10.0, "dataset.chain.settle_s", "s")
    _in(ch["substeps"], 1, 100, "dataset.chain.substeps")
    node_deg = 360.0 / int(cfg["mesh"]["n_theta"])
    _in(ch["contact_half_width_deg"], node_deg, 90.0, "dataset.chain.contact_half_width_deg",
        "deg", hi_open=True, why="at least one node spacing; the two mesh zones 180 deg "
                                 "apart must not overlap")
    ecc = cfg["variants"].get("eccentric_wg") or {}
    e_max = max([*(ecc.get("severities") or []), *((ecc.get("severity_linspace") or [])[:2]),
                 0.0])
    _in(ch["ecc_load_share"], 0.0, 1.0 / e_max if e_max > 0 else 10.0,
        "dataset.chain.ecc_load_share", why="the load share 1 ± κ e/w0 of a mesh zone must "
        "stay in [0, 2] for the largest eccentricity of dataset.variants.eccentric_wg")
    _in(cfg["load"]["j_out_kgm2"], 1e-4, 100.0, "dataset.load.j_out_kgm2", "kg m²")
    tol = cfg["tolerances"]
    for key, hi, unit in (("sd_theta_deg", 5.0, "deg"), ("sd_r_mm", 2.0, "mm"),
                          ("sd_beta_deg", 10.0, "deg"), ("sd_gain", 0.2, "")):
        _in(tol[key], 0.0, hi, f"dataset.tolerances.{key}", unit)
    dist = cfg["disturbance"]
    for key in ("offset_mvv", "harmonic_mvv"):
        _in(dist[key], 0.0, 1.0, f"dataset.disturbance.{key}", "mV/V")
    if dist["harmonic_mvv"] > 0:  # eq. (10): sub-harmonics down to order 1/4
        rev = ch["window_s"] * min(ops["n_in_rpm"]) / 60.0
        need = 4.0 * 60.0 / min(ops["n_in_rpm"])
        _req(rev >= 4.0 - 1e-9, f"dataset.chain.window_s={ch['window_s']:g} s holds {rev:.3g} "
             f"input revolutions at {min(ops['n_in_rpm']):g} rpm, less than one period of "
             f"eq. (10)'s lowest sub-harmonic (order 1/4); allowed: >= {need:.4g} s, or "
             "dataset.disturbance.harmonic_mvv=0")
    _req(len(cfg["gears"]) >= 1, "dataset.gears must list at least one gear")
    ids = [int(g["id"]) for g in cfg["gears"]]
    _req(len(set(ids)) == len(ids), f"dataset.gears: ids must be unique, got {ids}")
    for i, g in enumerate(cfg["gears"]):
        _in(g["id"], 1, 999, f"dataset.gears[{i}].id")
        _in(g["tolerance_seed"], 0, 2**32 - 1, f"dataset.gears[{i}].tolerance_seed")
        for k in ("b1_factor", "k1_factor"):
            _in(g[k], 0.0, 10.0, f"dataset.gears[{i}].{k}", lo_open=True)
    acq = parse_acquisition(cfg.get("acquisition"))
    if acq.amplifier is not None:
        lead_s = acq.amplifier.lead_samples(ch["sample_rate_hz"]) / ch["sample_rate_hz"]
        _req(ch["settle_s"] >= lead_s, f"dataset.chain.settle_s must be >= {lead_s:g} s "
                                       "(the amplifier's filter history), got "
                                       f"{ch['settle_s']}")
    _check_settling(cfg)
    parse_sensor_effects(cfg.get("sensor_effects") or [])
    friction_effects_from_config(cfg.get("friction_effects"))
    for g in cfg["gears"]:
        gear_with_ke(rt1_size20(), g.get("ke_extra") or [])
    unknown = set(cfg["variants"]) - set(FAULTS)
    _req(not unknown, f"dataset.variants: unknown fault(s) {sorted(unknown)}; allowed: "
                      f"{sorted(FAULTS)}")
    variants = {name: variant_list(name, spec) for name, spec in cfg["variants"].items()}
    # geometry-only truss (no factorisation) to check the gauge layout against the mesh
    n_theta = int(cfg["mesh"]["n_theta"])
    model = TrussModel(FlexsplineGeometry(), Mesh(n_theta))
    for g in cfg["gears"]:
        try:
            signal_rows(model, layout_for(cfg, g))
        except ValueError as e:
            key = ("dataset.mesh.n_theta" if "too coarse" in str(e)
                   else "dataset.sensors (r_torque_mm, r_pairs_mm, grid_length_mm)")
            raise ValueError(f"{key}: {e}") from None
    shards = []
    for g in cfg["gears"]:
        for si, n in enumerate(ops["n_in_rpm"]):
            wins = []
            for fault, vl in variants.items():
                for vi, (sev, pos) in enumerate(vl):
                    for t in ops["t_out_nm"]:
                        wins.append(WindowSpec(int(g["id"]), fault, vi, sev, pos, float(t),
                                               False))
            for t in ops["t_out_nm"]:
                wins.append(WindowSpec(int(g["id"]), "healthy", -1, 0.0, float("nan"),
                                       float(t), True))
            shards.append(ShardSpec(f"gear{g['id']}_n{int(round(n))}rpm.nc", int(g["id"]),
                                    si, float(n), tuple(wins)))
    return shards


# --------------------------------------------------------------------------- workers
def gear_influences(cfg: dict, shards: list[ShardSpec]) -> dict[int, dict[tuple, Influence]]:
    """Influences of every gear's layout on every structure the shards need.

    One factorisation of the healthy truss, one adjoint solve per gear, and a Woodbury
    update per root-crack variant (:class:`swgsim.influence.InfluenceSolver`). Computed
    once in the calling process; the shard workers need no truss.

    Returns
    -------
    dict
        gear id -> {(position_deg, severity): Influence}, ``NO_ROOT_CRACK`` healthy.
    """
    n_theta = int(cfg["mesh"]["n_theta"])
    solver = InfluenceSolver(TrussModel(FlexsplineGeometry(), Mesh(n_theta)))
    keys = set()
    for s in shards:
        for w in s.windows:
            if w.fault == "root_tooth_crack" and w.severity > 0:
                p = apply_fault(ChainParams(gear=rt1_size20()), w.fault, w.severity,
                                w.position_deg)
                keys.add(p.root_crack_key())
    out = {}
    for g in cfg["gears"]:
        lay = layout_for(cfg, g)
        adj = solver.adjoint(lay)
        healthy = solver.coefficients(*adj)
        inf = {NO_ROOT_CRACK: healthy}
        for pos, sev in sorted(keys):
            inf[(pos, sev)] = solver.root_crack_at(lay, pos, sev, adjoint=adj, healthy=healthy)
        out[int(g["id"])] = inf
    return out


SETTLE_DECAY_TIMES = 5.0  # transient left in the window: e^-5 = 0.7 % of the start's


def min_settle_s(cfg: dict) -> float:
    """Shortest ``chain.settle_s`` that lets the torsional mode ring down before the window.

    :data:`SETTLE_DECAY_TIMES` times the longest decay time
    (:func:`swgsim.dynamics.torsional_mode`) over the data set's gears and
    operating points [s].
    """
    ops = cfg["operating_points"]
    return SETTLE_DECAY_TIMES * max(
        torsional_mode(gear_params(cfg, g).gear, float(n), float(t))[1]
        for g in cfg["gears"] for n in ops["n_in_rpm"] for t in ops["t_out_nm"])


def _check_settling(cfg: dict) -> None:
    need = min_settle_s(cfg)
    _req(cfg["chain"]["settle_s"] >= need - 1e-12,
         f"dataset.chain.settle_s={cfg['chain']['settle_s']:g} s is shorter than "
         f"{SETTLE_DECAY_TIMES:g} decay times of the torsional mode with "
         f"dataset.load.j_out_kgm2={cfg['load']['j_out_kgm2']:g} kg m² (the window would "
         f"still ring from the start); allowed: >= {need:.3g} s")


def gear_params(cfg: dict, gear: dict):
    """Healthy ChainParams of one gear (paper Table IV factors on b1 and k1, the data
    set's output inertia).

    A gear entry may add kinematic-error harmonics found by the calibration loop:
    ``ke_extra: [{order, amp_rad, phase_rad}]`` (:func:`swgsim.dynamics.gear_with_ke`).
    """
    p = rt1_size20()
    p = dataclasses.replace(p, b1_nms=p.b1_nms * float(gear["b1_factor"]),
                            k1_nm_per_rad=p.k1_nm_per_rad * float(gear["k1_factor"]),
                            j_out_kgm2=float(cfg["load"]["j_out_kgm2"]))
    return ChainParams(gear=gear_with_ke(p, gear.get("ke_extra") or []))


def _motion_key(p: ChainParams, t_out_nm: float, phi0: float) -> tuple:
    """Windows with equal keys have the same dynamic motion (flexspline faults do not enter
    the I/O model, paper Table I)."""
    return (p.gear, float(t_out_nm), float(phi0))


def _signal_key(w: WindowSpec, phi0: float) -> tuple:
    """Windows with equal keys have the same clean signals (healthy copies, references)."""
    pos = None if np.isnan(w.position_deg) else float(w.position_deg)
    return (w.fault, float(w.severity), pos, float(w.t_out_nm), float(phi0))


def _unique(keys: list[tuple]) -> tuple[np.ndarray, np.ndarray]:
    """First index of each distinct key and, per item, the position of its key."""
    pos: dict[tuple, int] = {}
    first: list[int] = []
    inverse = np.empty(len(keys), np.int64)
    for i, k in enumerate(keys):
        if k not in pos:
            pos[k] = len(first)
            first.append(i)
        inverse[i] = pos[k]
    return np.asarray(first, np.int64), inverse


def simulate_shard(cfg: dict, shard: ShardSpec, influences: dict[tuple, Influence]):
    """Simulate one shard; return (xarray.Dataset, n_windows).

    Parameters
    ----------
    cfg : dict
        Validated data-set config.
    shard : ShardSpec
    influences : dict
        This gear's influences (:func:`gear_influences`).

    The dataset holds the clean windows, their disturbed twins (eq. 10, same motion) and
    the reference windows, in that order. Each distinct motion is integrated once and each
    distinct window synthesised once (with ``acquisition.start: fixed`` the healthy copies
    and the flexspline faults share the healthy gear's motion); the result is the same as
    simulating every window on its own.

    Randomness comes from three independent streams of ``SeedSequence(seed, spawn_key=
    (gear, speed index))``: window start angles, eq. (10) draws, amplifier noise; so the
    eq. (10) draws of a window do not depend on the acquisition protocol.
    """
    gear = next(g for g in cfg["gears"] if int(g["id"]) == shard.gear)
    ch = cfg["chain"]
    acq = parse_acquisition(cfg.get("acquisition"))
    amp = acq.amplifier
    q = 1 if amp is None else amp.oversample
    settings = ChainSettings(sample_rate_hz=float(ch["sample_rate_hz"]),
                             window_s=float(ch["window_s"]), settle_s=float(ch["settle_s"]),
                             substeps=int(ch["substeps"]),
                             contact_half_width_deg=float(ch["contact_half_width_deg"]),
                             ecc_load_share=float(ch["ecc_load_share"]))
    fs = settings.sample_rate_hz
    n_t = int(round(settings.window_s * fs))
    n_lead = 0 if amp is None else amp.lead_samples(fs)
    chain = SimulationChain.from_influences(layout_for(cfg, gear), influences, settings)
    healthy = gear_params(cfg, gear)
    ss = np.random.SeedSequence(int(cfg["seed"]), spawn_key=(shard.gear, shard.speed_index))
    rng_start, rng_dist, rng_noise = (np.random.default_rng(s) for s in ss.spawn(3))
    wins = shard.windows
    phi0 = start_angles(acq, len(wins), rng_start, healthy.gear.ratio)
    params = [apply_fault(healthy, w.fault, w.severity,
                          0.0 if np.isnan(w.position_deg) else w.position_deg)
              for w in wins]
    t_out = np.array([w.t_out_nm for w in wins])
    # each distinct motion once: (gear parameters, load, start angle)
    m_idx, m_inv = _unique([_motion_key(p, t, a) for p, t, a in zip(params, t_out, phi0,
                                                                        strict=True)])
    # the window plus n_lead samples before and after it (history of the amplifier's
    # filter), and one more to interpolate the last fine sample
    n_rec = n_t + 2 * n_lead + (q > 1)
    res = dynamics.simulate([params[k].gear for k in m_idx], shard.n_in_rpm, t_out[m_idx],
                            phi0[m_idx], fs, n_rec / fs, settings.settle_s - n_lead / fs,
                            settings.substeps,
                            friction_effects=friction_effects_from_config(
                                cfg.get("friction_effects")))
    if not res.success:
        raise RuntimeError(f"dynamic simulation failed in shard {shard.name}: {res.message}")
    win = slice(n_lead, n_lead + n_t)  # the window's samples
    eff = (res.p_out[:, win].mean(axis=1) / res.p_in[:, win].mean(axis=1))[m_inv]
    n_mean = res.states[1][:, win].mean(axis=1)[m_inv] * 60 / (2 * np.pi)
    t_mean = res.t_out[:, win].mean(axis=1)[m_inv]
    # each distinct window once, on the fine grid (q samples per sample) if q > 1
    s_idx, s_inv = _unique([_signal_key(w, a) for w, a in zip(wins, phi0, strict=True)])
    psi, t_act = fine_motion(res, q, m_inv[s_idx])
    sig_u = chain.signals_batch([params[k] for k in s_idx], psi, t_act)  # (U, 5, q n_rec')
    # (V, 5, ...): copies of the unique windows, unless every window is distinct
    sig = sig_u if np.array_equal(s_inv, np.arange(len(wins))) else sig_u[s_inv]
    if amp is None:
        sig = sig[:, :, win]
    time_s = np.arange(n_t) / fs
    sig = sig_u[s_inv]  # (V, 5, q (n + 2 lead)), views of the unique windows
    if amp is None:
        sig = sig[:, :, win]
    if cfg.get("sensor_effects"):
        # windows are taken one after another in shard order (thermal drift)
        t_fine = np.arange(sig.shape[-1]) / (fs * q)
        sig = apply_sensor_effects(sig, t_fine, n_mean, cfg["sensor_effects"],
                                   t_start_s=np.arange(len(wins)) * settings.window_s
                                   - n_lead / fs)
    if amp is not None:  # anti-aliasing filter, sampling, noise, ADC of the bench amplifier
        sig = acquire(sig, amp, rng_noise, n_lead)
    dspec = DisturbanceSpec(offset_mvv=float(cfg["disturbance"]["offset_mvv"]),
                            harmonic_mvv=float(cfg["disturbance"]["harmonic_mvv"]))
    ref = np.array([w.reference for w in wins])
    order = np.concatenate([np.flatnonzero(~ref), np.flatnonzero(ref)])
    n_clean = int((~ref).sum())
    clean = sig[order].astype(np.float32)  # (V, 5, n_t), clean windows then references
    dist = disturb(sig[order], time_s, n_mean[order], dspec, rng_dist).astype(np.float32)
    strain32 = np.concatenate([clean[:n_clean], dist[:n_clean], clean[n_clean:],
                               dist[n_clean:]])
    order = np.concatenate([order[:n_clean], order[:n_clean], order[n_clean:],
                            order[n_clean:]])
    disturbed = np.concatenate([np.zeros(n_clean, bool), np.ones(n_clean, bool),
                                np.zeros(ref.sum(), bool), np.ones(ref.sum(), bool)])
    meta = {
        "gear": np.array([wins[k].gear for k in order]),
        "fault": np.array([wins[k].fault for k in order]),
        "variant": np.array([wins[k].variant for k in order]),
        "severity": np.array([wins[k].severity for k in order]),
        "position_deg": np.array([wins[k].position_deg for k in order]),
        "n_in_rpm": np.full(order.size, shard.n_in_rpm),
        "t_out_nm": np.array([wins[k].t_out_nm for k in order]),
        "disturbed": disturbed,
        "reference": np.array([wins[k].reference for k in order]),
        "efficiency": eff[order],
        "n_in_mean_rpm": n_mean[order],
        "t_out_mean_nm": t_mean[order],
    }
    h = hashlib.sha256(strain32.tobytes())
    for k in sorted(meta):
        h.update(np.ascontiguousarray(meta[k]).astype(str if k == "fault" else meta[k].dtype)
                 .tobytes())
    attrs = {"config": cfg, "seed": int(cfg["seed"]), "shard": shard.name,
             "content_sha256": h.hexdigest(), "package_version": package_version(),
             "git_revision": git_revision(), "sample_rate_hz": fs}
    return dsio.make_dataset(strain32, time_s, meta, attrs), order.size


def fine_motion(res: dynamics.SimResult, q: int,
                rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """WG angle and output torque of some simulated variants on a q times finer grid.

    The dynamics are integrated at the data rate; the gauge signals of an amplifier model
    need ``q`` samples per sample. ψ is interpolated by cubic Hermite polynomials with its
    derivative ω_in − ω_out (a state), the output torque by a cubic spline; both are
    smooth on the scale of the sample rate (the torsional resonance lies near 0.2-0.5 kHz).

    Parameters
    ----------
    res : SimResult
        n_rec samples per variant at the data rate.
    q : int
        Fine samples per sample, >= 1.
    rows : ndarray of int, shape (U,)
        Variants to return.

    Returns
    -------
    psi, t_out : ndarray, shape (U, q (n_rec − 1)) or (U, n_rec) if q == 1
        [rad], [N m] at times k / (q fs), k = 0, 1, ...
    """
    psi, t_out = res.psi[rows], res.t_out[rows]
    if q == 1:
        return psi, t_out
    from scipy.interpolate import CubicHermiteSpline, CubicSpline

    t = res.time
    tf = np.arange(q * (t.size - 1)) * (t[1] - t[0]) / q
    dpsi = res.states[1][rows] - res.states[3][rows]
    return (CubicHermiteSpline(t, psi, dpsi, axis=1)(tf),
            CubicSpline(t, t_out, axis=1)(tf))


def _warm() -> None:
    """Import the simulation stack in a worker (runs while the parent factorises)."""
    import h5netcdf  # noqa: F401
    import xarray  # noqa: F401

    import swgsim.generate  # noqa: F401


def run_shard(cfg: dict, shard: ShardSpec, out_dir: str | os.PathLike,
              influences: dict[tuple, Influence]) -> dict:
    """Simulate and write one shard atomically, then its sidecar; return the sidecar."""
    t0 = time.perf_counter()
    ds, n = simulate_shard(cfg, shard, influences)
    path = Path(out_dir) / shard.name
    sha = dsio.write_shard(ds, path)
    side = {"sha256": sha, "n_samples": int(n), "config_hash": config_hash(cfg),
            "content_sha256": ds.attrs["content_sha256"]}
    dsio.atomic_write_json(path.with_suffix(".json"), side)
    log.info("shard %s: %d windows in %.1f s", shard.name, n, time.perf_counter() - t0)
    return side


def generate(cfg: dict, out_dir: str | os.PathLike, n_jobs: int = 1, overwrite: bool = False,
             shard_index: int | None = None, progress: bool = True) -> dict:
    """Generate (or complete) a data set.

    Parameters
    ----------
    cfg : dict
        Data-set config (:class:`swgsim.config.DatasetConfig` as a dict, e.g.
        :func:`swgsim.config.paper_config`).
    out_dir : path-like
        Target directory.
    n_jobs : int
        Worker processes for the shards (joblib, loky backend); 1 runs in-process.
    overwrite : bool
        Replace a data set of another config in ``out_dir``.
    shard_index : int, optional
        Compute only this shard (for cluster array jobs, e.g. the Hydra submitit
        launcher); the manifest is written by whichever call finds all shards present.
    progress : bool
        Show a progress bar.

    Returns
    -------
    dict
        Summary: ``out_dir``, ``windows`` (samples written), ``computed`` and ``skipped``
        shard names, ``wall_s``, ``complete``, ``content_sha256`` (when complete),
        ``replaced`` (what an ``overwrite`` replaced, or None).

    Raises
    ------
    ValueError
        On any invalid config value (see :func:`plan`) or a foreign ``out_dir``.
    """
    t0 = time.perf_counter()
    cfg = dataset_config(cfg)  # complete and checked: what is hashed and stored
    if int(n_jobs) < 1:
        raise ValueError(f"n_jobs must be >= 1, got {n_jobs}")
    shards = plan(cfg)
    if shard_index is not None and not 0 <= int(shard_index) < len(shards):
        raise ValueError(f"shard must lie in [0, {len(shards) - 1}], got {shard_index}")
    out = Path(out_dir)
    chash = config_hash(cfg)
    todo_all = shards if shard_index is None else [shards[int(shard_index)]]
    todo = [s for s in todo_all if not shard_done(out, s, chash)]
    check_disk_space(out, todo, cfg)  # before anything is written
    replaced = prepare_out_dir(out, cfg, overwrite)
    skipped = [s.name for s in todo_all if s not in todo]
    if skipped:
        log.info("resuming: %d shard(s) already done, skipped", len(skipped))
    from tqdm.auto import tqdm

    n_workers = min(int(n_jobs), len(todo))
    bar = tqdm(total=len(todo), desc=f"generate {cfg.get('name', '')}", unit="shard",
               disable=not progress or not todo)
    try:
        if n_workers <= 1:
            infl = gear_influences(cfg, todo) if todo else {}
            for s in todo:
                run_shard(cfg, s, out, infl[s.gear])
                bar.update()
        else:
            from joblib import Parallel, delayed

            def tasks():
                # the workers start and import while the parent factorises the truss:
                # joblib takes the first tasks before it asks for the shards
                for _ in range(n_workers):
                    yield delayed(_warm)()
                infl = gear_influences(cfg, todo)
                for s in todo:
                    yield delayed(run_shard)(cfg, s, out, infl[s.gear])

            par = Parallel(n_jobs=n_workers, return_as="generator_unordered",
                           pre_dispatch=f"{n_workers + 1}")
            for r in par(tasks()):
                if r is not None:
                    bar.update()
    finally:
        bar.close()
    complete = all(shard_done(out, s, chash) for s in shards)
    summary: dict[str, Any] = {"out_dir": str(out), "computed": [s.name for s in todo],
                               "skipped": skipped, "complete": complete, "replaced": replaced}
    if complete:
        manifest = finalize(out, cfg, shards)
        summary["windows"] = manifest["n_samples"]
        summary["content_sha256"] = manifest["content_sha256"]
    else:
        summary["windows"] = int(sum(len(s.windows) * 2 for s in todo))
    summary["wall_s"] = time.perf_counter() - t0
    return summary
