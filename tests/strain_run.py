"""Strain calibration through the public API, as the tests of the strain side run it:
build problem -> calibrate -> summarise (or write the files)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

from swgcal import SelectionConfig, build_problem, calibrate, summarize, write_outputs

SELECTION = {f.name for f in dataclasses.fields(SelectionConfig)} - {"candidates"}


def run_strain(data: Any, out_dir: str | Path | None = None, *, figures: bool = False,
               **options: Any) -> tuple[dict[str, Any], Any]:
    """Calibrate measured strain windows; selection settings and problem options in one
    keyword list. Returns the summary (as written when ``out_dir`` is given) and the
    CalibrationResult."""
    config = SelectionConfig(**{k: options.pop(k) for k in list(options) if k in SELECTION})
    result = calibrate(build_problem(data, **options), config)
    summary = (write_outputs(result, out_dir, figures=figures) if out_dir is not None
               else summarize(result))
    return summary, result
