"""Memory a generation run will need, checked before any work, as disk space is.

Every figure is arithmetic on the config (nothing per window is built) and was measured
with ``tracemalloc`` (NumPy's buffers included) around
:func:`swgsim.datasets.generate.simulate_shard` by ``scripts/bench_shard_memory.py``
(2026-11, NumPy 2); the estimate stays within a factor 2 of the measured peak on every
preset measured there.

*A grid or profile shard* is simulated whole in one worker: its windows' motions, their
gauge signals on the amplifier's fine grid (``oversample`` samples per sample) and the
recorded signals. The peak grows with the fine samples of the shard, windows × n_t ×
oversample: 56 B per fine sample on the bench and robot_joint shards (2,166 windows,
motions shared by many windows), 121-122 B on tiny_bench (100 windows, fewer shared); the
estimate takes :data:`BYTES_PER_FINE_SAMPLE` between them, plus :data:`SHARD_FIXED_BYTES`.

*A life's shard* (:mod:`swgsim.datasets.life`) holds its records and makes its windows
from them block by block; the peak is the larger of two phases, plus the records kept and
:data:`SHARD_FIXED_BYTES`:

- synthesising records, :data:`~swgsim.datasets.records.SIGNAL_GROUP` at once on the fine
  grid, each one wave-generator revolution at the duty cycle's slowest input speed plus a
  window (along a profile: the whole profile, one record at a time):
  :data:`BYTES_PER_RECORD_FINE_SAMPLE` per fine sample (tiny_life: 75 MiB for four
  records of 62,400 fine samples, of which about 20 MiB fixed);
- cutting windows: :data:`BYTES_PER_BLOCK_SAMPLE` per sample and bridge of the block in
  hand (:data:`~swgsim.datasets.life.BLOCK` windows, float64 working copies) and
  :data:`BYTES_PER_LIFE_SAMPLE` per sample and bridge of the whole life (its float32
  signals, their concatenation and the content hash).

The records are bounded by the duty points × the severity levels (plus the healthy one) ×
the payload factors (plus the commanded one).
"""

from __future__ import annotations

import math

from swgsim.datasets.config import gear_params
from swgsim.datasets.life import BLOCK, LifeSimulator
from swgsim.datasets.plan import DatasetPlan, ShardSpec
from swgsim.datasets.records import SIGNAL_GROUP
from swgsim.datasets.schedule import duty_cycle
from swgsim.files.inputs import available_memory

#: Peak bytes of simulating a grid or profile shard per fine sample (module docstring:
#: 56-122 measured).
BYTES_PER_FINE_SAMPLE = 85
#: Bytes per fine sample of a record being synthesised (its motion, gauge signals and
#: measurement chain).
BYTES_PER_RECORD_FINE_SAMPLE = 220
#: Bytes per sample and bridge of a life's block of windows in hand.
BYTES_PER_BLOCK_SAMPLE = 36
#: Bytes per sample and bridge of a life's windows, all of them.
BYTES_PER_LIFE_SAMPLE = 15
#: Bytes per data-rate sample of a record kept (float32 signals of 5 bridges, four
#: cumulative sums in float64).
BYTES_PER_RECORD_SAMPLE = 5 * 4 + 4 * 8
#: What a shard's worker holds whatever its size: the gear's truss influences and chain.
SHARD_FIXED_BYTES = 20 << 20
#: Memory left to everything else (the interpreter, the influences, the parent) [bytes].
RESERVE_BYTES = 1 << 30

__all__ = ["BYTES_PER_BLOCK_SAMPLE", "BYTES_PER_FINE_SAMPLE", "BYTES_PER_LIFE_SAMPLE",
           "BYTES_PER_RECORD_FINE_SAMPLE", "BYTES_PER_RECORD_SAMPLE", "SHARD_FIXED_BYTES",
           "check_memory", "life_records", "shard_memory"]


def _oversample(plan: DatasetPlan) -> tuple[int, int]:
    """The converter's oversampling and its filter's lead [samples] (1 and 0 without)."""
    amp, fs = plan.config.acquisition.amplifier, plan.config.chain.sample_rate_hz
    return (1, 0) if amp is None else (int(amp.oversample), int(amp.lead_samples(fs)))


def life_records(plan: DatasetPlan) -> tuple[int, int]:
    """Most records a life's shard holds and the data-rate samples of each.

    Returns
    -------
    (int, int)
        Records: duty points (one along a profile) × (severity levels + 1) × (payload
        factors + 1), × the viscous factors simulated where the friction acts in the
        dynamics (the rungs its first gear's life uses,
        :data:`~swgsim.datasets.life.VISCOUS_LADDER`); samples: one wave-generator
        revolution at the slowest input speed plus a window (the whole profile along one).
    """
    cfg = plan.config
    life, ch = cfg.life, cfg.chain
    fs = ch.sample_rate_hz
    n_t = int(round(ch.window_s * fs))
    f = life.fault
    levels = 1 if f.fault == "healthy" else (2 if f.growth == "step"
                                             else int(life.severity_levels) + 1)
    payloads = 1 + (len(life.conditions.payload) if life.conditions is not None else 0)
    if life.conditions is not None and life.conditions.viscous_in_dynamics:
        sim = LifeSimulator(plan, int(cfg.gears[0].id), life)  # its conditions, no record
        levels *= len({float(v) for v in sim.rungs[sim.rung_weights != 0]})
    if plan.profile is not None:
        return levels, int(math.ceil(plan.profile.speed.duration_s * fs)) + n_t
    ops = cfg.operating_points
    duty = duty_cycle(life, list(ops.n_in_rpm), list(ops.t_out_nm))
    n_low = min(abs(d.n_in_rpm) for d in duty)
    ratio = max(float(gear_params(cfg, g).gear.ratio) for g in cfg.gears)
    return (len({(d.n_in_rpm, d.t_out_nm) for d in duty}) * levels * payloads,
            int(math.ceil(ratio * 60.0 / n_low * fs)) + n_t)


def _life_memory(plan: DatasetPlan, shard: ShardSpec) -> int:
    """Estimated peak of a life's shard [bytes] (module docstring)."""
    ch = plan.config.chain
    q, n_lead = _oversample(plan)
    n_t = int(round(ch.window_s * ch.sample_rate_hz))
    n_rec, n_samples = life_records(plan)
    group = 1 if plan.profile is not None else min(n_rec, SIGNAL_GROUP)
    synth = BYTES_PER_RECORD_FINE_SAMPLE * group * (n_samples + 2 * n_lead) * q
    cut = 5 * n_t * (BYTES_PER_BLOCK_SAMPLE * min(shard.n_windows, BLOCK)
                     + BYTES_PER_LIFE_SAMPLE * shard.n_windows)
    kept = BYTES_PER_RECORD_SAMPLE * n_rec * n_samples
    return SHARD_FIXED_BYTES + kept + max(synth, cut)


def shard_memory(plan: DatasetPlan, shard: ShardSpec) -> int:
    """Estimated peak memory of simulating one shard [bytes] (module docstring).

    Parameters
    ----------
    plan : DatasetPlan
    shard : ShardSpec

    Returns
    -------
    int
    """
    if plan.kind == "life":
        return _life_memory(plan, shard)
    ch = plan.config.chain
    q, _ = _oversample(plan)
    n_t = int(round(ch.window_s * ch.sample_rate_hz))
    return SHARD_FIXED_BYTES + BYTES_PER_FINE_SAMPLE * shard.n_windows * n_t * q


def check_memory(plan: DatasetPlan, shards: list[ShardSpec], n_workers: int,
                 available: int | None = None) -> None:
    """Refuse a run whose largest shards, one per worker at once, cannot fit in memory.

    Parameters
    ----------
    plan : DatasetPlan
    shards : list of ShardSpec
        The shards still to simulate.
    n_workers : int
        Worker processes simulating shards at once.
    available : int, optional
        Available memory [bytes]; default :func:`available_memory` (no check where it is
        unknown).

    Raises
    ------
    ValueError
        One line naming the keys that drive the estimate (sample rate, window length,
        oversampling, windows of the largest shard, workers), the estimate and the memory
        available.
    """
    if not shards:
        return
    avail = available_memory() if available is None else available
    if avail is None:
        return
    big = sorted(shards, key=lambda s: s.n_windows, reverse=True)[:max(1, int(n_workers))]
    need = sum(shard_memory(plan, s) for s in big) + RESERVE_BYTES
    if need <= avail:
        return
    ch = plan.config.chain
    q, _ = _oversample(plan)
    gib = float(1 << 30)
    what = (f"dataset.life.hours={plan.config.life.hours:g} h at dataset.life.interval_min="
            f"{plan.config.life.interval_min:g} min ({big[0].n_windows} windows)"
            if plan.kind == "life" else f"{big[0].n_windows} windows in the largest shard")
    raise ValueError(
        f"not enough memory: dataset.chain.sample_rate_hz={ch.sample_rate_hz:g} Hz x "
        f"dataset.chain.window_s={ch.window_s:g} s x {what} ({big[0].name}) x oversample "
        f"{q} need about {shard_memory(plan, big[0]) / gib:.3g} GiB per shard, "
        f"{need / gib:.3g} GiB with {len(big)} worker(s) at once; {avail / gib:.3g} GiB "
        "available. Lower the sample rate, the window, the windows (or the life's hours) "
        "or n_jobs")
