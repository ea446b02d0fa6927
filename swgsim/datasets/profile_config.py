"""The operating profile of a data set (``dataset.profile``): its typed schema and own rules.

A gear's duty cycle as moves, holds and a load (:mod:`swgsim.gear.profile`), cut into
windows. The parts check their own fields (:func:`swgsim.base.typed.check_tree`); what a
profile must satisfy with the gears, the chain's step and window and the amplifier is
judged by the data set (:meth:`swgsim.datasets.config.DatasetConfig.check`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from swgsim.base.typed import check_range
from swgsim.gear.profile import (
    ConstantLoad,
    GravityLink,
    Hold,
    LoadSteps,
    Move,
    Profile,
    SpeedProfile,
)
from swgsim.sensing.angles import InputAngleSensor, OutputEncoder, check_channels

#: Longest profile [s]: a joint's cycle lasts seconds to minutes, and a profile is
#: integrated and held in memory whole (10 minutes at 10 kHz is 6 million samples).
MAX_PROFILE_S = 600.0

__all__ = ["MAX_PROFILE_S", "AngleChannelsConfig", "ConstantLoadConfig", "GravityLinkConfig",
           "HoldConfig", "LoadStepConfig", "LoadStepsConfig", "MoveConfig", "ProfileConfig",
           "ProfileLoadConfig", "SegmentConfig"]

@dataclass
class MoveConfig:
    """A ramp of the desired input speed (:class:`swgsim.gear.profile.Move`).

    Attributes
    ----------
    target_rpm : float
        Target input speed [rpm]; negative turns backward.
    accel_rpm_s : float
        Acceleration limit [rpm/s], > 0.
    """

    target_rpm: float
    accel_rpm_s: float


@dataclass
class HoldConfig:
    """Hold the speed (:class:`swgsim.gear.profile.Hold`): ``duration_s`` [s], >= 0."""

    duration_s: float


@dataclass
class SegmentConfig:
    """One segment of the speed profile: exactly one of ``move`` and ``hold``."""

    move: MoveConfig | None = None
    hold: HoldConfig | None = None


@dataclass
class ConstantLoadConfig:
    """A brake opposing the motion (:class:`swgsim.gear.profile.ConstantLoad`) [N m]."""

    torque_nm: float


@dataclass
class LoadStepConfig:
    """One load step: the signed load ``torque_nm`` [N m] from ``time_s`` [s] on."""

    time_s: float
    torque_nm: float


@dataclass
class LoadStepsConfig:
    """A signed, stepping load (:class:`swgsim.gear.profile.LoadSteps`).

    Attributes
    ----------
    initial_nm : float
        Load before the first step [N m], positive resisting forward motion.
    steps : list of LoadStepConfig
        In increasing time.
    """

    initial_nm: float
    steps: list[LoadStepConfig] = field(default_factory=list)


@dataclass
class GravityLinkConfig:
    """A link under gravity (:class:`swgsim.gear.profile.GravityLink`, whose defaults these are:
    the UR3e shoulder's links 2-6, no payload)."""

    mass_kg: float = GravityLink.mass_kg
    com_m: float = GravityLink.com_m
    payload_kg: float = GravityLink.payload_kg
    payload_m: float = GravityLink.payload_m
    q0_rad: float = GravityLink.q0_rad


@dataclass
class ProfileLoadConfig:
    """The load of a profile: exactly one of ``constant``, ``steps`` and ``gravity``."""

    constant: ConstantLoadConfig | None = None
    steps: LoadStepsConfig | None = None
    gravity: GravityLinkConfig | None = None


@dataclass
class AngleChannelsConfig:
    """The recorded angle channels of a profile data set (:mod:`swgsim.sensing.angles`).

    Attributes
    ----------
    input_counts_per_rev : int
        Counts per input revolution of the input angle sensor, >= 1
        (:class:`swgsim.sensing.angles.InputAngleSensor`; default its 24-count Hall sensor).
    output_encoder_bits : int or None
        None: no output encoder; else its resolution 2**bits counts per revolution, bits
        in [8, 32] (:class:`swgsim.sensing.angles.OutputEncoder`).
    """

    input_counts_per_rev: int = InputAngleSensor.counts_per_rev
    output_encoder_bits: int | None = None

    def input_sensor(self) -> InputAngleSensor:
        """The input angle sensor."""
        return InputAngleSensor(int(self.input_counts_per_rev))

    def output_encoder(self) -> OutputEncoder | None:
        """The output encoder, or None."""
        bits = self.output_encoder_bits
        return None if bits is None else OutputEncoder(int(bits))

    def check(self, where: str = "dataset.profile.angles") -> None:
        """Refuse channels the sensors cannot have
        (:func:`swgsim.sensing.angles.check_channels`)."""
        check_channels(self.input_counts_per_rev, self.output_encoder_bits, where)


@dataclass
class ProfileConfig:
    """A gear's duty cycle as an operating profile (:mod:`swgsim.gear.profile`), cut into windows.

    Each variant is simulated once along the whole profile (transients included) and the
    windows are cuts of that motion: at ``window_starts_s`` or, when None, tiling the
    profile from ``dataset.chain.settle_s`` on, ``dataset.chain.window_s`` each.

    Attributes
    ----------
    start_rpm : float
        Desired input speed at t = 0 [rpm].
    segments : list of SegmentConfig
        Moves and holds, in order.
    load : ProfileLoadConfig
    feedforward : bool
        Add the acceleration feed-forward torque to the motor torque.
    window_starts_s : list of float or None
        Start of each window [s] since the profile's start; None: tiling.
    start_jitter_s : float
        A gear life's windows (``dataset.life`` beside the profile) start up to this long
        after their slot's start, uniformly [s], >= 0 (:mod:`swgsim.datasets.slots`). The
        default, about one WG revolution at the robot joint's 2400 rpm cruise [choice],
        is a monitor whose windows are not locked to the motion command; one triggered by
        the controller's command sets its trigger's spread (a few servo cycles: UR
        controllers run at 500 Hz, 2 ms). Without any, every window of a slot holds the
        same motion.
    angles : AngleChannelsConfig
    """

    segments: list[SegmentConfig]
    load: ProfileLoadConfig
    start_rpm: float = 0.0
    feedforward: bool = False
    window_starts_s: list[float] | None = None
    start_jitter_s: float = 0.025
    angles: AngleChannelsConfig = field(default_factory=AngleChannelsConfig)

    def to_profile(self) -> Profile:
        """The :class:`swgsim.gear.profile.Profile` of this config.

        Raises
        ------
        ValueError
            A segment or the load not setting exactly one kind, naming its key.
        """
        segs: list[Move | Hold] = []
        for i, s in enumerate(self.segments):
            if (s.move is None) == (s.hold is None):
                raise ValueError(f"dataset.profile.segments[{i}] must set exactly one of "
                                 "move and hold")
            segs.append(Move(float(s.move.target_rpm), float(s.move.accel_rpm_s))
                        if s.move is not None else Hold(float(s.hold.duration_s)))
        ld = self.load
        kinds = [k for k in ("constant", "steps", "gravity") if getattr(ld, k) is not None]
        if len(kinds) != 1:
            raise ValueError("dataset.profile.load must set exactly one of constant, steps "
                             f"and gravity, got {kinds or 'none'}")
        if ld.constant is not None:
            load = ConstantLoad(float(ld.constant.torque_nm))
        elif ld.steps is not None:
            load = LoadSteps(float(ld.steps.initial_nm),
                             tuple((float(st.time_s), float(st.torque_nm))
                                   for st in ld.steps.steps))
        else:
            g = ld.gravity
            load = GravityLink(float(g.mass_kg), float(g.com_m), float(g.payload_kg),
                               float(g.payload_m), float(g.q0_rad))
        return Profile(SpeedProfile(float(self.start_rpm), tuple(segs)), load)

    def load_kind(self) -> str:
        """The key of the load set (``constant``, ``steps`` or ``gravity``)."""
        return next((k for k in ("constant", "steps", "gravity")
                     if getattr(self.load, k) is not None), "")

    def check(self, where: str = "dataset.profile") -> None:
        """Refuse a profile that sets no or two kinds of a segment or load, or lasts longer
        than :data:`MAX_PROFILE_S`; the limits of the gear are judged with the gears
        (:meth:`swgsim.datasets.config.DatasetConfig.check`).

        Raises
        ------
        ValueError
            ``dataset.profile.segments last ... s; allowed: at most 600 s ...`` and the like.
        """
        dur = self.to_profile().speed.duration_s
        if dur > MAX_PROFILE_S:
            raise ValueError(f"{where}.segments last {dur:.4g} s; allowed: at most "
                             f"{MAX_PROFILE_S:g} s (one cycle of a joint, integrated in memory)")

    def message(self, msg: str) -> str:
        """A message of :func:`swgsim.gear.profile.validate` with its keys as
        ``dataset.profile``'s."""
        p = "dataset.profile"
        msg = re.sub(r"\bspeed\.segments\[(\d+)\]\.(target_rpm|accel_rpm_s)",
                     rf"{p}.segments[\1].move.\2", msg)
        msg = re.sub(r"\bspeed\.segments\[(\d+)\]\.duration_s",
                     rf"{p}.segments[\1].hold.duration_s", msg)
        msg = re.sub(r"\bspeed\.segments\b", f"{p}.segments", msg)
        msg = re.sub(r"\bspeed\.start_rpm", f"{p}.start_rpm", msg)
        return re.sub(r"\bload([.:])", rf"{p}.load.{self.load_kind()}\1", msg)

    def lowest_cruise_rpm(self) -> float:
        """Lowest non-zero ``|speed|`` the profile holds [rpm]: of its holds at a non-zero
        speed, else of its non-zero corner speeds; 0 for a profile that never turns."""
        tk, nk = self.to_profile().speed.knots()
        held = [abs(nk[i]) for i in range(1, tk.size) if nk[i] == nk[i - 1] and nk[i] != 0
                and tk[i] > tk[i - 1]]
        moving = [abs(n) for n in nk if n != 0]
        return float(min(held or moving or [0.0]))

    def window_starts(self, window_s: float, settle_s: float, lead_s: float
                      ) -> tuple[float, ...]:
        """Start of every window [s] since the profile's start: ``window_starts_s`` or
        the tiling from ``settle_s`` on, each window inside the profile with ``lead_s`` of
        filter history before it (``dataset.chain.window_s``, ``settle_s`` [s]).

        Raises
        ------
        ValueError
            No window fits, or a given start puts its window outside the profile.
        """
        dur = self.to_profile().speed.duration_s
        if self.window_starts_s is None:
            n = int(np.floor((dur - lead_s - settle_s) / window_s + 1e-9))
            if n < 1:
                raise ValueError(
                    f"dataset.chain.window_s={window_s:g} s: no window fits the profile of "
                    f"{dur:g} s after dataset.chain.settle_s={settle_s:g} s; allowed: <= "
                    f"{dur - lead_s - settle_s:.4g} s")
            return tuple(round(float(settle_s + k * window_s), 12) for k in range(n))
        starts = tuple(float(t) for t in self.window_starts_s)
        if not starts:
            raise ValueError("dataset.profile.window_starts_s must list at least one start")
        for i, t in enumerate(starts):
            check_range(t, lead_s, dur - window_s - lead_s,
                        f"dataset.profile.window_starts_s[{i}]", "s",
                        why="the window inside the profile, with the amplifier's history")
        return starts
