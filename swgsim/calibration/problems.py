"""Measured data in: recognise the kind, load it, build a calibration problem.

Kinds:

1. a friction CSV (columns of :data:`~swgsim.calibration.friction.REQUIRED_COLUMNS`),
2. a schema-v1 data-set directory (``manifest.json``, strain signals; ``swgsim.data``).

The friction side is complete. The strain side (kind 2) is recognised, but its effect
library needs the strain prediction of the simulation chain, which is not wired yet:
:func:`build_problem` raises :class:`NotImplementedError` with that explanation.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .diagnose import friction_probes
from .friction import REQUIRED_COLUMNS, FrictionRecording, PaperLaw, load_friction_csv
from .friction_effects import FRICTION_LIBRARY
from .loop import CalibrationResult, Problem, SelectionConfig, calibrate
from .ripple_groups import group_ripples
from .split import time_block_split

log = logging.getLogger(__name__)

__all__ = ["detect_kind", "friction_problem", "build_problem", "calibrate_friction",
           "MeasuredDataError"]


#: Fewest samples a held-out time block of a friction recording must hold.
MIN_ROWS_PER_BLOCK = 20


class MeasuredDataError(ValueError):
    """The measured-data path is neither a friction CSV nor a data-set directory."""


def detect_kind(path: str | Path) -> str:
    """Recognise the kind of measured data at ``path``.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    str
        ``"friction"`` for a CSV whose header holds the friction columns, ``"strain"``
        for a directory holding ``manifest.json`` (schema-v1 data set).

    Raises
    ------
    MeasuredDataError
        The path does not exist, or is neither; the message names the path and what was
        expected.
    """
    p = Path(path)
    expected = (f"expected a friction CSV with columns {list(REQUIRED_COLUMNS)} or a "
                "schema-v1 data-set directory holding manifest.json")
    if not p.exists():
        raise MeasuredDataError(f"measured data {str(p)!r} does not exist; {expected}")
    if p.is_dir():
        if (p / "manifest.json").is_file():
            return "strain"
        raise MeasuredDataError(f"{str(p)!r} is a directory without manifest.json; {expected}")
    try:
        with p.open(encoding="utf-8", errors="replace") as fh:
            header = [h.strip() for h in fh.readline().split(",")]
    except OSError as e:
        raise MeasuredDataError(f"cannot read {str(p)!r}: {e}; {expected}") from e
    if all(c in header for c in REQUIRED_COLUMNS):
        return "friction"
    raise MeasuredDataError(f"{str(p)!r} is not a friction CSV (header {header[:8]}); "
                            f"{expected}")


def friction_problem(
    rec: FrictionRecording,
    *,
    v_s: float | None = None,
    v_s_rel: float = 0.01,
    n_blocks: int = 10,
    validation_blocks: Sequence[int] = (3, 7),
    test_blocks: Sequence[int] = (5, 9),
    guard_frac: float = 0.05,
    candidates: Sequence[str] | None = None,
    gear_ratio: float | None = None,
) -> Problem:
    """Calibration problem for one friction recording.

    Parameters
    ----------
    rec : FrictionRecording
    v_s : float, optional
        Smooth-sign velocity of the baseline [rad/s]; default ``v_s_rel`` times the 99th
        percentile of |q̇|.
    v_s_rel : float, default 0.01
    n_blocks, validation_blocks, test_blocks, guard_frac
        Held-out split, see :func:`~swgsim.calibration.split.time_block_split`.
    candidates : sequence of str, optional
        Library keys (default all of :data:`FRICTION_LIBRARY`).
    gear_ratio : float, optional
        Reduction ratio N of the strain wave gear (wave-generator turns per output
        turn), when known: ripple periods over q are then expressed and checked as
        wave-generator orders k = 2π / (period · N) (:mod:`.friction_ripples`).

    Returns
    -------
    Problem

    Raises
    ------
    ValueError
        Unknown candidate key, too few samples for the held-out blocks, or a gear
        ratio not above 1.
    """
    sig = rec.signals(v_s=v_s, v_s_rel=v_s_rel, gear_ratio=gear_ratio)
    keys = list(candidates) if candidates is not None else list(FRICTION_LIBRARY)
    unknown = [k for k in keys if k not in FRICTION_LIBRARY]
    if unknown:
        raise ValueError(f"selection.candidates: unknown friction effects {unknown}; library: "
                         f"{sorted(FRICTION_LIBRARY)}")
    if rec.n < MIN_ROWS_PER_BLOCK * n_blocks:
        raise ValueError(f"recording {rec.name!r}: {rec.n} samples are too few for "
                         f"split.n_blocks={n_blocks} held-out blocks of at least "
                         f"{MIN_ROWS_PER_BLOCK} samples; allowed: n_blocks <= "
                         f"{rec.n // MIN_ROWS_PER_BLOCK}")
    split = time_block_split(rec.t_s, n_blocks, validation_blocks, test_blocks, guard_frac)
    return Problem(
        name=rec.name, kind="friction", units="N m", signals=sig, y=rec.tau_nm, t=rec.t_s,
        baseline=(PaperLaw(),), library={k: FRICTION_LIBRARY[k] for k in keys},
        probes=friction_probes(), split=split,
        meta={"n_samples": rec.n, "duration_s": float(rec.t_s[-1] - rec.t_s[0]),
              "dt_median_s": sig.scales.dt_med, "v_s_rad_s": sig.v_s,
              "v_ref_rad_s": sig.scales.v_ref, "q_span_rad": sig.scales.q_span,
              "t0_s": sig.scales.t0, "ddq_source": rec.ddq_source,
              "has_load": rec.load_nm is not None, "data_notes": list(rec.notes),
              "gear_ratio": sig.gear_ratio})


def build_problem(path: str | Path, **kwargs: Any) -> Problem:
    """Recognise, load and wrap measured data (see :func:`detect_kind`).

    Parameters
    ----------
    path : str or Path
    **kwargs
        Passed to :func:`friction_problem` (plus ``accel_window`` for the loader).

    Returns
    -------
    Problem

    Raises
    ------
    MeasuredDataError
        Unrecognised path.
    NotImplementedError
        A strain data set: recognised, but its effect library is not available yet.
    """
    kind = detect_kind(path)
    if kind == "friction":
        aw = kwargs.pop("accel_window", 21)
        return friction_problem(load_friction_csv(path, accel_window=aw), **kwargs)
    raise NotImplementedError(
        f"{str(path)!r} is a schema-v1 strain data set (kind 2). The calibration framework "
        "(terms, selection loop, held-out split by recordings/operating points, report) is "
        "domain independent, but the strain-side effect library needs the strain "
        "prediction of the simulation chain, which is not wired into the calibration yet. "
        "Only friction CSVs (kind 1) can be calibrated in this version.")


def calibrate_friction(problem: Problem, config: SelectionConfig | None = None
                       ) -> CalibrationResult:
    """The calibration loop for a friction problem, then ripple grouping.

    :func:`~swgsim.calibration.loop.calibrate`, then
    :func:`~swgsim.calibration.ripple_groups.group_ripples`: ripple instances that are
    harmonics of one fundamental become one effect (wave-generator orders when the gear
    ratio is known), and a ripple without held-out evidence of its own in the final
    model is removed.

    Parameters
    ----------
    problem : Problem
        From :func:`friction_problem` or :func:`build_problem`.
    config : SelectionConfig, optional

    Returns
    -------
    CalibrationResult
        ``problem.meta["ripples"]`` records the grouping (summary key ``ripples``).

    Raises
    ------
    KeyError
        ``config.candidates`` names an effect that is not in the library.
    """
    return group_ripples(calibrate(problem, config))
