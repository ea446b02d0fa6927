"""One calibration API for both data kinds: recognise the measured data, then the kind's
steps build problem -> calibrate -> summarise -> render -> write.

Each kind (:mod:`swgcal.friction`, :mod:`swgcal.strain`, :mod:`swgcal.thermal`) is a
subpackage with the same step functions and ``REPORT``, its part of the one renderer
(:mod:`swgcal.report`); the functions here pick the kind from the data or from
``problem.kind``, and every step returns the same types whatever the kind: a
:class:`~swgcal.loop.Problem`, a :class:`~swgcal.loop.CalibrationResult`, a JSON-ready
summary dict, markdown.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from dataclasses import fields
from pathlib import Path
from types import ModuleType
from typing import Any

from swgsim.base.typed import build, complete, plain
from swgsim.datasets.joint_log import JointLog
from swgsim.files.inputs import check_input_file
from swgsim.files.ownership import atomic_write_bytes, atomic_write_json

from .friction.data import REQUIRED_COLUMNS, FrictionRecording, read_csv_header
from .loop import CalibrationResult, Problem, SelectionConfig
from .report import heldout_whiteness_figure, simulation_files
from .report import render_report as render_parts

__all__ = ["KINDS", "MeasuredDataError", "detect_kind", "kind_module", "options_from_config",
           "build_problem", "calibrate", "summarize", "render_report", "make_figures",
           "write_outputs"]

#: Data kind -> the subpackage that implements its steps.
KINDS = {"friction": "swgcal.friction", "strain": "swgcal.strain",
         "thermal": "swgcal.thermal"}

#: Data kind -> how messages name it.
KIND_LABELS = {"friction": "friction recording (kind 1)", "strain": "strain data set (kind 2)",
               "thermal": "joint log (kind 3)"}

#: Columns that mark a joint log's header (:data:`swgsim.datasets.joint_log.LOG_COLUMNS`).
JOINT_LOG_MARK = frozenset({"Timestamp", "Temperature_T0", "Current_J0", "Speed_J0"})

#: The step functions every kind subpackage defines (and ``REPORT``, its ReportParts).
STEPS = ("build_problem", "calibrate", "summarize", "make_figures")


class MeasuredDataError(ValueError):
    """The measured-data path is neither a friction CSV nor a data-set directory."""


def detect_kind(path: str | Path) -> str:
    """Recognise the kind of measured data at ``path``.

    Returns
    -------
    str
        ``"friction"`` for a CSV whose header holds the friction columns, ``"thermal"``
        for a joint log (:mod:`swgsim.datasets.joint_log`: its header holds
        :data:`JOINT_LOG_MARK`), ``"strain"`` for a directory holding ``manifest.json``
        (schema-v1 data set).

    Raises
    ------
    MeasuredDataError
        The path does not exist, or is neither (a FIFO, a device, a file over
        :data:`swgsim.files.inputs.MAX_INPUT_BYTES`, a sparse file, a binary file, a first
        line over :data:`swgsim.files.inputs.HEADER_BYTES`: refused before it is read); the
        message names the path and what was expected.
    """
    p = Path(path)
    expected = (f"expected a friction CSV with columns {list(REQUIRED_COLUMNS)}, a joint log "
                f"(';'-separated, with columns {sorted(JOINT_LOG_MARK)}) or a schema-v1 "
                "data-set directory holding manifest.json")
    if not p.exists():
        raise MeasuredDataError(f"measured data {str(p)!r} does not exist; {expected}")
    if p.is_dir():
        if (p / "manifest.json").is_file():
            return "strain"
        raise MeasuredDataError(f"{str(p)!r} is a directory without manifest.json; {expected}")
    try:  # a regular file under MAX_INPUT_BYTES, before anything is read
        check_input_file(p, "measured")
    except ValueError as e:
        raise MeasuredDataError(f"{e}; {expected}") from None
    try:
        header = read_csv_header(p)
    except OSError as e:
        raise MeasuredDataError(f"cannot read {str(p)!r}: {e}; {expected}") from e
    except ValueError as e:
        raise MeasuredDataError(f"{e}; {expected}") from None
    if all(c in header for c in REQUIRED_COLUMNS):
        return "friction"
    if JOINT_LOG_MARK <= {f.strip() for h in header for f in h.split(";")}:
        return "thermal"
    raise MeasuredDataError(f"{str(p)!r} is not a friction CSV (header {header[:8]}); "
                            f"{expected}")


def kind_module(kind: str) -> ModuleType:
    """The subpackage of a data kind (imported on first use).

    Raises
    ------
    ValueError
        Unknown kind (the message lists the known ones).
    """
    if kind not in KINDS:
        raise ValueError(f"unknown calibration kind {kind!r}; known: {sorted(KINDS)}")
    return importlib.import_module(KINDS[kind])


def options_from_config(kind: str, given: Mapping[str, Any], measured: Any = None
                        ) -> tuple[dict[str, Any], SelectionConfig]:
    """Typed, checked options of a calibration from a plain config (an app's keys).

    ``given`` holds ``selection`` (:class:`SelectionConfig` fields) and the option keys of
    every kind (each kind subpackage's ``OPTIONS`` dataclass, e.g.
    :class:`swgcal.friction.FrictionOptions`: ``base model``, ``gear_ratio``,
    ``accel_window``, ``split``). A key of another kind set away from its default is
    refused rather than ignored; every range is the one its dataclass declares.

    Parameters
    ----------
    kind : str
        From :func:`detect_kind`.
    given : mapping
        Plain config (lists and dicts).
    measured : optional
        The measured data, named in messages.

    Returns
    -------
    dict
        Keyword arguments of :func:`build_problem` (``candidates`` included).
    SelectionConfig

    Raises
    ------
    ValueError
        One line naming the key by its full name, the value and the allowed range (or the
        data kind it needs); nothing is loaded before.
    """
    own = kind_module(kind).OPTIONS
    own_keys = {f.name for f in fields(own)}
    for other in sorted(set(KINDS) - {kind}):
        cls = kind_module(other).OPTIONS
        foreign = [f.name for f in fields(cls) if f.name not in own_keys]
        defaults = plain(cls())
        for key in foreign:
            d = defaults[key]
            g = plain(given.get(key, d))
            changed = ([f"{key}.{k}={g[k]}" for k in g if g[k] != d.get(k)]
                       if isinstance(g, dict) else ([f"{key}={g}"] if g != d else []))
            if changed:
                names = ", ".join(f"{x}.*" if isinstance(defaults[x], dict) else x
                                  for x in foreign)
                raise ValueError(f"{changed[0]} applies to a {KIND_LABELS[other]}; "
                                 f"{measured} is a {KIND_LABELS[kind]}, whose calibration "
                                 f"takes none of {names}")
    picked = complete(given.get("selection") or {}, SelectionConfig, "selection")
    selection = build(picked, SelectionConfig, "selection")
    opts = build(complete({k: v for k, v in given.items() if k in own_keys}, own, ""), own, "")
    kwargs = opts.problem_kwargs()
    if selection.candidates is not None:
        kwargs["candidates"] = list(selection.candidates)
    return kwargs, selection


def _kind_of_data(measured: Any) -> str:
    if isinstance(measured, FrictionRecording):
        return "friction"
    if isinstance(measured, JointLog):
        return "thermal"
    if isinstance(measured, (str, Path)):
        return detect_kind(measured)
    return "strain"  # an xarray.Dataset or StrainWindows (the strain builder checks)


def build_problem(measured: Any, **options: Any) -> Problem:
    """Recognise measured data and build its calibration problem.

    Parameters
    ----------
    measured : str or Path or FrictionRecording or xarray.Dataset or StrainWindows
        A friction CSV or a schema-v1 data-set directory (:func:`detect_kind`), or data
        already loaded.
    **options
        The kind's problem options: :func:`swgcal.friction.build_problem`
        (``accel_window``, ``v_s``, ``n_blocks``, ``candidates``, ``gear_ratio``, ...) or
        :func:`swgcal.strain.build_problem` (``model``, ``select``,
        ``heldout``, ``candidates``, ...).

    Raises
    ------
    MeasuredDataError
        A path that is neither kind.
    TypeError
        An option the kind does not take.
    """
    return kind_module(_kind_of_data(measured)).build_problem(measured, **options)


def calibrate(problem: Problem, config: SelectionConfig | None = None) -> CalibrationResult:
    """Calibrate: the kind's selection of library effects on held-out evidence
    (friction: then ripples grouped by harmonics).

    Parameters
    ----------
    problem : Problem
        From :func:`build_problem`.
    """
    return kind_module(problem.kind).calibrate(problem, config)


def summarize(result: CalibrationResult, source: str | None = None) -> dict[str, Any]:
    """Machine-readable summary of a calibration (``summary.json``): the shared keys
    (:func:`swgcal.report.base_summary`) and the kind's own.

    Parameters
    ----------
    source : str, optional
        Path of the measured data.

    Returns
    -------
    dict
        JSON-serialisable.
    """
    return kind_module(result.problem.kind).summarize(result, source)


def render_report(result: CalibrationResult, summary: dict[str, Any],
                  figures: dict[str, str] | None = None) -> str:
    """Markdown report of a calibration (:func:`swgcal.report.render_report`).

    Parameters
    ----------
    summary : dict
        From :func:`summarize`.
    figures : dict of str to str, optional
        Figure key -> path relative to the report.
    """
    return render_parts(kind_module(result.problem.kind).REPORT, result, summary, figures)


def make_figures(result: CalibrationResult, out_dir: str | Path) -> dict[str, str]:
    """Diagnosis figures of a calibration, written to ``out_dir/figures/``: the kind's and
    the held-out whiteness test's (:func:`swgcal.report.heldout_whiteness_figure`).

    Returns
    -------
    dict of str to str
        Figure key -> path relative to ``out_dir``.
    """
    return {**kind_module(result.problem.kind).make_figures(result, out_dir),
            **heldout_whiteness_figure(result, out_dir)}


def write_outputs(result: CalibrationResult, out_dir: str | Path, *,
                  source: str | None = None, figures: bool = True) -> dict[str, Any]:
    """Write a calibration's files: ``report.md``, ``summary.json``, the accepted effects
    as a simulation option (friction: ``friction_effects.yaml``, strain:
    ``sensor_effects.yaml``, thermal: ``joint_thermal.yaml``) and ``figures/*.png``.

    Each file is written atomically (a temporary file renamed into place), ``summary.json``
    last (a folder holding it holds the whole calibration); nothing else in ``out_dir`` is
    touched (``swgsim-calibrate`` claims the folder ``fresh``: an earlier calibration's
    files are removed first).

    Parameters
    ----------
    out_dir : str or Path
        Created if absent.
    source : str, optional
        Path of the measured data (recorded in the summary).

    Returns
    -------
    dict
        The summary as written, with ``figures`` (key -> relative path) and ``files``
        (the file names written besides the figures).
    """
    kind = kind_module(result.problem.kind)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    summary = kind.summarize(result, source)
    summary["figures"] = make_figures(result, out) if figures else {}
    extra = simulation_files(kind.REPORT, summary)
    summary["files"] = ["report.md", "summary.json", *extra]
    atomic_write_bytes(out / "report.md",
                       render_parts(kind.REPORT, result, summary, summary["figures"]).encode())
    for name, text in extra.items():
        atomic_write_bytes(out / name, text.encode())
    atomic_write_json(out / "summary.json", summary)  # last: it lists the whole run
    return summary
