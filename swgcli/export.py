"""swgsim-export: the monitor's per-window stage as C99 for a microcontroller (Hydra app).

Trains the exported classifier on simulated lives of the data set's training gears (the
stage's own features, :mod:`swgmon.export.reference`), writes ``swg_monitor.h``,
``swg_monitor.c``, ``swg_tables.h`` and ``swg_model.h`` (with emlearn's headers) to
``out_dir``, checks the C compiled for the host against the Python pipeline on every
held-out window, and, with ``arm-none-eabi-gcc`` and ``qemu-system-arm`` on PATH,
measures flash, RAM and cycles on a Cortex-M4F; figures in ``out_dir/size.json`` and
``out_dir/summary.json``. Config: ``conf/export.yaml``; method: ``docs/EXPORT.md``.

Examples
--------
::

    swgsim-export                                   # bench, held-out gear 3
    swgsim-export dataset=robot_joint export.held_out_gear=1
    swgsim-export export.forest_bytes=8192 out_dir=/tmp/export
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

from hydra.core.config_store import ConfigStore
from omegaconf import DictConfig, OmegaConf

from swgcli.app import hydra_app
from swgmon.export.pipeline import ExportOptions
from swgsim.datasets.config import DatasetConfig
from swgsim.files.inputs import absolute_path


@dataclass
class ExportApp:
    """``swgsim-export``: the monitor's per-window stage as C."""

    OUT_DIRS: ClassVar[tuple[str, ...]] = ("out_dir",)

    dataset: DatasetConfig = field(default_factory=DatasetConfig)  # preset bench
    export: ExportOptions = field(default_factory=ExportOptions)
    out_dir: str = "reports/export"   # C files, size.json, summary.json
    cross: bool = True                # measure on the Cortex-M4F when the tools are there


ConfigStore.instance().store(name="export_schema", node=ExportApp)


def run_export_app(cfg) -> dict:
    """Run the export (task function); return the summary.

    Raises
    ------
    ValueError
        Bad options (named by key), a foreign file in ``out_dir`` (before any work), or a
        model the C stage cannot represent.
    """
    from swgmon.export.pipeline import run_export
    from swgsim.datasets.plan import plan

    app = OmegaConf.to_object(cfg) if isinstance(cfg, DictConfig) else cfg
    p = plan(app.dataset)
    return run_export(p, app.dataset.name, app.export, Path(absolute_path(app.out_dir)),
                      cross=app.cross)


#: The libraries its runs import, resolved before any work
#: (:func:`learn.tracking.preflight.check_imports`).
NEEDS = ("numpy", "scipy", "pandas", "xarray", "h5netcdf", "sklearn", "skops.io", "emlearn")


@hydra_app("export", ExportApp, "swgsim-export", NEEDS)
def main(cfg: DictConfig) -> dict:
    """Run the export and print the figures and where they went; a failed external tool
    (compiler, cross tool, QEMU) ends it with exit 2 and one line, after every file is
    written (:func:`swgmon.export.pipeline.run_export`)."""
    s = run_export_app(cfg)
    size, host = s["size"], s["host_c"]
    print(f"accuracy on held-out gear {s['held_out_gear']}: python {s['accuracy_python']:.4f}, "
          f"C {host.get('accuracy_c', float('nan')):.4f} (full monitor model "
          f"{s.get('accuracy_full_monitor_model', float('nan')):.4f})")
    if "classes_equal" in host:
        print(f"host C: {host['classes_equal']}/{host['windows']} classes equal, features "
              f"max |diff| {host['features_max_abs_diff']:.3g}")
    else:
        print(f"host C: {host['host_c']}")
    if size.get("flash_bytes") is not None:
        print(f"Cortex-M4F: flash {size['flash_bytes']} B, RAM {size['ram_bytes']} B, "
              f"{size['cycles_per_window']} cycles/window (high bound; "
              f"{size['ms_per_window_at_168mhz']:.2f} ms at 168 MHz)")
    else:
        print(f"Cortex-M4F: not measured ({s['target']['why']})")
    print(f"files: {Path(s['files'][0]).parent}")
    if s["failed"]:  # every file is written and listed; the figures it lacks say why
        raise ValueError(f"{s['failed'][0]}; the C files, size.json and summary.json are in "
                         f"{Path(s['files'][0]).parent}, what it did not measure marked "
                         "'not measured'")
    return s


if __name__ == "__main__":
    main()
