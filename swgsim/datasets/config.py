"""Typed schema of a data-set config, with the paper preset as its defaults.

:class:`DatasetConfig` and its parts are plain dataclasses (no Hydra): their defaults *are*
the paper's grid and acquisition (Sec. III-B, Tables IV-V). Its parts are the simulator's
own settings classes (chain, mesh, gauges, disturbance, acquisition), so every default is
written once, where the value is used. The apps register the schema as a Hydra structured
config (``swgcli.schema``) and hand the typed object on, so the YAML presets in
``conf/dataset/`` hold only what differs from the paper; library users get the same
defaults from ``DatasetConfig()`` (or :func:`paper_config` as plain data).

:func:`dataset_config` is the door for plain mappings: keys and types are checked by
:func:`swgsim.base.typed.complete`, and :func:`swgsim.base.typed.build` makes the typed
object. Ranges and physical validity are checked once, by
:func:`swgsim.datasets.plan.plan`, which first refuses NaN and infinity in every float of
the tree (:func:`swgsim.base.typed.check_finite`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from swgsim.base.typed import build, complete
from swgsim.datasets.schedule import LifeConfig
from swgsim.gear.chain import ChainSettings
from swgsim.gear.dynamics import J_OUT_BENCH_KGM2, KeHarmonic
from swgsim.gear.flexspline import Mesh
from swgsim.gear.friction.simulation import FrictionEffectsConfig
from swgsim.gear.profile import (
    ConstantLoad,
    GravityLink,
    Hold,
    LoadSteps,
    Move,
    Profile,
    SpeedProfile,
)
from swgsim.gear.sensors import SensorsConfig, TolerancesConfig
from swgsim.sensing.acquisition import Acquisition, Amplifier  # noqa: F401 - a schema part
from swgsim.sensing.angles import InputAngleSensor, OutputEncoder
from swgsim.sensing.disturbance import DisturbanceSpec
from swgsim.sensing.effects import SensorEffectConfig


@dataclass
class GearConfig:
    """One SWG model of the data set (paper Table IV).

    Attributes
    ----------
    id : int
        SWG model number, >= 1.
    b1_factor, k1_factor : float
        b1 and k1 relative to the nominal gear [-], in (0, 10].
    tolerance_seed : int
        Seed of this gear's gauge tolerances (its sensor model), >= 0.
    ke_extra : list of KeHarmonic
        Extra kinematic-error harmonics found by the calibration loop
        (:func:`swgsim.gear.dynamics.gear_with_ke`).
    """

    id: int = 1
    b1_factor: float = 1.0
    k1_factor: float = 1.0
    tolerance_seed: int = 101
    ke_extra: list[KeHarmonic] = field(default_factory=list)


@dataclass
class VariantSpec:
    """Variants of one class: severities (a list or a linspace) x positions x repeats."""

    severities: list[float] | None = None
    severity_linspace: list[float] | None = None  # [first, last, count]
    repeat: int = 1
    n_positions: int = 1


def _paper_variants() -> dict[str, VariantSpec]:
    # paper Table V (empty in the text): 60 variants per class, README *Design choices*
    return {
        "healthy": VariantSpec(severities=[0.0], repeat=60),
        "reduced_damping": VariantSpec(severity_linspace=[0.05, 0.3333, 60]),
        "reduced_stiffness": VariantSpec(severity_linspace=[0.05, 0.25, 60]),
        "eccentric_wg": VariantSpec(severities=[0.02, 0.05, 0.1], n_positions=20),
        "root_tooth_crack": VariantSpec(severities=[0.5, 0.7, 0.9], n_positions=20),
        "tip_tooth_crack": VariantSpec(severities=[0.5, 0.75, 1.0], n_positions=20),
    }


@dataclass
class OperatingPointsConfig:
    """The paper's six operating points (Sec. III-B)."""

    n_in_rpm: list[float] = field(default_factory=lambda: [2000.0, 4000.0])
    t_out_nm: list[float] = field(default_factory=lambda: [7.0, 39.0, 70.0])


@dataclass
class LoadConfig:
    """What the gear drives: its inertia sets the output side of the I/O model (eq. 1).

    Attributes
    ----------
    j_out_kgm2 : float
        Output inertia: flange, coupling and driven load [kg m²]; the bench's
        (:data:`swgsim.gear.dynamics.J_OUT_BENCH_KGM2`) by default, a robot link's for
        ``conf/dataset/robot_joint.yaml``.
    """

    j_out_kgm2: float = J_OUT_BENCH_KGM2


# -------------------------------------------------------------------------- profile
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


def _paper_gears() -> list[GearConfig]:
    # paper Table IV: b1 and k1 of SWG models 1-3 relative to nominal
    return [GearConfig(1, 1.0, 1.0, 101), GearConfig(2, 1.2, 1.2, 102),
            GearConfig(3, 0.8, 0.8, 103)]


@dataclass
class DatasetConfig:
    """A data set: grid, chain, disturbance and acquisition; defaults are the paper preset.

    The parts are the simulator's own settings classes (one definition, one default each):
    :class:`swgsim.gear.sensors.SensorsConfig` and
    :class:`~swgsim.gear.sensors.TolerancesConfig`, :class:`swgsim.gear.chain.ChainSettings`,
    :class:`swgsim.gear.flexspline.Mesh`, :class:`swgsim.sensing.disturbance.DisturbanceSpec`
    and :class:`swgsim.sensing.acquisition.Acquisition`.

    Attributes
    ----------
    name : str
        Name, also the default folder ``data/<name>``.
    seed : int
        Seed of every random draw of the data set, >= 0.
    gears : list of GearConfig
    tolerances, sensors, operating_points, chain, mesh, load, disturbance, acquisition
        See their classes.
    variants : dict of str to VariantSpec
        Class name -> its variants (paper Table V).
    sensor_effects : list of SensorEffectConfig
        Measurement-chain effects (:mod:`swgsim.sensing.effects`), applied before eq. (10).
    friction_effects : FrictionEffectsConfig or None
        Extra friction found by a calibration (:mod:`swgsim.gear.friction.simulation`).
    life : LifeConfig or None
        None: the grid of ``variants`` at every operating point. Set: each gear's life as
        one time-ordered stream (:mod:`swgsim.datasets.life`) instead of the grid.
    profile : ProfileConfig or None
        None: steady operating points. Set: every variant simulated along this profile
        and cut into windows (``operating_points`` unused).
    """

    name: str = "paper"
    seed: int = 2024
    gears: list[GearConfig] = field(default_factory=_paper_gears)
    tolerances: TolerancesConfig = field(default_factory=TolerancesConfig)
    sensors: SensorsConfig = field(default_factory=SensorsConfig)
    variants: dict[str, VariantSpec] = field(default_factory=_paper_variants)
    operating_points: OperatingPointsConfig = field(default_factory=OperatingPointsConfig)
    chain: ChainSettings = field(default_factory=ChainSettings)
    mesh: Mesh = field(default_factory=Mesh)
    load: LoadConfig = field(default_factory=LoadConfig)
    disturbance: DisturbanceSpec = field(default_factory=DisturbanceSpec)
    acquisition: Acquisition = field(default_factory=Acquisition)
    sensor_effects: list[SensorEffectConfig] = field(default_factory=list)
    friction_effects: FrictionEffectsConfig | None = None
    life: LifeConfig | None = None
    profile: ProfileConfig | None = None


def paper_config() -> dict:
    """The paper preset as a plain dict (:class:`DatasetConfig` defaults)."""
    return dataclasses.asdict(DatasetConfig())


def dataset_config(cfg: Mapping[str, Any] | DatasetConfig | None = None) -> DatasetConfig:
    """A complete, checked, typed data-set config: ``cfg`` over the paper preset's defaults.

    The door of the data-set config: keys and types are checked here (ranges and physics
    in :func:`swgsim.datasets.plan.plan`), and what leaves is a :class:`DatasetConfig`.

    Parameters
    ----------
    cfg : mapping or DatasetConfig, optional
        Partial or complete data-set config; None: the paper preset.

    Returns
    -------
    DatasetConfig

    Raises
    ------
    ValueError
        Naming the key (``dataset.<key>``) that is unknown or of the wrong type.
    """
    if isinstance(cfg, DatasetConfig):
        cfg = dataclasses.asdict(cfg)
    return build(complete(cfg or {}, DatasetConfig, "dataset"), DatasetConfig)
