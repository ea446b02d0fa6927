"""Operating profiles for the dynamic model: desired input speed and load torque over time
(docs/PHYSICS.md sec. 1.8).

A profile is a speed profile (trapezoidal moves to a target speed at an acceleration limit,
holds for dwell or cruise) and a load:

* :class:`ConstantLoad`: a brake that opposes the output motion, as the steady bench
  (``dynamics.simulate``);
* :class:`LoadSteps`: a signed load torque stepping at given times;
* :class:`GravityLink`: a link under gravity, T = (m l + m_p l_p) g cos(q + q0), signed.

Sign convention [choice]: q = −φ_out is the joint angle, increasing while the input turns
forward (positive speed; the output turns the other way, docs/PHYSICS.md sec. 1.1). A
signed load T_L > 0 resists forward motion, the gear then delivers T_L; the load takes
the power T_L q̇ (negative when it drives the gear: a lowered arm, an overhauling load).
An opposing load is T_L = T tanh(N q̇ / v_s), today's brake.

Limits, checked by :func:`validate` before any work (docs/PHYSICS.md sec. 2): ``|speed|`` <=
6500 rpm, its time average over the profile <= 3500 rpm, load torque <= 107 N m
(repeated peak torque), ``J_out |q̈| + max |T_L| <= 107`` N m during every move [derived], the
torque overshoot of a load step ``T_0 + 2 |ΔT| <= 191`` N m (momentary peak torque) [derived,
undamped step response], positive acceleration limits, finite numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

RPM = 2 * math.pi / 60.0
G_ACCEL = 9.81  # [m/s²]

#: Catalogue limits of the size-20, ratio-100 gear (Harmonic Drive CSG-20-100 / RT1-20),
#: docs/PHYSICS.md sec. 2: maximum input speed [rpm], limit for repeated peak torque and
#: limit for momentary peak torque [N m]. The momentary peak 191 N m is the CSG catalogue's
#: rating table as digitised in github.com/AimanHaidar/harmonic-drive-selector
#: (data/reducers_tables.py, row CSG 20 100, which also gives 107 N m and 6500 rpm).
MAX_INPUT_SPEED_RPM = 6500.0
#: Limit for average input speed [rpm] of the same catalogue row (a profile's time average
#: of |n|, :meth:`SpeedProfile.average_speed_rpm`); the paper's steady 4000 rpm points
#: exceed it and are kept, since the paper records them.
MAX_AVERAGE_INPUT_SPEED_RPM = 3500.0
REPEATED_PEAK_TORQUE_NM = 107.0
MOMENTARY_PEAK_TORQUE_NM = 191.0

#: UR3e shoulder (joint 2) carrying links 2-6 stretched horizontally, from the masses and
#: centres of mass Universal Robots publishes (conf/dataset/robot_joint.yaml,
#: docs/PHYSICS.md sec. 10): (mass [kg], distance from the joint axis [m]).
UR3E_LINKS = ((3.4445, 0.24355 - 0.13), (1.437, 0.24355 + 0.2132 - 0.05),
              (0.871 + 0.805 + 0.261, 0.24355 + 0.2132))
_UR3E_MASS = sum(m for m, _ in UR3E_LINKS)  # 6.8185 kg
_UR3E_COM = sum(m * r for m, r in UR3E_LINKS) / _UR3E_MASS  # 0.2728 m


def _finite(key: str, value: float) -> float:
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{key} must be a finite number, got {value}")
    return v


@dataclass(frozen=True)
class Move:
    """Ramp of the desired input speed to ``target_rpm`` at the acceleration limit.

    Attributes
    ----------
    target_rpm : float
        Target input speed [rpm]; negative turns backward (a reversal when the speed
        before is positive).
    accel_rpm_s : float
        Acceleration limit [rpm/s], > 0; the ramp lasts ``|Δn| / accel``.
    """

    target_rpm: float
    accel_rpm_s: float


@dataclass(frozen=True)
class Hold:
    """Hold the speed for ``duration_s`` [s], >= 0: a dwell at 0 rpm, a cruise otherwise."""

    duration_s: float


@dataclass(frozen=True)
class SpeedProfile:
    """Desired input speed over time: ``start_rpm`` at t <= 0, then the segments in order;
    the last speed is held after the end.

    Attributes
    ----------
    start_rpm : float
        Input speed at t = 0 [rpm].
    segments : tuple of Move or Hold
    """

    start_rpm: float
    segments: tuple[Move | Hold, ...] = ()

    def knots(self) -> tuple[np.ndarray, np.ndarray]:
        """Corner times [s] and speeds [rpm] of the piecewise-linear speed, shape (K,)."""
        t, n = [0.0], [float(self.start_rpm)]
        for s in self.segments:
            if isinstance(s, Move):
                dt = abs(float(s.target_rpm) - n[-1]) / float(s.accel_rpm_s)
                t.append(t[-1] + dt)
                n.append(float(s.target_rpm))
            else:
                t.append(t[-1] + float(s.duration_s))
                n.append(n[-1])
        return np.array(t), np.array(n)

    @property
    def duration_s(self) -> float:
        """End of the last segment [s]."""
        return float(self.knots()[0][-1])

    def average_speed_rpm(self) -> float:
        """Time average of ``|n|`` over the profile [rpm], the catalogue's average input speed
        of a duty cycle (``sum |n_i| t_i / sum t_i``), exact for the piecewise-linear speed;
        ``|start_rpm|`` for a profile of no duration (it keeps its speed)."""
        t, n = self.knots()
        dt, n0, n1 = np.diff(t), n[:-1], n[1:]
        same = n0 * n1 >= 0  # a ramp through 0 rpm covers (n0² + n1²) / (2 |n1 − n0|) of it
        area = np.where(same, (np.abs(n0) + np.abs(n1)) / 2,
                        (n0 ** 2 + n1 ** 2) / (2 * np.maximum(np.abs(n1 - n0), 1e-300))) * dt
        return float(area.sum() / t[-1]) if t[-1] > 0 else abs(float(n[0]))


@dataclass(frozen=True)
class ConstantLoad:
    """A brake torque ``torque_nm`` [N m], >= 0, opposing the output motion (steady bench).

    Needs a speed profile that keeps a positive speed: the brake switches within
    ``|n| < v_s`` = 0.05 rad/s, which fixed-step RK4 cannot resolve through a reversal.
    """

    torque_nm: float


@dataclass(frozen=True)
class LoadSteps:
    """A signed load torque: ``initial_nm`` until the first step, then ``steps`` as
    (time [s], torque [N m]) pairs in increasing time; positive resists forward motion."""

    initial_nm: float
    steps: tuple[tuple[float, float], ...] = ()


@dataclass(frozen=True)
class GravityLink:
    """A link under gravity at the output: T_L = (m l + m_p l_p) g cos(q + q0), signed.

    Defaults: the UR3e shoulder's links 2-6 lumped (6.8185 kg at 0.2728 m, 18.25 N m at
    horizontal), no payload; the UR3e's rated 3 kg payload at the wrist (0.4568 m) adds
    13.44 N m [derived]. The output inertia J_out of the gear parameters must include the
    payload's m_p l_p² (0.626 kg m² for 3 kg); the profile does not change it.

    Attributes
    ----------
    mass_kg, com_m : float
        Link mass [kg] and centre-of-mass distance from the joint axis [m].
    payload_kg, payload_m : float
        Payload mass [kg] and its distance from the joint axis [m].
    q0_rad : float
        Angle of the link above horizontal at q = 0 [rad].
    """

    mass_kg: float = _UR3E_MASS
    com_m: float = _UR3E_COM
    payload_kg: float = 0.0
    payload_m: float = UR3E_LINKS[2][1]
    q0_rad: float = 0.0

    @property
    def max_torque_nm(self) -> float:
        """(m l + m_p l_p) g [N m], the torque at horizontal."""
        return (self.mass_kg * self.com_m + self.payload_kg * self.payload_m) * G_ACCEL


Load = ConstantLoad | LoadSteps | GravityLink


@dataclass(frozen=True)
class Profile:
    """An operating profile: desired input speed and load.

    Attributes
    ----------
    speed : SpeedProfile
    load : ConstantLoad, LoadSteps or GravityLink
    """

    speed: SpeedProfile
    load: Load

    @property
    def opposing(self) -> bool:
        """Whether the load opposes the motion (a brake) rather than being signed."""
        return isinstance(self.load, ConstantLoad)


def speed_at(profile: Profile | SpeedProfile, t,
             side: str = "right") -> tuple[np.ndarray, np.ndarray]:
    """Desired input speed and its rate at times ``t``, vectorised.

    Parameters
    ----------
    profile : Profile or SpeedProfile
    t : array_like, shape (n,)
        Times [s].
    side : {"right", "left"}
        At a corner the rate of the segment after it ("right") or before it ("left"), the
        limit RK4's last stage needs; times within 1 ns of a corner count as on it.

    Returns
    -------
    w_d : ndarray, shape (n,)
        Desired input speed [rad/s], piecewise linear.
    dw_d : ndarray, shape (n,)
        Its rate dω_d/dt [rad/s²], piecewise constant.
    """
    sp = profile.speed if isinstance(profile, Profile) else profile
    tk, nk = sp.knots()
    t = np.asarray(t, dtype=float)
    w_d = np.interp(t, tk, nk) * RPM
    slope = np.zeros(tk.size + 1)
    dt = np.diff(tk)
    with np.errstate(divide="ignore", invalid="ignore"):
        slope[1:-1] = np.where(dt > 0, np.diff(nk) / np.where(dt > 0, dt, 1.0), 0.0)
    i = np.searchsorted(tk, t + (1e-9 if side == "right" else -1e-9), side="right")
    return w_d, slope[i] * RPM


def load_at(load: Load, t, q=None, q_dot=None, ratio: float = 100.0,
            v_smooth_rad_s: float = 0.05, side: str = "right") -> np.ndarray:
    """Load torque T_L at the output, positive resisting forward motion, vectorised.

    Parameters
    ----------
    load : ConstantLoad, LoadSteps or GravityLink
    t : array_like
        Times [s]; a step acts from its time on.
    q : array_like, optional
        Joint angle q = −φ_out [rad], broadcast with ``t``; needed for GravityLink.
    q_dot : array_like, optional
        Joint speed q̇ = −ω_out [rad/s]; needed for ConstantLoad.
    ratio, v_smooth_rad_s : float
        Gear ratio N and smooth-sign scale v_s of the brake, tanh(N q̇ / v_s).
    side : {"right", "left"}
        At a step time the torque after it ("right") or before it ("left"); times within
        1 ns of a step count as on it.

    Returns
    -------
    ndarray
        T_L [N m], shape of ``t`` broadcast with ``q`` / ``q_dot``.
    """
    t = np.asarray(t, dtype=float)
    if isinstance(load, ConstantLoad):
        return load.torque_nm * np.tanh(np.asarray(q_dot) * ratio / v_smooth_rad_s) + 0 * t
    if isinstance(load, LoadSteps):
        times = np.array([s[0] for s in load.steps], dtype=float)
        vals = np.array([load.initial_nm] + [s[1] for s in load.steps], dtype=float)
        eps = 1e-9 if side == "right" else -1e-9
        return vals[np.searchsorted(times, t + eps, side="right")]
    return load.max_torque_nm * np.cos(np.asarray(q) + load.q0_rad) + 0 * t


def max_load_nm(load: Load) -> float:
    """Largest ``|T_L|`` the load can reach [N m] (a brake's torque, the largest step, a link's
    torque at horizontal)."""
    if isinstance(load, ConstantLoad):
        return abs(load.torque_nm)
    if isinstance(load, LoadSteps):
        return max(abs(v) for v in [load.initial_nm] + [s[1] for s in load.steps])
    return abs(load.max_torque_nm)


def _check_speed(sp: SpeedProfile) -> None:
    def n_ok(key, n):
        if abs(_finite(key, n)) > MAX_INPUT_SPEED_RPM:
            raise ValueError(f"{key} must be within ±{MAX_INPUT_SPEED_RPM:g} rpm (catalogue "
                             f"maximum input speed, size 20), got {n}")

    n_ok("speed.start_rpm", sp.start_rpm)
    for i, s in enumerate(sp.segments):
        key = f"speed.segments[{i}]"
        if isinstance(s, Move):
            n_ok(f"{key}.target_rpm", s.target_rpm)
            if not _finite(f"{key}.accel_rpm_s", s.accel_rpm_s) > 0:
                raise ValueError(f"{key}.accel_rpm_s must be > 0 rpm/s, got {s.accel_rpm_s}")
        elif isinstance(s, Hold):
            if not _finite(f"{key}.duration_s", s.duration_s) >= 0:
                raise ValueError(f"{key}.duration_s must be >= 0 s, got {s.duration_s}")
        else:
            raise ValueError(f"{key} must be a Move or a Hold, got {type(s).__name__}")
    n_av = sp.average_speed_rpm()
    if n_av > MAX_AVERAGE_INPUT_SPEED_RPM:
        raise ValueError(f"speed.segments: the average input speed over the profile, "
                         f"{n_av:.4g} rpm, exceeds {MAX_AVERAGE_INPUT_SPEED_RPM:g} rpm (catalogue "
                         "limit for average input speed, size 20); add holds at lower speed")


def _check_load(load: Load, sp: SpeedProfile) -> None:
    lim = REPEATED_PEAK_TORQUE_NM
    if isinstance(load, ConstantLoad):
        t = _finite("load.torque_nm", load.torque_nm)
        if not 0 <= t <= lim:
            raise ValueError(f"load.torque_nm must be in [0, {lim:g}] N m (repeated peak "
                             f"torque), got {t}")
        n_min = float(sp.knots()[1].min())
        if t > 0 and n_min <= 0:
            raise ValueError(f"load.torque_nm: a brake (ConstantLoad) needs the speed to stay "
                             f"> 0 rpm, the profile reaches {n_min:g} rpm; use LoadSteps")
    elif isinstance(load, LoadSteps):
        vals = [_finite("load.initial_nm", load.initial_nm)]
        if abs(vals[0]) > lim:
            raise ValueError(f"load.initial_nm must be within ±{lim:g} N m (repeated peak "
                             f"torque), got {vals[0]}")
        t_prev = -math.inf
        for i, st in enumerate(load.steps):
            if len(st) != 2:
                raise ValueError(f"load.steps[{i}] must be a (time s, torque N m) pair, got {st}")
            ts, v = _finite(f"load.steps[{i}] time", st[0]), _finite(f"load.steps[{i}]", st[1])
            if abs(v) > lim:
                raise ValueError(f"load.steps[{i}] must be within ±{lim:g} N m (repeated peak "
                                 f"torque), got {v}")
            if not ts > t_prev:
                raise ValueError(f"load.steps[{i}] time must increase, got {ts} s after {t_prev} s")
            peak = abs(2 * v - vals[-1])  # undamped overshoot of the step
            if peak > MOMENTARY_PEAK_TORQUE_NM:
                raise ValueError(f"load.steps[{i}]: the step {vals[-1]:g} -> {v:g} N m "
                                 f"overshoots to {peak:g} N m, above the momentary peak torque "
                                 f"{MOMENTARY_PEAK_TORQUE_NM:g} N m")
            t_prev = ts
            vals.append(v)
    elif isinstance(load, GravityLink):
        for k in ("mass_kg", "com_m", "payload_kg", "payload_m"):
            if not _finite(f"load.{k}", getattr(load, k)) >= 0:
                raise ValueError(f"load.{k} must be >= 0, got {getattr(load, k)}")
        _finite("load.q0_rad", load.q0_rad)
        if load.max_torque_nm > lim:
            raise ValueError(f"load: the gravity torque (m l + m_p l_p) g = "
                             f"{load.max_torque_nm:.1f} N m exceeds {lim:g} N m (repeated peak "
                             "torque); lower load.mass_kg or load.payload_kg")
    else:
        raise ValueError(f"load must be ConstantLoad, LoadSteps or GravityLink, got "
                         f"{type(load).__name__}")


def validate(profile: Profile, j_out_kgm2: float, ratio: float = 100.0) -> None:
    """Refuse a profile beyond the catalogue limits of the size-20 gear, before any work.

    Parameters
    ----------
    profile : Profile
    j_out_kgm2 : float
        Output inertia [kg m²] (the largest of the variants').
    ratio : float
        Gear ratio N [-].

    Raises
    ------
    ValueError
        One line naming the key and the limit: a speed beyond ±6500 rpm, an average input
        speed over the profile beyond 3500 rpm, a load beyond
        ±107 N m, a step overshooting 191 N m or outside the profile's duration, an
        acceleration whose torque ``J_out a / N + max |T_L|`` exceeds 107 N m, a
        non-positive acceleration limit, a
        negative hold, a brake through 0 rpm, a non-finite number.
    """
    if not isinstance(profile, Profile):
        raise ValueError(f"profile must be a Profile, got {type(profile).__name__}")
    sp = profile.speed
    _check_speed(sp)
    _check_load(profile.load, sp)
    t_max = max_load_nm(profile.load)
    for i, s in enumerate(sp.segments):
        if isinstance(s, Move):
            # torque to accelerate the output inertia on top of the largest load [derived]
            need = j_out_kgm2 * s.accel_rpm_s * RPM / ratio + t_max
            if need > REPEATED_PEAK_TORQUE_NM:
                a_max = (REPEATED_PEAK_TORQUE_NM - t_max) * ratio / (j_out_kgm2 * RPM)
                raise ValueError(f"speed.segments[{i}].accel_rpm_s must be <= {a_max:.4g} "
                                 f"rpm/s: J_out a / N + max load = {need:.1f} N m exceeds "
                                 f"{REPEATED_PEAK_TORQUE_NM:g} N m (repeated peak torque)")
    if isinstance(profile.load, LoadSteps):  # after the speed's checks: they set its length
        for i, st in enumerate(profile.load.steps):
            if not 0 <= float(st[0]) <= sp.duration_s:
                raise ValueError(f"load.steps[{i}].time_s must lie in [0, {sp.duration_s:g}] "
                                 f"s (the profile's duration), got {float(st[0]):g} s")
