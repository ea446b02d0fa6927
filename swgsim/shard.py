"""Simulation of one shard of a data set: every window of one gear at one input speed.

Takes a checked :class:`~swgsim.plan.DatasetPlan` and checks nothing again. The steps:
the gear's influences (computed once in the parent, :func:`gear_influences`), the
dynamics of each distinct motion (:func:`simulate_motions`), the gauge signals of each
distinct window (:func:`synthesise`), the measurement chain (:func:`record`: sensor
effects, the bench amplifier), eq. (10)'s disturbed twins and the metadata
(:func:`assemble`). Randomness comes from three independent streams of
``SeedSequence(seed, spawn_key=(gear, speed index))``: window start angles, eq. (10)
draws, amplifier noise; so the content depends neither on the number of workers nor on
the order of shards, and the eq. (10) draws of a window not on the recording.

A profile data set (``dataset.profile``, :func:`simulate_profile_shard`) simulates each
variant of a gear once along the whole profile and cuts the windows from that motion.
"""

from __future__ import annotations

import hashlib
import logging
import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import data as dsio
from . import dynamics, profile_dynamics
from .acquisition import acquire, start_angles
from .angles import measure_angles
from .chain import SimulationChain
from .disturbance import disturb
from .dynamics import rt1_size20
from .faults import NO_ROOT_CRACK, ChainParams, apply_fault
from .flexspline import FlexsplineGeometry, TrussModel
from .influence import Influence, InfluenceSolver
from .measurement import apply_sensor_effects
from .outdir import git_revision, package_version
from .plan import DatasetPlan, ShardSpec, WindowSpec, gear_params, layout_for

log = logging.getLogger(__name__)


def gear_influences(plan: DatasetPlan, shards: list[ShardSpec] | tuple[ShardSpec, ...]
                    ) -> dict[int, dict[tuple | None, Influence]]:
    """Influences of every gear's layout on every structure the shards need.

    The root-crack structures of the shards' windows (:func:`influences_for`).

    Returns
    -------
    dict
        gear id -> {(position_deg, severity): Influence}, ``NO_ROOT_CRACK`` healthy.
    """
    keys = set()
    for s in shards:
        for w in s.windows:
            if w.fault == "root_tooth_crack" and w.severity > 0:
                p = apply_fault(ChainParams(gear=rt1_size20()), w.fault, w.severity,
                                w.position_deg)
                keys.add(p.root_crack_key())
    return influences_for(plan, [int(g.id) for g in plan.config.gears], keys)


def influences_for(plan: DatasetPlan, gear_ids: list[int], crack_keys
                   ) -> dict[int, dict[tuple | None, Influence]]:
    """Influences of some gears' layouts on the healthy truss and some root cracks.

    One factorisation of the healthy truss, one adjoint solve per gear, and a Woodbury
    update per root-crack structure (:class:`swgsim.influence.InfluenceSolver`). Computed
    once in the calling process; the shard workers need no truss.

    Parameters
    ----------
    plan : DatasetPlan
    gear_ids : list of int
    crack_keys : iterable of (position_deg, severity)
        :meth:`swgsim.faults.ChainParams.root_crack_key` of each cracked structure.

    Returns
    -------
    dict
        gear id -> {(position_deg, severity): Influence}, ``NO_ROOT_CRACK`` healthy.
    """
    solver = InfluenceSolver(TrussModel(FlexsplineGeometry(), plan.config.mesh))
    out = {}
    for gid in gear_ids:
        lay = layout_for(plan.config, plan.gear(gid))
        adj = solver.adjoint(lay)
        healthy = solver.coefficients(*adj)
        inf = {NO_ROOT_CRACK: healthy}
        for pos, sev in sorted(crack_keys):
            inf[(pos, sev)] = solver.root_crack_at(lay, pos, sev, adjoint=adj, healthy=healthy)
        out[int(gid)] = inf
    return out


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


@dataclass
class Motions:
    """The dynamics of a shard's windows, each distinct motion integrated once.

    Attributes
    ----------
    res : SimResult
        The distinct motions, ``n_rec`` samples each (window plus amplifier history).
    inverse : ndarray of int, shape (V,)
        Row of ``res`` of each window.
    efficiency, n_mean_rpm, t_mean_nm : ndarray, shape (V,)
        Per window over its samples: P_out/P_in, mean input speed, mean output torque.
    """

    res: dynamics.SimResult
    inverse: np.ndarray
    efficiency: np.ndarray
    n_mean_rpm: np.ndarray
    t_mean_nm: np.ndarray


def diverged(plan: DatasetPlan, where: str, why: str) -> str:
    """The one-line message of a dynamic simulation that failed for checked parameters.

    Parameters
    ----------
    plan : DatasetPlan
    where : str
        What was simulated: shard, gear, operating point, fault.
    why : str
        The integrator's message (e.g. ``non-finite states``).

    Returns
    -------
    str
        Naming the keys that set the integrator step and the dynamics.
    """
    ch = plan.config.chain
    return (f"dataset.chain.substeps={ch.substeps}, dataset.chain.sample_rate_hz="
            f"{ch.sample_rate_hz:g} Hz: the dynamic simulation of {where} failed ({why}); "
            "the parameters are in range but the integrator step "
            f"{1e3 / (ch.sample_rate_hz * ch.substeps):.3g} ms does not hold them with "
            f"dataset.load.j_out_kgm2={plan.config.load.j_out_kgm2:g} kg m²: raise "
            "dataset.chain.substeps")


def simulate_motions(plan: DatasetPlan, shard: ShardSpec, params: list[ChainParams],
                     phi0: np.ndarray, n_lead: int, oversample: int) -> Motions:
    """Integrate each distinct motion (gear parameters, load, start angle) once.

    Raises
    ------
    ValueError
        Naming the shard, the window and the chain's keys, if the integration fails
        (:func:`diverged`).
    """
    ch = plan.config.chain
    fs = ch.sample_rate_hz
    n_t = int(round(ch.window_s * fs))
    t_out = np.array([w.t_out_nm for w in shard.windows])
    m_idx, m_inv = _unique([_motion_key(p, t, a) for p, t, a in zip(params, t_out, phi0,
                                                                        strict=True)])
    # the window plus n_lead samples before and after it (history of the amplifier's
    # filter), and one more to interpolate the last fine sample
    n_rec = n_t + 2 * n_lead + (oversample > 1)
    res = dynamics.simulate([params[k].gear for k in m_idx], shard.n_in_rpm, t_out[m_idx],
                            phi0[m_idx], fs, n_rec / fs, ch.settle_s - n_lead / fs,
                            ch.substeps, friction_effects=plan.friction)
    if not res.success:
        bad = int(np.argmin(np.isfinite(res.states).all(axis=(0, 2))))  # first diverged
        w = shard.windows[m_idx[bad]]
        raise ValueError(diverged(plan, f"shard {shard.name} (gear {shard.gear}, "
                                        f"{shard.n_in_rpm:g} rpm, {w.t_out_nm:g} N m, fault "
                                        f"{w.fault} severity {w.severity:g})", res.message))
    win = slice(n_lead, n_lead + n_t)  # the window's samples
    eff = (res.p_out[:, win].mean(axis=1) / res.p_in[:, win].mean(axis=1))[m_inv]
    n_mean = res.states[1][:, win].mean(axis=1)[m_inv] * 60 / (2 * np.pi)
    t_mean = res.t_out[:, win].mean(axis=1)[m_inv]
    return Motions(res, m_inv, eff, n_mean, t_mean)


def synthesise(chain: SimulationChain, shard: ShardSpec, params: list[ChainParams],
               phi0: np.ndarray, motions: Motions, oversample: int) -> np.ndarray:
    """Gauge signals of every window, each distinct window synthesised once, on the fine
    grid (``oversample`` samples per sample) when ``oversample > 1``.

    Returns
    -------
    ndarray, shape (V, 5, oversample · n_rec')
        [mV/V]; windows that are copies of one another are views of one array.
    """
    s_idx, s_inv = _unique([_signal_key(w, a) for w, a in zip(shard.windows, phi0,
                                                                strict=True)])
    psi, t_act = fine_motion(motions.res, oversample, motions.inverse[s_idx])
    sig_u = chain.signals_batch([params[k] for k in s_idx], psi, t_act)
    return sig_u[s_inv]


def record(plan: DatasetPlan, sig: np.ndarray, n_mean: np.ndarray, n_lead: int,
           rng_noise: np.random.Generator) -> np.ndarray:
    """The measurement chain: sensor effects, then the bench amplifier if there is one.

    Parameters
    ----------
    sig : ndarray, shape (V, 5, n)
        Ideal bridge outputs [mV/V]: the window alone (ideal sampling) or, with an
        amplifier, the fine grid with ``n_lead`` samples of history on each side.

    Returns
    -------
    ndarray, shape (V, 5, n_t)
        [mV/V] at the data rate.
    """
    ch, amp = plan.config.chain, plan.config.acquisition.amplifier
    fs = ch.sample_rate_hz
    q = 1 if amp is None else amp.oversample
    if plan.sensor_effects:
        # windows are taken one after another in shard order (thermal drift)
        t_fine = np.arange(sig.shape[-1]) / (fs * q)
        sig = apply_sensor_effects(sig, t_fine, n_mean, plan.sensor_effects,
                                   t_start_s=np.arange(sig.shape[0]) * ch.window_s
                                   - n_lead / fs)
    if amp is not None:  # anti-aliasing filter, sampling, noise, ADC of the bench amplifier
        sig = acquire(sig, amp, rng_noise, n_lead)
    return sig


def assemble(plan: DatasetPlan, shard: ShardSpec, sig: np.ndarray, motions: Motions,
             rng_dist: np.random.Generator):
    """Clean windows, their eq. (10) twins and the references, with their metadata.

    Returns
    -------
    (xarray.Dataset, int)
        The shard (clean windows, disturbed twins, clean references, disturbed
        references, in that order) and its number of windows.
    """
    ch = plan.config.chain
    fs = ch.sample_rate_hz
    wins = shard.windows
    time_s = np.arange(sig.shape[-1]) / fs
    ref = np.array([w.reference for w in wins])
    order = np.concatenate([np.flatnonzero(~ref), np.flatnonzero(ref)])
    n_clean = int((~ref).sum())
    clean = sig[order].astype(np.float32)  # (V, 5, n_t), clean windows then references
    n_mean = motions.n_mean_rpm
    dist = disturb(sig[order], time_s, n_mean[order], plan.config.disturbance,
                   rng_dist).astype(np.float32)
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
        "efficiency": motions.efficiency[order],
        "n_in_mean_rpm": n_mean[order],
        "t_out_mean_nm": motions.t_mean_nm[order],
    }
    h = hashlib.sha256(strain32.tobytes())
    for k in sorted(meta):
        h.update(np.ascontiguousarray(meta[k]).astype(str if k == "fault" else meta[k].dtype)
                 .tobytes())
    attrs = {"config": plan.as_dict(), "seed": int(plan.config.seed), "shard": shard.name,
             "content_sha256": h.hexdigest(), "package_version": package_version(),
             "git_revision": git_revision(), "sample_rate_hz": fs}
    return dsio.make_dataset(strain32, time_s, meta, attrs), order.size


def simulate_shard(plan: DatasetPlan, shard: ShardSpec,
                   influences: dict[tuple | None, Influence]):
    """Simulate one shard; return (xarray.Dataset, n_windows).

    Parameters
    ----------
    plan : DatasetPlan
        The checked data set (:func:`swgsim.plan.plan`).
    shard : ShardSpec
    influences : dict
        This gear's influences (:func:`gear_influences`).

    The dataset holds the clean windows, their disturbed twins (eq. 10, same motion) and
    the reference windows, in that order. Each distinct motion is integrated once and each
    distinct window synthesised once (with ``acquisition.start: fixed`` the healthy copies
    and the flexspline faults share the healthy gear's motion); the result is the same as
    simulating every window on its own.
    """
    cfg = plan.config
    if cfg.life is not None:  # a gear's life, at steady points or along the profile
        from .life import simulate_life_shard

        return simulate_life_shard(plan, shard)
    if plan.profile is not None:
        return simulate_profile_shard(plan, shard, influences)
    gear = plan.gear(shard.gear)
    amp = cfg.acquisition.amplifier
    q = 1 if amp is None else amp.oversample
    fs = cfg.chain.sample_rate_hz
    n_t = int(round(cfg.chain.window_s * fs))
    n_lead = 0 if amp is None else amp.lead_samples(fs)
    chain = SimulationChain.from_influences(layout_for(cfg, gear), influences, cfg.chain)
    healthy = gear_params(cfg, gear)
    ss = np.random.SeedSequence(int(cfg.seed), spawn_key=(shard.gear, shard.speed_index))
    rng_start, rng_dist, rng_noise = (np.random.default_rng(s) for s in ss.spawn(3))
    wins = shard.windows
    phi0 = start_angles(cfg.acquisition, len(wins), rng_start, healthy.gear.ratio)
    params = [apply_fault(healthy, w.fault, w.severity,
                          0.0 if np.isnan(w.position_deg) else w.position_deg,
                          faults=plan.faults)
              for w in wins]
    motions = simulate_motions(plan, shard, params, phi0, n_lead, q)
    sig = synthesise(chain, shard, params, phi0, motions, q)
    if amp is None:
        sig = sig[:, :, n_lead:n_lead + n_t]
    sig = record(plan, sig, motions.n_mean_rpm, n_lead, rng_noise)
    return assemble(plan, shard, sig, motions, rng_dist)


@dataclass
class ProfileMotion:
    """The variants of a profile shard simulated along the whole profile.

    Attributes
    ----------
    params : list of ChainParams
        One per variant (``shard.windows``).
    phi0 : ndarray, shape (V,)
        Input angle at the profile's start [rad].
    res : profile_dynamics.ProfileResult
        The motion from t = 0 at the data rate.
    starts : ndarray of int, shape (W,)
        First sample of each window in ``res``.
    """

    params: list[ChainParams]
    phi0: np.ndarray
    res: profile_dynamics.ProfileResult
    starts: np.ndarray


def profile_motion(plan: DatasetPlan, shard: ShardSpec,
                   rng_start: np.random.Generator | None = None) -> ProfileMotion:
    """Simulate every variant of a profile shard once along the profile.

    Parameters
    ----------
    plan : DatasetPlan
        With a profile (``plan.profile``).
    shard : ShardSpec
    rng_start : numpy.random.Generator, optional
        Stream of the start angles; default the shard's (as :func:`simulate_profile_shard`).

    Returns
    -------
    ProfileMotion

    Raises
    ------
    ValueError
        Naming the chain's keys if the integration fails (:func:`diverged`).
    """
    cfg = plan.config
    ch, amp = cfg.chain, cfg.acquisition.amplifier
    fs = ch.sample_rate_hz
    n_t = int(round(ch.window_s * fs))
    n_lead = 0 if amp is None else amp.lead_samples(fs)
    healthy = gear_params(cfg, plan.gear(shard.gear))
    if rng_start is None:
        ss = np.random.SeedSequence(int(cfg.seed), spawn_key=(shard.gear, shard.speed_index))
        rng_start = np.random.default_rng(ss.spawn(3)[0])
    # the wave generator's angle as drawn, the output (the link's pose) within one
    # wave-generator revolution / N of its zero: the profile's load acts on that pose
    phi0 = np.mod(start_angles(cfg.acquisition, len(shard.windows), rng_start,
                               healthy.gear.ratio), 2 * np.pi)
    params = [apply_fault(healthy, w.fault, w.severity,
                          0.0 if np.isnan(w.position_deg) else w.position_deg,
                          faults=plan.faults)
              for w in shard.windows]
    starts = np.round(np.asarray(shard.window_starts_s) * fs).astype(np.int64)
    n_rec = int(starts.max()) + n_t + n_lead + 1
    res = profile_dynamics.simulate_profile([p.gear for p in params], plan.profile, phi0, fs,
                                    n_rec / fs, ch.substeps, cfg.profile.feedforward)
    if not res.success:
        raise ValueError(diverged(plan, f"shard {shard.name} (gear {shard.gear}, profile)",
                                  res.message))
    return ProfileMotion(params, phi0, res, starts)


def simulate_profile_shard(plan: DatasetPlan, shard: ShardSpec,
                           influences: dict[tuple | None, Influence]):
    """Simulate one gear's variants along the profile and cut the windows.

    Each variant is simulated once (:func:`profile_motion`); its gauge signals are
    synthesised on the whole motion (on the amplifier's fine grid when there is one), the
    windows cut at ``shard.window_starts_s``, the sensor effects applied with each
    window's ψ (gauge misplacement in the angle domain), then the amplifier. Windows are
    clean (no eq. (10) twins: its harmonics are defined at a steady speed), variant by
    variant in shard order, each variant's windows in time order, the reference last.

    Parameters
    ----------
    plan : DatasetPlan
        With a profile.
    shard : ShardSpec
    influences : dict
        This gear's influences (:func:`gear_influences`).

    Returns
    -------
    (xarray.Dataset, int)
        The shard, with the per-sample variables of schema v1 and the profile's
        (``window_start_s``, ``n_d_mean_rpm``, ``n_d_min_rpm``, ``n_d_max_rpm``,
        ``load_mean_nm``) and the angle channels ``phi_in_meas`` (and ``phi_out_meas``
        with an output encoder), (sample, time) [rad]; and its number of windows.
    """
    cfg = plan.config
    ch, amp = cfg.chain, cfg.acquisition.amplifier
    fs = ch.sample_rate_hz
    q = 1 if amp is None else amp.oversample
    n_t = int(round(ch.window_s * fs))
    n_lead = 0 if amp is None else amp.lead_samples(fs)
    ss = np.random.SeedSequence(int(cfg.seed), spawn_key=(shard.gear, shard.speed_index))
    rng_start, _, rng_noise = (np.random.default_rng(s) for s in ss.spawn(3))
    mo = profile_motion(plan, shard, rng_start)
    res, starts = mo.res, mo.starts
    chain = SimulationChain.from_influences(layout_for(cfg, plan.gear(shard.gear)),
                                            influences, cfg.chain)
    n_v, n_w = len(shard.windows), starts.size
    # the cut of each window, with n_lead samples of history on each side
    n_cut = q * (n_t + 2 * n_lead) if amp is not None else n_t
    idx = q * (starts - n_lead)[:, None] + np.arange(n_cut)[None, :]  # (W, n_cut)
    t_fine = np.arange(n_cut) / (fs * q)
    cuts = []
    for v in range(n_v):  # one variant at a time: the fine grid of a whole profile is long
        psi_f, t_f = fine_motion(res, q, np.array([v]))
        cut = chain.signals_batch([mo.params[v]], psi_f, t_f)[0][:, idx].transpose(1, 0, 2)
        if plan.sensor_effects:  # (W, 5, n_cut), the windows in time order
            cut = apply_sensor_effects(cut, t_fine, None, plan.sensor_effects,
                                       t_start_s=(starts - n_lead) / fs, psi=psi_f[0][idx])
        if amp is not None:
            cut = acquire(cut, amp, rng_noise, n_lead)
        cuts.append(cut.astype(np.float32))
    win = starts[:, None] + np.arange(n_t)[None, :]  # (W, n_t) at the data rate

    def per_window(x: np.ndarray) -> np.ndarray:  # (V, n_rec) -> (V · W, n_t)
        return x[:, win].reshape(n_v * n_w, n_t)

    w_d = np.broadcast_to(res.w_d[win] * 60 / (2 * np.pi), (n_v, n_w, n_t)).reshape(-1, n_t)
    load = per_window(res.load_nm)
    p_in, p_out = per_window(res.p_in).mean(axis=1), per_window(res.p_out).mean(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        eff = np.where(p_in != 0, p_out / np.where(p_in != 0, p_in, 1.0), np.nan)
    wins = [shard.windows[v] for v in range(n_v) for _ in range(n_w)]
    meta = {
        "gear": np.array([w.gear for w in wins]),
        "fault": np.array([w.fault for w in wins]),
        "variant": np.array([w.variant for w in wins]),
        "severity": np.array([w.severity for w in wins]),
        "position_deg": np.array([w.position_deg for w in wins]),
        "n_in_rpm": w_d.mean(axis=1),
        "t_out_nm": load.mean(axis=1),
        "disturbed": np.zeros(len(wins), bool),
        "reference": np.array([w.reference for w in wins]),
        "efficiency": eff,
        "n_in_mean_rpm": per_window(res.states[1]).mean(axis=1) * 60 / (2 * np.pi),
        "t_out_mean_nm": per_window(res.t_out).mean(axis=1),
    }
    extra = {
        "window_start_s": (np.tile(starts / fs, n_v), "s"),
        "n_d_mean_rpm": (w_d.mean(axis=1), "rpm"),
        "n_d_min_rpm": (w_d.min(axis=1), "rpm"),
        "n_d_max_rpm": (w_d.max(axis=1), "rpm"),
        "load_mean_nm": (load.mean(axis=1), "N m"),
    }
    angles = cfg.profile.angles
    enc = angles.output_encoder()
    meas = measure_angles(per_window(res.states[0]), per_window(res.states[2]),
                          input_sensor=angles.input_sensor(), output_encoder=enc)
    return _profile_dataset(plan, shard, np.concatenate(cuts), meta, extra, meas), len(wins)


def _profile_dataset(plan: DatasetPlan, shard: ShardSpec, strain32: np.ndarray, meta: dict,
                     extra: dict, meas: dict):
    """The profile shard as a schema-v1 dataset: signals (sample, 5, time) float32, the
    per-window ``meta`` of every data set, the profile's ``extra`` per-window variables
    (name -> (values, units)) and the angle channels ``meas`` (name -> (sample, time)
    [rad]), all of them in its ``content_sha256``."""
    cfg, fs = plan.config, plan.config.chain.sample_rate_hz
    h = hashlib.sha256(strain32.tobytes())
    for k in sorted(meta):
        h.update(np.ascontiguousarray(meta[k]).astype(str if k == "fault" else meta[k].dtype)
                 .tobytes())
    for k in sorted(extra):
        h.update(np.ascontiguousarray(extra[k][0]).tobytes())
    for k in sorted(meas):
        h.update(np.ascontiguousarray(meas[k]).tobytes())
    attrs = {"config": plan.as_dict(), "seed": int(cfg.seed), "shard": shard.name,
             "content_sha256": h.hexdigest(), "package_version": package_version(),
             "git_revision": git_revision(), "sample_rate_hz": fs}
    ds = dsio.make_dataset(strain32, np.arange(strain32.shape[-1]) / fs, meta, attrs)
    for k, (v, units) in extra.items():
        ds[k] = ("sample", v, {"units": units})
    for k, v in meas.items():
        ds[f"{k}_meas"] = (("sample", "time"), v, {"units": "rad"})
    return ds


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


def run_shard(plan: DatasetPlan, shard: ShardSpec, out_dir: str | os.PathLike,
              influences: dict[tuple | None, Influence]) -> dict:
    """Simulate and write one shard atomically, then its sidecar; return the sidecar."""
    t0 = time.perf_counter()
    ds, n = simulate_shard(plan, shard, influences)
    path = Path(out_dir) / shard.name
    sha = dsio.write_shard(ds, path)
    side = {"sha256": sha, "n_samples": int(n), "config_hash": plan.config_hash,
            "content_sha256": ds.attrs["content_sha256"]}
    dsio.atomic_write_json(path.with_suffix(".json"), side)
    log.info("shard %s: %d windows in %.1f s", shard.name, n, time.perf_counter() - t0)
    return side


__all__ = ["gear_influences", "influences_for", "simulate_shard", "run_shard", "fine_motion",
           "diverged", "simulate_motions", "synthesise", "record", "assemble", "Motions",
           "ProfileMotion", "profile_motion", "simulate_profile_shard"]
