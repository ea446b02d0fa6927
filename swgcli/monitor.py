"""swgsim-monitor: one gear's stream through the condition monitor (Hydra app around
:func:`swgmon.advisories.task.run_monitor_app`, which holds what it reads, runs and
writes). Config: ``conf/monitor.yaml``.
"""

from __future__ import annotations

from omegaconf import DictConfig

from swgcli.app import hydra_app
from swgcli.schema import MonitorApp
from swgmon.advisories.report import event_line
from swgmon.advisories.task import check_inputs, run_monitor_app
from swgmon.prognosis.stream import prognosis_line

#: The libraries its runs import, resolved before any work
#: (:func:`learn.tracking.preflight.check_imports`).
NEEDS = ("numpy", "scipy", "pandas", "xarray", "h5netcdf", "sklearn", "skops.io", "mlflow",
         "matplotlib")


@hydra_app("monitor", MonitorApp, "swgsim-monitor", NEEDS, inputs=check_inputs)
def main(cfg: DictConfig) -> dict:
    """Run the monitor and print the threshold it used, its events (one line each, by
    kind: :func:`swgmon.advisories.report.event_line`) and where the outputs went."""
    out = run_monitor_app(cfg)
    print(f"alarm threshold h = {out['threshold']:.2f}")
    if not out["alarms"]:
        print("no alarm")
    for e in out["events"]:
        print(event_line(e))
    for e in out["prognosis"] or []:
        print(prognosis_line(e))
    for k, v in out["files"].items():
        print(f"{k}: {v}")
    return out


if __name__ == "__main__":
    main()
