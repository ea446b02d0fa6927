"""A healthy joint's changing day: temperature, run-in, payload, duty and the bridges' drift.

``dataset.life.conditions`` (:class:`ConditionsConfig`; None, the default: nothing changes
but the fault) gives a life what a real joint lives through while its gear stays healthy,
each with a sourced magnitude (:mod:`swgsim.gear.thermal`, :mod:`swgsim.sensing.bridge_drift`):
the joint's temperature (modelled, or measured: :class:`TemperatureTrace`), the friction's
temperature law, run-in and re-greasing, the payload, a new program's dwells
(:class:`DutyChange`, acting in :func:`swgsim.datasets.schedule.schedule`), the bridges'
drift and the temperature sensor; :func:`window_conditions` gives each window its own. What
changes, how, what stays, the random streams: docs/DATASET.md, "Gear lives", *A life
through a real day*.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from swgsim.base.typed import LATER, allowed, check_range
from swgsim.files.inputs import check_text_file
from swgsim.gear.dynamics import RPM
from swgsim.gear.faults import ChainParams
from swgsim.gear.thermal import (
    REF_TEMP_C,
    REGREASE_DROP,
    REGREASE_TAU_H,
    RUN_IN_DROP,
    RUN_IN_TAU_H,
    TEMP_RANGE_C,
    FrictionLaw,
    JointThermal,
    joint_temperature,
    loss_power_w,
    network_temperatures,
    regrease_factor,
    run_in_factor,
    steady_efficiency,
    traced_temperature,
    wall_clock_h,
)
from swgsim.sensing.bridge_drift import (
    BridgeDrift,
    TemperatureSensor,
    bridge_temperatures,
    draw_bridge_drift,
    measure_temperature,
)

__all__ = ["DWELL_FACTOR_RANGE", "HOURS_TABLE_COLUMNS", "LOAD_SHIFT_BASE", "TRACE_MODES",
           "ConditionsConfig", "DutyChange", "Regrease", "RunInConfig", "TemperatureTrace",
           "WindowConditions", "efficiency_ratio", "trace_rise", "trace_table",
           "window_conditions"]

#: A step of a temperature trace longer than this ends its first continuous segment [min]
#: [choice: beyond a logger's hiccups (the UR3 CobotOps day has steps of 9 and 31 s),
#: short against a joint's thermal time constant (0.5-0.9 h there), so that the rise is
#: interpolated only over what a joint cannot do much in].
TRACE_GAP_MIN = 5.0
#: Modes of a temperature trace (:class:`TemperatureTrace`): the rise of a UR3-format
#: warm-up after every cold start, or a table of the joint's temperature on the life's
#: operating hours.
TRACE_MODES = ("rise", "hours")
#: The header of a table of mode ``hours``, as
#: :func:`swgsim.datasets.joint_log.write_temperature_table` writes it: operating hours
#: [h], the joint's temperature [°C].
HOURS_TABLE_COLUMNS = ("hour", "temperature_c")
#: Largest temperature table read [bytes]: 256 MiB, some ten million rows of
#: ``hour,temperature_c``, a year of a joint at 1 Hz (pandas holds it in a few times
#: that) [choice].
MAX_TRACE_BYTES = 256 * 2**20


#: Why the Coulomb term's own run-in fields are :data:`swgsim.base.typed.LATER`.
_SPLIT = "viscous and Coulomb friction apart"


class _CoulombApart:
    """The Coulomb term apart from the viscous ones (:class:`RunInConfig`, :class:`Regrease`)."""

    @property
    def split(self) -> bool:
        """Whether the Coulomb term runs in (again) by its own."""
        return self.coulomb_drop is not None or self.coulomb_tau_h is not None

    def _apart(self, factor) -> tuple[np.ndarray, np.ndarray]:
        """``factor(drop, tau_h)`` of the viscous terms and of the Coulomb term (its own
        drop and time constant where set; the same array where neither is)."""
        viscous = factor(self.drop, self.tau_h)
        if not self.split:
            return viscous, viscous
        return viscous, factor(self.drop if self.coulomb_drop is None else self.coulomb_drop,
                               self.tau_h if self.coulomb_tau_h is None else self.coulomb_tau_h)


@dataclass
class RunInConfig(_CoulombApart):
    """Friction of a new gear running in (:func:`swgsim.gear.thermal.run_in_factor`).

    Attributes
    ----------
    drop : float
        Excess friction of a new gear, in [0, 1] [-]: on every friction term, or on the
        viscous ones (b1, b2) where the Coulomb term runs in by its own.
    tau_h : float
        Time constant, > 0 [operating h].
    coulomb_drop, coulomb_tau_h : float or None
        The Coulomb term's (b0, and μ, the mesh's load-proportional friction) own excess
        and time constant: the grease's redistribution lowers the churning (viscous) loss,
        the surfaces' smoothing the boundary (Coulomb) friction, by other amounts and over
        other times (docs/PHYSICS.md sec. 5.4) [choice: no measured curves]; None: those
        of ``drop`` and ``tau_h``.
    """

    drop: float = field(default=RUN_IN_DROP, metadata=allowed(0.0, 1.0))
    tau_h: float = field(default=RUN_IN_TAU_H, metadata=allowed(0.0, 1e5, lo_open=True,
                                                                unit="h"))
    coulomb_drop: float | None = field(default=None,
                                       metadata={**allowed(0.0, 1.0), LATER: _SPLIT})
    coulomb_tau_h: float | None = field(default=None, metadata={
        **allowed(0.0, 1e5, lo_open=True, unit="h"), LATER: _SPLIT})

    def factors(self, hours: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The viscous and the Coulomb terms' run-in factors at operating ``hours``
        (:func:`swgsim.gear.thermal.run_in_factor`), shapes of ``hours`` [-]."""
        return self._apart(lambda d, t: run_in_factor(hours, d, t))


@dataclass
class Regrease(_CoulombApart):
    """Re-greasing in service: the friction steps up and runs in again
    (:func:`swgsim.gear.thermal.regrease_factor`; the latest re-greasing counts).

    Attributes
    ----------
    hours : list of float
        Operating hours of the re-greasings, increasing, inside the life [h].
    drop : float
        Excess friction just after a re-greasing, in [0, 1] [-] (0.3) [choice: fresh
        grease churns until it has redistributed].
    tau_h : float
        Time constant of running in again, > 0 [operating h] (8: over in about a day)
        [choice].
    coulomb_drop, coulomb_tau_h : float or None
        The Coulomb term's own (b0 and μ), as :class:`RunInConfig`'s; None: ``drop``,
        ``tau_h``.
    """

    hours: list[float]
    drop: float = field(default=REGREASE_DROP, metadata=allowed(0.0, 1.0))
    tau_h: float = field(default=REGREASE_TAU_H, metadata=allowed(0.0, 1e5, lo_open=True,
                                                                  unit="h"))
    coulomb_drop: float | None = field(default=None,
                                       metadata={**allowed(0.0, 1.0), LATER: _SPLIT})
    coulomb_tau_h: float | None = field(default=None, metadata={
        **allowed(0.0, 1e5, lo_open=True, unit="h"), LATER: _SPLIT})

    def factors(self, hours: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The viscous and the Coulomb terms' factors at operating ``hours``
        (:func:`swgsim.gear.thermal.regrease_factor`), shapes of ``hours`` [-]."""
        return self._apart(lambda d, t: regrease_factor(hours, self.hours, d, t))

    def check(self, where: str) -> None:
        """Refuse no hour or hours not increasing, in one line naming ``<where>.hours``
        (the ranges are the fields'; the life's length, :meth:`ConditionsConfig.check_inside`).
        """
        if len(self.hours) == 0:
            raise ValueError(f"{where}.hours must name at least one operating hour (no "
                             f"re-greasing: {where}: null)")
        if any(b <= a for a, b in zip(self.hours[:-1], self.hours[1:], strict=True)):
            raise ValueError(f"{where}.hours must increase, got {list(self.hours)}")


#: Largest factor a :attr:`DutyChange.load_shift` of 1 puts on the dwell at the cycle's
#: highest load (and its inverse at the lowest) [-] [choice: a new program spending up to
#: four times more or less time at high load].
LOAD_SHIFT_BASE = 4.0
#: Allowed factors on a duty point's dwell [-] [choice: a twentieth to twenty times].
DWELL_FACTOR_RANGE = (0.05, 20.0)


@dataclass
class DutyChange:
    """A new program from an operating hour on: the same duty points, held for other times
    (:func:`swgsim.datasets.schedule.schedule`; the cycle restarts at the change).

    Attributes
    ----------
    hour_h : float
        Operating hour of the change, >= 0, inside the life [h].
    dwell_factors : list of float
        Factor on each duty point's dwell from ``hour_h`` on, in the duty cycle's order, one
        per point, each in [0.05, 20] [-]; empty: from ``load_shift``.
    load_shift : float or None
        In [-1, 1]: duty point i's factor is ``LOAD_SHIFT_BASE ** (load_shift * z_i)``, z_i
        its torque placed on [-1, 1] between the cycle's lowest and highest (0 where all
        are equal): more time at high load (> 0) or less (< 0); None: ``dwell_factors``.
    """

    hour_h: float = field(metadata=allowed(0.0, None, unit="h"))
    dwell_factors: list[float] = field(default_factory=list)
    load_shift: float | None = field(default=None, metadata=allowed(-1.0, 1.0))

    def check(self, where: str) -> None:
        """Refuse both or neither of ``dwell_factors`` and ``load_shift``, or a factor
        outside [0.05, 20], in one line naming the key (the cycle's length:
        :meth:`factors`; the life's: :meth:`ConditionsConfig.check_inside`)."""
        if (len(self.dwell_factors) == 0) == (self.load_shift is None):
            raise ValueError(f"{where}: give dwell_factors or load_shift, one of them, got "
                             f"{list(self.dwell_factors)} and {self.load_shift}")
        for i, f in enumerate(self.dwell_factors):
            check_range(f, *DWELL_FACTOR_RANGE, f"{where}.dwell_factors[{i}]",
                        why="factor on the duty point's dwell")

    def factors(self, t_out_nm: list[float], where: str) -> np.ndarray:
        """The factor on each duty point's dwell, shape (P,) [-].

        Parameters
        ----------
        t_out_nm : list of float
            The duty cycle's torques, in its order [N m].
        where : str
            Full name of the change for messages, e.g. ``dataset.life.conditions.duty_change``.

        Raises
        ------
        ValueError
            ``dwell_factors`` not one per duty point, in one line naming the key.
        """
        if self.load_shift is None:
            if len(self.dwell_factors) != len(t_out_nm):
                raise ValueError(f"{where}.dwell_factors must hold {len(t_out_nm)} factors, one "
                                 f"per duty point of the cycle, got {len(self.dwell_factors)}")
            return np.asarray(self.dwell_factors, float)
        t = np.asarray(t_out_nm, float)
        span = t.max() - t.min()
        z = (2.0 * t - t.min() - t.max()) / span if span > 0 else np.zeros_like(t)
        return LOAD_SHIFT_BASE ** (float(self.load_shift) * z)


@dataclass
class TemperatureTrace:
    """A measured warm-up for the joint's temperature over a life, instead of the
    first-order model's rise (:func:`swgsim.gear.thermal.traced_temperature`,
    :func:`trace_rise`); or, in mode ``hours``, the joint's temperature itself on the
    life's operating hours (:func:`trace_table`): a two-column CSV ``hour,temperature_c``
    (comma-separated, decimal points, hours increasing from >= 0, temperatures in the
    viscosity law's [-40, 150] °C), interpolated linearly between its rows, its first
    value held before them and its last beyond; the hall and the day of ``thermal`` do not
    enter (it may be null), nor ``scale`` (1).

    E.g. a UR3's joint temperatures over a working day: M. Tyrovolas, K. Aliev,
    D. Antonelli and C. Stylios, "UR3 CobotOps", UCI Machine Learning Repository, 2024,
    doi:10.24432/C5J891 (CC BY 4.0), column ``Temperature_J1``: a rise of 7.9 K over its
    first 49 min (measured here), then a gap of 5.2 h. Held beyond the trace, its last value
    stays: that joint was still warming (a first-order time constant of 0.5-0.9 h), so the
    plateau of a longer day is underestimated. The file is the user's: the path is an
    input, not part of the project.

    Attributes
    ----------
    path : str
        A CSV, ``;``-separated with decimal commas (the UR3 CobotOps format; mode
        ``hours``: the table above); relative to the working directory. The config hash
        names the path, not the file's bytes.
    column : str or None
        The temperature column [°C], e.g. ``Temperature_J1`` (mode ``rise``: needed;
        ``hours``: not read).
    scale : float
        Factor on the measured rise, in [0, 10] [-] (1; mode ``hours``: 1).
    time_column : str
        The time column: ISO 8601 timestamps, or seconds where numeric (``Timestamp``;
        mode ``hours``: not read).
    mode : str
        ``rise`` (the default) or ``hours`` (:data:`TRACE_MODES`); left out of a data
        set's config hash at its default (:data:`swgsim.base.typed.LATER`).
    """

    path: str
    column: str | None = None
    scale: float = 1.0
    time_column: str = "Timestamp"
    mode: str = field(default=TRACE_MODES[0], metadata={LATER: "tables of hours"})


def trace_rise(trace: TemperatureTrace, key: str) -> tuple[np.ndarray, np.ndarray]:
    """The rise of a measured warm-up over its first start: the temperature minus its
    first reading against the hours since the first row, over the first continuous
    segment (up to the first step over :data:`TRACE_GAP_MIN`), rows without a reading
    left out.

    Parameters
    ----------
    trace : TemperatureTrace
    key : str
        Full name of the trace, e.g. ``dataset.life.conditions.temperature_trace``.

    Returns
    -------
    trace_h : ndarray, shape (N,)
        Hours since the segment's first reading, 0 first, increasing [h].
    rise_k : ndarray, shape (N,)
        Temperature minus the first reading [K].

    Raises
    ------
    ValueError
        One line naming ``<key>.path`` (no such file, not a regular text file of at most
        :data:`MAX_TRACE_BYTES`, :func:`swgsim.files.inputs.check_text_file`; not a
        table), ``<key>.column`` or ``<key>.time_column`` (missing, a cell not a number or
        time, a temperature outside [-40, 150] °C naming its row, times not increasing,
        fewer than two readings before the first gap); an empty cell is a missing reading,
        left out.
    """
    import pandas as pd

    p = Path(trace.path)
    if not p.exists():
        raise ValueError(f"{key}.path: no file {trace.path!r}")
    check_text_file(p, f"{key}.path", MAX_TRACE_BYTES)  # a regular text file, bounded
    if trace.column is None:
        raise ValueError(f"{key}.column: name the temperature column of {trace.path!r} "
                         f"(mode {trace.mode!r}), got none")
    try:
        head = pd.read_csv(p, sep=";", decimal=",", nrows=0).columns
    except (ValueError, UnicodeDecodeError) as e:
        raise ValueError(f"{key}.path: {trace.path!r} is not a ;-separated table: "
                         f"{str(e).splitlines()[0]}") from None
    named = [str(c) for c in head if not str(c).startswith("Unnamed")]
    for field_, col in (("column", trace.column), ("time_column", trace.time_column)):
        if col not in head:
            raise ValueError(f"{key}.{field_}: {col!r} is not a column of {trace.path!r}; "
                             f"columns: {', '.join(named)}")
    df = pd.read_csv(p, sep=";", decimal=",", usecols=[trace.time_column, trace.column])
    t_s = _seconds(df[trace.time_column], f"{key}.time_column")
    num = pd.to_numeric(df[trace.column], errors="coerce")
    text = np.flatnonzero(num.isna().to_numpy() & df[trace.column].notna().to_numpy())
    if text.size:
        raise ValueError(f"{key}.column: {trace.column!r} of {trace.path!r}, row "
                         f"{int(text[0]) + 1}: {df[trace.column].iloc[text[0]]!r} is not a "
                         f"number")
    temp = num.to_numpy(dtype=float)
    _check_temperatures(temp, f"{key}.column: {trace.column!r} of {trace.path!r}")
    steps = np.diff(t_s)
    if np.any(steps <= 0):
        raise ValueError(f"{key}.time_column: times of {trace.path!r} must increase")
    gaps = np.flatnonzero(steps > TRACE_GAP_MIN * 60.0)
    end = int(gaps[0]) + 1 if gaps.size else t_s.size
    ok = np.isfinite(temp[:end])
    if ok.sum() < 2:
        raise ValueError(f"{key}.column: {trace.column!r} holds fewer than 2 readings before "
                         f"the first gap of {trace.path!r}")
    t_s, temp = t_s[:end][ok], temp[:end][ok]
    return (t_s - t_s[0]) / 3600.0, temp - temp[0]


def trace_table(trace: TemperatureTrace, key: str) -> tuple[np.ndarray, np.ndarray]:
    """The table of a trace of mode ``hours``: operating hours and the joint's
    temperature (:class:`TemperatureTrace`).

    Parameters
    ----------
    trace : TemperatureTrace
    key : str
        Full name of the trace, e.g. ``dataset.life.conditions.temperature_trace``.

    Returns
    -------
    hour : ndarray, shape (N,)
        Operating hours, >= 0, increasing [h].
    temperature_c : ndarray, shape (N,)
        The joint's temperature, in :data:`swgsim.gear.thermal.TEMP_RANGE_C` [°C].

    Raises
    ------
    ValueError
        One line naming ``<key>.path``: no such file, not a regular text file of at most
        :data:`MAX_TRACE_BYTES` (:func:`swgsim.files.inputs.check_text_file`), not a
        comma-separated table with
        the columns :data:`HOURS_TABLE_COLUMNS`, no row, a cell not a number, hours
        negative or not increasing, a temperature outside [-40, 150] °C (the viscosity
        law's range, :data:`swgsim.gear.thermal.TEMP_RANGE_C`).
    """
    import pandas as pd

    p, name = Path(trace.path), f"{key}.path"
    if not p.exists():
        raise ValueError(f"{name}: no file {trace.path!r}")
    check_text_file(p, name, MAX_TRACE_BYTES)  # a regular text file, bounded
    try:
        df = pd.read_csv(p)
    except (ValueError, UnicodeDecodeError) as e:
        raise ValueError(f"{name}: {trace.path!r} is not a comma-separated table: "
                         f"{str(e).splitlines()[0]}") from None
    if tuple(str(c).strip() for c in df.columns) != HOURS_TABLE_COLUMNS or df.empty:
        raise ValueError(f"{name}: {trace.path!r} must hold the columns "
                         f"{','.join(HOURS_TABLE_COLUMNS)} and a row (mode 'hours'), got "
                         f"{','.join(map(str, df.columns))} and {len(df)} rows")
    num = df.apply(pd.to_numeric, errors="coerce").to_numpy(dtype=float)
    bad = np.argwhere(~np.isfinite(num))
    if bad.size:
        i, j = (int(v) for v in bad[0])
        raise ValueError(f"{name}: {HOURS_TABLE_COLUMNS[j]} of {trace.path!r}, row {i + 1}: "
                         f"{df.iloc[i, j]!r} is not a number")
    hour, temp = num[:, 0], num[:, 1]
    back = np.flatnonzero(np.diff(hour) <= 0)
    if hour[0] < 0 or back.size:
        i = int(back[0]) + 1 if hour[0] >= 0 else 0
        raise ValueError(f"{name}: hour of {trace.path!r} must increase from >= 0 h, got "
                         f"{hour[i]:g} at row {i + 1}" + (f" after {hour[i - 1]:g}" if i else ""))
    _check_temperatures(temp, f"{name}: temperature_c of {trace.path!r}")
    return hour, temp


def _check_temperatures(temp: np.ndarray, what: str) -> None:
    """Refuse a temperature outside :data:`swgsim.gear.thermal.TEMP_RANGE_C` (NaN, a missing
    reading, passes) in one line: ``<what> must lie in [-40, 150] °C, got <t> at row <i>``."""
    lo, hi = TEMP_RANGE_C
    out = np.flatnonzero((temp < lo) | (temp > hi))
    if out.size:
        i = int(out[0])
        raise ValueError(f"{what} must lie in [{lo:g}, {hi:g}] °C, got {temp[i]:g} at row "
                         f"{i + 1}")


def _check_trace(tr: TemperatureTrace, has_thermal: bool, key: str) -> None:
    """Refuse a temperature trace outside its ranges or unreadable, in one line naming
    ``<key>.<field>`` (``key``: the conditions')."""
    k = f"{key}.temperature_trace"
    if tr.mode not in TRACE_MODES:
        raise ValueError(f"{k}.mode must be one of {', '.join(TRACE_MODES)}, got {tr.mode!r}")
    if tr.mode == "hours":
        if tr.scale != 1.0:
            raise ValueError(f"{k}.scale must be 1 in mode 'hours' (the table is the "
                             f"joint's temperature), got {tr.scale:g}")
        trace_table(tr, k)
        return
    if not has_thermal:
        raise ValueError(f"{k} needs {key}.thermal (the hall and the operating day), got "
                         f"thermal: null")
    check_range(tr.scale, 0.0, 10.0, f"{k}.scale")
    trace_rise(tr, k)


def _seconds(col, key: str) -> np.ndarray:
    """A time column as seconds: numbers as they are, else ISO 8601 timestamps."""
    import pandas as pd

    if col.dtype.kind in "fiu":
        out = col.to_numpy(dtype=float)
    else:
        t = pd.to_datetime(col, utc=True, errors="coerce")
        out = (t - t.iloc[0]).dt.total_seconds().to_numpy(dtype=float)
    if not np.all(np.isfinite(out)):
        raise ValueError(f"{key}: {col.name!r} holds a value that is not a time")
    return out


@dataclass
class ConditionsConfig:
    """What changes while the gear stays healthy (DATASET.md, "Gear lives").

    Attributes
    ----------
    thermal : JointThermal or None
        The joint's temperature over the life; None: it stays at the catalogue's
        reference temperature (20 °C).
    temperature_trace : TemperatureTrace or None
        A measured warm-up after every cold start of ``thermal``'s day, on the hall's
        temperature, instead of the first-order rise, or (mode ``hours``) the joint's
        temperature on the life's operating hours; None: the model's.
    viscosity : bool
        Friction follows the temperature, by ``friction_law``.
    friction_law : FrictionLaw
        How (default: the grease's viscosity law, :func:`swgsim.gear.thermal.friction_scale`);
        an evaluation draws it from the family.
    viscous_in_dynamics : bool
        The joint's viscous friction acts in the gear's dynamics: each window's signals
        are those of the gear with b1, b2 times the window's factor (``friction``), not
        of the nominal gear with its efficiency rescaled alone (:mod:`swgsim.datasets.life`,
        :data:`~swgsim.datasets.life.VISCOUS_LADDER`): a warm joint's lower damping
        shows in its bridges as a reduced damping does. False: the nominal gear's signals.
    coulomb_law : FrictionLaw or None
        The Coulomb term's own law (b0; the viscous terms b1, b2 follow ``friction_law``):
        the viscous term follows the grease's viscosity, the Coulomb and mixed-lubrication
        term the film and the load, e.g. a ``u_shaped`` law rising again above its
        minimum (docs/PHYSICS.md sec. 5.4); None: ``friction_law`` on every term.
    run_in : RunInConfig or None
        A new gear's friction running in from hour 0; None: the gear is run in.
    regrease : Regrease or None
        Re-greasings in service, each followed by a run-in; None: none.
    payload : list of [float, float]
        ``[operating hour, factor]`` pairs, hours increasing: from each hour on, the acting
        load at every duty point is the commanded one times the factor (> 0); before the
        first, 1.
    bridge_drift : BridgeDrift or None
        The bridges' zero and span drift with temperature; None: none.
    temperature_sensor : TemperatureSensor or None
        The joint's temperature reading (``temperature_c``); None: the stream has none.
    duty_change : DutyChange or None
        A new program from an operating hour on: the duty points held for other times;
        None: one duty cycle for the whole life.
    """

    thermal: JointThermal | None = field(default_factory=JointThermal)
    temperature_trace: TemperatureTrace | None = field(default=None,
                                                       metadata={LATER: "measured warm-ups"})
    viscosity: bool = True
    coulomb_law: FrictionLaw | None = field(default=None, metadata={LATER: _SPLIT})
    viscous_in_dynamics: bool = field(default=False, metadata={LATER: "friction in dynamics"})
    friction_law: FrictionLaw = field(default_factory=FrictionLaw,
                                      metadata={LATER: "drawn friction laws"})
    run_in: RunInConfig | None = None
    regrease: Regrease | None = field(default=None, metadata={LATER: "re-greasing"})
    payload: list[list[float]] = field(default_factory=list)
    bridge_drift: BridgeDrift | None = field(default_factory=BridgeDrift)
    temperature_sensor: TemperatureSensor | None = field(default_factory=TemperatureSensor)
    duty_change: DutyChange | None = field(default=None, metadata={LATER: "duty changes"})

    def check(self, where: str) -> None:
        """Refuse conditions outside their ranges, in one line naming the key (run by
        :func:`swgsim.base.typed.check_tree` after the parts' own: the thermal model, the
        friction law, the re-greasing, the bridges' drift, the temperature sensor); the
        hours that must lie inside a life, by :meth:`check_inside`.

        Raises
        ------
        ValueError
            A temperature trace unreadable or outside its ranges (or without ``thermal``
            in mode ``rise``), a payload step not ``[hour, factor]``, its factor outside
            (0, 10] or its hours not increasing.
        """
        if self.temperature_trace is not None:
            _check_trace(self.temperature_trace, self.thermal is not None, where)
            if self.thermal is not None and self.thermal.network is not None:
                raise ValueError(f"{where}.thermal.network must be null with a "
                                 f"temperature_trace (the measured temperature replaces "
                                 f"the thermal model)")
        for i, step in enumerate(self.payload):
            if len(step) != 2:
                raise ValueError(f"{where}.payload[{i}] must be [hour, factor], got {step}")
            check_range(step[1], 0.0, 10.0, f"{where}.payload[{i}][1]", lo_open=True,
                        why="factor on the acting load")
        hours = [step[0] for step in self.payload]
        if any(b <= a for a, b in zip(hours[:-1], hours[1:], strict=True)):
            raise ValueError(f"{where}.payload: hours must increase, got {hours}")

    def check_inside(self, hours: float, where: str) -> None:
        """Refuse a payload step, a re-greasing or a duty change outside a life of ``hours``
        [h], in one line naming ``<where>.payload[i][0]``, ``<where>.regrease.hours[i]`` or
        ``<where>.duty_change.hour_h`` (run by
        :meth:`swgsim.datasets.schedule.LifeConfig.check`, after :meth:`check`)."""
        for i, step in enumerate(self.payload):
            check_range(step[0], 0.0, hours, f"{where}.payload[{i}][0]", "h",
                        why="an operating hour inside the life")
        for i, h in enumerate(self.regrease.hours if self.regrease is not None else ()):
            check_range(h, 0.0, hours, f"{where}.regrease.hours[{i}]", "h",
                        why="an operating hour inside the life")
        if self.duty_change is not None:
            check_range(self.duty_change.hour_h, 0.0, hours, f"{where}.duty_change.hour_h", "h",
                        why="an operating hour inside the life")


@dataclass(frozen=True)
class WindowConditions:
    """The conditions of every window of a life's schedule.

    Attributes
    ----------
    temperature_c : ndarray, shape (W,)
        The joint's true temperature [°C].
    reading_c : ndarray, shape (W,) or None
        The temperature sensor's reading [°C] (None without a sensor; NaN where its fault
        is a dropout).
    friction : ndarray, shape (W,)
        Factor on the load-independent friction (viscosity, run-in, re-greasing) [-]; on
        its viscous terms alone where ``coulomb`` is set.
    mu_factor : ndarray, shape (W,)
        Factor on the mesh's load-proportional friction μ (run-in, re-greasing; the
        Coulomb term's where it runs in by its own) [-].
    payload : ndarray, shape (W,)
        Factor on the acting load [-].
    zero_mvv_per_k, span_per_k : ndarray, shape (5,)
        The gear's bridge drift coefficients (zeros without drift).
    drift_ref_c : float
        Temperature of no drift [°C].
    bridge_temperature_c : ndarray, shape (W, 5), or None
        Each bridge's temperature where the bridges lag the joint
        (:func:`swgsim.sensing.bridge_drift.bridge_temperatures`); None: the joint's.
    coulomb : ndarray, shape (W,), or None
        Factor on the Coulomb term b0 where viscous and Coulomb friction follow their own
        laws or run in apart (:class:`ConditionsConfig`) [-]; None: ``friction``.
    housing_c : ndarray, shape (W,), or None
        The housing's temperature of a two-node joint (``thermal.network``; then
        ``temperature_c`` is the grease's, which the friction follows, and the sensor reads
        the housing) [°C]; None: one node.
    """

    temperature_c: np.ndarray
    reading_c: np.ndarray | None
    friction: np.ndarray
    mu_factor: np.ndarray
    payload: np.ndarray
    zero_mvv_per_k: np.ndarray
    span_per_k: np.ndarray
    drift_ref_c: float
    bridge_temperature_c: np.ndarray | None = None
    coulomb: np.ndarray | None = None
    housing_c: np.ndarray | None = None

    def bridge_gain_offset(self, rows: np.ndarray, zero_offsets_mvv: np.ndarray | None = None
                           ) -> tuple[np.ndarray, np.ndarray]:
        """Each window's bridge gain and the offset to add after it, shapes (n, 5) and
        (n, 5) [-, mV/V]: the drift at the window's temperature.

        The span drift (the modulus, the gauge factor) acts on the strain's signal, not on
        a bridge's zero offset z (its arms' imbalance): given the gear's ``zero_offsets_mvv``
        (shape (5,), :attr:`swgsim.gear.sensors.SensorLayout.zero_offsets_mvv`) of signals
        that hold them, the offset is (1 − gain) z + zero_c ΔT, so that gain · s + offset
        = gain (s − z) + z + zero_c ΔT.
        """
        dt = ((self.temperature_c[rows] - self.drift_ref_c)[:, None]
              if self.bridge_temperature_c is None
              else self.bridge_temperature_c[rows] - self.drift_ref_c)  # (n, 1) or (n, 5)
        gain, offset = 1.0 + self.span_per_k[None, :] * dt, self.zero_mvv_per_k[None, :] * dt
        if zero_offsets_mvv is not None:
            offset = offset + (1.0 - gain) * np.asarray(zero_offsets_mvv, float)[None, :]
        return gain, offset


def window_conditions(cfg: ConditionsConfig, hours: np.ndarray, n_in_rpm: np.ndarray,
                      t_out_nm: np.ndarray, gear: ChainParams, seed: int, gear_id: int,
                      life_seed: int) -> WindowConditions:
    """The conditions of a life's windows (DATASET.md, "Gear lives").

    Parameters
    ----------
    cfg : ConditionsConfig
        Checked (:meth:`ConditionsConfig.check`, :meth:`ConditionsConfig.check_inside`).
    hours : ndarray, shape (W,)
        Operating hours of the windows, increasing [h].
    n_in_rpm, t_out_nm : ndarray, shape (W,)
        Each window's commanded speed [rpm] and load [N m].
    gear : ChainParams
        The healthy gear (its loss heats the joint).
    seed, gear_id, life_seed : int
        The data set's seed, the gear, the life (random streams: DATASET.md, "Gear lives").

    Returns
    -------
    WindowConditions
    """
    payload = np.ones_like(hours)
    for h, f in cfg.payload:
        payload[hours >= h] = f
    temp, housing = _temperature(cfg, hours, n_in_rpm, t_out_nm, payload, gear)
    friction, coulomb, run_in = _friction(cfg, hours, temp)
    reading = None
    wall = (hours if cfg.thermal is None  # lags run over a stop too: they cool with the joint
            else wall_clock_h(hours, cfg.thermal.run_h_per_day))
    if cfg.temperature_sensor is not None:
        ss = np.random.SeedSequence(int(seed), spawn_key=(int(gear_id), int(life_seed), 2**22))
        reading = measure_temperature(temp if housing is None else housing,
                                      cfg.temperature_sensor, np.random.default_rng(ss),
                                      hours=hours, wall_h=wall)
    zero, span, ref, bridges = np.zeros(5), np.zeros(5), REF_TEMP_C, None
    if cfg.bridge_drift is not None:
        ss = np.random.SeedSequence(int(seed), spawn_key=(int(gear_id), 2**21))
        rng = np.random.default_rng(ss)
        zero, span = draw_bridge_drift(cfg.bridge_drift, rng)
        ref = float(cfg.bridge_drift.ref_c)
        bridges = bridge_temperatures(temp, wall, cfg.bridge_drift, rng, housing)
    return WindowConditions(temp, reading, np.asarray(friction, float), run_in, payload,
                            zero, span, ref, bridges, coulomb, housing)


def _friction(cfg: ConditionsConfig, hours: np.ndarray, temp: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """The factors on the viscous (or every load-independent) friction and on the Coulomb
    term (None: one factor on all), and the factor on μ, at the windows, shapes (W,) [-]."""
    ones = np.ones_like(hours)
    run_v, run_c = cfg.run_in.factors(hours) if cfg.run_in is not None else (ones, ones)
    if cfg.regrease is not None:
        rg_v, rg_c = cfg.regrease.factors(hours)
        run_v, run_c = run_v * rg_v, run_c * rg_c
    law_v = cfg.friction_law.factor(temp) if cfg.viscosity else 1.0
    friction = law_v * run_v
    split = (cfg.coulomb_law is not None or (cfg.run_in is not None and cfg.run_in.split)
             or (cfg.regrease is not None and cfg.regrease.split))
    if not split:
        return friction, None, run_v
    law_c = ((cfg.coulomb_law or cfg.friction_law).factor(temp) if cfg.viscosity else 1.0)
    return friction, np.asarray(law_c * run_c, float), run_c


def _temperature(cfg: ConditionsConfig, hours: np.ndarray, n_in_rpm: np.ndarray,
                 t_out_nm: np.ndarray, payload: np.ndarray, gear: ChainParams
                 ) -> tuple[np.ndarray, np.ndarray | None]:
    """The joint's true temperature at the windows [°C], shape (W,): a trace's table on
    the operating hours (mode ``hours``), the reference without a thermal model, the
    measured warm-up with a trace, else the thermal model at the acting loss (two nodes:
    the grease's, and the housing's beside it, else None); refused outside the viscosity
    law's range naming what sets it."""
    th, tr = cfg.thermal, cfg.temperature_trace
    housing = None
    if tr is not None and tr.mode == "hours":
        t_h, temp_c = trace_table(tr, "conditions.temperature_trace")
        return np.interp(hours, t_h, temp_c), None
    if th is None:
        return np.full(hours.shape, REF_TEMP_C), None
    if tr is not None:
        t_h, rise = trace_rise(tr, "conditions.temperature_trace")
        temp = traced_temperature(hours, t_h, rise, th, tr.scale)
        key, cause = "conditions.temperature_trace", (
            f"the hall, ambient_c {th.ambient_c:g} °C, plus scale {tr.scale:g} times the "
            f"rise of {tr.column!r} in {tr.path!r}")
    else:
        n, load = np.abs(n_in_rpm), np.abs(t_out_nm) * payload
        loss = loss_power_w(gear.gear, n, load)
        if th.network is None:
            temp = joint_temperature(hours, loss, th)
        else:  # the motor's torque: the load's through the ratio plus the gear's loss
            torque = load / gear.gear.ratio + loss / (n * RPM)
            temp, housing = network_temperatures(hours, loss, torque, th)
        key, cause = "conditions.thermal", (
            f"the hall, ambient_c {th.ambient_c:g} °C, plus the gear's loss times "
            f"r_th_k_per_w {th.r_th_k_per_w:g} K/W")
    lo, hi = TEMP_RANGE_C
    bad = np.flatnonzero((temp < lo) | (temp > hi))
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"{key}: the joint reaches {temp[i]:.4g} °C at operating hour "
                         f"{hours[i]:.4g} ({cause}); the viscosity law takes "
                         f"[{lo:g}, {hi:g}] °C")
    return temp, housing


def efficiency_ratio(gear: ChainParams, n_in_rpm, t_out_nm, friction: np.ndarray,
                     mu_factor: np.ndarray, coulomb: np.ndarray | None = None,
                     simulated: np.ndarray | None = None) -> np.ndarray:
    """The factor a window's efficiency changes by under its friction: the model's steady
    efficiency at the acting friction over that at the friction its record was simulated
    with (the nominal gear's, or with ``simulated``, the factor on its viscous terms b1, b2
    alone), at the record's speed and load, shape of ``friction`` [-]
    (:func:`swgsim.gear.thermal.steady_efficiency`)."""
    n = np.abs(np.asarray(n_in_rpm, float))
    t = np.abs(np.asarray(t_out_nm, float))
    if simulated is None:
        nominal = steady_efficiency(gear.gear, n, t)
    else:  # the viscous terms as simulated, the Coulomb term and mu nominal
        nominal = steady_efficiency(gear.gear, n, t, simulated, 1.0, coulomb=1.0)
        coulomb = friction if coulomb is None else coulomb
    acting = steady_efficiency(gear.gear, n, t, friction, mu_factor, coulomb)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(nominal > 0, acting / nominal, 1.0)
