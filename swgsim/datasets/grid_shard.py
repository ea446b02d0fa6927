"""A grid data set's shard: every window of one gear at one input speed.

Takes a checked :class:`~swgsim.datasets.plan.DatasetPlan` and checks nothing again. The
steps: the gear's influences (computed once in the parent,
:func:`swgsim.datasets.steps.gear_influences`), the dynamics of each distinct motion
(:func:`simulate_motions`), the gauge signals of each distinct window (:func:`synthesise`),
the measurement chain (:func:`record`: sensor effects, the bench amplifier), eq. (10)'s
disturbed twins and the metadata (:func:`assemble`). Randomness comes from three
independent streams of ``SeedSequence(seed, spawn_key=(gear, speed index))``: window
start angles, eq. (10) draws, amplifier noise; so the content depends neither on the
number of workers nor on the order of shards, and the eq. (10) draws of a window not on
the recording.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swgsim.datasets import steps
from swgsim.datasets.config import gear_params, layout_for
from swgsim.datasets.plan import DatasetPlan, ShardSpec, WindowSpec
from swgsim.datasets.schema import make_dataset
from swgsim.gear import dynamics
from swgsim.gear.chain import SimulationChain
from swgsim.gear.faults import ChainParams
from swgsim.gear.influence import Influence
from swgsim.sensing.acquisition import acquire, start_angles
from swgsim.sensing.disturbance import disturb
from swgsim.sensing.effects import apply_sensor_effects


def _motion_key(p: ChainParams, t_out_nm: float, phi0: float) -> tuple:
    """Windows with equal keys have the same dynamic motion (flexspline faults do not enter
    the I/O model, paper Table I)."""
    return (p.gear, float(t_out_nm), float(phi0))


def _signal_key(w: WindowSpec, phi0: float) -> tuple:
    """Windows with equal keys have the same clean signals (healthy copies, references)."""
    pos = None if np.isnan(w.position_deg) else float(w.position_deg)
    return (w.fault, float(w.severity), pos, float(w.t_out_nm), float(phi0))


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
    fs, _, n_t, _ = steps.sampling(plan.config)
    t_out = np.array([w.t_out_nm for w in shard.windows])
    m_idx, m_inv = steps.unique_index([_motion_key(p, t, a) for p, t, a
                                       in zip(params, t_out, phi0, strict=True)])
    # the window plus n_lead samples before and after it (history of the amplifier's
    # filter), and one more to interpolate the last fine sample
    n_rec = n_t + 2 * n_lead + (oversample > 1)
    res = dynamics.simulate([params[k].gear for k in m_idx], shard.n_in_rpm, t_out[m_idx],
                            phi0[m_idx], fs, n_rec / fs, ch.settle_s - n_lead / fs,
                            ch.substeps, friction_effects=plan.friction)
    if not res.success:
        bad = int(np.argmin(np.isfinite(res.states).all(axis=(0, 2))))  # first diverged
        w = shard.windows[m_idx[bad]]
        raise ValueError(steps.diverged(plan, f"shard {shard.name} (gear {shard.gear}, "
                                              f"{shard.n_in_rpm:g} rpm, {w.t_out_nm:g} N m, "
                                              f"fault {w.fault} severity {w.severity:g})",
                                        res.message))
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
    s_idx, s_inv = steps.unique_index([_signal_key(w, a) for w, a
                                       in zip(shard.windows, phi0, strict=True)])
    psi, t_act = steps.fine_motion(motions.res, oversample, motions.inverse[s_idx])
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
    fs, q, _, _ = steps.sampling(plan.config)
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
    fs = plan.config.chain.sample_rate_hz
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
        **steps.window_meta([wins[k] for k in order]),
        "n_in_rpm": np.full(order.size, shard.n_in_rpm),
        "t_out_nm": np.array([wins[k].t_out_nm for k in order]),
        "disturbed": disturbed,
        "efficiency": motions.efficiency[order],
        "n_in_mean_rpm": n_mean[order],
        "t_out_mean_nm": motions.t_mean_nm[order],
    }
    attrs = steps.shard_attrs(plan, shard, strain32, meta)
    return make_dataset(strain32, time_s, meta, attrs), order.size


def simulate_grid_shard(plan: DatasetPlan, shard: ShardSpec,
                        influences: dict[tuple | None, Influence]):
    """Simulate one shard of a grid data set; return (xarray.Dataset, n_windows).

    Parameters
    ----------
    plan : DatasetPlan
        The checked data set (:func:`swgsim.datasets.plan.plan`), neither a life nor a
        profile.
    shard : ShardSpec
    influences : dict
        This gear's influences (:func:`swgsim.datasets.steps.gear_influences`).

    The dataset holds the clean windows, their disturbed twins (eq. 10, same motion) and
    the reference windows, in that order. Each distinct motion is integrated once and each
    distinct window synthesised once (with ``acquisition.start: fixed`` the healthy copies
    and the flexspline faults share the healthy gear's motion); the result is the same as
    simulating every window on its own.
    """
    cfg = plan.config
    gear = plan.gears[shard.gear]
    amp = cfg.acquisition.amplifier
    _, q, n_t, n_lead = steps.sampling(cfg)
    chain = SimulationChain.from_influences(layout_for(cfg, gear), influences, cfg.chain)
    healthy = gear_params(cfg, gear)
    rng_start, rng_dist, rng_noise = steps.shard_streams(plan, shard)
    phi0 = start_angles(cfg.acquisition, len(shard.windows), rng_start, healthy.gear.ratio)
    params = steps.window_params(plan, shard, healthy)
    motions = simulate_motions(plan, shard, params, phi0, n_lead, q)
    sig = synthesise(chain, shard, params, phi0, motions, q)
    if amp is None:
        sig = sig[:, :, n_lead:n_lead + n_t]
    sig = record(plan, sig, motions.n_mean_rpm, n_lead, rng_noise)
    return assemble(plan, shard, sig, motions, rng_dist)


__all__ = ["Motions", "assemble", "record", "simulate_grid_shard", "simulate_motions",
           "synthesise"]
