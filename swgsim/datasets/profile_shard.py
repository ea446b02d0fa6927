"""A profile data set's shard: one gear's variants simulated along the operating profile
(``dataset.profile``) and cut into windows.

Each variant of a gear is simulated once along the whole profile (:func:`profile_motion`,
:func:`swgsim.gear.profile_dynamics.simulate_profile`) and its windows are cut from that
motion at the data set's window starts; the angle channels (:mod:`swgsim.sensing.angles`)
are recorded with every window.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swgsim.datasets import steps
from swgsim.datasets.config import gear_params, layout_for
from swgsim.datasets.plan import DatasetPlan, ShardSpec
from swgsim.datasets.schema import make_dataset
from swgsim.gear import profile_dynamics
from swgsim.gear.chain import SimulationChain
from swgsim.gear.faults import ChainParams
from swgsim.gear.influence import Influence
from swgsim.sensing.acquisition import acquire, start_angles
from swgsim.sensing.angles import measure_angles
from swgsim.sensing.effects import apply_sensor_effects

__all__ = ["ProfileMotion", "profile_motion", "simulate_profile_shard"]


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
    ch = cfg.chain
    fs, _, n_t, n_lead = steps.sampling(cfg)
    healthy = gear_params(cfg, plan.gears[shard.gear])
    if rng_start is None:
        rng_start = steps.shard_streams(plan, shard)[0]
    # the wave generator's angle as drawn, the output (the link's pose) within one
    # wave-generator revolution / N of its zero: the profile's load acts on that pose
    phi0 = np.mod(start_angles(cfg.acquisition, len(shard.windows), rng_start,
                               healthy.gear.ratio), 2 * np.pi)
    params = steps.window_params(plan, shard, healthy)
    starts = np.round(np.asarray(shard.window_starts_s) * fs).astype(np.int64)
    n_rec = int(starts.max()) + n_t + n_lead + 1
    res = profile_dynamics.simulate_profile([p.gear for p in params], plan.profile, phi0, fs,
                                    n_rec / fs, ch.substeps, cfg.profile.feedforward)
    if not res.success:
        raise ValueError(steps.diverged(
            plan, f"shard {shard.name} (gear {shard.gear}, profile)", res.message))
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
    cfg, amp = plan.config, plan.config.acquisition.amplifier
    fs, q, n_t, n_lead = steps.sampling(cfg)
    rng_start, _, rng_noise = steps.shard_streams(plan, shard)
    mo = profile_motion(plan, shard, rng_start)
    res, starts = mo.res, mo.starts
    chain = SimulationChain.from_influences(layout_for(cfg, plan.gears[shard.gear]),
                                            influences, cfg.chain)
    n_v, n_w = len(shard.windows), starts.size
    # the cut of each window, with n_lead samples of history on each side
    n_cut = q * (n_t + 2 * n_lead) if amp is not None else n_t
    idx = q * (starts - n_lead)[:, None] + np.arange(n_cut)[None, :]  # (W, n_cut)
    t_fine = np.arange(n_cut) / (fs * q)
    cuts = []
    for v in range(n_v):  # one variant at a time: the fine grid of a whole profile is long
        psi_f, t_f = steps.fine_motion(res, q, np.array([v]))
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
        **steps.window_meta(wins),
        "n_in_rpm": w_d.mean(axis=1),
        "t_out_nm": load.mean(axis=1),
        "disturbed": np.zeros(len(wins), bool),
        "efficiency": eff,
        "n_in_mean_rpm": per_window(res.states[1]).mean(axis=1) * 60 / (2 * np.pi),
        "t_out_mean_nm": per_window(res.t_out).mean(axis=1),
    }
    extra = {"window_start_s": (np.tile(starts / fs, n_v), "s"),  # name: (values, units)
             "n_d_mean_rpm": (w_d.mean(axis=1), "rpm"), "n_d_min_rpm": (w_d.min(axis=1), "rpm"),
             "n_d_max_rpm": (w_d.max(axis=1), "rpm"), "load_mean_nm": (load.mean(axis=1), "N m")}
    angles = cfg.profile.angles
    meas = measure_angles(per_window(res.states[0]), per_window(res.states[2]),
                          input_sensor=angles.input_sensor(),
                          output_encoder=angles.output_encoder())
    return _profile_dataset(plan, shard, np.concatenate(cuts), meta, extra, meas), len(wins)


def _profile_dataset(plan: DatasetPlan, shard: ShardSpec, strain32: np.ndarray, meta: dict,
                     extra: dict, meas: dict):
    """The profile shard as a schema-v1 dataset: signals (sample, 5, time) float32, the
    per-window ``meta`` of every data set, the profile's ``extra`` per-window variables
    (name -> (values, units)) and the angle channels ``meas`` (name -> (sample, time)
    [rad]), all of them in its ``content_sha256``."""
    attrs = steps.shard_attrs(plan, shard, strain32, meta,
                              *(extra[k][0] for k in sorted(extra)),
                              *(meas[k] for k in sorted(meas)))
    ds = make_dataset(strain32, np.arange(strain32.shape[-1]) / attrs["sample_rate_hz"], meta,
                      attrs)
    for k, (v, units) in extra.items():
        ds[k] = ("sample", v, {"units": units})
    for k, v in meas.items():
        ds[f"{k}_meas"] = (("sample", "time"), v, {"units": "rad"})
    return ds
