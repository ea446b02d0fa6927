"""Benchmark the memory estimate of a shard against its measured peak.

For each data-set preset (with optional overrides), plans the data set, simulates its
largest shard in this process under ``tracemalloc`` (NumPy's buffers included) and prints
the measured peak beside :func:`swgsim.datasets.resources.shard_memory`'s estimate and
their ratio. The estimate is what a generation run checks against the memory available
before any work (issue 35: within a factor 2 of the measured peak). The last line is one
JSON object with every row.

    python scripts/bench_shard_memory.py                     # tiny, tiny_life, tiny_motion_life
    python scripts/bench_shard_memory.py --preset tiny_life --set life.hours=24.0
"""

from __future__ import annotations

import argparse
import json
import time
import tracemalloc

from swgcli import dataset_preset
from swgsim.datasets.generate import simulate_shard
from swgsim.datasets.plan import plan
from swgsim.datasets.resources import shard_memory
from swgsim.datasets.steps import gear_influences


def _override(cfg: dict, item: str) -> None:
    """Apply one ``a.b.c=value`` (value parsed as JSON) to a preset's dict."""
    key, _, raw = item.partition("=")
    *path, last = key.split(".")
    d = cfg
    for k in path:
        d = d[k]
    d[last] = json.loads(raw)


def measure(preset: str, sets: list[str]) -> dict:
    """Estimate and measured peak of simulating the preset's largest shard [bytes]."""
    cfg = dataset_preset(preset)
    for s in sets:
        _override(cfg, s)
    p = plan(cfg)
    shard = max(p.shards, key=lambda s: s.n_windows)
    est = shard_memory(p, shard)
    infl = gear_influences(p, [shard])[shard.gear]  # as a worker gets them, outside the peak
    tracemalloc.start()
    t0 = time.perf_counter()
    ds, _ = simulate_shard(p, shard, infl)
    wall = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    del ds
    return {"preset": preset, "set": sets, "kind": p.kind, "shard": shard.name,
            "windows": shard.n_windows, "estimate_mib": est / 2**20,
            "peak_mib": peak / 2**20, "ratio": est / peak, "wall_s": wall}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--preset", action="append", help="data-set preset (repeatable)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=JSON",
                    help="override of the preset, e.g. life.hours=24.0 (repeatable)")
    a = ap.parse_args()
    rows = [measure(pr, a.set) for pr in (a.preset or ["tiny", "tiny_life",
                                                       "tiny_motion_life"])]
    for r in rows:
        print(f"{r['preset']:<18} {r['kind']:<8} {r['windows']:>6} windows  estimate "
              f"{r['estimate_mib']:8.1f} MiB  peak {r['peak_mib']:8.1f} MiB  "
              f"ratio {r['ratio']:.2f}  ({r['wall_s']:.1f} s)")
    print(json.dumps(rows))


if __name__ == "__main__":
    main()
