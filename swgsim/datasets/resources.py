"""Memory a generation run will need, checked before any work, as disk space is.

A shard is simulated whole in one worker: its windows' motions, their gauge signals on the
amplifier's fine grid (``oversample`` samples per sample) and the recorded signals. The
peak grows with the fine samples of the shard, windows × n_t × oversample; measured with
``tracemalloc`` around :func:`swgsim.datasets.generate.simulate_shard` on this project's presets
(2026-11, NumPy 2): 56 B per fine sample on the bench and robot_joint shards (2,166
windows), 121-122 B on tiny_bench (100 windows, fewer shared motions; the same at 10 and
20 kHz and at 0.12 and 0.48 s), 16 B on a gear life's shard (bench_life). The estimate
takes :data:`BYTES_PER_FINE_SAMPLE` for every shard, above all of them.
"""

from __future__ import annotations

import os

from swgsim.datasets.plan import DatasetPlan, ShardSpec

#: Peak bytes of simulating a shard per fine sample (module docstring: at most 122 measured).
BYTES_PER_FINE_SAMPLE = 130
#: Memory left to everything else (the interpreter, the influences, the parent) [bytes].
RESERVE_BYTES = 1 << 30

__all__ = ["BYTES_PER_FINE_SAMPLE", "available_memory", "check_memory", "shard_memory"]


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
    ch = plan.config.chain
    amp = plan.config.acquisition.amplifier
    q = 1 if amp is None else int(amp.oversample)
    n_t = int(round(ch.window_s * ch.sample_rate_hz))
    return BYTES_PER_FINE_SAMPLE * shard.n_windows * n_t * q


def available_memory() -> int | None:
    """Memory available to new allocations [bytes]: ``MemAvailable`` of /proc/meminfo
    (Linux), else the free physical pages (``os.sysconf``); None where neither is known."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


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
    ch, amp = plan.config.chain, plan.config.acquisition.amplifier
    q = 1 if amp is None else int(amp.oversample)
    gib = float(1 << 30)
    raise ValueError(
        f"not enough memory: dataset.chain.sample_rate_hz={ch.sample_rate_hz:g} Hz x "
        f"dataset.chain.window_s={ch.window_s:g} s x {big[0].n_windows} windows in the "
        f"largest shard ({big[0].name}) x oversample {q} need about "
        f"{shard_memory(plan, big[0]) / gib:.3g} GiB per shard, {need / gib:.3g} GiB with "
        f"{len(big)} worker(s) at once; {avail / gib:.3g} GiB available. Lower the sample "
        "rate, the window, the windows per operating point or n_jobs")
