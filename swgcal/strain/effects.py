"""Strain side of the calibration: base model and declared effect library.

The signals and their basis are defined in :mod:`.signals`, the residual probes in
:mod:`.probes` (both re-exported here). :class:`ChainBaseModel` scales the chain's two
patterns (the WG deflection and an overall gauge gain); :func:`strain_library` gives the
candidate effects, each a fit term over the form :mod:`swgsim.sensing.effects` applies,
mapping to a ``sensor_effects`` entry or, for the kinematic error, to the gear's ``ke_*``.
Parametrisations, residual signatures and what is identifiable without an encoder:
docs/PHYSICS.md sec. 5.2; ranges and sources: :mod:`.ranges`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from swgsim.base.lazy import lazy_module
from swgsim.base.registry import Registry
from swgsim.gear.terms import Param
from swgsim.sensing import effects as ms
from swgsim.sensing.dsp import fractional_delay, lowpass_coefficients

from ..terms import FitTerm
from .probes import strain_probes
from .ranges import (
    BRIDGE_K_RANGE,
    DRIFT_RANGE_MVV_S,
    GAIN_RANGE,
    KE_RANGE_RAD,
    LOWPASS_RANGE_HZ,
    MISPLACEMENT_RANGE_DEG,
    OFFSET_RANGE_MVV,
)
from .signals import SENSORS, MappedBasis, StrainSignals, constraint_basis

sps = lazy_module("scipy.signal")

__all__ = [
    "SENSORS",
    "StrainSignals",
    "ChainBaseModel",
    "ChannelOffset",
    "GainMismatch",
    "GaugeMisplacement",
    "BridgeNonlinearity",
    "AmplifierLowpass",
    "KinematicErrorHarmonic",
    "ThermalDrift",
    "STRAIN_LIBRARY",
    "strain_library",
    "strain_probes",
    "constraint_basis",
]

# ---------------------------------------------------------------------------------------
# base model


class ChainBaseModel(FitTerm):
    """The simulation chain's prediction for the nominal gear, two scales fitted.

    s = a_wg · s_wg + a_torque · s_t. With a common gauge gain G and a WG deflection w0,
    a_torque = G and a_wg = G w0 / w0_nom; reported as ``gauge_gain`` [-] and ``w0_mm``.
    """

    kind = "chain"
    linear = (Param("a_wg", "-", "scale of the WG-deflection pattern"),
              Param("a_torque", "-", "scale of the torque pattern (overall gauge gain)"))
    description = ("nominal simulation chain (swgsim.gear.chain) at each window's operating point, "
                   "aligned to the window's WG angle; fitted: WG deflection w0 and overall "
                   "gauge gain")
    source = "paper Fig. 2 chain: eq. (1)-(6) dynamics, flexspline truss, gauge bridges"

    def __init__(self, name: str | None = None, w0_nom_m: float = 0.254e-3) -> None:
        super().__init__(name)
        self.w0_nom_m = float(w0_nom_m)

    @classmethod
    def for_signals(cls, sig: StrainSignals, name: str | None = None) -> ChainBaseModel:
        return cls(name, sig.w0_nom_m)

    def columns(self, sig: StrainSignals, theta: np.ndarray) -> np.ndarray:
        return np.column_stack([sig.col("s_wg"), sig.col("s_t")])

    def derived(self, coef: np.ndarray, theta: np.ndarray) -> dict[str, float]:
        a_w, a_t = (float(x) for x in coef)
        return {"w0_mm": self.w0_nom_m * 1e3 * a_w / a_t if a_t else float("nan"),
                "gauge_gain": a_t}

    def derived_units(self) -> dict[str, str]:
        return {"w0_mm": "mm", "gauge_gain": "-"}

    def options(self) -> dict[str, Any]:
        return {"w0_nom_m": self.w0_nom_m}


# ---------------------------------------------------------------------------------------
# effects


class _PerChannel(FitTerm):
    """A value per channel (:meth:`channel_values`, reported as ``derived_fmt`` in
    ``derived_unit``, on the ``estimable`` channels) and their RMS, ``rms_name``, the
    primary parameter."""

    derived_fmt = "{}"
    derived_unit = "-"
    rms_name = ""
    estimable = np.ones(5, bool)

    def channel_values(self, coef: np.ndarray) -> np.ndarray:
        """Per-channel values in ``derived_unit``, shape (5,)."""
        return np.asarray(coef, float)

    def channel_param(self, c: int) -> str:
        """Name of the derived parameter of channel ``c``."""
        return self.derived_fmt.format(SENSORS[c])

    def derived(self, coef, theta):
        v = self.channel_values(coef)
        out = {self.channel_param(c): float(v[c]) for c in range(5) if self.estimable[c]}
        out[self.rms_name] = float(np.sqrt(np.mean(np.square(v[self.estimable]))))
        return out

    def derived_units(self):
        return {**{self.channel_param(c): self.derived_unit for c in range(5)
                   if self.estimable[c]}, self.rms_name: self.derived_unit}

    def primary(self):
        return (self.rms_name,)


class ChannelOffset(_PerChannel):
    """Zero offset of each bridge channel."""

    kind = "offset"
    linear = tuple(Param(f"o_{s}", "mV/V", f"offset of {s}") for s in SENSORS)
    description = "zero offset per channel (bridge imbalance, amplifier offset)"
    signature = "a constant per channel, the same in every window and operating point"
    source = "docs/PHYSICS.md sec. 5 (offsets); paper eq. (10) a_0"
    ranges = {f"o_{s}": (-OFFSET_RANGE_MVV, OFFSET_RANGE_MVV,
                         "input range of the bench converter, ADS131M04 at gain 128")
              for s in SENSORS}
    derived_fmt, derived_unit, rms_name = "o_{}", "mV/V", "offset_rms"

    def columns(self, sig: StrainSignals, theta: np.ndarray) -> np.ndarray:
        return ms.offset(0.0, sig.onehot)  # a unit offset of each channel

    def sensor_effect(self, coef: np.ndarray, theta: np.ndarray) -> dict[str, Any]:
        """The ``sensor_effects`` entry of :mod:`swgsim.sensing.effects`."""
        return {"name": "offset", "params": {"offset_mvv": [float(v) for v in coef]}}


class ThermalDrift(_PerChannel):
    """Zero drift of each channel over the recording sequence."""

    kind = "thermal_drift"
    linear = tuple(Param(f"r_{s}", "mV/V/s", f"drift rate of {s}") for s in SENSORS)
    description = ("thermal drift of the zero per channel, o_c(t) = r_c t_seq with t_seq the "
                   "time since the start of the sequence of windows")
    signature = "an offset per channel that grows along the sequence of windows"
    source = "docs/PHYSICS.md sec. 5 (gauge temperature drift); Hoffmann 1989 (apparent strain)"
    ranges = {f"r_{s}": (-DRIFT_RANGE_MVV_S, DRIFT_RANGE_MVV_S,
                         "thermal output ±1.8 µε/K (Kyowa SELCOM, Vishay TN-504) at <= 1 K/s")
              for s in SENSORS}
    derived_fmt, derived_unit, rms_name = "r_{}", "mV/V/s", "drift_rms"

    def columns(self, sig, theta):
        return ms.thermal_drift(0.0, sig.onehot, sig.t_seq_s[:, None])  # unit rates

    def sensor_effect(self, coef, theta):
        return {"name": "thermal_drift", "params": {"rate_mvv_per_s": [float(v) for v in coef]}}


class _Relative(_PerChannel):
    """Per-channel values v_c with Σ w_c v_c = 0 over the estimable channels: one raw
    parameter per estimable channel but one.

    A channel whose weight is below ``min_weight_share`` of the total carries almost no
    information on its value relative to the others: it is not estimated (held at 0,
    left out of :meth:`derived`, neutral in :meth:`sensor_effect`) and listed by
    :meth:`withheld`.
    """

    weight_key = ""
    raw_prefix = ""
    raw_unit = "-"
    min_weight_share = 0.0

    def __init__(self, name: str | None = None, weights: Any = None,
                 estimable: Any = None) -> None:
        super().__init__(name)
        self.weights = np.ones(5) if weights is None else np.asarray(weights, float)
        if estimable is None:
            share = self.weights / self.weights.sum()
            estimable = share >= self.min_weight_share
            if estimable.sum() < 2:
                estimable = np.ones(5, bool)
        self.estimable = np.asarray(estimable, bool)
        self.q, self.ref = constraint_basis(self.weights, self.estimable)
        self.free = [c for c in range(5) if c != self.ref and self.estimable[c]]
        self.linear = tuple(Param(f"{self.raw_prefix}_{SENSORS[c]}", self.raw_unit,
                                  f"relative value of {SENSORS[c]}") for c in self.free)

    @classmethod
    def for_signals(cls, sig: StrainSignals, name: str | None = None):
        return cls(name, sig.weights.get(cls.weight_key))

    def values(self, coef: np.ndarray) -> np.ndarray:
        """Per-channel values v = Q r, shape (5,) (0 on channels not estimated)."""
        return self.q @ np.asarray(coef, float)

    def channel_values(self, coef: np.ndarray) -> np.ndarray:
        return self.values(coef)

    def withheld(self, coef: np.ndarray, theta: np.ndarray, sig: Any = None
                 ) -> dict[int, tuple[str, str]]:
        """Channels not estimated: ``{channel: (parameter, reason)}``."""
        share = self.weights / self.weights.sum()
        return {c: (self.channel_param(c),
                    f"not estimated: {SENSORS[c]} carries {100 * share[c]:.2g} % of the "
                    f"{self.weight_key} weight (< {100 * self.min_weight_share:g} %)")
                for c in range(5) if not self.estimable[c]}

    def options(self) -> dict[str, Any]:
        return {"weights": [float(w) for w in self.weights],
                "estimable": [bool(e) for e in self.estimable]}


class GainMismatch(_Relative):
    """Gain of each channel relative to the mean gain (the base model's gauge gain)."""

    kind = "gain_mismatch"
    weight_key = "gain"
    raw_prefix = "g"
    linear = tuple(Param(f"g_r{j}", "-", "relative gain of a free channel") for j in range(4))
    description = ("gain of each channel relative to the mean of the five (gauge-factor and "
                   "amplifier-gain tolerance); the common gain is the base model's gauge_gain")
    signature = ("one channel's WG and torque pattern scaled, the same at every speed and "
                 "load; s1−s3 or s2−s4 no longer cancel")
    source = ("Godler et al. (per-gauge gain tuning); Schuller et al. 2024 (sensing ripple); "
              "docs/PHYSICS.md sec. 4")
    ranges = {f"g_{s}": (-GAIN_RANGE, GAIN_RANGE,
                         "gauge factor ±1 %, amplifier gain, lead wires, axial position")
              for s in SENSORS}

    derived_fmt, rms_name = "g_{}", "gain_rms"

    def columns(self, sig, theta):
        return ms.gain_mismatch(sig.prediction()[:, None], sig.onehot) @ self.q

    def sensor_effect(self, coef, theta, neutral=()):
        """The ``sensor_effects`` entry; channels in ``neutral`` get gain 1."""
        v = self.values(coef)
        v[list(neutral)] = 0.0
        return {"name": "gain_mismatch", "params": {"gain": [float(1.0 + x) for x in v]}}


class GaugeMisplacement(_Relative):
    """Angular misplacement of each gauge (bridge) relative to the aligned mean."""

    kind = "gauge_misplacement"
    weight_key = "misplacement"
    raw_prefix = "d"
    raw_unit = "rad"
    linear = tuple(Param(f"d_r{j}", "rad", "relative angle of a free channel")
                   for j in range(4))
    description = ("angular misplacement δ_c of each gauge along θ: s_c(ψ − δ_c), linearised "
                   "−δ_c ∂s_c/∂ψ; relative to the mean weighted like the WG-angle alignment "
                   "(which absorbs a common shift)")
    signature = ("the order-2 (ψ) pattern of one channel shifted in phase: a residual in "
                 "quadrature with that channel's signal, same angle at every speed")
    source = ("Taghirad & Bélanger; Schuller et al. 2024 (gauge positioning is the dominant "
              "ripple source); docs/PHYSICS.md sec. 4")
    min_weight_share = 0.01
    """A channel carrying less than 1 % of the WG-angle information (its ∂s/∂ψ
    orthogonal to its own signal, the alignment weight) is not estimated: its angle is
    measured by a signal that barely depends on ψ, so any small misfit of that channel
    (a torque-phase error, a model detail) reads as degrees. With the default layout this
    is the full bridge s0 (0.16 % of the weight; s2/s4 5.6 %, s1/s3 44 % each), whose
    grids 90° apart cancel the order-2 pattern: on planted data with s2 misplaced by 1.5°
    and no noise, s0's free angle came out +0.36° against a true −0.08° (20 standard
    errors; 1.3-1.7° at about 5 s.e. with more windows)."""
    ranges = {f"delta_{s}_deg": (-MISPLACEMENT_RANGE_DEG, MISPLACEMENT_RANGE_DEG,
                                 "placement tolerance of bonded gauges, Vishay TN-511")
              for s in SENSORS}

    derived_fmt, derived_unit, rms_name = "delta_{}_deg", "deg", "misplacement_rms_deg"

    def columns(self, sig, theta):
        return ms.gauge_misplacement_linear(sig.col("dpsi")[:, None], sig.onehot) @ self.q

    def channel_values(self, coef: np.ndarray) -> np.ndarray:
        return np.rad2deg(self.values(coef))

    def sensor_effect(self, coef, theta, neutral=()):
        """The ``sensor_effects`` entry; channels in ``neutral`` get 0°."""
        v = np.rad2deg(self.values(coef))
        v[list(neutral)] = 0.0
        return {"name": "gauge_misplacement", "params": {"delta_deg": [float(x) for x in v]}}


class BridgeNonlinearity(FitTerm):
    """Bridge output s / (1 + k s), one k for all channels (a transform of the basis)."""

    kind = "bridge_nonlinearity"
    nonlinear = (Param("k_per_mvv", "1/(mV/V)", "nonlinearity coefficient"),)
    is_transform = True
    description = ("bridge nonlinearity s/(1 + k s) on every channel (exact quarter bridge: "
                   "k = 2e-3 per mV/V; half and full bridges with opposite arm strains are "
                   "linear); applied to the nominal prediction p as p/(1 + k p) with the "
                   "base model scales outside, exact while those stay near 1")
    signature = ("∝ s² to first order: order 4 of ψ and a constant on s1/s3, a load-squared "
                 "offset and ripple on s0/s2/s4")
    source = "Hoffmann 1989 (Wheatstone bridge nonlinearity); docs/PHYSICS.md sec. 4"
    ranges = {"k_per_mvv": (-BRIDGE_K_RANGE, BRIDGE_K_RANGE,
                            "exact quarter bridge 2e-3 per mV/V, Hoffmann 1989")}

    @staticmethod
    def _k_max(sig: StrainSignals) -> float:
        p = np.abs(sig.raw["s_wg"] + sig.raw["s_t"]).max()
        return 0.5 / max(float(p), 1e-9)

    def bounds(self, sig):
        k = self._k_max(sig)
        return [(-k, k)]

    def starts(self, sig, residual, idx):
        k = self._k_max(sig)
        return [np.array([0.0]), np.array([0.2 * k]), np.array([-0.2 * k])]

    def transform(self, sig: StrainSignals, theta: np.ndarray) -> StrainSignals:
        k = float(theta[0])

        def apply(b: Mapping[str, np.ndarray]) -> Mapping[str, np.ndarray]:
            den = ms.bridge_denominator(b["s_wg"] + b["s_t"], k)

            def fn(key: str, x: np.ndarray) -> np.ndarray:
                # the signal itself: s/(1 + k s); its perturbations (dpsi): /(1 + k s)²
                return x / den if key in ("s_wg", "s_t") else x / (den * den)

            return MappedBasis(b, fn)

        return sig.replace(maps=sig.maps + (apply,))

    def sensor_effect(self, coef, theta):
        return {"name": "bridge_nonlinearity", "params": {"k_per_mvv": float(theta[0])}}


class AmplifierLowpass(FitTerm):
    """First-order amplifier low-pass on every channel (a transform of the basis)."""

    kind = "amplifier_lowpass"
    nonlinear = (Param("f_c_hz", "Hz", "cut-off frequency", log=True),)
    is_transform = True
    description = ("first-order low-pass of the strain amplifiers, cut-off f_c (bilinear, "
                   "pre-warped); the phase lag of the dominant order 2 of ψ is absorbed by "
                   "the WG-angle alignment, the rest (amplitude loss, relative phase of the "
                   "other orders) is what the data show")
    signature = ("amplitudes fall and phases lag with frequency = order × speed: the ripple "
                 "amplitude ratio between speeds differs from the model, higher orders lag "
                 "more")
    source = "docs/PHYSICS.md sec. 5 (amplifier low-pass, phase error growing with speed)"
    ranges = {"f_c_hz": (*LOWPASS_RANGE_HZ,
                         "sinc3 corner 0.262 f_DATA at 250 SPS-64 kSPS, TI ADS131M04")}

    def bounds(self, sig):
        return [tuple(sig.f_c_bounds)]

    def starts(self, sig, residual, idx):
        lo, hi = sig.f_c_bounds
        return [np.array([v]) for v in np.geomspace(lo * 1.5, hi / 2, 4)]

    def transform(self, sig: StrainSignals, theta: np.ndarray) -> StrainSignals:
        f_c = float(theta[0])
        fs = sig.fs
        b, a = lowpass_coefficients(f_c, fs)
        f2 = 2.0 * sig.psi_rate / (2 * np.pi)  # order 2 of ψ [Hz], (n_w,)
        _, h = sps.freqz(b, a, worN=2 * np.pi * f2 / fs)
        lag_samples = -np.angle(h) / (2 * np.pi * f2) * fs  # (n_w,)

        def fn(key: str, x: np.ndarray) -> np.ndarray:
            y = ms.amplifier_lowpass(x, f_c, fs)
            return fractional_delay(y, np.broadcast_to(-lag_samples[:, None], x.shape[:2]))

        return sig.replace(maps=sig.maps + (lambda b: MappedBasis(b, fn),))

    def sensor_effect(self, coef, theta):
        return {"name": "amplifier_lowpass", "params": {"f_c_hz": float(theta[0])}}


class KinematicErrorHarmonic(FitTerm):
    """An extra kinematic-error harmonic A sin(k φ_in + φ) of a given order k.

    A transform: the torque pattern becomes (T_out + a_sin ΔT_sin + a_cos ΔT_cos) h(ψ),
    ΔT the linear response of the output torque to a unit harmonic (simulated), and the
    torque phase of every window (its input angle, a nuisance) is re-aligned on that
    window's own data with this ripple: the input angle is known only through the
    torque ripple, so a harmonic that changes the ripple changes where each window sits.
    """

    kind = "ke_order"
    order = 0
    nonlinear = (Param("a_sin", "rad", "A cos φ (coefficient of sin k φ_in)"),
                 Param("a_cos", "rad", "A sin φ (coefficient of cos k φ_in)"))
    is_transform = True
    description = ("extra kinematic-error harmonic of the input angle, φ_err += c A sin(k φ_in "
                   "+ φ) in the dynamics (paper eq. 3), seen through the torque it adds "
                   "(ΔT(t) h(ψ)); each window's input angle is re-aligned with it")
    signature = ("order k of the input (and sidebands k ± 2 of ψ) in the torque-sensitive "
                 "channels s0, s2, s4, in proportion to their torque sensitivity")
    source = "Tuttle & Seering 1996 (kinematic error at WG frequencies); docs/PHYSICS.md sec. 1, 5"
    ranges = {"amplitude_rad": (0.0, KE_RANGE_RAD,
                                "1 arcmin positioning accuracy, Harmonic Drive CSF/CSG-20")}

    def applicable(self, sig):
        return sig.ripple is not None and self.order in sig.ke_orders

    def bounds(self, sig):
        b = float(sig.ke_bound_rad)
        return [(-b, b), (-b, b)]

    def starts(self, sig, residual, idx):
        """Linear estimate from the residual at the current alignment, and half of it; for
        an odd order also its negative: with every window's input angle re-aligned, the
        harmonic of sign −c with all windows 180° on predicts nearly the same signals
        (only the nominal odd orders tell them apart, :mod:`.align`), so both
        local optima are tried."""
        u = sig.ripple.unit(self.order)  # (2, n_w, 5, m)
        x = np.column_stack([np.ascontiguousarray(sig.window_part(u[j])).reshape(-1)[idx]
                             for j in range(2)])
        c, *_ = np.linalg.lstsq(x, np.asarray(residual, float)[idx], rcond=None)
        c = np.clip(c, -0.9 * sig.ke_bound_rad, 0.9 * sig.ke_bound_rad)
        return [c, 0.5 * c] + ([-c] if self.order % 2 else [])

    def transform(self, sig: StrainSignals, theta: np.ndarray) -> StrainSignals:
        ke = sig.ke + ((self.order, float(theta[0]), float(theta[1])),)
        upd = sig.ripple(ke)
        phi = np.broadcast_to(sig.window_part(upd["phi_in"])[:, None, :],
                              (sig.n_windows, 5, sig.n_t)).reshape(-1)
        return sig.replace(raw={**sig.raw, "s_t": upd["s_t"], "dpsi": upd["dpsi"]}, ke=ke,
                           phi_in_rad=phi)

    def derived(self, coef, theta):
        a, b = (float(x) for x in theta)
        return {"amplitude_rad": float(np.hypot(a, b)), "phase_rad": float(np.arctan2(b, a))}

    def derived_units(self):
        return {"amplitude_rad": "rad", "phase_rad": "rad"}

    def primary(self):
        return ("amplitude_rad",)

    def gear_harmonic(self, coef, theta) -> dict[str, float]:
        """``{order, amp_rad, phase_rad}`` to add to GearParams.ke_* (see
        :func:`swgsim.gear.dynamics.gear_with_ke`)."""
        d = self.derived(coef, theta)
        return {"order": int(self.order), "amp_rad": d["amplitude_rad"],
                "phase_rad": d["phase_rad"]}


def _ke_class(order: int) -> type[KinematicErrorHarmonic]:
    return type(f"KinematicErrorOrder{order}", (KinematicErrorHarmonic,),
                {"kind": f"ke_order{order}", "order": int(order),
                 "__doc__": f"Extra kinematic-error harmonic of order {order}."})


KE_ORDERS = (1, 2, 3, 4)
"""Orders of the kinematic-error candidates (1, 2 and 4 are the classical ones,
docs/PHYSICS.md sec. 1; 3 for completeness)."""


#: The strain-side effects the calibration may add, by name (a user's joins with
#: ``STRAIN_LIBRARY.add(name, cls)`` and travels to worker processes,
#: :mod:`swgsim.base.registry`); the kinematic-error candidates of :data:`KE_ORDERS`
#: among them, one ``ke_order{k}`` each.
STRAIN_LIBRARY: Registry[type[FitTerm]] = Registry("strain effect", __name__,
                                                    "STRAIN_LIBRARY", (
    ("offset", ChannelOffset),
    ("gain_mismatch", GainMismatch),
    ("gauge_misplacement", GaugeMisplacement),
    ("bridge_nonlinearity", BridgeNonlinearity),
    ("amplifier_lowpass", AmplifierLowpass),
    *((f"ke_order{k}", _ke_class(k)) for k in KE_ORDERS),
    ("thermal_drift", ThermalDrift),
))


def strain_library(ke_orders: tuple[int, ...] = KE_ORDERS) -> dict[str, type[FitTerm]]:
    """The declared strain-side library, keyed by effect name: :data:`STRAIN_LIBRARY` in
    its order, its kinematic-error candidates those of ``ke_orders`` (an order it lacks
    made and added last).

    Parameters
    ----------
    ke_orders : tuple of int
        Orders of the kinematic-error candidates (one key ``ke_order{k}`` each).
    """
    wanted = {f"ke_order{int(k)}": int(k) for k in ke_orders}
    lib = {name: cls for name, cls in STRAIN_LIBRARY.items()
           if not issubclass(cls, KinematicErrorHarmonic) or name in wanted}
    for name, k in wanted.items():
        lib.setdefault(name, _ke_class(k))
    return lib
