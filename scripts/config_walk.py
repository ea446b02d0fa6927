"""Follow the data-set config through the calls of one generation, and count the climbs.

Runs the generation of a preset in this process (``n_jobs=1``), with its typed config
built as ``swgsim-generate`` builds it, under a profiler hook, and records every call of
a project function that receives the config: the :class:`DatasetConfig` itself, one of
its parts (any dataclass object reachable from it) or an object that holds one of these
(a plan, a record bank, and so on).

- *stops*: the functions so reached (each counted once), in *modules*;
- *climbs*: the calls among them from a module into a module on a higher floor, i.e. a
  lower module calling back up. A module's floor is the length of its longest chain of
  import-time imports down to a module that imports nothing of the project
  (``scripts/import_graph.py``; imports inside functions and under ``TYPE_CHECKING`` are
  left out: they are how a lower module reaches back up without Python failing).
  Counted as distinct (caller, callee) pairs and as calls;
- *entries*: how often the walk enters each module from another one.

The same definitions hold for any layout, so the counts of two commits compare.

    python scripts/config_walk.py                    # tiny, tiny_life, tiny_motion_life
    python scripts/config_walk.py --preset tiny --list
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
from collections import Counter
from functools import cache
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import import_graph  # noqa: E402  (the project's import graph, from the source)

PACKAGES = ("swgsim", "swgcal", "learn")


def floors() -> dict[str, int]:
    """Module -> floor (longest chain of import-time imports down to a leaf)."""
    mods = import_graph.modules()
    graph = {m: import_graph.imports(m, f, set(mods), top_level=True)
             for m, f in mods.items()}
    comp = {m: c[0] for c in import_graph.cycles(graph) for m in c}
    rep = {m: comp.get(m, m) for m in graph}
    dag: dict[str, set[str]] = {}
    for m, ds in graph.items():
        dag.setdefault(rep[m], set()).update(rep[d] for d in ds if rep[d] != rep[m])

    @cache
    def depth(r: str) -> int:
        return 1 + max((depth(d) for d in dag.get(r, ())), default=-1)

    return {m: depth(rep[m]) for m in graph}


def _reachable(cfg) -> set[int]:
    """ids of the config and of every dataclass object inside it."""
    seen, stack = set(), [cfg]
    while stack:
        o = stack.pop()
        if id(o) in seen:
            continue
        if dataclasses.is_dataclass(o) and not isinstance(o, type):
            seen.add(id(o))
            stack.extend(getattr(o, f.name) for f in dataclasses.fields(o))
        elif isinstance(o, (list, tuple)):
            stack.extend(o)
        elif isinstance(o, dict):
            stack.extend(o.values())
    return seen


def walk(preset: str) -> list[tuple[str, str, str, str]]:
    """(caller module, caller, callee module, callee) of every call that carries the
    config, in call order (the caller empty when it is not project code)."""
    from omegaconf import OmegaConf

    from swgcli import compose_app
    from swgsim.datasets.generate import generate  # the data-set generation the app calls

    app = compose_app("generate", [f"dataset={preset}", "out_dir=unused", "n_jobs=1"])
    cfg = OmegaConf.to_object(app.dataset)  # the typed DatasetConfig, as the app builds it
    ids = _reachable(cfg)
    calls: list[tuple[str, str, str, str]] = []
    root = str(import_graph.ROOT)

    kept = []  # the holders, alive: a freed holder's id, reused, would count another

    def holds(v) -> bool:
        if id(v) in ids:
            return True
        d = getattr(v, "__dict__", None)
        if isinstance(d, dict) and any(id(x) in ids for x in d.values()):
            ids.add(id(v))  # a holder (a plan, a record bank): its holders count too
            kept.append(v)
            return True
        return False

    def ours(frame) -> str:
        mod = frame.f_globals.get("__name__", "") if frame is not None else ""
        ok = frame is not None and frame.f_code.co_filename.startswith(root)
        return mod if ok and mod.startswith(PACKAGES) else ""

    def hook(frame, event, arg):
        if event != "call" or not ours(frame):
            return
        code = frame.f_code
        args = [frame.f_locals.get(n) for n in code.co_varnames[:code.co_argcount
                                                                + code.co_kwonlyargcount]]
        if any(holds(a) for a in args):
            back = frame.f_back
            calls.append((ours(back), back.f_code.co_qualname if ours(back) else "",
                          ours(frame), code.co_qualname))

    with tempfile.TemporaryDirectory() as tmp:
        sys.setprofile(hook)
        try:
            generate(cfg, Path(tmp) / preset, n_jobs=1, progress=False)
        finally:
            sys.setprofile(None)
    return calls


def summary(calls: list[tuple[str, str, str, str]], floor: dict[str, int]) -> dict:
    """Counts of a walk (module docstring)."""
    stops = list(dict.fromkeys((m, f) for _, _, m, f in calls))
    up = [c for c in calls if c[0] and floor.get(c[2], 0) > floor.get(c[0], 0)]
    mods = [m for _, _, m, _ in calls]
    entries = Counter(b for a, b in zip(mods, mods[1:], strict=False) if a != b)
    return {"stops": len(stops), "modules": len({m for m, _ in stops}),
            "climbs": sorted(set(up)), "climb_calls": len(up), "calls": len(calls),
            "entries": entries}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", action="append", help="data-set presets (default: three)")
    ap.add_argument("--list", action="store_true", help="print every climb")
    args = ap.parse_args(argv)
    floor = floors()
    for preset in args.preset or ["tiny", "tiny_life", "tiny_motion_life"]:
        s = summary(walk(preset), floor)
        top = ", ".join(f"{m} {n}" for m, n in s["entries"].most_common(3))
        print(f"{preset}: {s['stops']} stops in {s['modules']} modules; climbs: "
              f"{len(s['climbs'])} caller-callee pairs, {s['climb_calls']} of {s['calls']} "
              f"calls; most entered: {top}")
        if args.list:
            for a, fa, b, fb in s["climbs"]:
                print(f"    {a}.{fa} ({floor.get(a, 0)}) -> {b}.{fb} ({floor.get(b, 0)})")


if __name__ == "__main__":
    main()
