"""Discovery on the friction side: the candidate basis of a friction calibration.

The friction adapter of :mod:`swgcal.discovery` (same mechanism,
:func:`~swgcal.discovery.discover`): :func:`friction_basis` builds from the friction
signals ripples over the joint angle at free periods (:func:`line_peaks`), tones in time,
load products, slow trends, other velocity laws and the acceleration; :func:`propose` runs
discovery on a calibration's result. The basis column by column, its nuisance and rows,
and the limits: docs/calibration.md, "Discovery beyond the library".
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from swgsim.gear.friction.ripples import wave_generator_order

from ..discovery import MIN_GAIN, Group, Projector, Proposal, discover, line_spectrum, model_design
from ..loop import CalibrationResult
from ..periodogram import periodogram_peaks
from .ranges import ripple_period_range

__all__ = ["friction_basis", "propose", "line_peaks"]

Describe = Callable[[dict[str, float]], tuple[str, dict[str, Any]]]


def line_peaks(x: np.ndarray, r: np.ndarray, p_min: float, p_max: float, n_peaks: int,
               harmonics: Sequence[int], exclude: Sequence[float] = ()) -> list[float]:
    """Strongest line frequencies of ``r`` over the coordinate ``x`` [cycles per unit of x].

    Coarse: :func:`swgcal.periodogram.periodogram_peaks` (5-fold oversampled FFT of
    the binned signal); a peak within one main lobe (1 / span of x) of a harmonic or
    subharmonic (1..max(harmonics)) of an earlier or excluded line is skipped. Fine: the
    least-squares line spectrum with ``harmonics`` fitted jointly
    (:func:`~swgcal.discovery.line_spectrum`) on ± lobe / 4, then ± lobe /
    80 (21 points each).

    Parameters
    ----------
    x, r : ndarray, shape (n,)
        Coordinate (q [rad] or t [s]) and residual.
    p_min, p_max : float
        Period range [units of x].
    exclude : sequence of float
        Line frequencies found already (e.g. by another search).

    Returns
    -------
    list of float
        Frequencies 1 / period, strongest first.
    """
    span = float(np.ptp(x))
    if span <= 0 or p_min >= p_max:
        return []
    lobe = 1.0 / span
    block = np.zeros(x.size, int)
    h_max = max(harmonics)
    out: list[float] = []
    for period, _ in periodogram_peaks(x, r, p_min, p_max, n_peaks=4 * n_peaks):
        f = 1.0 / period
        near = any(abs(f - h * g) < lobe or abs(f - g / h) < lobe / h
                   for g in list(exclude) + out for h in range(1, h_max + 1))
        if near:
            continue
        for half in (lobe / 4, lobe / 80):
            fine = np.linspace(max(f - half, 0.5 * f), f + half, 21)
            f = float(fine[int(np.argmax(line_spectrum(r, 2 * np.pi * x, block, fine,
                                                       harmonics)))])
        out.append(f)
        if len(out) >= n_peaks:
            break
    return out


def _amp(coef: dict[str, float], base: str, var: str) -> complex:
    suf = "" if var == "plain" else f"_x_{var}"
    return coef.get(f"{base}_cos{suf}", 0.0) - 1j * coef.get(f"{base}_sin{suf}", 0.0)


def _tone_words(kind: str, freq: float, harmonics: Sequence[int], variants: Sequence[str],
                mod_range: dict[str, tuple[float, float, float]], v_ref: float,
                gear_ratio: float | None, motion: float | None = None) -> Describe:
    """Describe function of a tone group over q (``kind="angle_ripple"``) or t
    (``"time_tone"``); ``mod_range``: modulator -> (lowest, mean, highest value);
    ``motion``: the line of the joint's own motion q(t) [Hz] this tone lies on, if any."""

    def describe(coef: dict[str, float]) -> tuple[str, dict[str, Any]]:
        a = {v: np.array([_amp(coef, f"h{h}", v) for h in harmonics]) for v in variants}
        mean = {v: (1.0 if v in ("plain", "sgn") else mod_range[v.removeprefix("sgn")][1])
                for v in variants}
        lvl = {part: sum(mean[v] * a[v] for v in variants
                         if v.startswith("sgn") == (part == "sgn")) for part in ("plain", "sgn")}
        amp = np.abs(lvl["plain"]) + np.abs(lvl["sgn"])  # (n_h,) at the mean operating point
        top = float(amp.max()) if amp.size else 0.0
        hs = [h for j, h in enumerate(harmonics) if amp[j] >= 0.2 * top and top > 0]
        jd = int(np.argmax(amp)) if amp.size else 0
        params: dict[str, Any] = {"harmonics": hs, "amplitude_nm": amp.tolist()}
        if kind == "angle_ripple":
            period = 1.0 / freq
            head = f"ripple over the joint angle, period {period:.4g} rad"
            params["period_rad"] = period
            if gear_ratio:
                k = wave_generator_order(period, gear_ratio)
                head += f" (order {k:.3g} of the wave generator for N = {gear_ratio:g})"
                params["wave_generator_order"] = k
            part_sgn = float(np.abs(lvl["sgn"][jd]))
            part_plain = float(np.abs(lvl["plain"][jd]))
            if part_sgn >= 2 * part_plain:
                head = "friction-level " + head + " (× sgn q̇: changes sign with the direction)"
            elif part_sgn >= 0.5 * part_plain:
                head += ", in part a friction-level ripple (× sgn q̇)"
            params["amplitude_sgn_part_nm"], params["amplitude_plain_part_nm"] = (
                part_sgn, part_plain)
        else:
            head = f"tone in time at {freq:.4g} Hz (fixed frequency, not periodic in q)"
            params["frequency_hz"] = freq
            params["motion_line_hz"] = motion
        extra = [f"{h}" for h in hs if h != 1]
        words = [head + (f" with harmonics {', '.join(extra)}" if extra else "")]
        if motion:  # after the harmonics: the caveat closes the head
            words[0] += (f" (on a line of the joint's own motion, {motion:.4g} Hz or a "
                         "harmonic: may be an effect of the motion, not a vibration)")
        changes = []
        for m, (lo, _, hi) in mod_range.items():
            d = sum((a[v][jd] for v in variants if v.removeprefix("sgn") == m), 0j)
            rest = sum((mean[v] * a[v][jd] for v in variants if v.removeprefix("sgn") != m), 0j)
            if d == 0:
                continue
            grow = abs(rest + hi * d) > abs(rest + lo * d)
            unit = f"per v_ref = {v_ref:.3g} rad/s" if m == "speed" else "per N m"
            txt = "the speed abs(q̇)" if m == "speed" else "the load"
            changes.append(f"amplitude {'growing' if grow else 'falling'} with {txt} "
                           f"({abs(d):.3g} N m {unit})")
            params[f"amplitude_per_{m}_nm"] = float(abs(d))
        words.append(", ".join(changes) if changes else f"amplitude {top:.3g} N m")
        return ", ".join(words), params

    return describe


def _tone_group(key: str, kind: str, freq: float, x: np.ndarray, harmonics: Sequence[int],
                mods: dict[str, np.ndarray], describe: Describe) -> Group:
    """Columns cos, sin(2π h f x) times each modulator (``"plain"`` = 1), named
    ``"h{h}_{cos|sin}[_x_{modulator}]"``."""
    cols, names = [], []
    for h in harmonics:
        ph = 2 * np.pi * h * freq * x
        for nm, f in (("cos", np.cos(ph)), ("sin", np.sin(ph))):
            for m, mv in mods.items():
                cols.append(f * mv)
                names.append(f"h{h}_{nm}" + ("" if m == "plain" else f"_x_{m}"))
    return Group(key, kind, np.column_stack(cols), tuple(names), describe)


@dataclass(frozen=True)
class _Rows:
    """The friction signals on the basis rows (fit and validation rows together), the
    modulators of the candidate columns (``mods``: ``|q̇| / v_ref``, and the load when it
    varies) and their (lowest, mean on the fit rows, highest) values."""

    n: int
    fit: np.ndarray
    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    acc: np.ndarray
    sgn: np.ndarray
    speed: np.ndarray
    load: np.ndarray | None
    mods: dict[str, np.ndarray]
    mod_range: dict[str, tuple[float, float, float]]
    v_ref: float
    dq_med: float
    dt_med: float
    gear_ratio: float | None


def _basis_rows(sig: Any, rows: np.ndarray, fit: np.ndarray) -> _Rows:
    """The signals on ``rows`` (``fit``: the fit rows among them) and the modulators."""
    t, q = sig.t_s[rows], sig.q_rad[rows]
    v, acc = sig.dq_rad_s[rows], sig.ddq_rad_s2[rows]
    sgn = np.tanh(v / sig.v_s)
    v_ref = sig.scales.v_ref
    speed = np.abs(v) / v_ref
    load = None if sig.load_nm is None else np.asarray(sig.load_nm, float)[rows]
    mods = {"speed": speed} | ({} if load is None or np.ptp(load) <= 0 else {"load": load})
    mod_range = {m: (float(mv.min()), float(mv[fit].mean()), float(mv.max()))
                 for m, mv in mods.items()}
    return _Rows(rows.size, fit, t, q, v, acc, sgn, speed, load, mods, mod_range, v_ref,
                 sig.scales.dq_med, sig.scales.dt_med, sig.gear_ratio)


def _angle_ripple_groups(b: _Rows, r0: np.ndarray, n_peaks: int,
                         harmonics: Sequence[int]) -> list[Group]:
    """Ripples over the joint angle at the strongest free periods of the residual: plain
    and × sgn q̇, each also × ``|q̇|`` and × load."""
    q, sgn, mods, fit = b.q, b.sgn, b.mods, b.fit
    q_mods = {"plain": np.ones(b.n), "sgn": sgn} | mods | {f"sgn{m}": sgn * mv
                                                            for m, mv in mods.items()}
    p_lo, p_hi, _ = ripple_period_range()
    p_min, p_max = max(p_lo, 4.0 * b.dq_med), min(p_hi, 0.5 * float(np.ptp(q)))
    found: list[float] = []
    # lines of the residual, of the residual × sgn q̇ (a friction-level ripple) and of
    # the residual × each centred modulator (a ripple whose mean amplitude the model
    # holds already, but not its growth with speed or load)
    centred = [(mv - mv[fit].mean()) / (mv[fit].std() or 1.0) for mv in mods.values()]
    for rr in [r0, r0 * sgn] + [r0 * c for c in centred]:
        found += line_peaks(q, rr, p_min, p_max, n_peaks, harmonics, exclude=found)
    groups = []
    for f in found:
        words = _tone_words("angle_ripple", f, harmonics, list(q_mods), b.mod_range, b.v_ref,
                            b.gear_ratio)
        groups.append(_tone_group(f"ripple over q {1 / f:.4g} rad", "angle_ripple", f, q,
                                  harmonics, q_mods, words))
    return groups


def _time_tone_groups(b: _Rows, r0: np.ndarray, n_peaks: int,
                      harmonics: Sequence[int]) -> list[Group]:
    """Tones in time at the strongest fixed frequencies of the residual, plain and × ``|q̇|``
    (and × load); a tone on a line of the joint's own motion says so."""
    t, q = b.t, b.q
    t_mods = {"plain": np.ones(b.n)} | b.mods
    dt_med, t_span = b.dt_med, float(np.ptp(t))
    lobe_t = 1.0 / max(t_span, 1e-12)
    motion_lines = line_peaks(t, q - q.mean(), 2.5 * dt_med, t_span / 2, 3, harmonics)
    groups = []
    for f in line_peaks(t, r0, 2.5 * dt_med, t_span / 4, n_peaks, harmonics):
        on = next((g for g in motion_lines for h in harmonics
                   if abs(f - h * g) < lobe_t), None)
        words = _tone_words("time_tone", f, harmonics, list(t_mods), b.mod_range, b.v_ref,
                            None, on)
        groups.append(_tone_group(f"tone in time {f:.4g} Hz", "time_tone", f, t, harmonics,
                                  t_mods, words))
    return groups


def _load_groups(b: _Rows) -> list[Group]:
    """Friction level and viscous friction times the load (none without a varying
    load)."""
    if "load" not in b.mods:
        return []

    def load_words(coef: dict[str, float]) -> tuple[str, dict[str, Any]]:
        c0, c1 = coef.get("sgn_load", 0.0), coef.get("v_load", 0.0)
        parts = [f"friction level {'grows' if c0 > 0 else 'falls'} with the load "
                 f"({c0:+.3g} N m per N m)"] if c0 else []
        if c1:
            parts.append(f"viscous friction {'grows' if c1 > 0 else 'falls'} with the "
                         f"load ({c1:+.3g} N m s/rad per N m)")
        return "; ".join(parts), {"level_per_load": c0, "viscous_per_load_s_per_rad": c1}
    return [Group("load", "load_modulation", np.column_stack([b.sgn * b.load, b.v * b.load]),
                  ("sgn_load", "v_load"), load_words)]


def _trend_groups(b: _Rows) -> list[Group]:
    """Slow trends in time (Legendre P1-P3 of the normalised time): an offset and, × sgn
    q̇ (P1, P2), a friction level that drift."""
    t = b.t
    t_span = float(np.ptp(t))
    tau = (t - 0.5 * (t.min() + t.max())) / max(0.5 * t_span, 1e-12)
    leg = [tau, 0.5 * (3 * tau ** 2 - 1), 0.5 * (5 * tau ** 3 - 3 * tau)]
    grid = np.linspace(-1, 1, 201)
    leg_g = [grid, 0.5 * (3 * grid ** 2 - 1), 0.5 * (5 * grid ** 3 - 3 * grid)]

    def trend_words(coef: dict[str, float], level: bool = False) -> tuple[str, dict[str, Any]]:
        c = [coef.get(f"p{i + 1}", 0.0) for i in range(3)]
        dev = float(np.max(np.abs(sum(ci * g for ci, g in zip(c, leg_g, strict=True)))))
        what = ("friction level drifts slowly in time (× sgn q̇)" if level
                else "slow trend in time (a torque offset that drifts)")
        return (f"{what}: up to {dev:.3g} N m over the recording",
                {"legendre_nm": c, "max_deviation_nm": dev})
    return [Group("trend", "trend", np.column_stack(leg), ("p1", "p2", "p3"), trend_words),
            Group("level trend", "level_trend", np.column_stack([b.sgn * g for g in leg[:2]]),
                  ("p1", "p2"), lambda c: trend_words(c, level=True))]


def _velocity_groups(b: _Rows, powers: Sequence[float]) -> list[Group]:
    """A velocity law beyond sgn, q̇, q̇³ (``sgn(q̇) |q̇ / v_ref|^p``) and a torque
    proportional to the acceleration."""
    v_ref = b.v_ref

    def vel_words(coef: dict[str, float]) -> tuple[str, dict[str, Any]]:
        terms = [f"{coef.get(f'pow{pw:g}', 0.0):+.3g} N m · sgn(q̇) abs(q̇/v_ref)^{pw:g}"
                 for pw in powers if coef.get(f"pow{pw:g}", 0.0)]
        return (f"velocity law beyond the model: {' '.join(terms)} (v_ref = {v_ref:.3g} "
                "rad/s)", {f"pow{pw:g}_nm": coef.get(f"pow{pw:g}", 0.0) for pw in powers})
    return [Group("velocity law", "velocity_law",
                  np.column_stack([b.sgn * b.speed ** pw for pw in powers]),
                  tuple(f"pow{pw:g}" for pw in powers), vel_words),
            Group("acceleration", "acceleration", b.acc[:, None], ("ddq",),
                  lambda c: (f"torque proportional to the acceleration q̈ "
                             f"({c.get('ddq', 0.0):+.3g} N m s²/rad)",
                             {"coef_nm_s2_per_rad": c.get("ddq", 0.0)}))]


def friction_basis(result: CalibrationResult, n_peaks: int = 2,
                   harmonics: Sequence[int] = (1, 2, 3),
                   powers: Sequence[float] = (0.5, 1.5, 2.0)
                   ) -> tuple[np.ndarray, list[Group], np.ndarray, np.ndarray, Projector]:
    """Candidate basis of a friction calibration
    (docs/calibration.md, "Discovery beyond the library").

    Parameters
    ----------
    result : CalibrationResult
        A friction calibration (``result.problem.kind == "friction"``).
    n_peaks : int, default 2
        Free periods over q (per search: residual, residual × sgn q̇) and fixed
        frequencies in time.
    harmonics : sequence of int, default (1, 2, 3)
    powers : sequence of float, default (0.5, 1.5, 2)
        Exponents p of the velocity-law columns ``sgn(q̇) |q̇ / v_ref|^p``.

    Returns
    -------
    target : ndarray, shape (n_rows,)
        Measured friction torque on the fit and validation rows [N m].
    groups : list of Group
    fit, validation : ndarray of int
        Row indices.
    projector : Projector
        The final model's design and a constant, fitted on the fit rows.

    Raises
    ------
    ValueError
        A problem that is not a friction problem.
    """
    p = result.problem
    if p.kind != "friction":
        raise ValueError(f"problem.kind must be 'friction' for friction_basis, got {p.kind!r}")
    rows = np.union1d(p.split.fit, p.split.validation)
    fit = np.searchsorted(rows, p.split.fit)
    val = np.searchsorted(rows, p.split.validation)
    x0, _ = model_design(result)
    proj = Projector(np.hstack([x0[rows], np.ones((rows.size, 1))]), fit)
    y = np.asarray(p.y, float)[rows]
    r0 = proj.resid(y)
    b = _basis_rows(p.signals, rows, fit)
    groups = (_angle_ripple_groups(b, r0, n_peaks, harmonics)
              + _time_tone_groups(b, r0, n_peaks, harmonics)
              + _load_groups(b) + _trend_groups(b) + _velocity_groups(b, powers))
    for g in groups:  # the candidate's key in the proposal (for propose_friction)
        g.describe = _keyed(g.describe, g.key)
    return y, groups, fit, val, proj


def _keyed(describe: Describe, key: str) -> Describe:
    def out(coef: dict[str, float]) -> tuple[str, dict[str, Any]]:
        words, params = describe(coef)
        return words, {**params, "candidate": key}
    return out


def propose(result: CalibrationResult, max_terms: int = 5, min_gain: float = MIN_GAIN,
            only_if_structured: bool = True) -> list[Proposal]:
    """Terms beyond the friction library: :func:`~swgcal.discovery.discover` on
    :func:`friction_basis`, repeated without the candidates whose held-out gain in the
    joint fit of the kept proposals is not above ``min_gain`` (forward selection admits
    a term on its gain at the time; once the variants are reduced, a later term can take
    its share), until every proposal gains more than ``min_gain`` (at most 5 rounds).

    Parameters
    ----------
    result : CalibrationResult
        A friction calibration.
    min_gain : float, default :data:`~swgcal.discovery.MIN_GAIN`
    only_if_structured : bool, default True
        Propose nothing when the loop's final residual is not structured
        (``result.unexplained`` false).

    Returns
    -------
    list of Proposal
        Each with ``parameters["candidate"]``, the key of its basis group.

    Raises
    ------
    ValueError
        Not a friction problem; ``max_terms`` or ``min_gain`` out of range
        (:func:`~swgcal.discovery.discover`).
    """
    if only_if_structured and not result.unexplained:
        return []
    y, groups, fit, val, proj = friction_basis(result)
    props: list[Proposal] = []
    for _ in range(5):
        props = discover(y, groups, fit, val, proj, max_terms=max_terms, min_gain=min_gain)
        weak = {p.parameters["candidate"] for p in props if p.heldout_gain <= min_gain}
        if not weak:
            return props
        groups = [g for g in groups if g.key not in weak]
    return [p for p in props if p.heldout_gain > min_gain]
