"""Discovery on the strain side: the candidate basis of a strain calibration.

Groups: crosstalk between channels, tones at a free order of the input rotation or a
fixed frequency with harmonics, per-channel gain and offset times load and speed, slow
trends; the engine (nuisance projection, lasso screening, held-out scoring, words) is
:func:`swgcal.discovery.discover`. Tones whose phase the model cannot know
(a free order, mains hum) get one phase per window and harmonic, estimated on that
window's own residual like the WG-angle alignment (:mod:`.model`), so held-out windows
are treated exactly like fit windows.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..discovery import (
    LOAD_SPEED_COLLINEAR,
    MIN_GAIN,
    Group,
    Projector,
    Proposal,
    discover,
    model_design,
    spectral_peaks,
    tone_group,
)
from ..loop import CalibrationResult
from .signals import SENSORS

__all__ = ["strain_basis", "propose"]


def _fmt_unit(v: float, unit: str) -> str:
    return f"{v * 1e3:.2g} µV/V" if unit == "mV/V" else f"{v:.3g} {unit}"


# ---------------------------------------------------------------------------------------
# strain adapter


def _mains(f: float) -> int | None:
    """50 or 60 when a fixed frequency lies within 2 % of that mains frequency."""
    return next((m for m in (50, 60) if abs(f - m) <= 0.02 * m), None)


def _tone_words(kind: str, value: float, harmonics: Sequence[int], channels: Sequence[str],
                mods: Mapping[str, tuple[float, float, str]], mean_mod: Mapping[str, float],
                unit: str, joint: str = "") -> Callable[[dict[str, float]],
                                                        tuple[str, dict[str, Any]]]:
    """Describe function of a tone group (see :func:`tone_group` for the column names).

    ``mods`` maps a modulator to (lowest, highest value in the data, words), ``mean_mod``
    to its mean; amplitudes are quoted at the mean operating point."""
    n_c = len(channels)

    def cplx(coef, h, c, suf=""):
        return coef.get(f"h{h}_{c}_cos{suf}", 0.0) - 1j * coef.get(f"h{h}_{c}_sin{suf}", 0.0)

    def describe(coef: dict[str, float]) -> tuple[str, dict[str, Any]]:
        a = {m: np.array([[cplx(coef, h, c, f"_x_{m}") for c in range(n_c)] for h in harmonics])
             for m in mods}
        a0 = np.array([[cplx(coef, h, c) for c in range(n_c)] for h in harmonics])
        at_mean = a0 + sum(mean_mod[m] * a[m] for m in mods)
        amp = np.abs(at_mean)  # (n_h, n_c)
        top = float(amp.max()) if amp.size else 0.0
        hs = [h for j, h in enumerate(harmonics) if amp[j].max() >= 0.2 * top]
        jd = int(np.argmax(amp.max(axis=1)))
        carry = [c for c in range(n_c) if amp[jd, c] >= 0.3 * amp[jd].max()]
        where = ("all channels" if len(carry) == n_c
                 else ", ".join(channels[c] for c in carry))
        m = _mains(value) if kind == "fixed_tone" else None
        if kind == "order_tone":
            head, extra = (f"tone at order {value:.2f} of the input rotation",
                           [f"orders {h * value:.2f}" for h in hs if h != 1])
        else:
            head = f"{m} Hz mains hum" if m else f"tone at {value:.4g} Hz (fixed frequency)"
            extra = [f"{h * (m or value):.4g} Hz" for h in hs if h != 1]
        more = f" with harmonics at {', '.join(extra)}" if extra else ""
        words = [f"{head}{more} in {where}"]
        params: dict[str, Any] = {
            ("order" if kind == "order_tone" else "frequency_hz"): value,
            "harmonics": hs, "channels": [channels[c] for c in carry],
            "amplitude_at_mean_op": {f"h{h}": amp[j].tolist() for j, h in enumerate(harmonics)},
            "unit": unit}
        changes = []
        for mn, (lo, hi, text) in mods.items():
            d = a[mn][jd, carry]
            if not np.any(d):
                continue
            rest = at_mean[jd, carry] - mean_mod[mn] * d
            grow = np.sum(np.abs(rest + hi * d)) > np.sum(np.abs(rest + lo * d))
            slope = float(np.mean(np.abs(d)))
            changes.append(f"amplitude {'growing' if grow else 'falling'} with {text} "
                           f"({_fmt_unit(slope, unit)} per {_MOD_UNIT[mn]})")
            params[f"amplitude_per_{mn}"] = np.abs(a[mn][jd]).tolist()
        words.append(", ".join(changes) + joint if changes else
                     f"amplitude {_fmt_unit(float(np.mean(amp[jd, carry])), unit)}")
        return ", ".join(words), params

    return describe


_MOD_UNIT = {"load": "N m", "speed": "1000 rpm", "time": "s"}
_MOD_TEXT = {"load": "load", "speed": "speed"}


def _mod_words(coef: Mapping[str, float], mods: Sequence[str], scale: float, unit: str,
               joint: str) -> tuple[list[str], dict[str, float]]:
    """'grows with load: +0.05 %/N m' per modulator with a non-zero coefficient."""
    out, params = [], {}
    for m in mods:
        b = coef.get(f"x_{m}", 0.0)
        params[f"per_{m}"] = b
        if b:
            val = f"{scale * b:+.2g} %" if unit == "%" else _fmt_unit(b, unit)
            out.append(f"{'grows' if b > 0 else 'falls'} with {_MOD_TEXT[m]}: {val}"
                       f"{'/' if unit == '%' else ' per '}{_MOD_UNIT[m]}")
    if out and joint:
        out[-1] += joint
    return out, params


@dataclass(frozen=True)
class _Rows:
    """A strain calibration on the basis rows (fit and validation rows together): window
    ``w`` and channel ``ch`` of every row, the channels one-hot (``oh``), the sample
    within the window (``t_idx``), the final model's signals ``pred`` (windows × channels
    × time), the modulators (``mods``: load, and speed unless it varies with the load;
    ``joint``: the words saying so), their ranges and means on the fit rows."""

    fit: np.ndarray
    w: np.ndarray
    ch: np.ndarray
    oh: np.ndarray
    t_idx: np.ndarray
    pred: np.ndarray
    mods: dict[str, np.ndarray]
    joint: str
    rng: dict[str, tuple[float, float, str]]
    mean_mod: dict[str, float]


def _nuisance(b: _Rows, x0: np.ndarray, sig_f: Any, t_seq: np.ndarray, rows: np.ndarray
              ) -> Projector:
    """The final model's design ``x0`` and the library's linear directions per channel
    (offset, gain, misplacement −∂s/∂ψ, drift ``t_seq``, the bridge nonlinearity's −s²)
    on the basis rows; local: each window's ∂s/∂ψ."""
    oh = b.oh
    pred_nom = sig_f.prediction()[rows]
    nuis = np.hstack([x0, oh, oh * t_seq[:, None], oh * pred_nom[:, None],
                      oh * (-sig_f.col("dpsi")[rows])[:, None], -(pred_nom ** 2)[:, None]])
    # each window's WG angle is a nuisance fitted on its own data (the alignment): its
    # first-order change, ∂s/∂ψ on all channels, is a local nuisance of the window
    return Projector(nuis, b.fit, sig_f.col("dpsi")[rows], b.w)


def _basis_rows(result: CalibrationResult, rows: np.ndarray, fit: np.ndarray) -> _Rows:
    """Windows, channels, the final model's signals and the modulators on ``rows``."""
    sig = result.problem.signals
    w, ch = sig.window[rows], sig.channel[rows]
    oh = (ch[:, None] == np.arange(5)[None, :]).astype(float)
    pred = result.final.predict(sig).reshape((sig.n_windows, 5, sig.n_t))
    t_idx = (np.arange(sig.n) % sig.n_t)[rows]
    load_w, speed_w = np.asarray(sig.t_out_nm, float), np.asarray(sig.n_in_rpm, float) / 1e3
    corr = (abs(np.corrcoef(load_w, speed_w)[0, 1])
            if np.ptp(load_w) > 0 and np.ptp(speed_w) > 0 else 1.0)
    mods = {"load": load_w[w]}
    joint = ""
    if corr < LOAD_SPEED_COLLINEAR:
        mods["speed"] = speed_w[w]
    else:
        joint = " (load and speed vary together in these data: either may be the cause)"
    rng = {m: (float(v.min()), float(v.max()), _MOD_TEXT[m]) for m, v in mods.items()}
    mean_mod = {m: float(v[fit].mean()) for m, v in mods.items()}
    return _Rows(fit, w, ch, oh, t_idx, pred, mods, joint, rng, mean_mod)


def _crosstalk_groups(b: _Rows, sig_f: Any) -> list[Group]:
    """Crosstalk: the final model's signal of channel a on the rows of channel b, plain
    and × load and speed; sources whose model signals are the same up to an offset (s1
    and s3, s2 and s4 of the nominal layout) are one source."""
    mods, mean_mod, joint, shape = b.mods, b.mean_mod, b.joint, b.pred.shape
    nom = sig_f.prediction().reshape(shape)
    nom = nom - nom.mean(axis=(0, 2), keepdims=True)
    same = [[a2 for a2 in range(5) if np.allclose(nom[:, a], nom[:, a2], rtol=1e-6,
                                                  atol=1e-6 * np.abs(nom).max())]
            for a in range(5)]
    groups = []
    for a in range(5):
        for c in range(5):
            if c in same[a] or min(same[a]) < a:  # a gain of c, or a source done already
                continue
            col = b.oh[:, c] * b.pred[b.w, a, b.t_idx]
            cols = np.column_stack([col] + [col * v for v in mods.values()])
            names = ("plain",) + tuple(f"x_{m}" for m in mods)
            alias = [SENSORS[x] for x in same[a] if x != a]
            src = SENSORS[a] + (f" (or {', '.join(alias)}: the same signal in the model)"
                                if alias else "")

            def xt_words(coef, a=a, c=c, src=src):
                mean = coef["plain"] + sum(mean_mod[m] * coef.get(f"x_{m}", 0.0) for m in mods)
                mw, mp = _mod_words(coef, list(mods), 100.0, "%", joint)
                txt = f"crosstalk: {100 * mean:.2g} % of {src} in {SENSORS[c]}"
                return ((txt + ", " + ", ".join(f"fraction {x}" for x in mw)) if mw else txt,
                        {"source": SENSORS[a], "target": SENSORS[c], "fraction": mean,
                         "fraction_plain": coef["plain"], **{f"fraction_{k}": v
                                                             for k, v in mp.items()}})
            groups.append(Group(f"crosstalk {SENSORS[a]}->{SENSORS[c]}", "crosstalk", cols,
                                names, xt_words))
    return groups


def _channel_groups(b: _Rows, t_seq: np.ndarray) -> list[Group]:
    """Per channel: gain and offset times load and speed, and a slow trend (Legendre P2,
    P3 of the time along the recording ``t_seq`` on the basis rows)."""
    mods, joint, oh = b.mods, b.joint, b.oh
    tau = (t_seq - 0.5 * (t_seq.min() + t_seq.max())) / max(0.5 * np.ptp(t_seq), 1e-12)
    groups = []
    for c in range(5):
        own = oh[:, c] * b.pred[b.w, c, b.t_idx]
        for kind, col, scale, unit, what in (("gain_modulation", own, 100.0, "%", "gain"),
                                             ("offset_modulation", oh[:, c], 1.0, "mV/V",
                                              "offset")):
            def mod_words(coef, c=c, scale=scale, unit=unit, what=what):
                mw, mp = _mod_words(coef, list(mods), scale, unit, joint)
                return (f"{what} of {SENSORS[c]} " + " and ".join(mw),
                        {"channel": SENSORS[c], "unit": "-" if unit == "%" else unit,
                         **{f"{what}_{k}": v for k, v in mp.items()}})
            groups.append(Group(f"{what} {SENSORS[c]}", kind,
                                np.column_stack([col * v for v in mods.values()]),
                                tuple(f"x_{m}" for m in mods), mod_words))
        tr = np.column_stack([oh[:, c] * 0.5 * (3 * tau ** 2 - 1),
                              oh[:, c] * 0.5 * (5 * tau ** 3 - 3 * tau)])

        def trend_words(coef, c=c):
            a2, a3 = coef.get("p2", 0.0), coef.get("p3", 0.0)
            grid = np.linspace(-1, 1, 201)
            dev = float(np.max(np.abs(a2 * 0.5 * (3 * grid ** 2 - 1)
                                      + a3 * 0.5 * (5 * grid ** 3 - 3 * grid))))
            return (f"slow trend of {SENSORS[c]} along the recording (curved, beyond a "
                    f"linear drift: up to {_fmt_unit(dev, 'mV/V')})",
                    {"channel": SENSORS[c], "legendre_p2_mvv": a2, "legendre_p3_mvv": a3,
                     "max_deviation_mvv": dev})
        groups.append(Group(f"trend {SENSORS[c]}", "trend", tr, ("p2", "p3"), trend_words))
    return groups


def _tone_groups(b: _Rows, sig: Any, phi: np.ndarray, t_s: np.ndarray, r0: np.ndarray,
                 n_peaks: int, harmonics: Sequence[int], max_order: float,
                 f_range_hz: tuple[float, float]) -> list[Group]:
    """Tones at the strongest free orders of the input rotation (``phi``, on the basis
    rows) and fixed frequencies (time ``t_s``) of the residual ``r0``, one phase per
    window and harmonic."""
    fit, w, ch = b.fit, b.w, b.ch
    blk = w * 5 + ch
    twopi_t = 2 * np.pi * t_s
    revs = sig.n_t / sig.fs * float(np.min(sig.n_in_rpm)) / 60.0
    lobe_o, lobe_f = 1.0 / revs, sig.fs / sig.n_t
    searches = (("order_tone", phi, (0.5, max_order), lobe_o / 8, lobe_o),
                ("fixed_tone", twopi_t, (f_range_hz[0], min(f_range_hz[1], 0.4 * sig.fs)),
                 lobe_f / 8, lobe_f))
    groups = []
    for kind, coord, (lo, hi), step, lobe in searches:
        for v in spectral_peaks(r0[fit], coord[fit], blk[fit], lo, hi, step, lobe, n_peaks,
                                max(harmonics)):
            words = _tone_words(kind, v, harmonics, SENSORS, b.rng, b.mean_mod, "mV/V",
                                b.joint)
            groups.append(tone_group(f"{kind} {v:.4g}", kind, v, coord, r0, w, ch, 5, fit,
                                     harmonics, b.mods, words))
    return groups


def strain_basis(result: CalibrationResult, n_peaks: int = 2,
                 harmonics: Sequence[int] = (1, 2, 3), max_order: float = 20.0,
                 f_range_hz: tuple[float, float] = (20.0, 1000.0)
                 ) -> tuple[np.ndarray, list[Group], np.ndarray, np.ndarray, Projector]:
    """Candidate basis of a strain calibration (windows × channels s0..s4 × time).

    Groups: crosstalk (the final model's signal of channel a on the rows of channel b),
    tones at the ``n_peaks`` strongest free orders of the input rotation and fixed
    frequencies (up to ``max_order``, in ``f_range_hz``) with ``harmonics``, per-channel
    gain and offset times load and speed, per-channel slow trends (Legendre P2, P3 of
    the time along the recording); crosstalk and tones also times load and speed.
    Nuisance: the final model's design and the library's linear directions per channel
    (offset, gain, misplacement −∂s/∂ψ, drift, the bridge nonlinearity's −s²); local:
    each window's ∂s/∂ψ (its WG-angle shift).

    Returns
    -------
    target : ndarray, shape (n_rows,)
        Measured signals on the fit and validation rows [mV/V].
    groups : list of Group
    fit, validation : ndarray of int
        Row indices.
    projector : Projector
    """
    p = result.problem
    sig = p.signals
    rows = np.union1d(p.split.fit, p.split.validation)
    fit = np.searchsorted(rows, p.split.fit)
    val = np.searchsorted(rows, p.split.validation)
    x0, sig_f = model_design(result)
    b = _basis_rows(result, rows, fit)
    proj = _nuisance(b, x0[rows], sig_f, sig.t_seq_s[rows], rows)
    y = p.y[rows]
    r0 = proj.resid(y)
    groups = (_crosstalk_groups(b, sig_f) + _channel_groups(b, sig.t_seq_s[rows])
              + _tone_groups(b, sig, sig_f.phi_in_rad[rows], sig.t_s[rows], r0, n_peaks,
                             harmonics, max_order, f_range_hz))
    return y, groups, fit, val, proj


def propose(result: CalibrationResult, max_terms: int = 5, min_gain: float = MIN_GAIN,
            only_if_structured: bool = True) -> list[Proposal]:
    """Terms beyond the library for the final residual of a strain calibration.

    Parameters
    ----------
    result : CalibrationResult
        Of a strain problem (:func:`swgcal.strain.build_problem`).
    max_terms, min_gain
        See :func:`swgcal.discovery.discover`.
    only_if_structured : bool, default True
        Propose nothing when the loop's final residual is not structured
        (``result.unexplained`` false).

    Returns
    -------
    list of Proposal
        Empty when nothing beyond the library pays on held-out data.
    """
    if only_if_structured and not result.unexplained:
        return []
    target, groups, fit, val, proj = strain_basis(result)
    return discover(target, groups, fit, val, proj, max_terms=max_terms, min_gain=min_gain)
