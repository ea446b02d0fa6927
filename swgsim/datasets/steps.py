"""Steps every shard runner shares: the gears' influences, the random streams, the windows'
parameters and metadata, the motion on a finer grid, a divergence's message, the attributes.
"""

from __future__ import annotations

import hashlib

import numpy as np

from swgsim.base.lazy import lazy_module
from swgsim.datasets.config import DatasetConfig, layout_for
from swgsim.datasets.plan import DatasetPlan, ShardSpec, WindowSpec
from swgsim.files.provenance import git_revision, package_version
from swgsim.gear import dynamics
from swgsim.gear.dynamics import rt1_size20
from swgsim.gear.faults import NO_ROOT_CRACK, ChainParams, apply_fault
from swgsim.gear.flexspline import FlexsplineGeometry, TrussModel
from swgsim.gear.influence import Influence, InfluenceSolver

interpolate = lazy_module("scipy.interpolate")

__all__ = ["diverged", "fine_motion", "gear_influences", "influences_for", "shard_attrs",
           "sampling", "shard_streams", "unique_index", "window_meta", "window_params"]


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
    update per root-crack structure (:class:`swgsim.gear.influence.InfluenceSolver`). Computed
    once in the calling process; the shard workers need no truss.

    Parameters
    ----------
    plan : DatasetPlan
    gear_ids : list of int
    crack_keys : iterable of (position_deg, severity)
        :meth:`swgsim.gear.faults.ChainParams.root_crack_key` of each cracked structure.

    Returns
    -------
    dict
        gear id -> {(position_deg, severity): Influence}, ``NO_ROOT_CRACK`` healthy.
    """
    solver = InfluenceSolver(TrussModel(FlexsplineGeometry(), plan.config.mesh))
    out = {}
    for gid in gear_ids:
        lay = layout_for(plan.config, plan.gears[gid])
        adj = solver.adjoint(lay)
        healthy = solver.coefficients(*adj)
        inf = {NO_ROOT_CRACK: healthy}
        for pos, sev in sorted(crack_keys):
            inf[(pos, sev)] = solver.root_crack_at(lay, pos, sev, adjoint=adj, healthy=healthy)
        out[int(gid)] = inf
    return out


def sampling(cfg: DatasetConfig) -> tuple[float, int, int, int]:
    """The data rate fs [Hz], the amplifier's fine samples per sample q (1 without one), a
    window's samples n_t and the amplifier's samples of history n_lead (0 without one)."""
    amp, fs = cfg.acquisition.amplifier, cfg.chain.sample_rate_hz
    return (fs, 1 if amp is None else amp.oversample, int(round(cfg.chain.window_s * fs)),
            0 if amp is None else amp.lead_samples(fs))


def shard_streams(plan: DatasetPlan, shard: ShardSpec) -> list[np.random.Generator]:
    """The shard's random streams of start angles, eq. (10) draws and amplifier noise."""
    ss = np.random.SeedSequence(int(plan.config.seed), spawn_key=(shard.gear, shard.speed_index))
    return [np.random.default_rng(s) for s in ss.spawn(3)]


def window_params(plan: DatasetPlan, shard: ShardSpec, healthy: ChainParams
                  ) -> list[ChainParams]:
    """The chain parameters of each of the shard's windows: ``healthy`` with the window's
    fault (at position 0 where the window has none)."""
    return [apply_fault(healthy, w.fault, w.severity,
                        0.0 if np.isnan(w.position_deg) else w.position_deg,
                        faults=plan.faults)
            for w in shard.windows]


def window_meta(wins: list[WindowSpec]) -> dict[str, np.ndarray]:
    """The per-window variables the windows' specs hold: gear, fault, variant, severity,
    position_deg, reference; each shape (len(wins),)."""
    return {k: np.array([getattr(w, k) for w in wins])
            for k in ("gear", "fault", "variant", "severity", "position_deg", "reference")}


def shard_attrs(plan: DatasetPlan, shard: ShardSpec, strain32: np.ndarray, meta: dict,
                *more: np.ndarray) -> dict:
    """A simulated shard's attributes: config, seed, shard, sample rate, provenance and
    ``content_sha256`` of the float32 signals, the per-window ``meta`` in sorted order
    (``fault`` as text) and the arrays ``more`` in turn."""
    h = hashlib.sha256(strain32.tobytes())
    for k in sorted(meta):
        h.update(np.ascontiguousarray(meta[k]).astype(str if k == "fault" else meta[k].dtype)
                 .tobytes())
    for v in more:
        h.update(np.ascontiguousarray(v).tobytes())
    return {"config": plan.plain, "seed": int(plan.config.seed), "shard": shard.name,
            "content_sha256": h.hexdigest(), "package_version": package_version(),
            "git_revision": git_revision(), "sample_rate_hz": plan.config.chain.sample_rate_hz}


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
    t = res.time
    tf = np.arange(q * (t.size - 1)) * (t[1] - t[0]) / q
    dpsi = res.states[1][rows] - res.states[3][rows]
    return (interpolate.CubicHermiteSpline(t, psi, dpsi, axis=1)(tf),
            interpolate.CubicSpline(t, t_out, axis=1)(tf))


def unique_index(keys: list) -> tuple[np.ndarray, np.ndarray]:
    """First index of each distinct key, and per item the position of its key among them.

    Parameters
    ----------
    keys : list of hashable, length V

    Returns
    -------
    first : ndarray of int, shape (U,)
        Index of the first item of each distinct key, in order of appearance.
    inverse : ndarray of int, shape (V,)
        Row of ``first`` of each item.
    """
    pos: dict = {}
    first: list[int] = []
    inverse = np.empty(len(keys), np.int64)
    for i, k in enumerate(keys):
        if k not in pos:
            pos[k] = len(first)
            first.append(i)
        inverse[i] = pos[k]
    return np.asarray(first, np.int64), inverse
