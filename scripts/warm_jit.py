"""Compile the numba kernels once, right after the set-up installs the environment.

    python scripts/warm_jit.py

numba compiles a kernel on its first call and, with ``cache=True``, keeps the machine code
beside its source (``__pycache__``), so that later processes load it. A fresh environment
has none: its first test run or study pays for every compilation, once per process that
needs a kernel before another has cached it. The costly one is aeon's MiniRocket (about
21 s on the 2-core machine); the simulator's integrator, deflection chain, influence
lookup, disturbance and input-angle edges, and the monitor's tree walk and angle-domain
basis, take about 3 s together.
``scripts/quickstart.sh`` runs this once after installing (its output goes to the set-up
log); it calls each kernel on tiny inputs of the types the project passes them, and prints
the time it took.
"""

from __future__ import annotations

import tempfile
import time

import numpy as np
from sklearn.ensemble import HistGradientBoostingClassifier

from learn.inputs.health import NUISANCE_ORDERS
from learn.inputs.signals import angle_fit
from learn.learners.rocket import MiniRocketClassifier
from swgcli import dataset_preset
from swgmon.assessment.trees import CompiledTrees
from swgsim.datasets.config import dataset_config
from swgsim.datasets.generate import generate
from swgsim.sensing.angles import edge_interpolate


def main() -> None:
    t0 = time.perf_counter()
    rng = np.random.default_rng(0)
    X, y = rng.standard_normal((8, 5, 64)), np.repeat(["a", "b"], 4)
    MiniRocketClassifier(n_kernels=84, random_state=0).fit(X, y).predict(X)
    t1 = time.perf_counter()
    with tempfile.TemporaryDirectory() as out:
        generate(dataset_config(dataset_preset("tiny")), out, progress=False)
    x = rng.standard_normal((40, 3))
    CompiledTrees(HistGradientBoostingClassifier(max_iter=2).fit(x, x[:, 0] > 0)).raw(x)
    t = np.arange(64) / 1e4
    edge_interpolate(t, np.floor(2.0 * np.pi * 30.0 * t / 0.3)[None] * 0.3, 0.3)
    angle_fit(X, np.tile(0.5 * np.arange(64), (8, 1)), 1.01, 3, NUISANCE_ORDERS)
    print(f"numba kernels compiled: MiniRocket {t1 - t0:.1f} s, "
          f"simulator and monitor {time.perf_counter() - t1:.1f} s")


if __name__ == "__main__":
    main()
