"""Start-up time of every app: ``--help`` and a refused bad override, as a user types them.

    python scripts/bench_startup.py [--runs 5] [--apps monitor,train]

Runs each app's console script (``.venv/bin/swgsim-<app>`` beside this interpreter) as a
whole process, ``--help`` and then an override of a key the app does not have (refused in
one line, exit code 2), ``--runs`` times each, and prints the minimum and median wall time
in seconds; the target is at most 1 s on the 2-core machine with nothing else running.
Also lists the heavy libraries (torch, scikit-learn, skops, MLflow, aeon, pandas,
matplotlib, the scipy submodules) that importing the app's module loads: none should be.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

APPS = ("generate", "train", "calibrate", "paper", "observability", "monitor", "export",
        "import")
#: libraries a run imports when it needs them, never an app's ``--help``
HEAVY = ("torch", "sklearn", "skops.io", "mlflow", "aeon", "pandas", "matplotlib",
         "scipy.signal", "scipy.sparse", "scipy.stats", "scipy.special",
         "scipy.interpolate", "scipy.optimize", "xarray", "pyarrow")
#: the app's module (``swgsim-import`` lives in ``swgcli.importer``)
MODULES = {app: f"swgcli.{'importer' if app == 'import' else app}" for app in APPS}
_PROBE = """import importlib, sys
importlib.import_module(sys.argv[1])
print(' '.join(m for m in sys.argv[2:] if m in sys.modules))"""


def heavy_loaded(module: str) -> list[str]:
    """The :data:`HEAVY` libraries that importing ``module`` in a fresh interpreter loads
    (a stand-in of :func:`swgsim.base.lazy.lazy_module` not yet used is no import)."""
    out = subprocess.run([sys.executable, "-c", _PROBE, module, *HEAVY], check=True,
                         capture_output=True, text=True).stdout
    return out.split()


def wall_s(cmd: list[str], expect_rc: int) -> float:
    """Wall time of one run of ``cmd`` [s]; raises if it ends with another exit code."""
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    dt = time.perf_counter() - t0
    if proc.returncode != expect_rc:
        raise SystemExit(f"{' '.join(cmd)}: exit code {proc.returncode}, expected "
                         f"{expect_rc}:\n{proc.stderr[-2000:]}")
    return dt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5, help="runs per command (default 5)")
    ap.add_argument("--apps", default=",".join(APPS),
                    help=f"comma-separated apps (default all: {','.join(APPS)})")
    args = ap.parse_args()
    apps = [a for a in args.apps.split(",") if a]
    unknown = sorted(set(apps) - set(APPS))
    if unknown or args.runs < 1:
        ap.error(f"--apps: unknown {unknown}, allowed {list(APPS)}" if unknown
                 else "--runs: at least 1")
    bindir = Path(sys.executable).parent
    print(f"{'app':<22}{'--help min / median [s]':>26}{'bad override min / median [s]':>32}"
          "   heavy libraries loaded by the module")
    worst = 0.0
    for app in apps:
        exe = str(bindir / f"swgsim-{app}")
        row = []
        for extra, rc in ((["--help"], 0), (["no_such_key=1"], 2)):
            times = [wall_s([exe, *extra], rc) for _ in range(args.runs)]
            row.append(f"{min(times):.2f} / {statistics.median(times):.2f}")
            worst = max(worst, statistics.median(times))
        heavy = heavy_loaded(MODULES[app])
        print(f"{'swgsim-' + app:<22}{row[0]:>26}{row[1]:>32}   {', '.join(heavy) or 'none'}")
    print(f"slowest median: {worst:.2f} s (target 1 s)")


if __name__ == "__main__":
    main()
