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
object. Ranges and physical validity live in the parts' ``check`` methods, each part its
own, :meth:`DatasetConfig.check` the rules across parts (the gears' dynamics and the
integrator, the settling time, the gauges on the mesh, a profile within the gears'
limits); :func:`swgsim.base.typed.check_tree` runs them all in one pass, NaN and infinity
refused first, and :func:`swgsim.datasets.plan.plan` runs that pass before it plans.
:func:`gear_params` and :func:`layout_for` give each gear's dynamic parameters and
gauge layout to every part of generation that simulates it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from swgsim.base.typed import LATER, build, check_range, complete
from swgsim.datasets.profile_config import ProfileConfig
from swgsim.datasets.schedule import LifeConfig, duty_cycle
from swgsim.gear import profile as pf
from swgsim.gear import profile_dynamics
from swgsim.gear.chain import ChainSettings
from swgsim.gear.dynamics import J_OUT_BENCH_KGM2, KeHarmonic, gear_with_ke, rt1_size20
from swgsim.gear.faults import FAULTS, ChainParams, get_fault
from swgsim.gear.flexspline import FlexsplineGeometry, Mesh, TrussModel
from swgsim.gear.friction.simulation import FrictionEffectsConfig
from swgsim.gear.modes import linear_eigenvalues, rk4_stable, torsional_mode
from swgsim.gear.sensors import (
    SensorLayout,
    SensorsConfig,
    TolerancesConfig,
    gear_layout,
    signal_rows,
)
from swgsim.sensing.acquisition import Acquisition, Amplifier  # noqa: F401 - a schema part
from swgsim.sensing.disturbance import DisturbanceSpec
from swgsim.sensing.effects import SensorEffectConfig

SETTLE_DECAY_TIMES = 5.0  # transient left in the window: e^-5 = 0.7 % of the start's


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

    def check(self, where: str = "gear") -> None:
        """Refuse an id, seed or factor outside its range or kinematic-error harmonics the
        gear model cannot take, naming ``<where>.<key>``."""
        check_range(self.id, 1, 999, f"{where}.id")
        check_range(self.tolerance_seed, 0, 2**32 - 1, f"{where}.tolerance_seed")
        for k in ("b1_factor", "k1_factor"):
            check_range(getattr(self, k), 0.0, 10.0, f"{where}.{k}", lo_open=True)
        try:
            gear_with_ke(rt1_size20(), self.ke_extra)
        except (TypeError, ValueError) as e:
            raise ValueError(f"{where}.ke_extra: {e}") from None


@dataclass
class VariantSpec:
    """Variants of one class: severities (a list or a linspace) x positions x repeats."""

    severities: list[float] | None = None
    severity_linspace: list[float] | None = None  # [first, last, count]
    repeat: int = 1
    n_positions: int = 1

    def expand(self, name: str) -> list[tuple[float, float]]:
        """(severity, position_deg) of every variant of fault class ``name``, in variant
        order (position NaN for a class without one).

        Raises
        ------
        ValueError
            Unknown fault, severity outside its range (:func:`swgsim.gear.faults.get_fault`),
            or a non-positive count, naming ``dataset.variants.<name>``.
        """
        f, key = get_fault(name), f"dataset.variants.{name}"
        lo, hi = f.severity_range
        lin, given = self.severity_linspace, self.severities
        _req((lin is None) != (given is None), f"{key}: give either severities or "
                                               "severity_linspace [first, last, count]")
        if lin is not None:
            _req(len(lin) == 3, f"{key}.severity_linspace must be [first, last, count], "
                                f"got {lin}")
            a, b, n = lin
            _req(int(n) >= 1 and n == int(n), f"{key}.severity_linspace: count must be an "
                                              f"integer >= 1, got {n}")
            sev = list(np.linspace(float(a), float(b), int(n)))
        else:
            sev = [float(v) for v in given]
            _req(len(sev) >= 1, f"{key}.severities must list at least one severity")
        for v in sev:
            _req(lo <= v <= hi, f"{key}: severity {v} outside the allowed range [{lo}, {hi}]")
        _req(self.repeat >= 1, f"{key}.repeat must be >= 1, got {self.repeat}")
        if f.uses_position:
            n_pos = int(self.n_positions)
            _req(n_pos >= 1, f"{key}.n_positions must be >= 1, got {n_pos}")
            out = [(v, 360.0 * k / n_pos) for v in sev for k in range(n_pos)]
        else:
            out = [(v, float("nan")) for v in sev]
        return [v for v in out for _ in range(int(self.repeat))]


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

    def check(self, where: str = "operating_points") -> None:
        """Refuse an empty or repeating list, a speed outside (0, 6500] rpm or a torque
        outside [0, 107] N m (size 20's catalogue limits), naming ``<where>.<key>``."""
        for key, lo, hi, unit, why in (
                ("n_in_rpm", 0.0, 6500.0, "rpm", "catalogue max input speed of size 20"),
                ("t_out_nm", 0.0, 107.0, "N m", "repeated peak torque of size 20")):
            vals = getattr(self, key)
            _req(len(vals) >= 1 and len(set(vals)) == len(vals),
                 f"{where}.{key} must list one or more distinct values, got {vals}")
            for v in vals:
                check_range(v, lo, hi, f"{where}.{key}", unit, lo_open=key == "n_in_rpm",
                            why=why)


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

    def check(self, where: str = "load") -> None:
        """Refuse an inertia outside [1e-4, 100] kg m², naming ``<where>.j_out_kgm2``."""
        check_range(self.j_out_kgm2, 1e-4, 100.0, f"{where}.j_out_kgm2", "kg m²")


def _paper_gears() -> list[GearConfig]:
    # paper Table IV: b1 and k1 of SWG models 1-3 relative to nominal
    return [GearConfig(1, 1.0, 1.0, 101), GearConfig(2, 1.2, 1.2, 102),
            GearConfig(3, 0.8, 0.8, 103)]


#: Range of the b1 and k1 factors of a drawn gear instance [-]: paper Table IV's three
#: gears span 0.8-1.2 of nominal [src]; drawn uniformly and independently within it
#: [choice: the distribution of a production lot is not given].
POPULATION_FACTORS = (0.8, 1.2)
#: Lowest tolerance seed of a drawn population; the paper's gears use 101-103 [choice].
POPULATION_SEED_BASE = 10_000


def gear_population(n: int, seed: int, factors: tuple[float, float] = POPULATION_FACTORS
                    ) -> list[GearConfig]:
    """``n`` gear instances of one model, as a production lot gives them: each its own
    healthy damping and stiffness (b1 and k1 factors uniform in ``factors``) and its own
    sensor model (gauge placements and gains, the bridges' zero offsets: a tolerance seed
    of its own, drawn with the data set's tolerances, :func:`layout_for`).

    Parameters
    ----------
    n : int
        Instances, in [1, 999] (ids 1..n).
    seed : int
        The population's seed, >= 0: ``default_rng([seed, 0x9EA5])`` draws b1, k1 and
        instance i's tolerance seed ``POPULATION_SEED_BASE + 1000 seed + i`` (distinct from
        the paper's 101-103 and across populations of seeds below 2**22).
    factors : (float, float)
        Range of the b1 and k1 factors, within (0, 10] [-].

    Returns
    -------
    list of GearConfig
        Instance i (id i) with its factors and tolerance seed, in id order; a population of
        ``n`` is the first ``n`` of a larger one of the same seed.

    Raises
    ------
    ValueError
        ``n``, ``seed`` or ``factors`` out of range, naming it.
    """
    check_range(n, 1, 999, "population.n")
    check_range(seed, 0, 2**22 - 1, "population.seed")
    lo, hi = (float(f) for f in factors)
    if not 0.0 < lo <= hi <= 10.0:
        raise ValueError(f"population.factors must be [lo, hi] within (0, 10], got {factors}")
    u = np.random.default_rng([int(seed), 0x9EA5]).uniform(size=(999, 2))[:n]
    b1, k1 = (lo + (hi - lo) * u[:, j] for j in (0, 1))
    return [GearConfig(i + 1, float(b1[i]), float(k1[i]),
                       POPULATION_SEED_BASE + 1000 * int(seed) + i + 1) for i in range(n)]


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
    profile: ProfileConfig | None = field(default=None, metadata={LATER: "profiles"})

    def check(self, where: str = "dataset") -> None:
        """The rules across the data set's parts, run by :func:`swgsim.base.typed.check_tree`
        after every part's own (so each part is valid here): the name and seed, the gears,
        the variants, the contact width on the mesh, the eccentric load share, eq. (10)'s
        lowest sub-harmonic in the window, a profile within the gears' limits, the settling
        time, the integrator's stability, the gauges on the mesh, the bridges' zero offsets
        within the converter's range, a life on a profile and a duty change's factors (one
        per duty point).

        Raises
        ------
        ValueError
            One line naming the key and the allowed range, e.g. ``dataset.chain.substeps=1
            at dataset.chain.sample_rate_hz=10000 Hz: the integrator step ... is too long
            ...; allowed: dataset.chain.substeps >= 3``.
        """
        check_range(self.seed, 0, 2**32 - 1, f"{where}.seed")
        _req(bool(self.name) and "/" not in self.name and self.name not in (".", ".."),
             f"{where}.name must be a non-empty folder name, got {self.name!r}")
        _check_mesh_zones(self)
        _check_window(self)
        _req(len(self.gears) >= 1, f"{where}.gears must list at least one gear")
        ids = [int(g.id) for g in self.gears]
        _req(len(set(ids)) == len(ids), f"{where}.gears: ids must be unique, got {ids}")
        if self.profile is not None:
            _check_profile(self)
        _check_settling(self)
        _check_step(self)
        unknown = set(self.variants) - set(FAULTS)
        _req(not unknown, f"{where}.variants: unknown fault(s) {sorted(unknown)}; allowed: "
                          f"{sorted(FAULTS)}")
        for name, spec in self.variants.items():
            spec.expand(name)
        _check_layout(self)
        _check_zero_offsets(self)
        if self.life is not None:
            _check_life(self, where)


def _check_life(cfg: DatasetConfig, where: str) -> None:
    """A life on a profile (no duty points, payload or duty changes of its own: the profile
    is its duty cycle), and a duty change's factors, one per duty point."""
    life, cond = cfg.life, cfg.life.conditions
    change = None if cond is None else cond.duty_change
    if cfg.profile is not None:
        _req(not life.duty, f"{where}.life.duty must be empty with {where}.profile: "
                            "the profile is the life's duty cycle")
        _req(cond is None or not cond.payload,
             f"{where}.life.conditions.payload: payload changes are for lives at steady "
             f"operating points; on a profile, set {where}.profile.load.gravity.payload_kg")
        _req(change is None, f"{where}.life.conditions.duty_change: duty changes are for "
                             "lives at steady operating points; on a profile, the profile "
                             "is the life's duty cycle")
    elif change is not None:
        ops = cfg.operating_points
        change.factors([d.t_out_nm for d in duty_cycle(life, ops.n_in_rpm, ops.t_out_nm)],
                       f"{where}.life.conditions.duty_change")


def _req(cond: bool, msg: str) -> None:
    if not cond:
        raise ValueError(msg)


def gear_params(cfg: DatasetConfig, gear: GearConfig) -> ChainParams:
    """Healthy ChainParams of one gear (paper Table IV factors on b1 and k1, the data
    set's output inertia, the gear's extra kinematic-error harmonics ``ke_extra``)."""
    p = rt1_size20()
    p = dataclasses.replace(p, b1_nms=p.b1_nms * float(gear.b1_factor),
                            k1_nm_per_rad=p.k1_nm_per_rad * float(gear.k1_factor),
                            j_out_kgm2=float(cfg.load.j_out_kgm2))
    return ChainParams(gear=gear_with_ke(p, gear.ke_extra))


def layout_for(cfg: DatasetConfig, gear: GearConfig) -> SensorLayout:
    """The sensor layout of one gear, with its placement and gain tolerances."""
    return gear_layout(cfg.sensors, cfg.tolerances, gear.tolerance_seed)


# ------------------------------------------------------- rules across the parts
def _max_eccentricity(variants: Mapping[str, VariantSpec]) -> float:
    ecc = variants.get("eccentric_wg")
    if ecc is None:
        return 0.0
    return max([*(ecc.severities or []), *((ecc.severity_linspace or [])[:2]), 0.0])


def _check_mesh_zones(cfg: DatasetConfig) -> None:
    """Each mesh zone at least one node wide, the two 180 deg apart not overlapping, and
    the eccentric load share 1 ± κ e/w0 within [0, 2] for the largest eccentricity."""
    ch = cfg.chain
    check_range(ch.contact_half_width_deg, 360.0 / int(cfg.mesh.n_theta), 90.0,
                "dataset.chain.contact_half_width_deg", "deg", hi_open=True,
                why="at least one node spacing; the two mesh zones 180 deg apart must not overlap")
    e_max = _max_eccentricity(cfg.variants)
    check_range(ch.ecc_load_share, 0.0, 1.0 / e_max if e_max > 0 else 10.0,
                "dataset.chain.ecc_load_share", why="the load share 1 ± κ e/w0 of a mesh zone must "
                "stay in [0, 2] for the largest eccentricity of dataset.variants.eccentric_wg")


def _check_window(cfg: DatasetConfig) -> None:
    """A window holding one period of eq. (10)'s lowest sub-harmonic (order 1/4) at the
    lowest speed (a profile's windows have no eq. (10) twins)."""
    if cfg.disturbance.harmonic_mvv > 0 and cfg.profile is None:
        n_min = min(cfg.operating_points.n_in_rpm)
        rev = cfg.chain.window_s * n_min / 60.0
        need = 4.0 * 60.0 / n_min
        _req(rev >= 4.0 - 1e-9, f"dataset.chain.window_s={cfg.chain.window_s:g} s holds "
             f"{rev:.3g} input revolutions at {n_min:g} rpm, less than one period of "
             f"eq. (10)'s lowest sub-harmonic (order 1/4); allowed: >= {need:.4g} s, or "
             "dataset.disturbance.harmonic_mvv=0")


def _speeds_and_loads(cfg: DatasetConfig) -> tuple[list[float], list[float]]:
    """Input speeds [rpm] and load torques [N m] at which the dynamics are judged: the
    operating points, or a profile's non-zero speeds ``|n|`` at its largest load."""
    if cfg.profile is None:
        ops = cfg.operating_points
        return [float(n) for n in ops.n_in_rpm], [float(t) for t in ops.t_out_nm]
    prof = cfg.profile.to_profile()
    speeds = sorted({abs(float(n)) for n in prof.speed.knots()[1] if n != 0})
    return speeds or [cfg.profile.lowest_cruise_rpm()], [pf.max_load_nm(prof.load)]


def lead_s(cfg: DatasetConfig) -> float:
    """Filter history the amplifier needs before a window [s] (0 without one)."""
    amp, fs = cfg.acquisition.amplifier, cfg.chain.sample_rate_hz
    return 0.0 if amp is None else (amp.lead_samples(fs) + 1) / fs


def _check_profile(cfg: DatasetConfig) -> None:
    """A profile within every gear's limits, stable for RK4 at standstill, windows of at
    least one wave-generator revolution at its lowest cruise speed and inside it."""
    pc, ch = cfg.profile, cfg.chain
    prof = pc.to_profile()
    step = 1.0 / (float(ch.sample_rate_hz) * int(ch.substeps))
    for i, g in enumerate(cfg.gears):
        p = gear_params(cfg, g).gear
        try:
            pf.validate(prof, float(p.j_out_kgm2), float(p.ratio))
        except ValueError as e:
            raise ValueError(pc.message(str(e))) from None
        try:
            profile_dynamics.check_standstill_step([p], prof, step)
        except ValueError as e:
            raise ValueError(f"dataset.chain.substeps={ch.substeps} at dataset.chain."
                             f"sample_rate_hz={ch.sample_rate_hz:g} Hz, dataset.gears[{i}]: "
                             f"{str(e).removeprefix('substeps: ')}") from None
    n_low = pc.lowest_cruise_rpm()
    _req(n_low > 0, "dataset.profile.segments: the profile never turns the input; allowed: "
                    "a move to a non-zero target_rpm")
    rev_s = 60.0 / n_low
    _req(ch.window_s >= rev_s - 1e-12,
         f"dataset.chain.window_s={ch.window_s:g} s is shorter than one wave-generator "
         f"revolution at the profile's lowest cruise speed {n_low:g} rpm; allowed: >= "
         f"{rev_s:.4g} s")
    check_range(pc.start_jitter_s, 0.0, ch.window_s, "dataset.profile.start_jitter_s", "s",
                why="a life's window starts within one window of their slot's")
    pc.window_starts(ch.window_s, ch.settle_s, lead_s(cfg))


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


def _check_settling(cfg: DatasetConfig) -> None:
    """``settle_s`` covering the amplifier's filter history and
    :data:`SETTLE_DECAY_TIMES` decay times of the torsional mode."""
    amp, settle = cfg.acquisition.amplifier, cfg.chain.settle_s
    if amp is not None:
        fs = cfg.chain.sample_rate_hz
        lead = amp.lead_samples(fs) / fs
        _req(settle >= lead, f"dataset.chain.settle_s must be >= {lead:g} s (the amplifier's "
                             f"filter history), got {settle}")
    need = min_settle_s(cfg)
    _req(settle >= need - 1e-12,
         f"dataset.chain.settle_s={settle:g} s is shorter than "
         f"{SETTLE_DECAY_TIMES:g} decay times of the torsional mode with "
         f"dataset.load.j_out_kgm2={cfg.load.j_out_kgm2:g} kg m² (the window would "
         f"still ring from the start); allowed: >= {need:.3g} s")


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


def _check_zero_offsets(cfg: DatasetConfig) -> None:
    """The bridges' zero offsets leave at least half of the converter's input range to
    the signals (an amplifier's range holds the un-nulled bridge and its strain)."""
    amp = cfg.acquisition.amplifier
    if amp is None:
        return
    check_range(cfg.tolerances.zero_offset_mvv, 0.0, amp.range_mvv / 2,
                "dataset.tolerances.zero_offset_mvv", "mV/V",
                why=f"half of the input range ±{amp.range_mvv:.3g} mV/V of "
                    "dataset.acquisition.amplifier, the rest left to the signals")


def paper_config() -> dict:
    """The paper preset as a plain dict (:class:`DatasetConfig` defaults)."""
    return dataclasses.asdict(DatasetConfig())


def dataset_config(cfg: Mapping[str, Any] | DatasetConfig | None = None) -> DatasetConfig:
    """A complete, checked, typed data-set config: ``cfg`` over the paper preset's defaults.

    The door of the data-set config: keys and types are checked here (ranges and physics
    by the parts' ``check`` methods, in :func:`swgsim.base.typed.check_tree`, which
    :func:`swgsim.datasets.plan.plan` runs), and what leaves is a :class:`DatasetConfig`.

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
