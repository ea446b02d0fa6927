"""Calibrate the joint thermal model on the UR3 CobotOps day, every joint; print the table
and draw the before/after figure.

Data: M. Tyrovolas, K. Aliev, D. Antonelli and C. Stylios, "UR3 CobotOps", UCI Machine
Learning Repository, 2024, doi:10.24432/C5J891, CC BY 4.0. The file is not in the
repository: its path is the first argument.

For every joint (J0..J5): the loop of ``swgsim-calibrate`` (:func:`swgcal.thermal.calibrate`,
library defaults), fitted before the day's 5.2-h gap, effects chosen on the first half of
the part after it and the errors before and after on its second half; the table gives the
RMSE before (the project's first-order model) and after (with the kept effects), the
effects kept and their parameters, the base model's time constant and whether the
residual stays unexplained. An effect kept on one joint is carried to the joints it was
not fitted on (:func:`transfer_effects`): it holds for the arm where it lowers their
held-out error with evidence on most of them.

Joints not used in the fit: an effect kept on one joint is carried to every other joint
with the time constants it was fitted with (its nonlinear parameters held; its gain and
the other joint's base model refitted on that joint's fit part, since the joints differ in
size), and its error on that joint's held-out part (validation and test, after the gap)
compared with the base model's alone, on the loop's evidence scale (:mod:`swgcal.loop`:
2 ln Λ = (n / τ_int) ln(RMSE_base² / RMSE_with²), τ_int of the base's held-out residual).
An effect holds for the arm when it passes on most of the joints it was not fitted on
[choice: a majority, as the joints differ in size, load and place].

    python scripts/thermal_ur3.py PATH/ur3_cobotops_2022-10-26.csv
    python scripts/thermal_ur3.py PATH/ur3.csv --figure docs/figures/thermal_ur3.png
    python scripts/thermal_ur3.py PATH/ur3.csv --room-c 22.5   # a measured room [°C]
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from swgcal.core import fit_terms, integrated_autocorr_time
from swgcal.loop import CalibrationResult, SelectionConfig


def _row(res) -> dict:
    """One joint's table row from its CalibrationResult."""
    base = res.base_model_final.estimates_of("first_order")
    effects = {n: {k: (e.value, e.std, e.bound) for k, e in res.final.estimates_of(n).items()}
               for n in res.added}
    kept = [c for it in res.iterations for c in it.candidates if c.accepted]
    return {"joint": res.problem.meta["joint"], "rmse": res.rmse,
            "tau_min": base["tau_min"].value, "tau_std": base["tau_min"].std,
            "r_th": base["r_th_k_per_w"].value, "r_th_std": base["r_th_k_per_w"].std,
            "ambient_c": base["ambient_c"].value, "effects": effects, "kept": kept,
            "final_base": {k: (e.value, e.std, e.bound)
                           for k, e in res.final.estimates_of("first_order").items()},
            "unexplained": res.unexplained, "signature": res.residual_signature,
            "removed": res.problem.meta.get("removed", []),
            "best": (min(res.iterations[-1].candidates, key=lambda c: c.val_rmse)
                     if res.iterations and res.iterations[-1].candidates else None)}


def _heldout_rmse(result: CalibrationResult, terms, starts, fixed) -> tuple[float, np.ndarray]:
    """RMSE on the held-out part of a model fitted on the fit part, and its residual."""
    p = result.problem
    f = fit_terms(terms, p.signals, p.y, p.split.fit, starts, fixed=fixed, uncertainty=False,
                  max_starts=1)
    idx = np.concatenate([p.split.validation, p.split.test])
    r = (p.y - f.predict(p.signals))[idx]
    return float(np.sqrt(np.mean(r * r))), r


def transfer_effects(results: Sequence[CalibrationResult],
                     config: SelectionConfig | None = None) -> list[dict[str, Any]]:
    """Carry every effect kept on one joint to the others (module docstring, "Joints not
    used in the fit").

    Parameters
    ----------
    results : sequence of CalibrationResult
        One per joint (thermal problems), e.g. of the six joints of a log.
    config : SelectionConfig, optional
        Its ``min_heldout_evidence`` is the bar (10).

    Returns
    -------
    list of dict
        One per effect kept: ``effect``, ``from_joint``, ``nonlinear`` (the time constants
        carried), ``to`` (per other joint: ``joint``, ``rmse_base``, ``rmse_with`` [K] on
        its held-out part, ``evidence`` 2 ln Λ, ``passes``), ``passes_on`` (count),
        ``holds_for_arm`` (a majority of the others).
    """
    bar = (config or SelectionConfig()).min_heldout_evidence
    out = []
    for rj in results:
        for term in rj.effect_terms():
            theta = rj.final.thetas[rj.final.terms.index(term)]
            rows = []
            for rk in results:
                if rk is rj:
                    continue
                base = rk.base_model_final
                b, r_b = _heldout_rmse(rk, base.terms, [[base.thetas[0]]], [False])
                a, _ = _heldout_rmse(rk, (*base.terms, type(term)()),
                                     [[base.thetas[0]], [theta]], [False, True])
                tau = max(integrated_autocorr_time(r_b), 1.0)
                ev = float(r_b.size / tau * np.log(b * b / (a * a)))
                rows.append({"joint": rk.problem.meta.get("joint"), "rmse_base": b,
                             "rmse_with": a, "evidence": ev, "passes": ev > bar})
            n_pass = sum(r["passes"] for r in rows)
            out.append({"effect": term.name, "from_joint": rj.problem.meta.get("joint"),
                        "nonlinear": {p.name: float(v) for p, v in zip(term.nonlinear, theta,
                                                                        strict=True)},
                        "to": rows, "passes_on": n_pass,
                        "holds_for_arm": 2 * n_pass > len(rows)})
    return out


def _figure(results, path: Path) -> None:
    """Six panels, measured and both models, the held-out part shaded, attribution."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from swgcal.thermal.report import ATTRIBUTION, measured, plot_joint

    fig, axes = plt.subplots(2, 3, figsize=(10, 5.2), sharex=True)
    for ax, res in zip(axes.flat, results, strict=True):
        p = res.problem
        before, after = res.predictions()
        # the 5.2-h gap squeezed to 0.2 h: hours after it shifted back
        h = p.t / 3600.0
        g = int(p.split.fit.max()) + 1
        shift = h[g] - h[g - 1] - 0.2
        h = h.copy()
        h[g:] -= shift
        plot_joint(ax, h, measured(p), before, after, g - 1)
        ax.axvline(h[g - 1] + 0.1, color="k", lw=0.5, ls=":")
        rb, ra = res.rmse["test"]["before"], res.rmse["test"]["after"]
        ph = p.meta.get("physical") or {}
        scored = not (ph.get("before") or ph.get("after"))
        ax.set_title(f"J{p.meta['joint']}: test RMSE {rb:.3f} -> {ra:.3f} K" if scored else
                     f"J{p.meta['joint']}: unphysical fit, not scored", fontsize=8)
        ax.set_xlabel(f"h (gap of {shift + 0.2:.1f} h cut at the dotted line)", fontsize=7)
        ax.tick_params(labelsize=7)
        if ax is not axes.flat[0]:
            ax.get_legend().remove()
    fig.text(0.01, 0.005, ATTRIBUTION, fontsize=6)
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=72)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    """Run every joint, print the table (and write the figure)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("path", type=Path, help="ur3_cobotops_2022-10-26.csv")
    ap.add_argument("--joints", type=int, nargs="*", default=list(range(6)))
    ap.add_argument("--figure", type=Path, default=None)
    ap.add_argument("--room-c", type=float, default=None,
                    help="the room's measured temperature [°C]: the ambient held at it")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    from swgcal.thermal import build_problem, calibrate
    from swgsim.datasets.joint_log import read_joint_log

    t0 = time.perf_counter()
    log = read_joint_log(args.path)
    results = [calibrate(build_problem(log, joint=j, room_c=args.room_c)) for j in args.joints]
    rows = [_row(r) for r in results]
    kept_on = Counter(n.split("#")[0] for r in rows for n in r["effects"])
    meta = results[0].problem.meta
    print(f"sensor resolution (smallest step between readings): {meta['resolution']:.4g} K; "
          + (f"the room measured, {meta['room_c']:.4g} °C (the ambient held at it)"
             if meta.get("room_c") is not None else
             f"the room <= the coolest joint's first reading, {meta['room_max_c']:.4g} °C"))
    print("| joint | physical (alone / final) | R_th [K/W] | τ [min] | T_amb [°C] | ΔT_0 [K] | "
          "effects kept | forward: fit A, RMSE on B [K] | backward: fit B, RMSE on A [K] |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r, res in zip(rows, results, strict=True):
        fb, ph = r["final_base"], res.problem.meta["physical"]
        cv = res.problem.meta["crossval"]["rows"]

        def pe(k, fb=fb):
            v, sd, b = fb[k]
            return f"{v:.3g} ± {sd:.2g}" + (" (bound)" if b.startswith("on its") else "")

        fx = "; ".join(n + " (" + ", ".join(f"{k} {v:.3g} ± {sd:.2g}"
                                            for k, (v, sd, _) in q.items()) + ")"
                       for n, q in r["effects"].items()) or "none"
        way = {w: " -> ".join(f"{c[w]['rmse']:.3f}" for c in cv) for w in ("forward", "backward")}
        print(f"| J{r['joint']} | {'no' if ph['before'] else 'yes'} / "
              f"{'no' if ph['after'] else 'yes'} | {pe('r_th_k_per_w')} | {pe('tau_min')} | "
              f"{pe('ambient_c')} | {pe('initial_k')} | {fx} | {way['forward']} | "
              f"{way['backward']} |")
    print(f"\neffects kept on (of {len(rows)} joints): {dict(kept_on) or 'none'}")
    for c in transfer_effects(results):
        print(f"{c['effect']} of J{c['from_joint']} ({c['nonlinear']}) carried to the others: "
              f"passes on {c['passes_on']} of {len(c['to'])}, holds for the arm: "
              f"{c['holds_for_arm']}")
    for r in rows:
        print(f"J{r['joint']}: {r['signature']}" + (f" removed: {r['removed']}"
                                                    if r["removed"] else ""))
        print("    unphysical: " + str(results[rows.index(r)].problem.meta["physical"]))
        for c in r["kept"]:
            print(f"    kept {c.name}: validation gain {100 * c.rel_improvement:.3g} %, held-out "
                  f"2 ln Λ {c.heldout_evidence:.3g}, effective ΔBIC {c.delta_bic_eff:+.4g}; "
                  "base with it: " + ", ".join(f"{k} {v:.4g} ± {s:.2g}"
                                               for k, (v, s, _) in r["final_base"].items()))
        if r["best"] is not None:
            b = r["best"]
            print(f"    best candidate {b.name}: validation RMSE {b.val_rmse:.3f} K, "
                  f"{', '.join(f'{k} {v:.3g}' for k, v in b.params.items())}; {b.status}")
    if args.figure:
        _figure(results, args.figure)
        print(f"figure {args.figure} ({args.figure.stat().st_size / 1024:.0f} kB)")
    print(f"{time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
