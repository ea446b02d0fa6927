"""Angle channels of a joint: the input-angle sensor, an optional output encoder, and the
wave-generator angle ψ and the output twist estimated from them.

A real joint knows its angles. The sensorised RT1-T sends the torque together with the
drive-shaft (input) angle from a Hall sensor **[unverified: the project's issue "A joint
in motion"; the idea is in patent application US 2026/0160619 A1, "method for
determining a torque and a drive shaft angle of a gear mechanism": torque sensor and
Hall sensor integrated in the gear, one data set over a single communication line
(abstract read; applicant and resolution not stated there)]**. A joint with an output
encoder measures the twist itself.

Sign convention of :mod:`swgsim.gear.dynamics` (docs/PHYSICS.md sec. 1.1): states
[φ_in, ω_in, φ_out, ω_out, ∫e]; the rigid gear has φ_out = −φ_in / N, the output twist is
δ = φ_out + φ_in / N, and the WG angle relative to the flexspline is
ψ = φ_in − φ_out = φ_in (1 + 1/N) − δ.

This module is a library; no data set records these channels yet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from swgsim.gear.dynamics import GearParams

ARCSEC = math.pi / (180.0 * 3600.0)  #: one arc second [rad]

#: Hall states per electrical revolution of three Hall sensors 120 electrical degrees
#: apart: six sectors of 60 electrical degrees [src: Microchip developer help,
#: "Introduction to Six-Step Sensored Brushless DC (BLDC) Motor Commutation",
#: developerhelp.microchip.com/xwiki/bin/view/applications/motors/control-algorithms/
#: bldc/sensored/]; times the pole pairs per mechanical revolution.
HALL_STATES_PER_ELEC_REV = 6

_HALL_SRC = ("Hall sensor, 6 states per electrical revolution x pole pairs [src: Microchip "
             "developer help, six-step sensored BLDC commutation, 60-degree sectors]; the "
             "RT1-T's own Hall resolution is not public [choice: pole pairs]")
_ENC_SRC = "encoder with 2**bits counts per revolution [choice: bits]"


#: Most counts per input revolution: a 32-bit encoder's (:meth:`InputAngleSensor.encoder`).
MAX_COUNTS_PER_REV = 2 ** 32
#: Output encoder resolutions allowed, bits (2**bits counts per revolution).
ENCODER_BITS = (8, 32)


def _int_range(key: str, value, lo: int, hi: int, what: str) -> int:
    """``value`` as an int in [lo, hi]; a one-line ValueError naming ``key``, the range and
    what the value is otherwise."""
    ok = (isinstance(value, (int, np.integer)) and not isinstance(value, bool)
          and lo <= value <= hi)
    if not ok:
        raise ValueError(f"{key} must be an integer in [{lo}, {hi}] ({what}), got {value!r}")
    return int(value)


def check_channels(input_counts_per_rev, output_encoder_bits,
                   key: str = "dataset.profile.angles") -> None:
    """Refuse angle channels the sensors cannot have, naming the config keys, before any
    work.

    Parameters
    ----------
    input_counts_per_rev : int
        Counts per input revolution, in [1, :data:`MAX_COUNTS_PER_REV`].
    output_encoder_bits : int or None
        None: no output encoder; else bits in :data:`ENCODER_BITS`.
    key : str
        Where the two were given (``<key>.input_counts_per_rev``, ...).

    Raises
    ------
    ValueError
        ``dataset.profile.angles.input_counts_per_rev must be an integer in [1, ...]
        (counts per input revolution), got 0``.
    """
    _int_range(f"{key}.input_counts_per_rev", input_counts_per_rev, 1, MAX_COUNTS_PER_REV,
               "counts per input revolution")
    if output_encoder_bits is not None:
        _int_range(f"{key}.output_encoder_bits", output_encoder_bits, *ENCODER_BITS,
                   "output encoder resolution: 2**bits counts per revolution; null: none")


def _source(value) -> None:
    if not (isinstance(value, str) and value.strip()):
        raise ValueError(f"source must be a non-empty string, got {value!r}")


@dataclass(frozen=True)
class InputAngleSensor:
    """Incremental angle sensor on the input (wave-generator / drive) shaft.

    Build with :meth:`hall` or :meth:`encoder`.

    Attributes
    ----------
    counts_per_rev : int
        Distinguishable states per input revolution, >= 1.
    source : str
        Where the resolution comes from.

    Notes
    -----
    Default: a Hall sensor on a 4-pole-pair magnet, 6 · 4 = 24 counts per revolution
    (15°) **[choice]**: the RT1-T's Hall resolution is not stated in the public sources
    found (module docstring); 4 pole pairs is a typical small BLDC motor.
    """

    counts_per_rev: int = HALL_STATES_PER_ELEC_REV * 4
    source: str = _HALL_SRC

    def __post_init__(self):
        _int_range("InputAngleSensor.counts_per_rev", self.counts_per_rev, 1,
                   MAX_COUNTS_PER_REV, "counts per input revolution")
        _source(self.source)

    @classmethod
    def hall(cls, pole_pairs: int = 4) -> InputAngleSensor:
        """Hall sensor: 6 states per electrical revolution times ``pole_pairs`` (>= 1)."""
        pp = _int_range("InputAngleSensor.hall pole_pairs", pole_pairs, 1, 1000,
                        "pole pairs of the motor's magnet")
        return cls(HALL_STATES_PER_ELEC_REV * pp, _HALL_SRC)

    @classmethod
    def encoder(cls, bits: int = 14) -> InputAngleSensor:
        """Incremental or absolute encoder of ``bits`` (in [8, 32]): 2**bits counts per
        revolution (for an incremental one: 4 counts per line in quadrature)."""
        b = _int_range("InputAngleSensor.encoder bits", bits, *ENCODER_BITS,
                       "2**bits counts per revolution")
        return cls(2 ** b, _ENC_SRC)

    @property
    def resolution_rad(self) -> float:
        """One count, 2π / counts_per_rev [rad]."""
        return 2.0 * math.pi / self.counts_per_rev


@dataclass(frozen=True)
class OutputEncoder:
    """Absolute encoder on the joint's output (flexspline side).

    Attributes
    ----------
    bits : int
        Counts per revolution 2**bits, bits in [8, 32]; default 20 bits = 1.24 arcsec
        per count **[choice: a common single-turn resolution of robot-joint output
        encoders; no data sheet read here]**.
    source : str
        Where the resolution comes from.
    """

    bits: int = 20
    source: str = "absolute output encoder, 2**bits counts per revolution [choice: 20 bits]"

    def __post_init__(self):
        _int_range("OutputEncoder.bits", self.bits, *ENCODER_BITS,
                   "2**bits counts per revolution")
        _source(self.source)

    @property
    def resolution_rad(self) -> float:
        """One count, 2π / 2**bits [rad] (20 bits: 5.99e-6 rad = 1.24 arcsec)."""
        return 2.0 * math.pi / 2 ** self.bits


def _finite(key: str, x) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.size == 0 or not np.all(np.isfinite(a)):
        raise ValueError(f"{key} must be a non-empty array of finite angles [rad]")
    return a


def _like(key: str, x, key_of: str, of) -> np.ndarray:
    """``x`` as :func:`_finite` takes it, refused unless of the shape of ``of``."""
    a = _finite(key, x)
    if a.shape != np.shape(of):
        raise ValueError(f"{key} must have {key_of}'s shape {np.shape(of)}, got {a.shape}")
    return a


def quantise(phi, resolution_rad: float) -> np.ndarray:
    """Recorded angle of a counting sensor: floor(φ / res) · res, on the unwrapped
    (continuous) count, so 0 <= φ − recorded < res.

    Parameters
    ----------
    phi : array_like
        True angle [rad], any shape; the sensor's zero is at φ = 0 **[choice]**.
    resolution_rad : float
        One count [rad], > 0.

    Returns
    -------
    ndarray
        Same shape as ``phi`` [rad].
    """
    a = _finite("phi", phi)
    if not (math.isfinite(resolution_rad) and resolution_rad > 0):
        raise ValueError(f"resolution_rad must be finite and > 0, got {resolution_rad!r}")
    return np.floor(a / resolution_rad) * resolution_rad


def measure_angles(phi_in, phi_out=None, *, input_sensor: InputAngleSensor | None = None,
                   output_encoder: OutputEncoder | None = None) -> dict[str, np.ndarray]:
    """Quantised angle channels as a joint records them.

    Parameters
    ----------
    phi_in : array_like or SimResult
        True input angle φ_in [rad], any shape (e.g. (V, n_t)); or a result of
        :func:`swgsim.gear.dynamics.simulate` / ``simulate_profile`` (its ``states[0]`` and
        ``states[2]`` are used, and ``phi_out`` must be None).
    phi_out : array_like, optional
        True output angle φ_out [rad], same shape; needed with ``output_encoder``, unused
        without one.
    input_sensor : InputAngleSensor, optional
        Default :class:`InputAngleSensor` () (24-count Hall sensor).
    output_encoder : OutputEncoder, optional
        None: no output channel.

    Returns
    -------
    dict
        ``"phi_in"``: the recorded input angle [rad]; ``"phi_out"`` (only with an output
        encoder): the recorded output angle [rad]. Each is floor-quantised on its sensor's
        continuous count (:func:`quantise`). No noise is added: no source at hand gives
        one for these sensors, and a counting sensor's error is its count.
    """
    states = getattr(phi_in, "states", None)
    if states is not None:
        if phi_out is not None:
            raise ValueError("phi_out must be None when phi_in is a simulation result")
        phi_in, phi_out = states[0], states[2]
    sensor = InputAngleSensor() if input_sensor is None else input_sensor
    out = {"phi_in": quantise(phi_in, sensor.resolution_rad)}
    if output_encoder is not None:
        if phi_out is None:
            raise ValueError("phi_out is required with an output_encoder")
        po = _like("phi_out", phi_out, "phi_in", phi_in)
        out["phi_out"] = quantise(po, output_encoder.resolution_rad)
    return out


def _ratio(ratio: float) -> float:
    if not (math.isfinite(ratio) and ratio >= 1):
        raise ValueError(f"ratio must be finite and >= 1, got {ratio!r}")
    return float(ratio)


def psi_estimate(phi_in_meas, phi_out_meas=None, ratio: float = 100.0) -> np.ndarray:
    """WG angle relative to the flexspline, ψ, from the measured angle channels.

    With an output encoder ψ = φ_in − φ_out (measured), error within one count of each
    sensor. Without one the rigid gear is assumed, φ_out = −φ_in / N, so
    ψ ≈ φ_in (1 + 1/N); its error is exactly the output twist, ψ̂ − ψ = δ (plus the input
    count times 1 + 1/N) - *not* divided by N: see :func:`twist_bound_rad`.

    Parameters
    ----------
    phi_in_meas : array_like
        Measured input angle [rad], any shape.
    phi_out_meas : array_like, optional
        Measured output angle [rad], same shape.
    ratio : float
        Gear ratio N (>= 1).

    Returns
    -------
    ndarray
        ψ [rad], shape of ``phi_in_meas``.
    """
    n = _ratio(ratio)
    pin = _finite("phi_in_meas", phi_in_meas)
    if phi_out_meas is None:
        return pin * (1.0 + 1.0 / n)
    return pin - _like("phi_out_meas", phi_out_meas, "phi_in_meas", pin)


def twist_estimate(phi_in_meas, phi_out_meas, ratio: float = 100.0) -> np.ndarray:
    """Torsional twist at the output, δ = φ_out + φ_in / N [rad] (dynamics' convention:
    positive when the gear carries a load against forward motion).

    Error within one output count plus one input count / N (floor quantisation).

    Raises
    ------
    ValueError
        Without an output angle: the input angle alone cannot see the twist.
    """
    if phi_out_meas is None:
        raise ValueError("phi_out_meas is required: the twist needs an output encoder")
    n = _ratio(ratio)
    pin = _finite("phi_in_meas", phi_in_meas)
    return _like("phi_out_meas", phi_out_meas, "phi_in_meas", pin) + pin / n


def twist_bound_rad(gear: GearParams, mesh_torque_nm: float) -> float:
    """Upper bound on ``|δ|``, the error of ψ from the input angle alone [rad].

    Derivation (docs/PHYSICS.md sec. 1.1-1.2): Δφ_k = c δ + c e(φ_in) with e the
    kinematic error, ``|e| <= Σ A_k``, and T_stiff = k1 Δφ_k + k2 Δφ_k³ carries the mesh torque
    ``c |T_stiff|``. For k2 >= 0 the linear stiffness is the softest, ``|Δφ_k| <= |T_stiff| / k1``,
    so ``|δ| <= T_mesh / (c² k1) + Σ A_k`` (+ backlash / 2, the dead zone). The mesh torque is
    the load plus the output friction, T_load / η at steady speed (η the efficiency).

    Rated 52 N m at η = 0.77: 67.5 N m / (7.40 · 2103 N m/rad) = 4.34e-3 rad (14.9 arcmin)
    plus Σ A_k = 1.7e-4 rad (0.58 arcmin). The catalogue's "about 11 arcmin" is
    52 N m / (c² k1) without friction; the cubic stiffness of ``rt1_size20`` gives a mean
    twist of 8.1 arcmin at 52 N m, 2000 rpm (tests/swgsim/test_angles.py).

    Parameters
    ----------
    gear : GearParams
        Gear (k2 >= 0 assumed).
    mesh_torque_nm : float
        Largest mesh torque ``c |T_stiff|`` [N m], >= 0.
    """
    if not (math.isfinite(mesh_torque_nm) and mesh_torque_nm >= 0):
        raise ValueError(f"mesh_torque_nm must be finite and >= 0, got {mesh_torque_nm!r}")
    c = gear.c_out
    ke = float(np.sum(np.abs(gear.ke_amp_rad)))
    return mesh_torque_nm / (c * c * gear.k1_nm_per_rad) + ke + 0.5 * gear.backlash_rad


def edge_interpolate(time, phi_meas, resolution_rad: float) -> np.ndarray:
    """Smooth angle from a coarse counting sensor by edge-time interpolation.

    The angle is known exactly at the count edges (a boundary k · res), only the time of an
    edge is uncertain, to one sample. Each edge is placed at the middle of the sample
    interval in which the count changed (several edges in one interval are spread evenly
    over it), and the angle is interpolated linearly in time between edges; before the
    first and after the last edge it is extrapolated with the slope over up to four edge
    intervals that move one way. At constant speed ω the error is at most ω Δt / 2 between
    edges (Δt the sample interval), somewhat more at the window's ends; near a reversal
    or standstill the edges are sparse and the error grows to about one count. Without
    any edge the input is returned (the count's lower boundary).

    Parameters
    ----------
    time : array_like, shape (n_t,)
        Sample times [s], strictly increasing.
    phi_meas : array_like, shape (..., n_t)
        Recorded angle, a multiple of ``resolution_rad`` [rad] (:func:`quantise`).
    resolution_rad : float
        One count [rad], > 0.

    Returns
    -------
    ndarray, shape (..., n_t)
        Interpolated angle [rad].
    """
    t = _finite("time", time)
    if t.ndim != 1 or t.size < 2 or np.any(np.diff(t) <= 0):
        raise ValueError("time must be a 1-D, strictly increasing array of >= 2 samples [s]")
    ph = _finite("phi_meas", phi_meas)
    if ph.shape[-1] != t.size:
        raise ValueError(f"phi_meas's last axis must have {t.size} samples, got {ph.shape}")
    if not (math.isfinite(resolution_rad) and resolution_rad > 0):
        raise ValueError(f"resolution_rad must be finite and > 0, got {resolution_rad!r}")
    flat = np.ascontiguousarray(ph.reshape(-1, t.size))
    out = np.empty_like(flat)
    for r in range(flat.shape[0]):
        _edges_row(t, flat[r], float(resolution_rad), out[r])
    return out.reshape(ph.shape)


@numba.njit(cache=True)
def _edges_row(t, phi, res, out):
    """:func:`edge_interpolate` of one row into ``out``, compiled (its array form, the
    reference, is in tests/swgsim/test_angles.py): 18 against 97 µs a row of a 0.12-s
    window at 10 kHz, 5-50 input revolutions a second past a 24-count sensor (one core of
    this project's 2-core machine, 2026-11-28)."""
    k = np.rint(phi / res).astype(np.int64)
    n_e = 0
    for i in range(t.size - 1):
        n_e += abs(k[i + 1] - k[i])
    if n_e == 0:
        out[:] = phi
        return
    te, ang = np.empty(n_e), np.empty(n_e)
    e = 0
    for i in range(t.size - 1):  # one entry per boundary crossed, spread over its interval
        dk = k[i + 1] - k[i]
        m = abs(dk)
        for w in range(m):
            # going up from k to k+1 it is (k+1) res, going down from k it is k res
            bound = k[i] + (w + 1 if dk > 0 else -w)
            te[e] = t[i] + (w + 0.5) / m * (t[i + 1] - t[i])
            ang[e] = bound * res
            e += 1
    if n_e == 1:
        out[:] = ang[0]
        return
    lo = _end_slope(te, ang)
    hi = _end_slope(-te[::-1], ang[::-1]) * -1.0
    j = 0
    for i in range(t.size):  # linear between edges, as np.interp computes it
        x = t[i]
        if x < te[0]:
            out[i] = ang[0] + (x - te[0]) * lo
        elif x > te[-1]:
            out[i] = ang[-1] + (x - te[-1]) * hi
        else:
            while j < n_e - 1 and te[j + 1] <= x:
                j += 1
            if j == n_e - 1 or te[j] == x:
                out[i] = ang[j]
            else:
                out[i] = (ang[j + 1] - ang[j]) / (te[j + 1] - te[j]) * (x - te[j]) + ang[j]


@numba.njit(cache=True)
def _end_slope(te, ang, n_max=4):
    """Slope at the first edge over up to ``n_max`` edge intervals moving one way: a longer
    base than one interval divides the edges' timing error (±Δt / 2 each)."""
    n = min(n_max, ang.size - 1)
    k = n
    for j in range(1, n):
        if np.sign(ang[j + 1] - ang[j]) != np.sign(ang[1] - ang[0]):
            k = j
            break
    return (ang[k] - ang[0]) / (te[k] - te[0])


def psi_smooth(time, phi_in_meas, input_sensor: InputAngleSensor,
               phi_out_meas=None, ratio: float = 100.0) -> np.ndarray:
    """ψ for order tracking from a coarse input sensor: :func:`edge_interpolate` on the
    input channel, then :func:`psi_estimate` (with the output channel if given, which is
    fine enough to use as recorded).

    Parameters
    ----------
    time : array_like, shape (n_t,)
        Sample times [s].
    phi_in_meas : array_like, shape (..., n_t)
        Recorded input angle [rad].
    input_sensor : InputAngleSensor
        The sensor that recorded it (its count).
    phi_out_meas : array_like, optional
        Recorded output angle [rad], same shape.
    ratio : float
        Gear ratio N.

    Returns
    -------
    ndarray, shape (..., n_t)
        ψ [rad].
    """
    smooth = edge_interpolate(time, phi_in_meas, input_sensor.resolution_rad)
    return psi_estimate(smooth, phi_out_meas, ratio)
