"""
Calibration on a synthetic friction recording
=============================================

The calibration loop (:mod:`swgcal`) on "measured" friction data whose truth is known: a
joint's angle, velocity and torque simulated with the paper's friction law (eq. 5-6) plus
two planted effects the law lacks, presliding and a Stribeck bump, and a little noise
(:func:`swgcal.friction.synthetic.synthetic_recording`). The loop fits the law, diagnoses
the residual, adds the effects the held-out data support and reports the error before and
after on held-out blocks.
"""

import matplotlib.pyplot as plt
import numpy as np

from swgcal import build_problem, calibrate, summarize
from swgcal.friction.synthetic import PLANTED, synthetic_recording

planted = [{"kind": k, "params": PLANTED[k]["params"]} for k in ("presliding", "stribeck")]
recording, truth = synthetic_recording(planted, noise_rel=0.003, rng=np.random.default_rng(0))
result = calibrate(build_problem(recording))
summary = summarize(result)

# %%
# What the loop found, against what was planted: each accepted effect with its fitted
# parameters, and the held-out RMSE of the paper's law alone and after the loop [N m].

for effect in planted:
    print("planted:", effect["kind"], effect["params"])
for effect in summary["effects_added"]:
    print("added:  ", effect["name"], {k: round(v["value"], 4)
                                        for k, v in effect["params"].items()})
print(f"held-out RMSE: {summary['rmse_before']:.4f} -> {summary['rmse_after']:.4f} N m")

# %%
# The residual of the model before and after, over the first seconds of the recording:
# what is left of the presliding transients at each reversal and of the low-speed bump
# once the loop has added them.

problem = result.problem
first = problem.t < problem.t[0] + 10.0
fig, ax = plt.subplots(figsize=(7, 3.5))
for label, fit in (("paper law", result.base_model_final), ("after the loop", result.final)):
    residual = problem.y - fit.predict(problem.signals)
    ax.plot(problem.t[first], residual[first], lw=0.7, label=label)
ax.set_xlabel("time [s]")
ax.set_ylabel(f"residual [{problem.units}]")
ax.legend()
fig.tight_layout()
