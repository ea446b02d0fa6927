"""Measured strain windows (data kind 2) as a calibration problem, and its calibration.

Input: a schema-v1 data set of bench windows with their operating points; output: the
fitted chain, the effects the data need from the declared library (:mod:`.effects`), the
error before and after on held-out windows and the accepted effects as a simulation option.
:func:`build_problem` (or :func:`strain_problem`) simulates each operating point once
(:class:`StrainModel`), aligns every window's two phases on its own data and splits whole
windows or operating points; :func:`calibrate` runs :mod:`swgcal.loop`. The window's
model, the held-out split, the limitations: docs/calibration.md, "Strain windows (kind 2)".
"""

from __future__ import annotations

import contextlib
import logging
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from swgsim.sensing.effects import psi_rate

from ..loop import CalibrationResult, Problem, SelectionConfig, check_candidates, select_effects
from ..split import HeldOutSplit, group_split
from .data import StrainWindows, heldout_split, strain_windows
from .effects import ChainBaseModel, StrainSignals, strain_library, strain_probes
from .model import Realigner, StrainModel

log = logging.getLogger(__name__)

__all__ = [
    "StrainWindows",
    "StrainModel",
    "strain_windows",
    "strain_problem",
    "build_problem",
    "calibrate",
    "one_blas_thread",
    "StrainOptions",
    "OPTIONS",
]


@dataclass(frozen=True)
class StrainOptions:
    """The app options of a strain problem besides ``selection``: none (the held-out
    split comes from the data set's metadata; see :func:`strain_problem`)."""

    def problem_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :func:`build_problem` (none)."""
        return {}


#: The typed options of this kind's problem (read by :func:`swgcal.api.options_from_config`).
OPTIONS = StrainOptions

def strain_problem(win: StrainWindows, model: StrainModel | None = None, *,
                   heldout: str = "windows", validation: Sequence[int] | None = None,
                   test: Sequence[int] | None = None, candidates: Sequence[str] | None = None,
                   window_period_s: float | None = None,
                   f_c_bounds_hz: tuple[float, float] | None = None,
                   ke_bound_rad: float = 2e-3) -> Problem:
    """Calibration problem for measured strain windows.

    Parameters
    ----------
    model : StrainModel, optional
        Reused across calls to share simulated operating points.
    heldout : {"windows", "operating_points"}
        Hold out whole windows (default) or whole operating points.
    validation, test : sequence of int, optional
        Data-set sample indices (``heldout="windows"``) or operating-point indices
        (``"operating_points"``); default chosen by metadata (docs/calibration.md,
        "Strain windows (kind 2)").
    candidates : sequence of str, optional
        Library keys to try (default: all of :func:`strain_library`).
    window_period_s : float, optional
        Time between the starts of consecutive data-set samples, for the thermal drift
        [s]; default the window length (back-to-back windows).
    f_c_bounds_hz : (float, float), optional
        Range of the low-pass cut-off [Hz]; default half the highest order-2 frequency
        to 0.45 fs.
    ke_bound_rad : float, default 2e-3
        Bound of the extra kinematic-error coefficients [rad] (7 arcmin, far above the
        catalogue's about 1 arcmin in total).

    Raises
    ------
    ValueError
        Unknown candidate (:func:`swgcal.loop.check_candidates`), bad held-out settings, a
        window shorter than one WG half revolution, or bad bounds.
    """
    model = model if model is not None else StrainModel()
    lib_all = strain_library(model.ke_orders)
    keys = check_candidates(candidates, lib_all, "strain")
    rate, (lo, hi), n_lead, n_tail = _filter_margins(win, model, f_c_bounds_hz)
    role, held_text = heldout_split(win, heldout, validation, test)
    sim = _simulate_windows(win, model, n_lead, n_tail)
    period = float(window_period_s) if window_period_s is not None else win.n_t / win.fs
    if not period > 0:
        raise ValueError(f"window_period_s must be > 0 [s], got {window_period_s}")
    sig = _strain_signals(win, model, sim, rate, period, (lo, hi), ke_bound_rad)
    split = _window_split(win, role, held_text, heldout, sig.window)
    meta = _problem_meta(win, model, sim, role, period, (lo, hi), n_tail, sig.weights)
    return Problem(name=win.name, kind="strain", units="mV/V", signals=sig,
                   y=win.y.reshape(-1).astype(float), t=sig.t_s,
                   base_model=(ChainBaseModel.for_signals(sig),),
                   library={k: lib_all[k] for k in keys}, probes=strain_probes(), split=split,
                   meta=meta)


def _filter_margins(win: StrainWindows, model: StrainModel,
                    f_c_bounds_hz: tuple[float, float] | None
                    ) -> tuple[np.ndarray, tuple[float, float], int, int]:
    """ψ̇ per window [rad/s], the low-pass cut-off range [Hz] and the lead and tail of
    simulated history that filters and shifts need [samples]."""
    fs, n_t = win.fs, win.n_t
    rate = psi_rate(win.n_in_mean_rpm, float(model.params.gear.ratio))  # (n_w,)
    f2 = 2 * rate / (2 * np.pi)
    if n_t / fs < np.pi / rate.min():
        raise ValueError(f"windows of {n_t / fs * 1e3:.1f} ms are shorter than half a WG "
                         f"revolution ({np.pi / rate.min() * 1e3:.1f} ms): cannot align")
    lo, hi = f_c_bounds_hz if f_c_bounds_hz is not None else (0.5 * f2.max(), 0.45 * fs)
    if not 0 < lo < hi < 0.5 * fs:
        raise ValueError(f"f_c_bounds_hz must satisfy 0 < lo < hi < {0.5 * fs:g} Hz, got "
                         f"{(lo, hi)}")
    n_lead = int(np.ceil(6.0 / (2 * np.pi * lo) * fs)) + 4
    n_tail = int(np.ceil(np.max(np.arctan(f2 / lo) / (2 * np.pi * f2)) * fs)) + 6
    return rate, (lo, hi), n_lead, n_tail


def _simulate_windows(win: StrainWindows, model: StrainModel, n_lead: int,
                      n_tail: int) -> dict[str, Any]:
    """The chain at each operating point, aligned to each window: the basis signals
    (``s_wg``, ``s_t``, ``dpsi``; shape (n_w, 5, n_lead + n_t + n_tail)), ψ and φ_in of
    the windows, the alignment shifts [s], the model efficiency and the realigner."""
    n_w, n_t, fs = win.n_windows, win.n_t, win.fs
    parts: dict[str, np.ndarray] = {}
    shifts = np.empty(n_w)
    eff = np.empty(n_w)
    opms = []
    for i, (n_in, t_out) in enumerate(win.ops):
        ws = np.flatnonzero(win.op == i)
        opm = model.op_model(n_in, t_out, fs, n_t, n_lead, n_tail)
        opms.append(opm)
        sh = model.align_psi(opm, win.y[ws])
        for k, v in model.psi_parts(opm, sh, n_t, n_lead, n_tail).items():
            parts.setdefault(k, np.empty((n_w,) + v.shape[1:]))[ws] = v
        shifts[ws] = sh
        eff[ws] = opm.efficiency
    realign = Realigner(model, opms, win.op, parts, win.y, n_lead)
    first = realign(())
    return {"basis": {"s_wg": parts["s_wg"], "s_t": first["s_t"], "dpsi": first["dpsi"]},
            "psi_w": parts["psi"][:, n_lead:n_lead + n_t],
            "phi_w": first["phi_in"][:, n_lead:n_lead + n_t],
            "shifts": shifts, "shifts_t": first["shift_t"], "efficiency": eff,
            "realign": realign, "n_lead": n_lead}


def _constraint_weights(basis: Mapping[str, np.ndarray], n_lead: int, n_t: int
                        ) -> dict[str, np.ndarray]:
    """Constraint weights, shape (5,) each: gains relative to the plain mean;
    misplacements relative to the mean weighted like the alignment (sensitivity of the
    correlation to each channel)."""
    sl = slice(n_lead, n_lead + n_t)
    p = basis["s_wg"][:, :, sl] + basis["s_t"][:, :, sl]
    d = basis["dpsi"][:, :, sl]
    p = p - p.mean(-1, keepdims=True)
    d = d - d.mean(-1, keepdims=True)
    proj = (d * p).sum(-1, keepdims=True) / np.maximum((p * p).sum(-1, keepdims=True), 1e-30)
    w_mis = ((d - proj * p) ** 2).sum(-1).sum(0)  # (5,)
    w_mis = np.maximum(w_mis, 1e-12 * w_mis.max())
    return {"gain": np.ones(5), "misplacement": w_mis}


def _strain_signals(win: StrainWindows, model: StrainModel, sim: Mapping[str, Any],
                    rate: np.ndarray, period: float, f_c_bounds: tuple[float, float],
                    ke_bound_rad: float) -> StrainSignals:
    """The signals of the fit, one sample per (window, channel, time), flattened."""
    n_w, n_t, n_lead = win.n_windows, win.n_t, sim["n_lead"]
    t_start = (win.sample - win.sample.min()) * period  # (n_w,)
    shape = (n_w, 5, n_t)
    wi = np.broadcast_to(np.arange(n_w)[:, None, None], shape).ravel()
    ci = np.broadcast_to(np.arange(5)[None, :, None], shape).ravel()
    ts = np.broadcast_to(win.time_s[None, None, :] - win.time_s[0], shape).ravel()
    return StrainSignals(
        raw=sim["basis"], n_lead=n_lead, n_t=n_t, fs=win.fs, window=wi, channel=ci,
        op=win.op[wi], t_s=ts, t_seq_s=t_start[wi] + ts,
        phi_in_rad=np.broadcast_to(sim["phi_w"][:, None, :], shape).ravel(),
        psi_rad=np.broadcast_to(sim["psi_w"][:, None, :], shape).ravel(),
        psi_rate=rate, n_in_rpm=win.n_in_mean_rpm, t_out_nm=win.t_out_mean_nm, ops=win.ops,
        w0_nom_m=float(model.params.w0_m),
        weights=_constraint_weights(sim["basis"], n_lead, n_t), maps=(),
        ripple=sim["realign"], ke=(), ke_orders=model.ke_orders,
        ke_bound_rad=float(ke_bound_rad), f_c_bounds=(float(f_c_bounds[0]),
                                                      float(f_c_bounds[1])))


def _window_split(win: StrainWindows, role: np.ndarray, held_text: str, heldout: str,
                  groups: np.ndarray) -> HeldOutSplit:
    """Held-out split of whole windows (``groups``: the window of each sample). The
    diagnosis splits samples into halves of contiguous blocks of Problem.t: with the time
    within the window, the halves are interleaved time slices of every window."""
    split = group_split(groups, np.flatnonzero(role == 1).tolist(),
                        np.flatnonzero(role == 2).tolist())
    desc = dict(split.description)
    desc.update({"method": ("whole windows held out by metadata" if heldout == "windows" else
                            "whole operating points held out"),
                 "text": held_text,
                 "validation_samples": win.sample[role == 1].tolist(),
                 "test_samples": win.sample[role == 2].tolist(),
                 "fit_samples": win.sample[role == 0].tolist()})
    return HeldOutSplit(split.fit, split.validation, split.test, desc)


def _problem_meta(win: StrainWindows, model: StrainModel, sim: Mapping[str, Any],
                  role: np.ndarray, period: float, f_c_bounds: tuple[float, float],
                  n_tail: int, weights: Mapping[str, np.ndarray]) -> dict[str, Any]:
    """What the report carries: sizes, operating points, the alignment of each window."""
    n_w, n_t, fs = win.n_windows, win.n_t, win.fs
    rng_psi0 = np.rad2deg(np.mod(sim["psi_w"][:, 0], np.pi))
    phi0 = np.rad2deg(np.mod(sim["phi_w"][:, 0], 2 * np.pi))
    return {
        "n_windows": n_w, "n_t": n_t, "sample_rate_hz": fs, "window_s": n_t / fs,
        "operating_points": [list(o) for o in win.ops],
        "windows_per_op": np.bincount(win.op, minlength=len(win.ops)).tolist(),
        "n_lead": sim["n_lead"], "n_tail": n_tail, "window_period_s": period,
        "alignment": [{"sample": int(s), "op": int(o), "shift_psi_s": float(sh),
                       "shift_torque_s": float(st), "psi0_deg": float(a),
                       "phi_in0_deg": float(b), "role": ("fit", "validation", "test")[r]}
                      for s, o, sh, st, a, b, r in zip(win.sample, win.op, sim["shifts"],
                                                       sim["shifts_t"], rng_psi0, phi0, role,
                                                       strict=True)],
        "model_efficiency": sim["efficiency"].tolist(),
        "weights": {k: v.tolist() for k, v in weights.items()},
        "f_c_bounds_hz": [float(f_c_bounds[0]), float(f_c_bounds[1])],
        "gear_ratio": float(model.params.gear.ratio), "w0_nom_m": float(model.params.w0_m),
        "source": win.source,
    }


# ---------------------------------------------------------------------------------------
# the kind's steps: build problem -> calibrate (summarise, render: .report; figures)

_PROBLEM_KEYS = ("heldout", "validation", "test", "candidates", "window_period_s",
                 "f_c_bounds_hz", "ke_bound_rad")


@contextlib.contextmanager
def one_blas_thread():
    """BLAS limited to one thread within the block (through ``threadpoolctl`` where
    installed). The strain side's products are small (hundreds × hundreds): one thread
    is fastest, and on shared cores threading cost 20× (measured)."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - optional
        yield
        return
    with threadpool_limits(limits=1, user_api="blas"):
        yield


def build_problem(measured: Any, *, model: StrainModel | None = None,
                  select: Mapping[str, Any] | None = None, max_windows: int | None = None,
                  name: str | None = None, **options: Any) -> Problem:
    """Calibration problem of measured strain windows (data kind 2).

    Parameters
    ----------
    measured : path-like or xarray.Dataset or StrainWindows
        A schema-v1 data-set directory (``manifest.json``), a loaded data set, or windows.
    model : StrainModel, optional
        Reuse simulated operating points across calls (default: a new nominal model).
    select, max_windows, name
        Window selection and the data set's name, see :func:`strain_windows`.
    **options
        ``heldout``, ``validation``, ``test``, ``candidates``, ``window_period_s``,
        ``f_c_bounds_hz``, ``ke_bound_rad``: see :func:`strain_problem`.

    Returns
    -------
    Problem
        ``kind="strain"``, units mV/V.

    Raises
    ------
    TypeError
        An unknown option (the message lists the allowed ones).
    ValueError
        An unknown candidate, before the data are read
        (:func:`swgcal.loop.check_candidates`); see :func:`strain_windows`,
        :func:`strain_problem`.
    """
    unknown = sorted(set(options) - set(_PROBLEM_KEYS))
    if unknown:
        raise TypeError(f"unknown strain problem options {unknown}; allowed: "
                        f"{sorted(_PROBLEM_KEYS)}")
    model = model if model is not None else StrainModel()
    # before the data set is loaded
    check_candidates(options.get("candidates"), strain_library(model.ke_orders), "strain")
    win = (measured if isinstance(measured, StrainWindows)
           else strain_windows(measured, select, max_windows, name))
    with one_blas_thread():
        return strain_problem(win, model, **options)


def calibrate(problem: Problem, config: SelectionConfig | None = None) -> CalibrationResult:
    """Calibrate the chain against measured strain windows: the selection loop
    (:func:`swgcal.loop.select_effects`) with BLAS on one thread.

    Parameters
    ----------
    problem : Problem
        From :func:`build_problem`.

    Raises
    ------
    KeyError
        ``config.candidates`` names an effect that is not in the problem's library.
    """
    t0 = time.perf_counter()
    with one_blas_thread():
        result = select_effects(problem, config)
    log.info("strain calibration of %s: test RMSE %.4g -> %.4g mV/V, added %s, unexplained "
             "%s (%.1f s)", problem.name, result.rmse_before, result.rmse_after,
             [t.name for t in result.effect_terms()], result.unexplained,
             time.perf_counter() - t0)
    return result
