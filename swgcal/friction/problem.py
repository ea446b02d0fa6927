"""A friction recording (data kind 1) as a calibration problem, and its calibration.

:func:`build_problem` loads a friction CSV (or takes a recording) and wraps it:
paper-law base model, the effects with a fit in the one registry
(:data:`swgsim.gear.friction.FRICTION_LIBRARY`, :mod:`.library`), the residual probes
(:mod:`.probes`) and a held-out split in time blocks;
:func:`calibrate` runs the selection loop and groups ripples by harmonics.
"""

from __future__ import annotations

import inspect
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from swgsim.base.typed import build, complete
from swgsim.gear.friction import FRICTION_LIBRARY

from ..loop import CalibrationResult, Problem, SelectionConfig, check_candidates, select_effects
from ..split import time_block_split
from ..terms import FitTerm
from .data import FrictionRecording, load_friction_csv
from .library import PaperLaw
from .options import BaseModelOptions, FrictionOptions, SplitOptions
from .probes import friction_probes
from .ripple_groups import group_ripples

__all__ = ["friction_problem", "build_problem", "calibrate", "MIN_ROWS_PER_BLOCK", "OPTIONS"]

#: The typed options of this kind's problem (read by :func:`swgcal.api.options_from_config`).
OPTIONS = FrictionOptions
#: Fewest samples a held-out time block of a friction recording must hold.
MIN_ROWS_PER_BLOCK = 20


def friction_problem(
    rec: FrictionRecording,
    *,
    v_s: float | None = BaseModelOptions.v_s,
    v_s_rel: float = BaseModelOptions.v_s_rel,
    n_blocks: int = SplitOptions.n_blocks,
    validation_blocks: Sequence[int] = SplitOptions.validation_blocks,
    test_blocks: Sequence[int] = SplitOptions.test_blocks,
    guard_frac: float = SplitOptions.guard_frac,
    candidates: Sequence[str] | None = None,
    gear_ratio: float | None = FrictionOptions.gear_ratio,
) -> Problem:
    """Calibration problem for one friction recording.

    Parameters
    ----------
    v_s : float, optional
        Smooth-sign velocity of the base model [rad/s]; default ``v_s_rel`` times the 99th
        percentile of ``|q̇|``.
    v_s_rel : float, default 0.01
    n_blocks, validation_blocks, test_blocks, guard_frac
        Held-out split, see :func:`~swgcal.split.time_block_split`. Defaults and ranges
        of every option: :mod:`swgcal.friction.options`.
    candidates : sequence of str, optional
        Kinds of :data:`~swgsim.gear.friction.FRICTION_LIBRARY` with a fit
        (:class:`~swgcal.terms.FitTerm`); default all of them.
    gear_ratio : float, optional
        Reduction ratio N of the strain wave gear (wave-generator turns per output
        turn), when known: ripple periods over q are then expressed and checked as
        wave-generator orders k = 2π / (period · N) (:mod:`swgsim.gear.friction.ripples`).

    Raises
    ------
    ValueError
        An option outside its range (named by its app key, e.g. ``split.n_blocks``),
        an unknown candidate key, or too few samples for the held-out blocks.
    """
    given = {"base_model": {"v_s": v_s, "v_s_rel": v_s_rel}, "gear_ratio": gear_ratio,
             "split": {"n_blocks": n_blocks, "guard_frac": guard_frac,
                       "validation_blocks": list(validation_blocks),
                       "test_blocks": list(test_blocks)}}
    build(complete(given, FrictionOptions, ""), FrictionOptions, "")
    sig = rec.signals(v_s=v_s, v_s_rel=v_s_rel, gear_ratio=gear_ratio)
    fitted = {k: c for k, c in FRICTION_LIBRARY.items() if issubclass(c, FitTerm)}
    keys = check_candidates(candidates, fitted, "friction", "library (the effects with a fit)")
    if rec.n < MIN_ROWS_PER_BLOCK * n_blocks:
        raise ValueError(f"recording {rec.name!r}: {rec.n} samples are too few for "
                         f"split.n_blocks={n_blocks} held-out blocks of at least "
                         f"{MIN_ROWS_PER_BLOCK} samples; allowed: n_blocks <= "
                         f"{rec.n // MIN_ROWS_PER_BLOCK}")
    split = time_block_split(rec.t_s, n_blocks, validation_blocks, test_blocks, guard_frac)
    return Problem(
        name=rec.name, kind="friction", units="N m", signals=sig, y=rec.tau_nm, t=rec.t_s,
        base_model=(PaperLaw(),), library={k: fitted[k] for k in keys},
        probes=friction_probes(temperature=rec.temperature_c is not None), split=split,
        meta={"n_samples": rec.n, "duration_s": float(rec.t_s[-1] - rec.t_s[0]),
              "dt_median_s": sig.scales.dt_med, "v_s_rad_s": sig.v_s,
              "v_ref_rad_s": sig.scales.v_ref, "q_span_rad": sig.scales.q_span,
              "t0_s": sig.scales.t0, "ddq_source": rec.ddq_source,
              "has_load": rec.load_nm is not None, "data_notes": list(rec.notes),
              "temperature_c": None if rec.temperature_c is None else [
                  float(rec.temperature_c.min()), float(rec.temperature_c.max())],
              "gear_ratio": sig.gear_ratio})


def build_problem(measured: str | Path | FrictionRecording, *,
                  accel_window: int = FrictionOptions.accel_window,
                  **options: Any) -> Problem:
    """Calibration problem of a friction recording (data kind 1).

    Parameters
    ----------
    measured : str or Path or FrictionRecording
        A friction CSV (:func:`~swgcal.friction.data.load_friction_csv`) or a
        loaded recording.
    accel_window : int, default 21
        Samples of the Savitzky-Golay estimate of q̈ when the CSV has none.
    **options
        ``v_s``, ``v_s_rel``, ``n_blocks``, ``validation_blocks``, ``test_blocks``,
        ``guard_frac``, ``candidates``, ``gear_ratio``: see :func:`friction_problem`.

    Returns
    -------
    Problem
        ``kind="friction"``, units N m.

    Raises
    ------
    TypeError
        An unknown option (the message lists the allowed ones).
    ValueError
        See :func:`load_friction_csv` and :func:`friction_problem`.
    """
    allowed = [k for k in inspect.signature(friction_problem).parameters if k != "rec"]
    unknown = sorted(set(options) - set(allowed))
    if unknown:
        raise TypeError(f"unknown friction problem options {unknown}; allowed: "
                        f"{sorted(allowed + ['accel_window'])}")
    build(complete({"accel_window": accel_window}, FrictionOptions, ""), FrictionOptions, "")
    rec = (measured if isinstance(measured, FrictionRecording)
           else load_friction_csv(measured, accel_window=accel_window))
    return friction_problem(rec, **options)


def calibrate(problem: Problem, config: SelectionConfig | None = None) -> CalibrationResult:
    """Calibrate a friction problem: :func:`~swgcal.loop.select_effects`, then
    :func:`~swgcal.friction.ripple_groups.group_ripples` (ripple instances that are
    harmonics of one fundamental become one effect; a ripple without held-out evidence of
    its own in the final model is removed).

    Parameters
    ----------
    problem : Problem
        From :func:`friction_problem` or :func:`build_problem`.

    Returns
    -------
    CalibrationResult
        ``problem.meta["ripples"]`` records the grouping (summary key ``ripples``).

    Raises
    ------
    KeyError
        ``config.candidates`` names an effect that is not in the library.
    """
    return group_ripples(select_effects(problem, config))
