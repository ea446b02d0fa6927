"""Power of the strain-side acceptance rule: planted effects found, clean data left alone.

For each seed, bench windows (2 operating points × 5 windows of 40 ms) are simulated
through the chain's standard path with their own random WG start angles
(``simulate_windows`` of the tests' ``tests/planted_strain.py``), white noise of
``noise_rel`` of the signal range (1 % by default) with its own seed, once with a planted
effect and once clean; both are calibrated (:mod:`swgcal.strain.problem`). A planted
effect is *found* when it is accepted and every planted parameter is recovered within
``rel_tol`` of its true value (relative values for gains and gauge angles,
``expected_values`` there); clean data are *left alone* when no effect is accepted.
Power = found seeds / seeds; the false-alarm side = 1 − left alone / seeds. Prints the
table (effect, planted parameter, true value, seeds found / seeds, median estimate, clean
seeds left alone / seeds, wall time) and, per seed, what was added and the planted
candidate's evidence. The last line is JSON.

    python scripts/strain_power.py [--seeds 10] [--effects gauge_misplacement_s2 ...]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from swgcal.loop import SelectionConfig
from swgcal.strain.model import StrainModel
from swgcal.strain.problem import build_problem, calibrate
from swgcal.strain.report import summarize
from swgsim.gear.chain import SimulationChain

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import planted_strain as syn  # noqa: E402  (the planted bench data, tests/planted_strain.py)

POWER_EFFECTS: dict[str, dict[str, Any]] = {
    "gauge_misplacement_s2": {
        "key": "gauge_misplacement",
        "sensor_effects": [{"name": "gauge_misplacement",
                            "params": {"delta_deg": {"s2": 1.5}}}],
        "check": {"delta_deg": [0.0, 0.0, 1.5, 0.0, 0.0]}},
    "gauge_misplacement_s1": {
        "key": "gauge_misplacement",
        "sensor_effects": [{"name": "gauge_misplacement",
                            "params": {"delta_deg": {"s1": 1.5}}}],
        "check": {"delta_deg": [0.0, 1.5, 0.0, 0.0, 0.0]}},
}
"""Planted cases of the power study: a 1.5° misplacement of one gauge (s2: a torque
half bridge; s1: a WG-bending half bridge); every key of
``PLANTED`` of ``tests/planted_strain.py`` that is not marked implausible is accepted too."""


@dataclass
class PowerRow:
    """Outcome of one planted effect over the seeds.

    Attributes
    ----------
    effect : str
    parameter : str
        The planted parameter of the median column (the first planted one).
    true_value : float
        Its true (relative) value.
    found, n_seeds : int
        Seeds in which the effect was accepted and recovered.
    estimates : list of float
        The parameter's estimate in every seed where the effect was accepted.
    clean_left_alone : int
        Seeds whose clean data got no effect.
    clean_added : list of list of str
        Effects accepted on the clean data, per seed.
    wall_s : float
        Wall time of this effect's runs plus the clean runs (shared by all rows) [s].
    details : list of dict
        Per seed: added effects, statuses of the planted candidate.
    """

    effect: str
    parameter: str
    true_value: float
    found: int
    n_seeds: int
    estimates: list[float] = field(default_factory=list)
    clean_left_alone: int = 0
    clean_added: list[list[str]] = field(default_factory=list)
    wall_s: float = 0.0
    details: list[dict[str, Any]] = field(default_factory=list)

    @property
    def median_estimate(self) -> float:
        return float(np.median(self.estimates)) if self.estimates else float("nan")

    def as_dict(self) -> dict[str, Any]:
        return {"effect": self.effect, "parameter": self.parameter,
                "true_value": self.true_value, "found": self.found, "n_seeds": self.n_seeds,
                "median_estimate": self.median_estimate, "estimates": self.estimates,
                "clean_left_alone": self.clean_left_alone, "clean_added": self.clean_added,
                "wall_s": self.wall_s, "details": self.details}


def _spec(effect: str) -> dict[str, Any]:
    if effect in POWER_EFFECTS:
        return POWER_EFFECTS[effect]
    if effect in syn.PLANTED and not syn.PLANTED[effect].get("implausible"):
        return {"key": effect, **syn.PLANTED[effect]}
    allowed = sorted(POWER_EFFECTS) + sorted(k for k, v in syn.PLANTED.items()
                                             if not v.get("implausible"))
    raise KeyError(f"unknown power-study effect {effect!r}; allowed: {allowed}")


def _recovered(spec: Mapping[str, Any], summary: Mapping[str, Any], rel_tol: float
               ) -> tuple[bool, dict[str, float], dict[str, float]]:
    """(found, estimates, truths) of the planted parameters in a summary."""
    key = spec["key"]
    eff = next((e for e in summary["effects_added"] if e["kind"] == key), None)
    if eff is None:
        return False, {}, {}
    primary, _ = syn.expected_values(key, eff, spec["check"])
    est = {p: float(eff["params"][p]["value"]) for p in primary if p in eff["params"]}
    ok = len(est) == len(primary) and all(
        abs(est[p] - t) <= rel_tol * abs(t) for p, t in primary.items())
    return ok, est, {p: float(t) for p, t in primary.items()}


def power_study(effects: Sequence[str], seeds: Iterable[int] = range(10), *,
                noise_rel: float = 0.01, n_per_op: int = 5, rel_tol: float = 0.2,
                chain: SimulationChain | None = None, model: StrainModel | None = None,
                clean: bool = True, **options: Any) -> list[PowerRow]:
    """Power of the acceptance rule for planted effects, and its false alarms on clean
    data, over independent seeds.

    Parameters
    ----------
    effects : sequence of str
        Keys of :data:`POWER_EFFECTS` or plausible keys of
        ``PLANTED`` (``tests/planted_strain.py``).
    seeds : iterable of int
        Seed k draws the WG start angles (``k``) and the noise (``1000 + k``).
    noise_rel : float, default 0.01
        Noise standard deviation relative to the signal range.
    n_per_op : int, default 5
        Windows per operating point (2 operating points).
    rel_tol : float, default 0.2
        A planted parameter counts as recovered within this relative error.
    chain, model : optional
        Shared chain and calibration model (built once otherwise: about 2 s).
    clean : bool, default True
        Also calibrate the clean data of every seed (once, shared by all effects).
    **options
        Selection settings (:class:`~swgcal.loop.SelectionConfig` fields).

    Returns
    -------
    list of PowerRow
        One per effect, in order.

    Raises
    ------
    KeyError
        Unknown effect.
    """
    specs = [(e, _spec(e)) for e in effects]
    config = SelectionConfig(**options)
    chain = chain if chain is not None else SimulationChain()
    model = model if model is not None else StrainModel(chain=chain)
    bench = _Bench(chain, model, config, noise_rel, n_per_op, rel_tol)
    seeds = [int(s) for s in seeds]
    clean_added, t_clean = _clean_runs(bench, seeds, clean)
    return [_effect_row(bench, name, spec, seeds, clean_added, t_clean)
            for name, spec in specs]


@dataclass
class _Bench:
    """What every run of a power study shares: the chain, the calibration model, the
    selection settings, the noise, windows per operating point, the recovery tolerance,
    and the clean windows of every seed (``windows``)."""

    chain: SimulationChain
    model: StrainModel
    config: SelectionConfig
    noise_rel: float
    n_per_op: int
    rel_tol: float
    windows: dict[int, Any] = field(default_factory=dict)

    def run(self, ds: Any, **problem_options: Any) -> dict[str, Any]:
        """The summary of a bench data set, calibrated."""
        return summarize(calibrate(build_problem(ds, model=self.model, **problem_options),
                                   self.config))


def _clean_runs(bench: _Bench, seeds: Sequence[int], clean: bool
                ) -> tuple[list[list[str]], float]:
    """Simulate every seed's windows (into ``bench.windows``) and, with ``clean``,
    calibrate its clean data; (effects accepted per seed, wall time of the clean runs)."""
    clean_added: list[list[str]] = []
    t_clean = 0.0
    for k in seeds:
        bench.windows[k] = syn.simulate_windows(bench.chain, n_per_op=bench.n_per_op, seed=k)
        if clean:
            t0 = time.perf_counter()
            ds, _ = syn.bench_dataset(bench.windows[k], (), noise_rel=bench.noise_rel,
                                      seed=1000 + k)
            s = bench.run(ds)
            clean_added.append([e["name"] for e in s["effects_added"]])
            t_clean += time.perf_counter() - t0
    return clean_added, t_clean


def _seed_outcome(bench: _Bench, spec: Mapping[str, Any], k: int
                  ) -> tuple[bool, dict[str, float], dict[str, float], dict[str, Any]]:
    """One seed of a planted effect: plant it, calibrate; (found, estimates, true
    values, details: added effects and the planted candidate's statuses)."""
    win = bench.windows[k]
    if spec.get("ke"):
        win = syn.simulate_windows(bench.chain, n_per_op=bench.n_per_op, seed=k, ke=spec["ke"])
    period = spec.get("window_period_s")
    ds, _ = syn.bench_dataset(win, spec.get("sensor_effects", ()), noise_rel=bench.noise_rel,
                              seed=1000 + k, window_period_s=period)
    s = bench.run(ds, **({} if period is None else {"window_period_s": period}))
    ok, est, truth = _recovered(spec, s, bench.rel_tol)
    cand = [c for it in s["iterations"] for c in it["candidates"] if c["name"] == spec["key"]]
    details = {"seed": k, "added": [e["name"] for e in s["effects_added"]],
               "found": ok, "estimates": est,
               "statuses": [c["status"] for c in cand],
               "heldout_evidence": [c["heldout_evidence"] for c in cand],
               "delta_bic_eff": [c["delta_bic_eff"] for c in cand]}
    return ok, est, truth, details


def _effect_row(bench: _Bench, name: str, spec: Mapping[str, Any], seeds: Sequence[int],
                clean_added: list[list[str]], t_clean: float) -> PowerRow:
    """A planted effect over the seeds: found seeds, the first parameter's estimates,
    the clean runs' outcome."""
    t0 = time.perf_counter()
    found, est_first, details = 0, [], []
    truth0: dict[str, float] = {}
    for k in seeds:
        ok, est, truth, detail = _seed_outcome(bench, spec, k)
        truth0 = truth0 or truth
        found += ok
        if est:
            est_first.append(next(iter(est.values())))
        details.append(detail)
    param, true = (next(iter(truth0.items())) if truth0 else
                   (next(iter(spec["check"])), float("nan")))
    return PowerRow(
        effect=name, parameter=param, true_value=float(true) if np.isscalar(true)
        else float("nan"), found=found, n_seeds=len(seeds), estimates=est_first,
        clean_left_alone=sum(1 for a in clean_added if not a), clean_added=clean_added,
        wall_s=time.perf_counter() - t0 + t_clean, details=details)


def format_power_table(rows: Sequence[PowerRow]) -> str:
    """The power table as text: effect, parameter, true value, seeds found, median
    estimate, clean seeds left alone, wall time."""
    head = (f"{'effect':<24} {'parameter':<18} {'true':>9} {'found':>7} {'median est.':>12} "
            f"{'clean left alone':>17} {'wall [s]':>9}")
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r.effect:<24} {r.parameter:<18} {r.true_value:>9.4g} "
                     f"{r.found:>3}/{r.n_seeds:<3} {r.median_estimate:>12.4g} "
                     f"{r.clean_left_alone:>12}/{len(r.clean_added):<4} {r.wall_s:>9.1f}")
    return "\n".join(lines)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=10, help="number of seeds (0..n-1)")
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--effects", nargs="+", default=["gauge_misplacement_s2",
                                                     "gauge_misplacement_s1"],
                    help="keys of POWER_EFFECTS or PLANTED of tests/planted_strain.py")
    ap.add_argument("--noise", type=float, default=0.01,
                    help="noise standard deviation relative to the signal range")
    ap.add_argument("--no-clean", action="store_true", help="skip the clean runs")
    args = ap.parse_args(argv)

    t0 = time.perf_counter()
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    rows = power_study(args.effects, seeds, noise_rel=args.noise, clean=not args.no_clean)
    print(format_power_table(rows))
    for r in rows:
        print(f"\n{r.effect}:")
        for d in r.details:
            ev = ", ".join(f"2lnΛ {h:.3g} / effΔBIC {b:.3g}" for h, b in
                           zip(d["heldout_evidence"], d["delta_bic_eff"], strict=True))
            est = ", ".join(f"{k} {v:.3g}" for k, v in d["estimates"].items())
            print(f"  seed {d['seed']}: found {d['found']}, added {d['added'] or '-'}, "
                  f"{est or 'no estimate'}; evidence {ev or '-'}")
    if rows and rows[0].clean_added:
        print("\nclean data, added per seed:", rows[0].clean_added)
    out = {"rows": [r.as_dict() for r in rows], "wall_s": time.perf_counter() - t0}
    print(json.dumps(out, default=str))
    return out


if __name__ == "__main__":
    sys.exit(0 if main() else 1)
