"""Measurement-chain effects on simulated bridge signals (the ``sensor_effects`` option).

A real bench adds to the chain's ideal bridges (:mod:`swgsim.gear.chain`) gauges off their
nominal angle, the bridge's nonlinearity, amplifier gains and low-pass, sampling delay,
offsets and a thermal drift of the zero. Each effect is one function named like it
(:func:`offset`, :func:`gain_mismatch`, ...), applied in physical order whatever the list's
order by :func:`apply_sensor_effects`; the calibration's fit terms
(:mod:`swgcal.strain.effects`) evaluate the same functions. Effects, parameters, sources,
speed and edges: docs/PHYSICS.md sec. 5.1.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from swgsim.gear.sensors import SENSORS
from swgsim.sensing.dsp import fractional_delay, lowpass, spline_at

__all__ = ["SENSOR_EFFECTS", "APPLY_ORDER", "QUARTER_BRIDGE_K", "SensorEffect",
           "parse_sensor_effects", "apply_sensor_effects", "per_channel", "psi_rate",
           "gauge_misplacement", "gauge_misplacement_linear", "gauge_misplacement_angle",
           "angle_positions", "bridge_denominator", "bridge_nonlinearity", "gain_mismatch",
           "amplifier_lowpass", "time_delay", "offset", "thermal_drift"]

QUARTER_BRIDGE_K = 2.0e-3
"""k of the exact quarter bridge s / (1 + k s) [1/(mV/V)]: GF ε / (4 + 2 GF ε) in V/V
with s = 1e3 GF ε / 4 gives k = 2e-3, whatever the gauge factor [derived]."""

#: name -> {param: (neutral value, lower bound, upper bound, unit, per channel)}
SENSOR_EFFECTS: dict[str, dict[str, tuple[float, float, float, str, bool]]] = {
    "gauge_misplacement": {"delta_deg": (0.0, -10.0, 10.0, "deg", True)},
    "bridge_nonlinearity": {"k_per_mvv": (0.0, -10.0, 10.0, "1/(mV/V)", True)},
    "gain_mismatch": {"gain": (1.0, 0.5, 2.0, "-", True)},
    "amplifier_lowpass": {"f_c_hz": (np.inf, 0.0, np.inf, "Hz", False)},
    "time_delay": {"delay_s": (0.0, 0.0, 0.05, "s", False)},
    "offset": {"offset_mvv": (0.0, -10.0, 10.0, "mV/V", True)},
    "thermal_drift": {"rate_mvv_per_s": (0.0, -10.0, 10.0, "mV/V/s", True)},
}
"""Declared measurement effects: parameter, neutral value, allowed (open/closed) range,
unit and whether it is given per channel."""

APPLY_ORDER = ("gauge_misplacement", "bridge_nonlinearity", "gain_mismatch",
               "amplifier_lowpass", "time_delay", "offset", "thermal_drift")
"""Physical order in which :func:`apply_sensor_effects` applies the effects."""


@dataclass(frozen=True)
class SensorEffect:
    """One validated measurement effect.

    Attributes
    ----------
    name : str
        A key of :data:`SENSOR_EFFECTS`.
    params : dict
        Parameter name -> float, or ndarray of shape (5,) for per-channel parameters.
    """

    name: str
    params: dict[str, Any]


def per_channel(value: Any, neutral: float, what: str) -> np.ndarray:
    """A per-channel parameter as an array of shape (5,).

    Parameters
    ----------
    value : float, sequence of 5 floats, or mapping of "s0".."s4" to float
    neutral : float
        Value of channels a mapping does not name.
    what : str
        Parameter name for error messages.

    Raises
    ------
    ValueError
        Wrong length, unknown channel name or non-numeric value.
    """
    if isinstance(value, Mapping):
        out = np.full(5, float(neutral))
        for k, v in value.items():
            if k not in SENSORS:
                raise ValueError(f"{what}: unknown channel {k!r}; allowed {list(SENSORS)}")
            out[SENSORS.index(k)] = float(v)
        return out
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        return np.full(5, float(arr))
    if arr.shape != (5,):
        raise ValueError(f"{what}: give a scalar, 5 values (s0..s4) or a mapping by channel, "
                         f"got shape {arr.shape}")
    return arr.copy()


@dataclass
class SensorEffectConfig:
    """One entry of the data-set option ``sensor_effects`` (what a strain calibration
    writes to ``sensor_effects.yaml``).

    Attributes
    ----------
    name : str
        A key of :data:`SENSOR_EFFECTS` (a ``#k`` suffix is ignored).
    params : dict
        Parameter name -> value; per-channel parameters take a list of five values or a
        mapping channel -> value (:func:`per_channel`).
    """

    name: str
    params: dict[str, Any] = field(default_factory=dict)


def parse_sensor_effects(effects: Sequence[SensorEffectConfig | Mapping[str, Any]] | None
                         ) -> list[SensorEffect]:
    """Validate a ``sensor_effects`` list.

    Parameters
    ----------
    effects : sequence of SensorEffectConfig
        The option's entries; a plain mapping ``{"name": key of SENSOR_EFFECTS,
        "params": {...}}`` is taken as one (``"kind"`` is accepted for ``"name"``).

    Returns
    -------
    list of SensorEffect
        In the order given (:func:`apply_sensor_effects` applies them in
        :data:`APPLY_ORDER`).

    Raises
    ------
    ValueError
        Unknown effect or parameter, a value outside its range (the message names the
        parameter and the allowed range), or an effect given twice.
    """
    out: list[SensorEffect] = []
    seen: set[str] = set()
    for i, e in enumerate(effects or ()):
        if not isinstance(e, SensorEffectConfig):  # a calibration's list read as YAML or JSON
            if not isinstance(e, Mapping):
                raise ValueError(f"sensor_effects[{i}] must be a mapping {{name, params}}, "
                                 f"got {e!r}")
            e = SensorEffectConfig(str(e.get("name") or e.get("kind") or ""),
                                   dict(e.get("params") or {}))
        name = e.name.split("#")[0]
        if name not in SENSOR_EFFECTS:
            raise ValueError(f"sensor_effects[{i}]: unknown effect {name!r}; allowed: "
                             f"{sorted(SENSOR_EFFECTS)}")
        if name in seen:
            raise ValueError(f"sensor_effects: {name} given twice; merge its parameters")
        seen.add(name)
        spec = SENSOR_EFFECTS[name]
        params = dict(e.params)
        if name == "bridge_nonlinearity" and "bridge" in params:
            bridge = params.pop("bridge")
            if bridge not in ("quarter", "linear"):
                raise ValueError(f"sensor_effects.{name}.bridge must be 'quarter' or 'linear', "
                                 f"got {bridge!r}")
            params.setdefault("k_per_mvv", QUARTER_BRIDGE_K if bridge == "quarter" else 0.0)
        extra = sorted(set(params) - set(spec))
        if extra:
            raise ValueError(f"sensor_effects.{name}: unknown parameters {extra}; expected "
                             f"{sorted(spec)}")
        missing = sorted(set(spec) - set(params))
        if missing:
            raise ValueError(f"sensor_effects.{name}: missing parameters {missing}")
        vals: dict[str, Any] = {}
        for p, (neutral, lo, hi, unit, chan) in spec.items():
            v = per_channel(params[p], neutral, f"sensor_effects.{name}.{p}") if chan else float(
                params[p])
            arr = np.atleast_1d(v)
            strict_lo = name in ("amplifier_lowpass", "gain_mismatch")
            bad = ~np.isfinite(arr) | (arr <= lo if strict_lo else arr < lo) | (arr > hi)
            if np.any(bad):
                lo_br = "(" if strict_lo else "["
                raise ValueError(f"sensor_effects.{name}.{p} must lie in {lo_br}{lo:g}, {hi:g}] "
                                 f"[{unit}], got {params[p]!r}")
            vals[p] = v
        out.append(SensorEffect(name, vals))
    return out


def psi_rate(n_in_rpm: np.ndarray | float, ratio: float = 100.0) -> np.ndarray:
    """Rate of the WG angle relative to the flexspline, ψ̇ = ω_in (1 + 1/N) [rad/s].

    With the circular spline fixed and the flexspline as output, φ_out = −φ_in / N, so
    ψ = φ_in − φ_out = φ_in (1 + 1/N) (docs/PHYSICS.md sec. 1 and 4).
    """
    return np.asarray(n_in_rpm, float) * 2 * np.pi / 60.0 * (1.0 + 1.0 / ratio)


# ---------------------------------------------------------------------------------------
# the effects, one forward function each (also the forms the calibration fits,
# :mod:`swgcal.strain.effects`)
#
# Each takes the signal and its parameters already broadcast against it (windows:
# (n_windows, 5, n_t) with a per-channel parameter as shape (5, 1); the calibration's
# stacked samples: (n, 1) with one-hot channel columns (n, 5)). An effect linear in its
# parameters, f(s, p) = s + p u(s) or p s, evaluated with one-hot parameters gives the
# design columns the calibration fits.


def gauge_misplacement(x: np.ndarray, delta_rad: np.ndarray, psi_rate_rad_s: np.ndarray,
                       fs_hz: float) -> np.ndarray:
    """Gauges δ_c further along θ than nominal: s_c(ψ − δ_c), a delay of δ_c / ψ̇.

    Parameters
    ----------
    x : ndarray, shape (n_windows, 5, n_t)
        Bridge signals [mV/V].
    delta_rad : ndarray, shape (5,)
        Angular misplacement of each channel's gauges [rad].
    psi_rate_rad_s : ndarray, shape (n_windows,)
        ψ̇ of each window [rad/s] (:func:`psi_rate`).
    fs_hz : float
        Sample rate [Hz].

    Returns
    -------
    ndarray, shape of ``x``
        [mV/V]; the delay by :func:`fractional_delay` (Schuller et al. 2024: gauge
        positioning, the dominant ripple source; docs/PHYSICS.md sec. 4).
    """
    d = delta_rad[None, :] / psi_rate_rad_s[:, None] * fs_hz  # (n_w, 5) samples
    return fractional_delay(x, d)


def angle_positions(psi: np.ndarray, delta_rad: float) -> np.ndarray:
    """Sample positions at which a monotone ψ(t) takes the values ψ(t_k) − δ.

    The inverse t(ψ) is interpolated linearly between samples (exact for a linear ψ, i.e.
    a constant speed) and extrapolated beyond the window at the rate of its end intervals.

    Parameters
    ----------
    psi : ndarray, shape (n,)
        WG angle relative to the flexspline at the samples [rad], strictly monotone.
    delta_rad : float
        Angular offset δ [rad].

    Returns
    -------
    ndarray, shape (n,)
        Fractional positions [samples], 0 the first sample; k − δ / (ψ̇ Δt) at constant ψ̇.
    """
    u, target = (psi, psi - delta_rad) if psi[-1] > psi[0] else (-psi, -psi + delta_rad)
    k = np.arange(psi.size, dtype=float)
    pos = np.interp(target, u, k)
    lo, hi = target < u[0], target > u[-1]
    pos[lo] = (target[lo] - u[0]) / (u[1] - u[0])
    pos[hi] = psi.size - 1 + (target[hi] - u[-1]) / (u[-1] - u[-2])
    return pos


def gauge_misplacement_angle(x: np.ndarray, delta_rad: np.ndarray,
                             psi: np.ndarray) -> np.ndarray:
    """Gauges δ_c further along θ than nominal, in the angle domain: s_c at ψ(t) − δ_c.

    The speed-general form of :func:`gauge_misplacement`: each channel is interpolated
    (:func:`spline_at`) at the time where ψ took the value ψ(t) − δ_c
    (:func:`angle_positions`), a delay δ_c / ψ̇ that varies with the speed. At constant
    ψ̇ it is the constant delay of :func:`gauge_misplacement` (to rounding, tested).

    Parameters
    ----------
    x : ndarray, shape (n_windows, 5, n_t)
        Bridge signals [mV/V].
    delta_rad : ndarray, shape (5,)
        Angular misplacement of each channel's gauges [rad].
    psi : ndarray, shape (n_windows, n_t)
        ψ = φ_in − φ_out at the samples of ``x`` [rad] (:attr:`swgsim.gear.dynamics.SimResult.psi`),
        strictly monotone in each window.

    Returns
    -------
    ndarray, shape of ``x``
        [mV/V].

    Raises
    ------
    ValueError
        ψ not strictly monotone in a window (a reversal or standstill: the angle ψ − δ is
        then not, or not once, in the recorded motion).
    """
    x = np.asarray(x, float)
    out = x.copy()
    for w in range(x.shape[0]):
        dpsi = np.diff(psi[w])
        if not (np.all(dpsi > 0) or np.all(dpsi < 0)):
            raise ValueError("sensor_effects.gauge_misplacement: psi must be strictly "
                             f"monotone in every window (no reversal or standstill), window {w}")
        pos = np.stack([angle_positions(psi[w], float(d)) for d in delta_rad])  # (5, n_t)
        moved = np.asarray(delta_rad) != 0
        if np.any(moved):
            out[w, moved] = spline_at(x[w, moved], pos[moved])
    return out


def gauge_misplacement_linear(ds_dpsi: np.ndarray, delta_rad: np.ndarray) -> np.ndarray:
    """First order of :func:`gauge_misplacement` in δ: s_c(ψ − δ_c) − s_c(ψ) ≈ −δ_c ∂s_c/∂ψ.

    Parameters
    ----------
    ds_dpsi : ndarray
        ∂s/∂ψ at fixed torque [mV/V / rad].
    delta_rad : ndarray, broadcastable against ``ds_dpsi``
        Misplacement [rad] (one-hot channels: the calibration's design columns).

    Returns
    -------
    ndarray
        The change of the signal [mV/V].
    """
    return -delta_rad * ds_dpsi


def bridge_denominator(s: np.ndarray, k_per_mvv: np.ndarray | float) -> np.ndarray:
    """1 + k s, the denominator of the bridge output s / (1 + k s) (Hoffmann 1989).

    Parameters
    ----------
    s : ndarray
        Linear bridge output [mV/V] (for the calibration's basis: the sum of its parts,
        each part then divided by this common denominator).
    k_per_mvv : float or ndarray, broadcastable against ``s``
        Nonlinearity coefficient [1/(mV/V)] (:data:`QUARTER_BRIDGE_K` for the exact
        quarter bridge).

    Returns
    -------
    ndarray
    """
    return 1.0 + k_per_mvv * s


def bridge_nonlinearity(x: np.ndarray, k_per_mvv: np.ndarray | float) -> np.ndarray:
    """Bridge output s / (1 + k s) (:func:`bridge_denominator`).

    Parameters
    ----------
    x : ndarray
        Linear bridge output [mV/V].
    k_per_mvv : float or ndarray, broadcastable against ``x``
        [1/(mV/V)].

    Returns
    -------
    ndarray, shape of ``x``
        [mV/V].

    Raises
    ------
    ValueError
        1 + k s not positive somewhere.
    """
    den = bridge_denominator(x, k_per_mvv)
    if np.any(den <= 0):
        raise ValueError("sensor_effects.bridge_nonlinearity: 1 + k_per_mvv * s must "
                         f"stay > 0; |k_per_mvv| < {1.0 / np.abs(x).max():.3g} for "
                         "these signals")
    return x / den


def gain_mismatch(x: np.ndarray, gain: np.ndarray) -> np.ndarray:
    """Per-channel amplifier and gauge-factor gain, g_c s.

    Parameters
    ----------
    x : ndarray
        [mV/V].
    gain : ndarray, broadcastable against ``x``
        Gain [-] (shape (5, 1) for windows (n_windows, 5, n_t)).

    Returns
    -------
    ndarray
        [mV/V].
    """
    return x * gain


def amplifier_lowpass(x: np.ndarray, f_c_hz: float, fs_hz: float) -> np.ndarray:
    """First-order amplifier low-pass on every channel (:func:`lowpass`).

    Parameters
    ----------
    x : ndarray, shape (..., n_t)
        [mV/V].
    f_c_hz : float
        Cut-off [Hz], below the Nyquist frequency.
    fs_hz : float
        Sample rate [Hz].

    Returns
    -------
    ndarray, shape of ``x``

    Raises
    ------
    ValueError
        ``f_c_hz`` not below fs / 2.
    """
    if f_c_hz >= 0.5 * fs_hz:
        raise ValueError(f"sensor_effects.amplifier_lowpass.f_c_hz must lie in "
                         f"(0, {0.5 * fs_hz:g}) Hz, got {f_c_hz}")
    return lowpass(x, f_c_hz, fs_hz)


def time_delay(x: np.ndarray, delay_s: float, fs_hz: float) -> np.ndarray:
    """Sampling delay common to all channels, s(t − τ) (:func:`fractional_delay`).

    Parameters
    ----------
    x : ndarray, shape (n_windows, 5, n_t)
        [mV/V].
    delay_s : float
        τ [s].
    fs_hz : float
        Sample rate [Hz].

    Returns
    -------
    ndarray, shape of ``x``
    """
    return fractional_delay(x, np.full(x.shape[:2], delay_s * fs_hz))


def offset(x: np.ndarray | float, offset_mvv: np.ndarray) -> np.ndarray:
    """Zero offset, s + o_c (bridge imbalance, amplifier offset; docs/PHYSICS.md sec. 5).

    Parameters
    ----------
    x : ndarray or float
        [mV/V].
    offset_mvv : ndarray, broadcastable against ``x``
        [mV/V].

    Returns
    -------
    ndarray
        [mV/V].
    """
    return x + offset_mvv


def thermal_drift(x: np.ndarray | float, rate_mvv_per_s: np.ndarray,
                  t_s: np.ndarray) -> np.ndarray:
    """Zero drift, s + r_c t (gauge temperature drift; docs/PHYSICS.md sec. 5).

    Parameters
    ----------
    x : ndarray or float
        [mV/V].
    rate_mvv_per_s : ndarray
        r_c [mV/V/s], broadcastable against ``x``.
    t_s : ndarray
        Time since the start of the recording sequence [s], broadcastable against ``x``.

    Returns
    -------
    ndarray
        [mV/V].
    """
    return x + rate_mvv_per_s * t_s


@dataclass(frozen=True)
class _Windows:
    """What the effects of :func:`apply_sensor_effects` need besides the signals."""

    time_s: np.ndarray
    dt: float
    n_in: np.ndarray
    ratio: float
    n_lead: int
    t_start_s: Any
    psi: np.ndarray | None = None

    def t_seq(self, n_w: int, n_t: int) -> np.ndarray:
        """Time of every sample since the start of the sequence, shape (n_w, n_t) [s]."""
        if self.t_start_s is None:
            t0 = np.arange(n_w) * (n_t - self.n_lead) * self.dt
        else:
            t0 = np.broadcast_to(np.asarray(self.t_start_s, float), (n_w,))
        return t0[:, None] + (self.time_s - self.time_s[self.n_lead])[None, :]

    @property
    def fs(self) -> float:
        """Sample rate [Hz]."""
        return 1.0 / self.dt


_STEPS: dict[str, Any] = {
    "gauge_misplacement": lambda x, p, w: gauge_misplacement(
        x, np.deg2rad(p["delta_deg"]), psi_rate(w.n_in, w.ratio), w.fs) if w.psi is None
    else gauge_misplacement_angle(x, np.deg2rad(p["delta_deg"]), w.psi),
    "bridge_nonlinearity": lambda x, p, w: bridge_nonlinearity(
        x, p["k_per_mvv"][None, :, None]),
    "gain_mismatch": lambda x, p, w: gain_mismatch(x, p["gain"][None, :, None]),
    "amplifier_lowpass": lambda x, p, w: amplifier_lowpass(x, p["f_c_hz"], w.fs),
    "time_delay": lambda x, p, w: time_delay(x, p["delay_s"], w.fs),
    "offset": lambda x, p, w: offset(x, p["offset_mvv"][None, :, None]),
    "thermal_drift": lambda x, p, w: thermal_drift(
        x, p["rate_mvv_per_s"][None, :, None], w.t_seq(*x.shape[::2])[:, None, :]),
}
"""Effect name -> step ``(signals, params, windows) -> signals`` of
:func:`apply_sensor_effects`."""


def apply_sensor_effects(signals: np.ndarray, time_s: np.ndarray,
                         n_in_rpm: np.ndarray | float | None,
                         effects: Sequence[Mapping[str, Any]] | Sequence[SensorEffect] | None,
                         *, t_start_s: np.ndarray | float | None = None, n_lead: int = 0,
                         ratio: float = 100.0, psi: np.ndarray | None = None) -> np.ndarray:
    """Apply measurement-chain effects to simulated windows (the ``sensor_effects`` hook).

    Parameters
    ----------
    signals : ndarray, shape (n_windows, 5, n_t)
        Ideal bridge outputs s0..s4 [mV/V], possibly with ``n_lead`` samples of history
        before each window.
    time_s : ndarray, shape (n_t,)
        Sample times [s], uniformly spaced; the window starts at ``time_s[n_lead]``.
    n_in_rpm : float or ndarray, shape (n_windows,), or None
        Input speed of each window [rpm] (the acting mean; sets a constant ψ̇ for gauge
        misplacement), > 0; ignored (may be None) when ``psi`` is given.
    effects : sequence of mapping or SensorEffect
        See :func:`parse_sensor_effects`; empty or None returns a copy.
    t_start_s : float or ndarray, shape (n_windows,), optional
        Time of each window's first sample since the start of the recording sequence
        [s] (thermal drift); default ``window index × window length``.
    n_lead : int, default 0
        Leading history samples, used to start filters and shifts and dropped from the
        output.
    ratio : float, default 100
        Gear ratio N (ψ̇ = ω_in (1 + 1/N)).
    psi : ndarray, shape (n_windows, n_t), optional
        ψ = φ_in − φ_out at every sample of ``signals`` [rad] (windows at varying speed,
        e.g. :meth:`swgsim.gear.chain.SimulationChain.simulate_profile`): gauge misplacement
        then acts in the angle domain (:func:`gauge_misplacement_angle`), which needs a
        strictly monotone ψ per window. The other effects do not depend on the speed.

    Returns
    -------
    ndarray, shape (n_windows, 5, n_t − n_lead)
        [mV/V].

    Raises
    ------
    ValueError
        Bad shapes, non-positive speed (without ``psi``), ``n_lead`` outside [0, n_t), an
        invalid effect, a bridge nonlinearity whose denominator 1 + k s is not positive,
        or gauge misplacement on a ``psi`` that reverses or stands still in a window.
    """
    x = np.array(signals, dtype=float)
    if x.ndim != 3 or x.shape[1] != 5:
        raise ValueError(f"signals must have shape (n_windows, 5, n_t), got {x.shape}")
    windows = _check_windows(x, time_s, n_in_rpm, t_start_s, n_lead, ratio, psi)
    items = [e if isinstance(e, SensorEffect) else None for e in (effects or ())]
    if any(e is None for e in items):
        items = parse_sensor_effects(effects)  # type: ignore[arg-type]
    by = {e.name: e for e in items}
    for name in APPLY_ORDER:
        if name in by:
            x = _STEPS[name](x, by[name].params, windows)
    return x[:, :, windows.n_lead:]


def _check_windows(x: np.ndarray, time_s: np.ndarray, n_in_rpm: np.ndarray | float | None,
                   t_start_s: Any, n_lead: int, ratio: float,
                   psi: np.ndarray | None = None) -> _Windows:
    """The time axis and operating points of :func:`apply_sensor_effects`, checked."""
    n_w, _, n_t = x.shape
    time_s = np.asarray(time_s, float)
    if time_s.shape != (n_t,) or n_t < 2:
        raise ValueError(f"time_s must have shape ({n_t},) with n_t >= 2, got {time_s.shape}")
    if not 0 <= int(n_lead) < n_t:
        raise ValueError(f"n_lead must lie in [0, {n_t}), got {n_lead}")
    dt = float(time_s[1] - time_s[0])
    if not dt > 0:
        raise ValueError("time_s must be increasing")
    if psi is not None:
        psi = np.asarray(psi, float)
        if psi.shape != (n_w, n_t) or not np.all(np.isfinite(psi)):
            raise ValueError(f"psi must be finite with shape ({n_w}, {n_t}), got {psi.shape}")
        return _Windows(time_s, dt, np.full(n_w, np.nan), ratio, int(n_lead), t_start_s, psi)
    n_in = np.broadcast_to(np.asarray(n_in_rpm, float), (n_w,))
    if np.any(~np.isfinite(n_in)) or np.any(n_in <= 0):
        raise ValueError(f"n_in_rpm must be > 0 rpm, got {n_in_rpm}")
    return _Windows(time_s, dt, n_in, ratio, int(n_lead), t_start_s)
