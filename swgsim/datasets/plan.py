"""What a data set holds, decided before any simulation: checks, variants and shards.

:func:`plan` takes a typed :class:`~swgsim.datasets.config.DatasetConfig` (or a mapping, checked
at the door by :func:`swgsim.datasets.config.dataset_config`), checks every range and physical
limit once, and returns a :class:`DatasetPlan`: the config, its parsed effects and the
list of shards. One shard holds every window of one gear at one input speed (all
classes, variants and load torques, plus the commissioning reference windows); with a
``profile`` one shard holds every variant of one gear along the profile, cut into windows.
The shard runners and the orchestration (:mod:`swgsim.datasets.generate`) take the plan
and check nothing again.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from swgsim.base.typed import check_finite, check_range
from swgsim.datasets.conditions import ConditionsConfig, TemperatureTrace
from swgsim.datasets.config import (
    DatasetConfig,
    GearConfig,
    ProfileConfig,
    VariantSpec,
    dataset_config,
)
from swgsim.datasets.gears import gear_params, layout_for
from swgsim.datasets.schedule import FaultOnset, check_life, n_windows
from swgsim.datasets.slots import slots_of
from swgsim.files.digest import config_digest
from swgsim.gear import profile as pf
from swgsim.gear import profile_dynamics
from swgsim.gear.dynamics import gear_with_ke, rt1_size20
from swgsim.gear.faults import FAULTS, Fault, get_fault
from swgsim.gear.flexspline import FlexsplineGeometry, TrussModel
from swgsim.gear.friction import FrictionEffects, friction_effects_from_config
from swgsim.gear.modes import linear_eigenvalues, rk4_stable, torsional_mode
from swgsim.gear.sensors import signal_rows
from swgsim.sensing.acquisition import check_acquisition
from swgsim.sensing.angles import check_channels
from swgsim.sensing.bridge_drift import TemperatureSensor
from swgsim.sensing.effects import SensorEffect, parse_sensor_effects

MIN_GRID_LENGTH_MM = 0.2  # shortest foil strain-gauge grids on the market (0.2 mm)
SETTLE_DECAY_TIMES = 5.0  # transient left in the window: e^-5 = 0.7 % of the start's


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
    profile : swgsim.gear.profile.Profile or None
        The checked ``profile`` option.
    """

    config: DatasetConfig
    shards: tuple[ShardSpec, ...]
    faults: dict[str, Fault]
    sensor_effects: tuple[SensorEffect, ...]
    friction: FrictionEffects | None
    config_hash: str
    profile: pf.Profile | None = None

    @property
    def kind(self) -> str:
        """``"life"`` (``dataset.life``, at steady points or along a profile),
        ``"profile"`` (every variant along ``dataset.profile``) or ``"grid"`` (the
        variants at steady operating points): which shard runner simulates it
        (:data:`swgsim.datasets.generate.RUNNERS`)."""
        if self.config.life is not None:
            return "life"
        return "profile" if self.profile is not None else "grid"

    def gear(self, gear_id: int) -> GearConfig:
        """The config of the gear with this id."""
        return next(g for g in self.config.gears if int(g.id) == int(gear_id))

    def as_dict(self) -> dict[str, Any]:
        """The config as plain data (stored in the manifest and the shards)."""
        return plain_config(self.config)


#: Fields added to ``life.conditions`` (:class:`ConditionsConfig`) and to its
#: ``temperature_sensor`` (:class:`TemperatureSensor`) after data sets were made: where one
#: holds its default, :func:`plain_config` leaves it out.
LATER_CONDITIONS = ("friction_law", "regrease", "temperature_trace")
LATER_SENSOR = ("fault", "fault_hour", "drift_k_per_h")
LATER_FAULT = ("to_failure",)  # life.fault (:class:`FaultOnset`)
LATER_TRACE = ("mode",)  # life.conditions.temperature_trace (:class:`TemperatureTrace`)


def _without_defaults(d: dict, schema: type, names: tuple[str, ...]) -> dict:
    """``d`` without the fields ``names`` that hold the schema's defaults (read from its
    fields: a schema with required fields, such as :class:`TemperatureTrace`, works too)."""
    ref = {}
    for f in dataclasses.fields(schema):
        v = f.default_factory() if f.default_factory is not dataclasses.MISSING else f.default
        ref[f.name] = dataclasses.asdict(v) if dataclasses.is_dataclass(v) else v
    return {k: v for k, v in d.items() if not (k in names and v == ref[k])}


def plain_config(cfg: DatasetConfig | Mapping[str, Any]) -> dict[str, Any]:
    """A data-set config as plain data, without ``profile``, ``life.conditions`` and
    ``life.fault.to_failure`` when they are None and without the fields of
    :data:`LATER_CONDITIONS`, :data:`LATER_SENSOR` and :data:`LATER_TRACE` (the friction
    law, re-greasing, a temperature trace, the sensor's fault, the trace's mode) that hold
    their defaults, so that a data set
    keeps the config (and :func:`config_hash`) it had before these options."""
    out = dict(dataclasses.asdict(cfg) if isinstance(cfg, DatasetConfig) else cfg)
    if "profile" in out and out["profile"] is None:
        del out["profile"]
    life = out.get("life")
    if isinstance(life, dict) and "conditions" in life and life["conditions"] is None:
        out["life"] = {k: v for k, v in life.items() if k != "conditions"}
    fault = life.get("fault") if isinstance(life, dict) else None
    if isinstance(fault, dict):  # a fault not run to failure: as before the option
        out["life"] = {**out["life"], "fault": _without_defaults(fault, FaultOnset, LATER_FAULT)}
    cond = (out.get("life") or {}).get("conditions") if isinstance(out.get("life"), dict) \
        else None
    if isinstance(cond, dict):
        cond = _without_defaults(cond, ConditionsConfig, LATER_CONDITIONS)
        if isinstance(cond.get("temperature_sensor"), dict):
            cond["temperature_sensor"] = _without_defaults(cond["temperature_sensor"],
                                                           TemperatureSensor, LATER_SENSOR)
        if isinstance(cond.get("temperature_trace"), dict):
            cond["temperature_trace"] = _without_defaults(cond["temperature_trace"],
                                                          TemperatureTrace, LATER_TRACE)
        out["life"] = {**out["life"], "conditions": cond}
    return out


def config_hash(cfg: DatasetConfig | Mapping[str, Any]) -> str:
    """SHA-256 of the canonical JSON of a data-set config (first 16 hex digits), of
    :func:`plain_config`."""
    return config_digest(plain_config(cfg))


# ------------------------------------------------------------------------- checks
def _req(cond: bool, msg: str) -> None:
    if not cond:
        raise ValueError(msg)


def _check_name_and_points(cfg: DatasetConfig) -> None:
    check_range(cfg.seed, 0, 2**32 - 1, "dataset.seed")
    _req(bool(cfg.name) and "/" not in cfg.name and cfg.name not in (".", ".."),
         f"dataset.name must be a non-empty folder name, got {cfg.name!r}")
    for key, lo, hi, unit, why in (
            ("n_in_rpm", 0.0, 6500.0, "rpm", "catalogue max input speed of size 20"),
            ("t_out_nm", 0.0, 107.0, "N m", "repeated peak torque of size 20")):
        vals = getattr(cfg.operating_points, key)
        _req(len(vals) >= 1 and len(set(vals)) == len(vals),
             f"dataset.operating_points.{key} must list one or more distinct values, "
             f"got {vals}")
        for v in vals:
            check_range(v, lo, hi, f"dataset.operating_points.{key}", unit,
                        lo_open=key == "n_in_rpm", why=why)


def _max_eccentricity(variants: Mapping[str, VariantSpec]) -> float:
    ecc = variants.get("eccentric_wg")
    if ecc is None:
        return 0.0
    return max([*(ecc.severities or []), *((ecc.severity_linspace or [])[:2]), 0.0])


def _check_chain(cfg: DatasetConfig) -> None:
    n_theta = int(cfg.mesh.n_theta)
    _req(n_theta % 20 == 0 and 20 <= n_theta <= 2000, "dataset.mesh.n_theta must be a "
         f"multiple of 20 in [20, 2000], got {cfg.mesh.n_theta}")
    ch = cfg.chain
    check_range(ch.sample_rate_hz, 0.0, 1e6, "dataset.chain.sample_rate_hz", "Hz", lo_open=True)
    check_range(ch.window_s, 0.0, 10.0, "dataset.chain.window_s", "s", lo_open=True)
    check_range(ch.settle_s, 0.0, 10.0, "dataset.chain.settle_s", "s")
    check_range(ch.substeps, 1, 100, "dataset.chain.substeps")
    check_range(ch.contact_half_width_deg, 360.0 / n_theta, 90.0,
                "dataset.chain.contact_half_width_deg", "deg", hi_open=True,
                why="at least one node spacing; the two mesh zones 180 deg apart must not overlap")
    e_max = _max_eccentricity(cfg.variants)
    check_range(ch.ecc_load_share, 0.0, 1.0 / e_max if e_max > 0 else 10.0,
                "dataset.chain.ecc_load_share", why="the load share 1 ± κ e/w0 of a mesh zone must "
                "stay in [0, 2] for the largest eccentricity of dataset.variants.eccentric_wg")
    check_range(cfg.load.j_out_kgm2, 1e-4, 100.0, "dataset.load.j_out_kgm2", "kg m²")


def _check_tolerances_and_disturbance(cfg: DatasetConfig) -> None:
    for key, hi, unit in (("sd_theta_deg", 5.0, "deg"), ("sd_r_mm", 2.0, "mm"),
                          ("sd_beta_deg", 10.0, "deg"), ("sd_gain", 0.2, "")):
        check_range(getattr(cfg.tolerances, key), 0.0, hi, f"dataset.tolerances.{key}", unit)
    for key in ("offset_mvv", "harmonic_mvv"):
        check_range(getattr(cfg.disturbance, key), 0.0, 1.0, f"dataset.disturbance.{key}", "mV/V")
    # eq. (10): sub-harmonics down to order 1/4 (a profile's windows have no eq. (10) twins)
    if cfg.disturbance.harmonic_mvv > 0 and cfg.profile is None:
        n_min = min(cfg.operating_points.n_in_rpm)
        rev = cfg.chain.window_s * n_min / 60.0
        need = 4.0 * 60.0 / n_min
        _req(rev >= 4.0 - 1e-9, f"dataset.chain.window_s={cfg.chain.window_s:g} s holds "
             f"{rev:.3g} input revolutions at {n_min:g} rpm, less than one period of "
             f"eq. (10)'s lowest sub-harmonic (order 1/4); allowed: >= {need:.4g} s, or "
             "dataset.disturbance.harmonic_mvv=0")


def _check_gears(cfg: DatasetConfig) -> None:
    _req(len(cfg.gears) >= 1, "dataset.gears must list at least one gear")
    ids = [int(g.id) for g in cfg.gears]
    _req(len(set(ids)) == len(ids), f"dataset.gears: ids must be unique, got {ids}")
    for i, g in enumerate(cfg.gears):
        check_range(g.id, 1, 999, f"dataset.gears[{i}].id")
        check_range(g.tolerance_seed, 0, 2**32 - 1, f"dataset.gears[{i}].tolerance_seed")
        for k in ("b1_factor", "k1_factor"):
            check_range(getattr(g, k), 0.0, 10.0, f"dataset.gears[{i}].{k}", lo_open=True)
        try:
            gear_with_ke(rt1_size20(), g.ke_extra)
        except (TypeError, ValueError) as e:
            raise ValueError(f"dataset.gears[{i}].ke_extra: {e}") from None


def _speeds_and_loads(cfg: DatasetConfig) -> tuple[list[float], list[float]]:
    """Input speeds [rpm] and load torques [N m] at which the dynamics are judged: the
    operating points, or a profile's non-zero speeds ``|n|`` at its largest load."""
    if cfg.profile is None:
        ops = cfg.operating_points
        return [float(n) for n in ops.n_in_rpm], [float(t) for t in ops.t_out_nm]
    prof = cfg.profile.to_profile()
    speeds = sorted({abs(float(n)) for n in prof.speed.knots()[1] if n != 0})
    return speeds or [lowest_cruise_rpm(cfg.profile)], [pf.max_load_nm(prof.load)]


def lowest_cruise_rpm(profile: ProfileConfig) -> float:
    """Lowest non-zero ``|speed|`` the profile holds [rpm]: of its holds at a non-zero speed,
    else of its non-zero corner speeds; 0 for a profile that never turns."""
    tk, nk = profile.to_profile().speed.knots()
    held = [abs(nk[i]) for i in range(1, tk.size) if nk[i] == nk[i - 1] and nk[i] != 0
            and tk[i] > tk[i - 1]]
    moving = [abs(n) for n in nk if n != 0]
    return float(min(held or moving or [0.0]))


def _check_step(cfg: DatasetConfig) -> None:
    """The integrator step 1 / (sample_rate_hz · substeps) stable for every gear's
    linearised dynamics at every operating point (explicit RK4 diverges beyond it)."""
    ch = cfg.chain
    fs, k = float(ch.sample_rate_hz), int(ch.substeps)
    speeds, loads = _speeds_and_loads(cfg)
    for i, g in enumerate(cfg.gears):
        p = gear_params(cfg, g).gear
        for n in speeds:
            for t in loads:
                lam = linear_eigenvalues(p, float(n), float(t))
                if rk4_stable(lam, 1.0 / (fs * k)):
                    continue
                need = next((m for m in range(k + 1, 101) if rk4_stable(lam, 1.0 / (fs * m))),
                            None)
                allowed = (f"allowed: dataset.chain.substeps >= {need}" if need is not None
                           else "allowed: a higher dataset.chain.sample_rate_hz")
                raise ValueError(
                    f"dataset.chain.substeps={k} at dataset.chain.sample_rate_hz={fs:g} Hz: "
                    f"the integrator step {1e3 / (fs * k):.3g} ms is too long for the "
                    f"dynamics of dataset.gears[{i}] (id {int(g.id)}) with "
                    f"dataset.load.j_out_kgm2={cfg.load.j_out_kgm2:g} kg m² at {n:g} rpm, "
                    f"{t:g} N m (fastest mode {np.max(np.abs(lam)):.3g} 1/s; the "
                    f"simulation would diverge); {allowed}")


def _check_acquisition(cfg: DatasetConfig) -> None:
    acq = check_acquisition(cfg.acquisition)
    if acq.amplifier is not None:
        fs = cfg.chain.sample_rate_hz
        lead_s = acq.amplifier.lead_samples(fs) / fs
        _req(cfg.chain.settle_s >= lead_s, f"dataset.chain.settle_s must be >= {lead_s:g} s "
                                           "(the amplifier's filter history), got "
                                           f"{cfg.chain.settle_s}")
    need = min_settle_s(cfg)
    _req(cfg.chain.settle_s >= need - 1e-12,
         f"dataset.chain.settle_s={cfg.chain.settle_s:g} s is shorter than "
         f"{SETTLE_DECAY_TIMES:g} decay times of the torsional mode with "
         f"dataset.load.j_out_kgm2={cfg.load.j_out_kgm2:g} kg m² (the window would "
         f"still ring from the start); allowed: >= {need:.3g} s")


def _check_sensors(cfg: DatasetConfig) -> None:
    """The gauge layout's own ranges, before the mesh resolves it (:func:`_check_layout`):
    radii inside the collar's clamped edge, a grid from :data:`MIN_GRID_LENGTH_MM` up to the
    collar's radial extent, a gauge factor of foil (about 2) up to semiconductor gauges
    (about 150; Hoffmann, *An Introduction to Measurements using Strain Gages*, HBM 1989,
    sec. 2)."""
    geo = FlexsplineGeometry()
    s, r_c = cfg.sensors, geo.r_collar_m * 1e3
    check_range(s.r_torque_mm, 0.0, r_c, "dataset.sensors.r_torque_mm", "mm", lo_open=True,
                why="inside the collar's clamped edge")
    check_range(s.r_pairs_mm, 0.0, r_c, "dataset.sensors.r_pairs_mm", "mm", lo_open=True,
                why="inside the collar's clamped edge")
    # no mesh resolves a grid shorter than the shortest foil grids sold (0.2 mm) or lays
    # one longer than the collar's radial extent (sleeve to clamped edge): the grid's own
    # range, so that the mesh (dataset.mesh.n_theta) is not blamed for it
    check_range(s.grid_length_mm, MIN_GRID_LENGTH_MM, r_c - geo.r_mid_m * 1e3,
                "dataset.sensors.grid_length_mm", "mm",
                why="foil grids from 0.2 mm, no longer than the collar's radial extent")
    check_range(s.gauge_factor, 0.0, 200.0, "dataset.sensors.gauge_factor", lo_open=True,
                why="foil gauges about 2, semiconductor gauges up to about 150")


def _check_layout(cfg: DatasetConfig) -> None:
    """Every gear's gauges on the collar and resolved by the mesh (geometry only, no
    factorisation)."""
    model = TrussModel(FlexsplineGeometry(), cfg.mesh)
    for g in cfg.gears:
        try:
            signal_rows(model, layout_for(cfg, g))
        except ValueError as e:
            key = ("dataset.mesh.n_theta" if "too coarse" in str(e)
                   else "dataset.sensors (r_torque_mm, r_pairs_mm, grid_length_mm)")
            raise ValueError(f"{key}: {e}") from None


def _profile_key(msg: str, profile: ProfileConfig) -> str:
    """A message of :func:`swgsim.gear.profile.validate` with its keys as ``dataset.profile``'s."""
    p = "dataset.profile"
    msg = re.sub(r"\bspeed\.segments\[(\d+)\]\.(target_rpm|accel_rpm_s)",
                 rf"{p}.segments[\1].move.\2", msg)
    msg = re.sub(r"\bspeed\.segments\[(\d+)\]\.duration_s", rf"{p}.segments[\1].hold.duration_s",
                 msg)
    msg = re.sub(r"\bspeed\.segments\b", f"{p}.segments", msg)
    msg = re.sub(r"\bspeed\.start_rpm", f"{p}.start_rpm", msg)
    return re.sub(r"\bload([.:])", rf"{p}.load.{profile.load_kind()}\1", msg)


#: Longest profile [s]: a joint's cycle lasts seconds to minutes, and a profile is
#: integrated and held in memory whole (10 minutes at 10 kHz is 6 million samples).
MAX_PROFILE_S = 600.0


def _check_profile(cfg: DatasetConfig) -> tuple[pf.Profile, tuple[float, ...]]:
    """A profile within the gear's limits and stable for RK4 at standstill, and its
    window starts [s]; before any work."""
    pc, ch = cfg.profile, cfg.chain
    check_channels(pc.angles.input_counts_per_rev, pc.angles.output_encoder_bits)
    prof = pc.to_profile()
    dur = prof.speed.duration_s
    _req(dur <= MAX_PROFILE_S, f"dataset.profile.segments last {dur:.4g} s; allowed: at most "
                               f"{MAX_PROFILE_S:g} s (one cycle of a joint, integrated in "
                               "memory)")
    step = 1.0 / (float(ch.sample_rate_hz) * int(ch.substeps))
    for i, g in enumerate(cfg.gears):
        p = gear_params(cfg, g).gear
        try:
            pf.validate(prof, float(p.j_out_kgm2), float(p.ratio))
        except ValueError as e:
            raise ValueError(_profile_key(str(e), pc)) from None
        try:
            profile_dynamics.check_standstill_step([p], prof, step)
        except ValueError as e:
            raise ValueError(f"dataset.chain.substeps={ch.substeps} at dataset.chain."
                             f"sample_rate_hz={ch.sample_rate_hz:g} Hz, dataset.gears[{i}]: "
                             f"{str(e).removeprefix('substeps: ')}") from None
    n_low = lowest_cruise_rpm(pc)
    _req(n_low > 0, "dataset.profile.segments: the profile never turns the input; allowed: "
                    "a move to a non-zero target_rpm")
    rev_s = 60.0 / n_low
    _req(ch.window_s >= rev_s - 1e-12,
         f"dataset.chain.window_s={ch.window_s:g} s is shorter than one wave-generator "
         f"revolution at the profile's lowest cruise speed {n_low:g} rpm; allowed: >= "
         f"{rev_s:.4g} s")
    check_range(pc.start_jitter_s, 0.0, ch.window_s, "dataset.profile.start_jitter_s", "s",
                why="a life's window starts within one window of their slot's")
    amp = cfg.acquisition.amplifier
    lead_s = 0.0 if amp is None else (amp.lead_samples(ch.sample_rate_hz) + 1) / ch.sample_rate_hz
    if pc.window_starts_s is None:
        n = int(np.floor((dur - lead_s - ch.settle_s) / ch.window_s + 1e-9))
        _req(n >= 1, f"dataset.chain.window_s={ch.window_s:g} s: no window fits the profile "
                     f"of {dur:g} s after dataset.chain.settle_s={ch.settle_s:g} s; allowed: "
                     f"<= {dur - lead_s - ch.settle_s:.4g} s")
        starts = tuple(round(float(ch.settle_s + k * ch.window_s), 12) for k in range(n))
    else:
        starts = tuple(float(t) for t in pc.window_starts_s)
        _req(len(starts) >= 1, "dataset.profile.window_starts_s must list at least one start")
        for i, t in enumerate(starts):
            check_range(t, lead_s, dur - ch.window_s - lead_s,
                        f"dataset.profile.window_starts_s[{i}]", "s",
                        why="the window inside the profile, with the amplifier's history")
    return prof, starts


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
def variant_list(name: str, spec: VariantSpec) -> list[tuple[float, float]]:
    """(severity, position_deg) of every variant of a class, in variant order.

    Raises
    ------
    ValueError
        Unknown fault, severity outside its range, or a non-positive variant count.
    """
    f = get_fault(name)
    lo, hi = f.severity_range
    lin, given = spec.severity_linspace, spec.severities
    _req((lin is None) != (given is None), f"dataset.variants.{name}: give either severities "
                                           "or severity_linspace [first, last, count]")
    if lin is not None:
        _req(len(lin) == 3, f"dataset.variants.{name}.severity_linspace must be [first, last, "
                            f"count], got {lin}")
        a, b, n = lin
        _req(int(n) >= 1 and n == int(n), f"dataset.variants.{name}.severity_linspace: count "
                                          f"must be an integer >= 1, got {n}")
        sev = list(np.linspace(float(a), float(b), int(n)))
    else:
        sev = [float(s) for s in given]
        _req(len(sev) >= 1, f"dataset.variants.{name}.severities must list at least one "
                            "severity")
    for s in sev:
        _req(lo <= s <= hi, f"dataset.variants.{name}: severity {s} outside the allowed "
                            f"range [{lo}, {hi}]")
    _req(spec.repeat >= 1, f"dataset.variants.{name}.repeat must be >= 1, got {spec.repeat}")
    if f.uses_position:
        n_pos = int(spec.n_positions)
        _req(n_pos >= 1, f"dataset.variants.{name}.n_positions must be >= 1, got {n_pos}")
        pos = [360.0 * k / n_pos for k in range(n_pos)]
        out = [(s, p) for s in sev for p in pos]
    else:
        out = [(s, float("nan")) for s in sev]
    return [v for v in out for _ in range(int(spec.repeat))]


def _variants(cfg: DatasetConfig) -> dict[str, list[tuple[float, float]]]:
    unknown = set(cfg.variants) - set(FAULTS)
    _req(not unknown, f"dataset.variants: unknown fault(s) {sorted(unknown)}; allowed: "
                      f"{sorted(FAULTS)}")
    return {name: variant_list(name, spec) for name, spec in cfg.variants.items()}


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
        With the parameter's name: NaN or infinity in any float (checked first, for every
        key, :func:`swgsim.base.typed.check_finite`); then with the allowed range: unknown
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
    check_finite(cfg, "dataset")  # before any range check compares with a NaN
    _check_name_and_points(cfg)
    _check_chain(cfg)
    _check_tolerances_and_disturbance(cfg)
    _check_gears(cfg)
    prof, starts = _check_profile(cfg) if cfg.profile is not None else (None, ())
    _check_acquisition(cfg)
    _check_step(cfg)
    _check_sensors(cfg)
    effects = tuple(parse_sensor_effects(cfg.sensor_effects))
    friction = friction_effects_from_config(cfg.friction_effects)
    variants = _variants(cfg)
    _check_layout(cfg)
    faults = {name: get_fault(name) for name in ("healthy", *variants)}
    if cfg.life is not None:
        shards = _life_shards(cfg, prof, starts)
    elif cfg.profile is not None:
        shards = _profile_shards(cfg, variants, starts)
    else:
        shards = _shards(cfg, variants)
    return DatasetPlan(cfg, shards, faults, effects, friction, config_hash(cfg), prof)


def _life_shards(cfg: DatasetConfig, prof, starts: tuple[float, ...]) -> tuple[ShardSpec, ...]:
    """One shard per gear holding its life; on a profile (the duty cycle is the profile,
    swgsim.datasets.slots) with the profile's window starts, and no duty points of its own."""
    check_life(cfg.life)
    life = cfg.life
    if prof is not None:
        _req(not life.duty, "dataset.life.duty must be empty with dataset.profile: the "
                            "profile is the life's duty cycle")
        _req(life.conditions is None or not life.conditions.payload,
             "dataset.life.conditions.payload: payload changes are for lives at steady "
             "operating points; on a profile, set dataset.profile.load.gravity.payload_kg")
        slots_of(cfg, prof, starts)  # refused here if no window of the profile turns enough
    n = n_windows(life)  # arithmetic: nothing per window is built before the disk check
    return tuple(ShardSpec(f"gear{int(g.id)}_life.nc", int(g.id), 0, float("nan"), (), n,
                           starts) for g in cfg.gears)


def min_settle_s(cfg: DatasetConfig) -> float:
    """Shortest ``chain.settle_s`` that lets the torsional mode ring down before the window.

    :data:`SETTLE_DECAY_TIMES` times the longest decay time
    (:func:`swgsim.gear.modes.torsional_mode`) over the data set's gears and
    operating points [s].
    """
    speeds, loads = _speeds_and_loads(cfg)
    decay = []
    for i, g in enumerate(cfg.gears):
        for n in speeds:
            for t in loads:
                try:
                    decay.append(torsional_mode(gear_params(cfg, g).gear, float(n),
                                                float(t))[1])
                except ValueError as e:
                    raise ValueError(
                        f"dataset.load.j_out_kgm2={cfg.load.j_out_kgm2:g} kg m² with "
                        f"dataset.gears[{i}] (b1_factor={g.b1_factor:g}, k1_factor="
                        f"{g.k1_factor:g}): {e}; the window's settling time cannot be "
                        "judged") from None
    return SETTLE_DECAY_TIMES * max(decay)


__all__ = ["DatasetPlan", "ShardSpec", "WindowSpec", "SETTLE_DECAY_TIMES",
           "config_hash", "lowest_cruise_rpm", "plain_config", "min_settle_s", "plan",
           "variant_list"]
