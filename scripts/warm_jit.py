"""Compile the numba kernels once, right after the set-up installs the environment.

    python scripts/warm_jit.py

numba compiles a kernel on its first call and, with ``cache=True``, keeps the machine code
beside its source (``__pycache__``), so that later processes load it. A fresh environment
has none: its first test run or study pays for every compilation, once per process that
needs a kernel before another has cached it. The costly one is aeon's MiniRocket (about
21 s on the 2-core machine); the simulator's integrator, deflection chain, influence
lookup and disturbance, and the monitor's tree walk, take about 3 s together.
``scripts/quickstart.sh`` runs this once after installing (its output goes to the set-up
log); it calls each kernel on tiny inputs of the types the project passes them, and prints
the time it took.
"""

from __future__ import annotations

import tempfile
import time

import numpy as np
from sklearn.ensemble import HistGradientBoostingClassifier

from learn.learners.rocket import MiniRocketClassifier
from learn.monitor.trees import CompiledTrees
from swgcli import dataset_preset
from swgsim.datasets.config import dataset_config
from swgsim.datasets.generate import generate


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
    print(f"numba kernels compiled: MiniRocket {t1 - t0:.1f} s, "
          f"simulator and monitor {time.perf_counter() - t1:.1f} s")


if __name__ == "__main__":
    main()
