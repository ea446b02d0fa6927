"""What a data set holds, decided before any simulation: variants and shards.

:func:`plan` takes a typed :class:`~swgsim.datasets.config.DatasetConfig` (or a mapping, checked
at the door by :func:`swgsim.datasets.config.dataset_config`), has it checked in one pass
(:func:`swgsim.base.typed.check_tree`: every part's ``check``, the data set's rules across
parts last) and returns a :class:`DatasetPlan`: the config, its parsed effects and the
list of shards. One shard holds every window of one gear at one input speed (all
classes, variants and load torques, plus the commissioning reference windows); with a
``profile`` one shard holds every variant of one gear along the profile, cut into windows.
The shard runners and the orchestration (:mod:`swgsim.datasets.generate`) take the plan
and check nothing again.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from swgsim.base.typed import check_tree, without_later_defaults
from swgsim.datasets.config import DatasetConfig, GearConfig, dataset_config, lead_s
from swgsim.datasets.schedule import n_windows
from swgsim.datasets.slots import slots_of
from swgsim.files.digest import config_digest
from swgsim.gear import profile as pf
from swgsim.gear.faults import Fault, get_fault
from swgsim.gear.friction import FrictionEffects, friction_effects_from_config
from swgsim.sensing.effects import SensorEffect, parse_sensor_effects


@dataclass(frozen=True)
class WindowSpec:
    """One window to simulate: gear, class, variant and operating point."""

    gear: int
    fault: str
    variant: int
    severity: float
    position_deg: float
    t_out_nm: float
    reference: bool


@dataclass(frozen=True)
class ShardSpec:
    """One shard: all windows of one gear at one input speed."""

    name: str
    gear: int
    speed_index: int
    n_in_rpm: float
    windows: tuple[WindowSpec, ...]
    n_life_windows: int = 0  # a gear's life (dataset.life): its windows, no WindowSpec
    window_starts_s: tuple[float, ...] = ()  # a profile's cuts (dataset.profile)

    @property
    def n_windows(self) -> int:
        """Windows written: the grid's clean and disturbed twins, the life's, or every
        variant's cuts of a profile."""
        if self.n_life_windows:
            return self.n_life_windows
        if self.window_starts_s:
            return len(self.windows) * len(self.window_starts_s)
        return 2 * len(self.windows)


@dataclass(frozen=True)
class DatasetPlan:
    """A checked data set: its config, what was parsed from it, and its shards.

    Attributes
    ----------
    config : DatasetConfig
        Complete and checked; what is hashed and stored with the data.
    shards : tuple of ShardSpec
    faults : dict of str to Fault
        The fault classes the data set uses, from the registry
        (:func:`swgsim.gear.faults.register_fault`): shards are simulated with these, so a
        class registered by a user needs no registration in the worker processes.
    sensor_effects : tuple of SensorEffect
        The parsed ``sensor_effects`` option.
    friction : FrictionEffects or None
        The parsed ``friction_effects`` option.
    config_hash : str
        :func:`config_hash` of ``config``.
    kind : {"grid", "profile", "life"}
        ``"life"`` (``dataset.life``, at steady points or along a profile), ``"profile"``
        (every variant along ``dataset.profile``) or ``"grid"`` (the variants at steady
        operating points): which shard runner simulates it
        (:data:`swgsim.datasets.generate.RUNNERS`).
    plain : dict
        The config as plain data (:func:`plain_config`; stored in the manifest and the
        shards; read, never changed).
    gears : dict of int to GearConfig
        Each gear's config by its id.
    profile : swgsim.gear.profile.Profile or None
        The checked ``profile`` option.
    """

    config: DatasetConfig
    shards: tuple[ShardSpec, ...]
    faults: dict[str, Fault]
    sensor_effects: tuple[SensorEffect, ...]
    friction: FrictionEffects | None
    config_hash: str
    kind: str
    plain: dict[str, Any]
    gears: dict[int, GearConfig]
    profile: pf.Profile | None = None


def plain_config(cfg: DatasetConfig | Mapping[str, Any]) -> dict[str, Any]:
    """A data-set config as plain data, without the options added after data sets were made
    (fields marked :data:`swgsim.base.typed.LATER`: a profile, the real day, a run to
    failure, re-greasing, drawn friction laws, ...) that hold their defaults, so that a data
    set keeps the config (and :func:`config_hash`) it had before these options
    (:func:`swgsim.base.typed.without_later_defaults`)."""
    out = dict(dataclasses.asdict(cfg) if isinstance(cfg, DatasetConfig) else cfg)
    return without_later_defaults(out, DatasetConfig)


def config_hash(cfg: DatasetConfig | Mapping[str, Any]) -> str:
    """SHA-256 of the canonical JSON of a data-set config (first 16 hex digits), of
    :func:`plain_config`."""
    return config_digest(plain_config(cfg))


def _profile_shards(cfg: DatasetConfig, variants: dict[str, list[tuple[float, float]]],
                    starts: tuple[float, ...]) -> tuple[ShardSpec, ...]:
    """One shard per gear: every variant (and a healthy reference) along the profile."""
    shards = []
    for g in cfg.gears:
        gid = int(g.id)
        wins = [WindowSpec(gid, fault, vi, sev, pos, float("nan"), False)
                for fault, vl in variants.items() for vi, (sev, pos) in enumerate(vl)]
        wins.append(WindowSpec(gid, "healthy", -1, 0.0, float("nan"), float("nan"), True))
        shards.append(ShardSpec(f"gear{gid}_profile.nc", gid, 0, float("nan"), tuple(wins),
                                window_starts_s=starts))
    return tuple(shards)


# ------------------------------------------------------------------------ the plan
def _shards(cfg: DatasetConfig, variants: dict[str, list[tuple[float, float]]]
            ) -> tuple[ShardSpec, ...]:
    ops = cfg.operating_points
    shards = []
    for g in cfg.gears:
        gid = int(g.id)
        for si, n in enumerate(ops.n_in_rpm):
            wins = [WindowSpec(gid, fault, vi, sev, pos, float(t), False)
                    for fault, vl in variants.items()
                    for vi, (sev, pos) in enumerate(vl)
                    for t in ops.t_out_nm]
            wins += [WindowSpec(gid, "healthy", -1, 0.0, float("nan"), float(t), True)
                     for t in ops.t_out_nm]
            shards.append(ShardSpec(f"gear{gid}_n{int(round(n))}rpm.nc", gid, si, float(n),
                                    tuple(wins)))
    return tuple(shards)


def plan(cfg: DatasetConfig | Mapping[str, Any] | DatasetPlan) -> DatasetPlan:
    """Check a data-set config and list its shards, before any simulation.

    Parameters
    ----------
    cfg : DatasetConfig, mapping or DatasetPlan
        A mapping is checked for keys and types first, at the door
        (:func:`swgsim.datasets.config.dataset_config`); a typed config (e.g. composed by Hydra
        from the schema, which checked its keys and types) is taken as it is; a plan is
        returned as it is.

    Returns
    -------
    DatasetPlan

    Raises
    ------
    ValueError
        From :func:`swgsim.base.typed.check_tree`, with the parameter's name: NaN or
        infinity in any float (checked first, for every key); then with the allowed range
        (each part's ``check``, :meth:`~swgsim.datasets.config.DatasetConfig.check`): unknown
        fault, severity outside its range, non-positive speed, negative torque or variant
        count, a gauge off the collar, a truss too coarse for the gauge layout, bad chain
        settings; with a profile (``dataset.profile``): a profile beyond the gear's limits
        (:func:`swgsim.gear.profile.validate`), an RK4 step unstable at standstill, a window
        shorter than one wave-generator revolution at the lowest cruise speed, or windows
        outside the profile.
    """
    if isinstance(cfg, DatasetPlan):
        return cfg
    if not isinstance(cfg, DatasetConfig):
        cfg = dataset_config(cfg)
    check_tree(cfg, "dataset")  # every part's rules, then the data set's (DatasetConfig.check)
    prof, starts = None, ()
    if cfg.profile is not None:
        prof = cfg.profile.to_profile()
        starts = cfg.profile.window_starts(cfg.chain.window_s, cfg.chain.settle_s, lead_s(cfg))
    variants = {name: spec.expand(name) for name, spec in cfg.variants.items()}
    faults = {name: get_fault(name) for name in ("healthy", *variants)}
    if cfg.life is not None:
        shards = _life_shards(cfg, prof, starts)
    elif cfg.profile is not None:
        shards = _profile_shards(cfg, variants, starts)
    else:
        shards = _shards(cfg, variants)
    plain = plain_config(cfg)
    kind = "life" if cfg.life is not None else "profile" if prof is not None else "grid"
    return DatasetPlan(cfg, shards, faults, tuple(parse_sensor_effects(cfg.sensor_effects)),
                       friction_effects_from_config(cfg.friction_effects),
                       config_digest(plain), kind, plain, {int(g.id): g for g in cfg.gears},
                       prof)


def _life_shards(cfg: DatasetConfig, prof, starts: tuple[float, ...]) -> tuple[ShardSpec, ...]:
    """One shard per gear holding its life; on a profile (the duty cycle is the profile,
    swgsim.datasets.slots) with the profile's window starts, and no duty points of its own."""
    if prof is not None:
        slots_of(cfg, prof, starts)  # refused here if no window of the profile turns enough
    n = n_windows(cfg.life)  # arithmetic: nothing per window is built before the disk check
    return tuple(ShardSpec(f"gear{int(g.id)}_life.nc", int(g.id), 0, float("nan"), (), n,
                           starts) for g in cfg.gears)


__all__ = ["DatasetPlan", "ShardSpec", "WindowSpec", "config_hash", "plain_config", "plan"]
