"""Typed schema of a data-set config, with the paper preset as its defaults.

:class:`DatasetConfig` and its parts are plain dataclasses (no Hydra): their defaults *are*
the paper's grid and recording (Sec. III-B, Tables IV-V). Its parts are the simulator's
own settings classes (chain, mesh, gauges, disturbance, acquisition), so every default is
written once, where the value is used. The apps register the schema as a Hydra structured
config (``swgcli.schema``) and hand the typed object on, so the YAML presets in
``conf/dataset/`` hold only what differs from the paper; library users get the same
defaults from ``DatasetConfig()`` (or :func:`paper_config` as plain data).

:func:`dataset_config` is the door for plain mappings: :func:`check_keys` refuses every
unknown, missing or mistyped key with its full name, e.g.
``dataset.chain.windows_s: unknown key; allowed: sample_rate_hz, window_s, ...``, and
:func:`build` makes the typed object. Ranges and physical validity are checked once, by
:func:`swgsim.plan.plan`, which first refuses NaN and infinity in every float of the tree
(:func:`check_finite`): every comparison with NaN is false, so NaN passes a range check
written ``if v < lo or v > hi: raise``, and any key that has no range check.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import types
import typing
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any, Union

import numpy as np

from .acquisition import Acquisition, Amplifier  # noqa: F401 - Amplifier: a schema part
from .angles import InputAngleSensor, OutputEncoder
from .chain import ChainSettings
from .disturbance import DisturbanceSpec
from .dynamics import J_OUT_BENCH_KGM2, KeHarmonic
from .flexspline import Mesh
from .friction.simulation import FrictionEffectsConfig
from .life import LifeConfig
from .measurement import SensorEffectConfig
from .profile import ConstantLoad, GravityLink, Hold, LoadSteps, Move, Profile, SpeedProfile
from .sensors import SensorsConfig, TolerancesConfig

MISSING = "???"  # Hydra's and OmegaConf's marker of a mandatory value


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
        (:func:`swgsim.dynamics.gear_with_ke`).
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
        (:data:`swgsim.dynamics.J_OUT_BENCH_KGM2`) by default, a robot link's for
        ``conf/dataset/robot_joint.yaml``.
    """

    j_out_kgm2: float = J_OUT_BENCH_KGM2


# -------------------------------------------------------------------------- profile
@dataclass
class MoveConfig:
    """A ramp of the desired input speed (:class:`swgsim.profile.Move`).

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
    """Hold the speed (:class:`swgsim.profile.Hold`): ``duration_s`` [s], >= 0."""

    duration_s: float


@dataclass
class SegmentConfig:
    """One segment of the speed profile: exactly one of ``move`` and ``hold``."""

    move: MoveConfig | None = None
    hold: HoldConfig | None = None


@dataclass
class ConstantLoadConfig:
    """A brake opposing the motion (:class:`swgsim.profile.ConstantLoad`) [N m]."""

    torque_nm: float


@dataclass
class LoadStepConfig:
    """One load step: the signed load ``torque_nm`` [N m] from ``time_s`` [s] on."""

    time_s: float
    torque_nm: float


@dataclass
class LoadStepsConfig:
    """A signed, stepping load (:class:`swgsim.profile.LoadSteps`).

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
    """A link under gravity (:class:`swgsim.profile.GravityLink`, whose defaults these are:
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
    """The recorded angle channels of a profile data set (:mod:`swgsim.angles`).

    Attributes
    ----------
    input_counts_per_rev : int
        Counts per input revolution of the input angle sensor, >= 1
        (:class:`swgsim.angles.InputAngleSensor`; default its 24-count Hall sensor).
    output_encoder_bits : int or None
        None: no output encoder; else its resolution 2**bits counts per revolution, bits
        in [8, 32] (:class:`swgsim.angles.OutputEncoder`).
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
    """A gear's duty cycle as an operating profile (:mod:`swgsim.profile`), cut into windows.

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
        after their slot's start, uniformly [s], >= 0 (:mod:`swgsim.life_profile`). The
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
        """The :class:`swgsim.profile.Profile` of this config.

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
    """A data set: grid, chain, disturbance and recording; defaults are the paper preset.

    The parts are the simulator's own settings classes (one definition, one default each):
    :class:`swgsim.sensors.SensorsConfig` and :class:`~swgsim.sensors.TolerancesConfig`,
    :class:`swgsim.chain.ChainSettings`, :class:`swgsim.flexspline.Mesh`,
    :class:`swgsim.disturbance.DisturbanceSpec` and :class:`swgsim.acquisition.Acquisition`.

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
        Measurement-chain effects (:mod:`swgsim.measurement`), applied before eq. (10).
    friction_effects : FrictionEffectsConfig or None
        Extra friction found by a calibration (:mod:`swgsim.friction.simulation`).
    life : LifeConfig or None
        None: the grid of ``variants`` at every operating point. Set: each gear's life as
        one time-ordered stream (:mod:`swgsim.life`) instead of the grid.
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


# ------------------------------------------------------------------------ checking
_SCALARS = {int: "an integer", float: "a number", str: "a string", bool: "true or false"}


def _describe(tp) -> str:
    origin = typing.get_origin(tp)
    if tp in _SCALARS:
        return _SCALARS[tp]
    if origin in (list, tuple):
        return "a list"
    if origin in (dict, Mapping) or dataclasses.is_dataclass(tp):
        return "a mapping"
    return str(tp)


def _fields(schema: type) -> dict[str, Any]:
    hints = typing.get_type_hints(schema)
    return {f.name: hints[f.name] for f in dataclasses.fields(schema)}


def _default(schema: type, name: str) -> Any:
    f = {f.name: f for f in dataclasses.fields(schema)}[name]
    if f.default_factory is not dataclasses.MISSING:
        value = f.default_factory()
    elif f.default is not dataclasses.MISSING:
        value = f.default
    else:
        value = MISSING
    return _plain(value)


def _plain(value: Any) -> Any:
    if dataclasses.is_dataclass(value):
        return dataclasses.asdict(value)
    if isinstance(value, list):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


def _value(value: Any, tp, where: str, fill: bool) -> Any:
    if isinstance(value, str) and value == MISSING:
        raise ValueError(f"{where}: missing value (give {where}=...)")
    if tp is Any:
        return value
    origin = typing.get_origin(tp)
    if origin in (Union, types.UnionType):
        args = typing.get_args(tp)
        if value is None and type(None) in args:
            return None
        inner = [a for a in args if a is not type(None)]
        return _value(value, inner[0], where, fill)
    if value is None:
        raise ValueError(f"{where}: must be {_describe(tp)}, got null")
    if dataclasses.is_dataclass(tp):
        if not isinstance(value, Mapping):
            raise ValueError(f"{where}: must be a mapping of {', '.join(_fields(tp))}, "
                             f"got {value!r}")
        return _mapping(value, tp, where, fill)
    if origin in (list, tuple):
        if not isinstance(value, (list, tuple)):
            raise ValueError(f"{where}: must be a list, got {value!r}")
        (item,) = typing.get_args(tp)[:1] or (Any,)
        return [_value(v, item, f"{where}[{i}]", fill) for i, v in enumerate(value)]
    if origin is dict:
        if not isinstance(value, Mapping):
            raise ValueError(f"{where}: must be a mapping, got {value!r}")
        _, item = typing.get_args(tp)
        return {k: _value(v, item, f"{where}.{k}", fill) for k, v in value.items()}
    if tp is bool:
        ok = isinstance(value, bool)
    elif tp is int:
        ok = isinstance(value, int) and not isinstance(value, bool)
    elif tp is float:
        ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    elif tp is str:
        ok = isinstance(value, str)
    else:
        ok = True
    if not ok:
        raise ValueError(f"{where}: must be {_describe(tp)}, got {value!r}")
    return value


#: Key of a field's metadata holding its allowed range ``(lo, hi, what)`` (None: an open
#: end), checked with the keys (:func:`check_keys`, :func:`complete`), so before any work:
#: ``n_jobs: int = field(default=2, metadata=allowed(1, None, "worker processes"))``.
RANGE = "range"


def allowed(lo: float | None, hi: float | None, what: str = "") -> dict[str, tuple]:
    """Field metadata declaring the allowed range of a number (:data:`RANGE`).

    Parameters
    ----------
    lo, hi : float or None
        Inclusive bounds; None leaves that end open.
    what : str
        What the value is, for the message (e.g. ``"worker processes"``).

    Returns
    -------
    dict
        ``{RANGE: (lo, hi, what)}``, for ``dataclasses.field(metadata=...)``.
    """
    return {RANGE: (lo, hi, what)}


def _check_range(value: Any, spec: tuple, where: str) -> None:
    """Refuse a number outside its field's :data:`RANGE`, naming the key and the range."""
    lo, hi, what = spec
    if value is None or isinstance(value, bool) or not isinstance(value, numbers.Real):
        return
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        rng = (f"[{lo:g}, {hi:g}]" if lo is not None and hi is not None
               else f">= {lo:g}" if lo is not None else f"<= {hi:g}")
        raise ValueError(f"{where}={value}: out of range; allowed: {rng}"
                         f"{' (' + what + ')' if what else ''}")


def _mapping(cfg: Mapping[str, Any], schema: type, where: str, fill: bool) -> dict:
    fields = _fields(schema)
    ranges = {f.name: f.metadata[RANGE] for f in dataclasses.fields(schema)
              if RANGE in f.metadata}
    pre = f"{where}." if where else ""
    unknown = [k for k in cfg if k not in fields]
    if unknown:
        raise ValueError(f"{pre}{unknown[0]}: unknown key; allowed: {', '.join(fields)}")
    out = {}
    for name, tp in fields.items():
        if name in cfg:
            out[name] = _value(cfg[name], tp, f"{pre}{name}", fill)
            if name in ranges:
                _check_range(out[name], ranges[name], f"{pre}{name}")
        elif fill:
            default = _default(schema, name)
            if isinstance(default, str) and default == MISSING:
                raise ValueError(f"{pre}{name}: missing key")
            out[name] = _value(default, tp, f"{pre}{name}", fill)
        else:
            raise ValueError(f"{pre}{name}: missing key")
    return out


def check_keys(cfg: Mapping[str, Any], schema: type, where: str) -> None:
    """Check a complete mapping against a dataclass schema, recursively.

    Parameters
    ----------
    cfg : mapping
        Config to check, every key of the schema present (e.g. a composed app config).
    schema : dataclass type
        E.g. :class:`DatasetConfig`. Fields typed ``Any`` are not looked into.
    where : str
        Full name of ``cfg`` for messages, e.g. ``"dataset"`` ("" for a root config).

    Raises
    ------
    ValueError
        One line naming the first unknown key (with the allowed ones), missing key,
        value of the wrong type or number outside its field's range (:func:`allowed`), by
        its full name.
    """
    _mapping(cfg, schema, where, fill=False)


def complete(cfg: Mapping[str, Any], schema: type, where: str) -> dict:
    """A checked copy of a mapping with the keys it leaves out taken from the schema.

    Parameters
    ----------
    cfg, schema, where
        As in :func:`check_keys`; keys absent from ``cfg`` (at any depth) take the
        schema's defaults, except mandatory ones.

    Returns
    -------
    dict
        Plain, complete config.

    Raises
    ------
    ValueError
        As :func:`check_keys` (unknown key, mandatory key missing, wrong type).
    """
    return _mapping(cfg, schema, where, fill=True)


def build(value: Any, tp: Any) -> Any:
    """A typed object of schema ``tp`` from a checked plain value (:func:`complete`).

    Dataclasses are built from their mappings, recursively through lists, dicts and
    optional fields; fields typed ``Any`` keep their plain value.
    """
    origin = typing.get_origin(tp)
    if tp is Any or value is None:
        return value
    if origin in (Union, types.UnionType):
        inner = [a for a in typing.get_args(tp) if a is not type(None)]
        return build(value, inner[0])
    if dataclasses.is_dataclass(tp):
        hints = _fields(tp)
        return tp(**{k: build(v, hints[k]) for k, v in value.items()})
    if origin in (list, tuple):
        (item,) = typing.get_args(tp)[:1] or (Any,)
        return [build(v, item) for v in value]
    if origin is dict:
        _, item = typing.get_args(tp)
        return {k: build(v, item) for k, v in value.items()}
    if tp is float:
        return float(value)
    return value


# ------------------------------------------------------------------- finiteness
#: Key of a field's metadata that lets it hold NaN or infinity, with the reason as its value:
#: ``field(default=..., metadata={NONFINITE: "inf: no cut-off"})``. No field of
#: :class:`DatasetConfig` or :class:`~swgsim.life.LifeConfig` sets it.
NONFINITE = "nonfinite"


def _nonfinite(value: Any, where: str) -> Iterator[tuple[str, Any]]:
    """(full key, value) of every NaN or infinity in ``value``, depth first, in field order.

    Dataclasses are walked field by field (a field whose metadata holds :data:`NONFINITE`
    is skipped), mappings by key, lists and tuples by index, arrays element by element;
    integers, booleans, strings and None are finite by nature.
    """
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        for f in dataclasses.fields(value):
            if NONFINITE not in f.metadata:
                yield from _nonfinite(getattr(value, f.name), f"{where}.{f.name}")
    elif isinstance(value, Mapping):
        for k, v in value.items():
            yield from _nonfinite(v, f"{where}.{k}")
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            yield from _nonfinite(v, f"{where}[{i}]")
    elif isinstance(value, np.ndarray):
        if value.dtype.kind in "fc":
            for idx in np.argwhere(~np.isfinite(value)):
                yield f"{where}[{', '.join(str(int(i)) for i in idx)}]", value[tuple(idx)]
        elif value.dtype.kind == "O":
            for idx in np.ndindex(value.shape):
                yield from _nonfinite(value[idx], f"{where}[{', '.join(map(str, idx))}]")
    elif (isinstance(value, numbers.Real) and not isinstance(value, numbers.Integral)
          and not math.isfinite(value)):
        yield where, value


def check_finite(obj: Any, where: str) -> None:
    """Refuse NaN and infinity in any float of a config tree, naming its full key.

    Every float is checked, whatever its key: in nested dataclasses, lists, tuples, dicts
    and arrays, and in fields typed ``Any`` (e.g. ``sensor_effects[i].params``), unless
    the dataclass field declares otherwise in its metadata (:data:`NONFINITE`). A NaN
    can arrive as ``.nan`` in YAML, ``nan`` on the command line or from a program; it is
    refused here, before any range check compares with it.

    Parameters
    ----------
    obj : Any
        The config: a dataclass (e.g. :class:`DatasetConfig`), a mapping, a list, ...
    where : str
        Full name of ``obj`` for the message, e.g. ``"dataset"``.

    Raises
    ------
    ValueError
        One line naming the first non-finite value by its full key, e.g.
        ``dataset.sensors.grid_length_mm must be a finite number, got nan``.
    """
    for key, value in _nonfinite(obj, where):
        raise ValueError(f"{key} must be a finite number, got {value}")


def dataset_config(cfg: Mapping[str, Any] | DatasetConfig | None = None) -> DatasetConfig:
    """A complete, checked, typed data-set config: ``cfg`` over the paper preset's defaults.

    The door of the data-set config: keys and types are checked here (ranges and physics
    in :func:`swgsim.plan.plan`), and what leaves is a :class:`DatasetConfig`.

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
