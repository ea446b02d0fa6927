"""Health features of one window: what the monitor scores, cheap enough for every window.

Per bridge, a least-squares Fourier series in the WG angle ψ (harmonics 1..H of the ψ
rotation, 1 + 1/N per input revolution seen from the flexspline-fixed gauges; Sec. II-C:
every fault of Table I changes these amplitudes or the offset), with eq. (10)'s
sub-harmonics of orders 1/4, 1/3 and 1/2 fitted alongside and dropped:

* the offset c0 [mV/V] (eccentric WG: offsets of the WG-bending pair; sensor offsets),
* the amplitudes ``|c_h|``, h = 1..H [mV/V] (phase-free: windows start at arbitrary angles),
* log10 of the RMS of what the series leaves [mV/V] (tip crack: short deviations),

and the window's efficiency (mean P_out / mean P_in; reduced damping). The basis is built
once per (speed, window) from the duty point's desired speed, so a stream at one
operating point costs one matrix product per window.

At varying speed (a move, a reversal) that basis no longer follows the gear, and the
window's own ψ(t) [rad] (measured, or estimated from the motor encoder) may be passed:
the basis is then built per window in the angle domain (computed order tracking by least
squares): [1, cos hψ, sin hψ] for h = 1..H and the nuisance orders as multiples of the
input angle, φ_in ≈ ψ N / (N + 1) (exact for a rigid gear, φ_out = −φ_in / N; the elastic
twist shifts it by the output-side twist angle, mostly a constant phase, which phase-free
amplitudes ignore [not measured]; the nuisance terms are dropped anyway). The fit takes
the non-uniform ψ samples as they are: no resampling to uniform ψ, hence no interpolation
error, and a reversal does not fold orders (each sample keeps its angle). A window whose
ψ covers too little angle for the basis (condition number above
:data:`learn.inputs.signals.MAX_CONDITION`: below about 1.45 ψ revolutions for H = 12 with
orders 1/4, 1/3, 1/2, e.g. a steady 0.12 s window at 700 rpm, accepted at 750 rpm) is
refused, naming the window; the solver is :func:`learn.inputs.signals.angle_fit`, shared
with the synchronous residual. Cost: about 0.4 ms per window against 0.07 ms for the
cached basis (H = 12, 1200 samples, one core).
"""

from __future__ import annotations

import functools

import numpy as np

from learn.inputs.signals import angle_fit, pinv
from swgsim.datasets.plan import DatasetPlan

N_HARMONICS = 12
NUISANCE_ORDERS = (0.25, 1 / 3, 0.5)
RATIO = 100.0  # gear ratio N of the size-20 gear (swgsim.gear.dynamics.GearParams.ratio)


@functools.lru_cache(maxsize=16)
def _basis(n_in_rpm: float, fs_hz: float, n_t: int, n_harmonics: int
           ) -> tuple[np.ndarray, np.ndarray]:
    """Basis B (T, P) and its pseudo-inverse (P, T): [1, cos hψ, sin hψ, nuisance]."""
    f_in = n_in_rpm / 60.0
    t = np.arange(n_t) / fs_hz
    orders = np.concatenate([(1.0 + 1.0 / RATIO) * np.arange(1, n_harmonics + 1),
                             NUISANCE_ORDERS])
    ang = 2 * np.pi * f_in * t[:, None] * orders[None, :]
    b = np.concatenate([np.ones((n_t, 1)), np.cos(ang), np.sin(ang)], axis=1)
    p = pinv(b)
    b.setflags(write=False)
    p.setflags(write=False)
    return b, p


def feature_names(n_harmonics: int = N_HARMONICS, twist: bool = False) -> list[str]:
    """Names of the columns of :func:`window_features` (and, with ``twist``, of
    :func:`twist_features` after them)."""
    out = []
    for s in range(5):
        out += [f"s{s}_offset", *(f"s{s}_h{h}" for h in range(1, n_harmonics + 1)),
                f"s{s}_log_rest"]
    return [*out, "efficiency", *(TWIST_FEATURES if twist else ())]


#: Columns of :func:`twist_features`.
TWIST_FEATURES = ("twist_mean_arcmin", "twist_rms_arcmin")


def window_angles(meta: dict[str, np.ndarray], input_sensor, fs_hz: float,
                  ratio: float = RATIO) -> tuple[np.ndarray | None, np.ndarray | None]:
    """ψ and the output twist of windows from their recorded angle channels.

    The input channel of a coarse sensor (a 24-count Hall sensor: 15° steps) is
    interpolated between its edges first (:func:`swgsim.sensing.angles.psi_smooth`); the output
    encoder, where there is one, is used as recorded (20 bits: 1.24 arcsec).

    Parameters
    ----------
    meta : dict
        Per-window metadata; ``phi_in_meas`` (n, n_t) [rad] and optionally
        ``phi_out_meas`` (n, n_t) [rad].
    input_sensor : swgsim.sensing.angles.InputAngleSensor
        The sensor that recorded ``phi_in_meas``.
    fs_hz : float
        Sample rate [Hz].
    ratio : float
        Gear ratio N.

    Returns
    -------
    psi : ndarray, shape (n, n_t), or None
        WG angle ψ [rad]; None without an input angle channel (steady windows).
    twist : ndarray, shape (n, n_t), or None
        Output twist δ = φ_out + φ_in / N [rad] (:func:`swgsim.sensing.angles.twist_estimate`);
        None without an output encoder.
    """
    from swgsim.sensing.angles import edge_interpolate, psi_estimate, twist_estimate

    if "phi_in_meas" not in meta:
        return None, None
    t = np.arange(meta["phi_in_meas"].shape[-1]) / fs_hz
    phi_in = edge_interpolate(t, meta["phi_in_meas"], input_sensor.resolution_rad)
    phi_out = meta.get("phi_out_meas")
    psi = psi_estimate(phi_in, phi_out, ratio)
    return psi, None if phi_out is None else twist_estimate(phi_in, phi_out, ratio)


def health_features(signals: np.ndarray, meta: dict[str, np.ndarray], fs_hz: float,
                    input_sensor=None) -> np.ndarray:
    """The monitor's features of windows as they come: :func:`window_features`, in the
    angle domain when ``meta`` carries the angle channels (a life on a profile), with
    :func:`twist_features` after them when it carries an output encoder's.

    Parameters
    ----------
    signals : ndarray, shape (n, 5, n_t)
        Bridge outputs [mV/V].
    meta : dict
        ``n_in_rpm`` (n,), ``efficiency`` (n,), optionally ``phi_in_meas`` and
        ``phi_out_meas`` (n, n_t) [rad].
    fs_hz : float
        Sample rate [Hz].
    input_sensor : swgsim.sensing.angles.InputAngleSensor, optional
        The sensor of ``phi_in_meas`` (needed with it).

    Returns
    -------
    ndarray, shape (n, F)
        Columns :func:`feature_names` (``twist`` with an output encoder).
    """
    psi, twist = window_angles(meta, input_sensor, fs_hz)
    f = window_features(signals, meta["n_in_rpm"], meta["efficiency"], fs_hz, psi=psi)
    return f if twist is None else np.concatenate([f, twist_features(twist)], axis=1)


def twist_features(twist: np.ndarray) -> np.ndarray:
    """Mean and RMS about the mean of each window's output twist [arcmin].

    Under a load the twist is the torque over the torsional stiffness (paper eq. (3),
    k1 δ + k2 δ³): a stiffness loss raises the mean twist at the same operating point in
    proportion (k1 −25 %: +33 %), which the gauges' torque ripple shows only as r²/(1 − r²)
    below the torsional mode (docs/results/observability.md, "what a monitor needs to see
    stiffness").

    Parameters
    ----------
    twist : ndarray, shape (n, n_t)
        [rad].

    Returns
    -------
    ndarray, shape (n, 2)
        Columns :data:`TWIST_FEATURES`.
    """
    arcmin = np.asarray(twist, float) * (180 * 60 / np.pi)
    m = arcmin.mean(axis=1)
    return np.stack([m, np.sqrt(np.mean((arcmin - m[:, None]) ** 2, axis=1))], axis=1)


def window_features(signals: np.ndarray, n_in_rpm: np.ndarray, efficiency: np.ndarray,
                    fs_hz: float, n_harmonics: int = N_HARMONICS,
                    psi: np.ndarray | None = None) -> np.ndarray:
    """Health features of windows (module docstring).

    Parameters
    ----------
    signals : ndarray, shape (n, 5, n_t)
        Bridge outputs s0..s4 [mV/V].
    n_in_rpm : ndarray, shape (n,)
        Desired input speed of each window's duty point [rpm].
    efficiency : ndarray, shape (n,)
        Mean P_out / mean P_in of each window [-].
    fs_hz : float
        Sample rate [Hz].
    n_harmonics : int
        H.
    psi : ndarray, shape (n, n_t), optional
        WG angle ψ = φ_in − φ_out of each sample [rad] (measured or estimated; e.g.
        ``SimResult.psi``): fit in the angle domain (module docstring). None: the basis of
        the desired speed (steady speed only).

    Returns
    -------
    ndarray, shape (n, 5 (H + 2) + 1)
        Columns as :func:`feature_names`.

    Raises
    ------
    ValueError
        If the highest harmonic reaches the Nyquist frequency (of the desired speed, or of
        ψ's fastest step), shapes disagree, or a window's ψ covers too little angle.
    """
    x = np.asarray(signals, dtype=np.float64)
    n, c, n_t = x.shape
    speeds = np.asarray(n_in_rpm, float)
    if c != 5 or speeds.shape != (n,) or np.shape(efficiency) != (n,):
        raise ValueError(f"signals must be (n, 5, n_t) with n speeds and efficiencies, got "
                         f"{x.shape}, {speeds.shape}, {np.shape(efficiency)}")
    if n and speeds.max() / 60.0 * n_harmonics >= fs_hz / 2:
        raise ValueError(f"harmonic {n_harmonics} of {speeds.max():g} rpm reaches the Nyquist "
                         f"frequency of {fs_hz:g} Hz")
    if psi is not None:
        coef, rest = _fit_in_angle(x, psi, fs_hz, n_harmonics)
    else:
        coef, rest = np.empty((n, c, 2 * (n_harmonics + 3) + 1)), np.empty_like(x)
        for v in np.unique(speeds):
            idx = np.flatnonzero(speeds == v)
            b, p = _basis(float(v), float(fs_hz), n_t, n_harmonics)
            coef_v = x[idx] @ p.T  # (m, 5, P)
            coef[idx], rest[idx] = coef_v, x[idx] - coef_v @ b.T
    h, k = n_harmonics, len(NUISANCE_ORDERS)
    out = np.empty((n, c, h + 2))
    out[..., 0] = coef[..., 0]
    out[..., 1:h + 1] = np.hypot(coef[..., 1:h + 1], coef[..., 1 + h + k:1 + 2 * h + k])
    out[..., -1] = np.log10(np.sqrt(np.mean(rest ** 2, axis=-1)) + 1e-9)
    return np.concatenate([out.reshape(n, -1), np.asarray(efficiency, float)[:, None]],
                          axis=1)


def _fit_in_angle(x: np.ndarray, psi: np.ndarray, fs_hz: float, n_harmonics: int
                  ) -> tuple[np.ndarray, np.ndarray]:
    """The coefficients (n, 5, P) and rest (n, 5, n_t) of :func:`window_features` with
    ``psi`` (n, n_t) given, from windows ``x`` (n, 5, n_t)."""
    n, c, n_t = x.shape
    ang = np.asarray(psi, dtype=np.float64)
    if ang.shape != (n, n_t) or not np.all(np.isfinite(ang)):
        raise ValueError(f"psi must be finite with shape (n, n_t) = {(n, n_t)}, got "
                         f"{ang.shape}")
    if n and n_t > 1:
        step = np.abs(np.diff(ang, axis=1)).max()  # [rad per sample]
        if step * n_harmonics >= np.pi:
            raise ValueError(f"harmonic {n_harmonics} of psi's fastest step "
                             f"{step * fs_hz / (2 * np.pi) * 60:g} rpm (WG) reaches the "
                             f"Nyquist frequency of {fs_hz:g} Hz")
    coef, rest = np.empty((n, c, 2 * (n_harmonics + 3) + 1)), np.empty_like(x)
    for i in range(0, n, 32):  # chunks of 32 windows: the bases stay in cache
        coef[i:i + 32], rest[i:i + 32] = angle_fit(
            x[i:i + 32], ang[i:i + 32], 1.0 + 1.0 / RATIO, n_harmonics, NUISANCE_ORDERS, i)
    return coef, rest


def life_features(plan: DatasetPlan, sig: np.ndarray, meta: dict[str, np.ndarray]) -> np.ndarray:
    """Health features of a block of a life's windows: :func:`window_features`, in the
    angle domain when the windows carry angle channels (a profile), and the twist
    features with an output encoder; shape (n, F)."""
    sensor = plan.config.profile.angles.input_sensor() if plan.profile is not None else None
    return health_features(sig, meta, plan.config.chain.sample_rate_hz, sensor)
