"""swgsim-import: a user's recording of a joint as a stream for ``swgsim-monitor`` (Hydra
app, config ``conf/import.yaml``).

Reads a recording (CSV or Parquet, one row per sample) and its column mapping (a YAML,
:class:`swgsim.datasets.recording_mapping.RecordingMapping`; an example in
``examples/own_joint_mapping.yaml``), checks both before any work, and writes the windows
as a schema-v1 stream with a manifest and an ownership stamp
(:func:`swgsim.datasets.recordings.import_recording`). The walk-through is
``docs/OWN_JOINT.md``.

Examples
--------
    swgsim-import recording=joint.csv mapping=joint.yaml out_dir=data/joint
    swgsim-monitor stream=data/joint diagnosis_model=reports/monitor/models/<model>.skops
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

from hydra.core.config_store import ConfigStore
from omegaconf import MISSING, DictConfig, OmegaConf

from swgcli.app import hydra_app
from swgsim.base.typed import allowed
from swgsim.datasets.recording_table import MAX_READ_BYTES, MAX_TABLE_BYTES
from swgsim.datasets.recordings import import_recording
from swgsim.files.inputs import absolute_path


@dataclass
class ImportApp:
    """``swgsim-import``: a recording as a stream the monitor reads."""

    OUT_DIRS: ClassVar[tuple[str, ...]] = ("out_dir",)  # folders written (app.check_out_dirs)

    recording: str = MISSING     # the table: CSV (.csv, .txt) or Parquet (.parquet, .pq)
    mapping: str = MISSING       # its column mapping, a YAML (docs/OWN_JOINT.md)
    out_dir: str = MISSING       # the stream's folder (then swgsim-monitor stream=<out_dir>)
    overwrite: bool = False      # replace a stream or data set this project wrote there
    # reading needs 2-4 times the file's size: at most MAX_READ_BYTES (4096 MiB)
    max_file_mb: float = field(default=MAX_TABLE_BYTES / 2**20,
                               metadata=allowed(1.0, MAX_READ_BYTES / 2**20,
                                                "largest table read [MiB]"))
    progress: bool = True


# the schema registered where the app is defined, as swgsim-calibrate's (swgcli.schema
# importing this module would close an import cycle through swgcli.app)
ConfigStore.instance().store(name="import_schema", node=ImportApp)


def run_import(cfg: DictConfig | ImportApp) -> dict:
    """Import the recording (task function, no Hydra needed).

    Parameters
    ----------
    cfg : DictConfig or ImportApp
        Composed ``conf/import.yaml``.

    Returns
    -------
    dict
        The summary of :func:`swgsim.datasets.recordings.import_recording`.

    Raises
    ------
    FileNotFoundError, ValueError
        One line naming the file, the mapping key, the column or the row; before
        anything is written.
    """
    app = OmegaConf.to_object(cfg) if isinstance(cfg, DictConfig) else cfg
    return import_recording(absolute_path(app.recording), absolute_path(app.mapping),
                            absolute_path(app.out_dir), overwrite=bool(app.overwrite),
                            max_bytes=int(app.max_file_mb * 2**20),
                            progress=bool(app.progress))


def summary_lines(s: dict) -> list[str]:
    """The console's lines of an import's summary."""
    comm = ", ".join(f"{v} at {k}" for k, v in s["commissioning_windows"].items())
    return [f"swgsim-import: {s['windows']} windows of {s['window_samples']} samples at "
            f"{s['sample_rate_hz']:g} Hz from {s['rows']} rows in {s['segments']} segment(s), "
            f"{s['hours'][0]:.2f}-{s['hours'][1]:.2f} h -> {s['out_dir']}",
            f"swgsim-import: commissioning {comm}; of {s['windows_cut']} whole windows "
            f"{s['stopped_windows']} in a stop left out, {s['outside_points']} outside the "
            f"declared operating points; mean "
            f"speeds up to {s['speed_offset_rpm']:.3g} rpm from their point's"]


#: The libraries its runs import, resolved before any work
#: (:func:`learn.tracking.preflight.check_imports`).
NEEDS = ("numpy", "pandas", "xarray", "h5netcdf", "pyarrow", "yaml")


@hydra_app("import", ImportApp, "swgsim-import", NEEDS)
def main(cfg: DictConfig) -> dict:
    """Import the recording and print a summary."""
    s = run_import(cfg)
    for line in summary_lines(s):
        print(line)
    return s


if __name__ == "__main__":
    main()
