"""What the joint's temperature does to the five strain-gauge bridges s0..s4, and the
temperature sensor that measures it.

Two effects per bridge, linear in ΔT = T − T_ref: s' = (1 + span_c ΔT) s + zero_c ΔT [mV/V],
the zero drift from the gauges' mismatched apparent strain, the span drift from the steel's
modulus, its expansion and the gauge factor. :class:`BridgeDrift` holds the coefficients'
means and spreads, :func:`draw_bridge_drift` draws a gear's; :class:`TemperatureSensor` and
:func:`measure_temperature` give the joint's reading and its faults. Derivation, sources
and what is not modelled: docs/PHYSICS.md sec. 5.4.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from swgsim.base.typed import LATER, check_range

#: Reference temperature of the drift coefficients [°C] (the temperature at commissioning
#: is not known in advance; docs/PHYSICS.md sec. 5.4).
REF_TEMP_C = 20.0

#: Number of bridges s0..s4.
N_BRIDGES = 5

#: Relative change of the steel's modulus [1/K]: carbon-molybdenum steels, 206.2 / 201.3 /
#: 196.5 GPa at −73 / 21 / 93 °C, central difference (Roark's *Formulas for Stress and
#: Strain*, table of elastic moduli against temperature) [src; derived].
MODULUS_TC_PER_K = -2.9e-4
#: Linear expansion of steel [1/K]: the expansion to which gauges for steel are
#: compensated, suffix "-11" of TML gauges [src, suffix].
STEEL_EXPANSION_PER_K = 11e-6
#: Relative change of the gauge factor of constantan [1/K], about +1e-4 [unverified].
GAUGE_FACTOR_TC_PER_K = 1.0e-4


@dataclass
class BridgeDrift:
    """Temperature coefficients of the five bridges: their means and per-gear spreads.

    Attributes
    ----------
    zero_mean_mvv_per_k : float
        Mean zero drift of every bridge [mV/V per K] (0: the arms' common apparent strain
        cancels, docs/PHYSICS.md sec. 5.4).
    gauge_mismatch_ue_per_k : float
        Sd of one gauge's apparent strain about its bridge's common value [µε/K] (0.2)
        [choice]; sets the zero drift's spread (:attr:`zero_sd_mvv_per_k`).
    gauge_factor : float
        Gauge factor [-] (2.0, constantan foil, docs/PHYSICS.md sec. 4.2).
    active_arms : list of int
        Active arms of s0..s4 (4, 2, 2, 2, 2): full bridge s0, half bridges s1..s4
        (docs/PHYSICS.md sec. 4.3).
    span_mean_per_k : float
        Mean relative gain change [1/K]: −modulus + gauge factor − 3 × expansion terms,
        +3.57e-4 (docs/PHYSICS.md sec. 5.4) [derived].
    span_sd_per_k : float
        Bridge-to-bridge sd of the gain change [1/K] (5e-5) [choice].
    ref_c : float
        Temperature at which the coefficients give no change [°C] (20).
    lag_spread_min : float
        Each bridge's temperature lags the joint's by its own first-order time constant,
        drawn per gear and bridge uniformly in [0, ``lag_spread_min``] [min] (0, the
        default: every bridge at the joint's temperature). During a warm-up the collar is
        not at one temperature: the wave generator and its bearing heat first, the collar
        later, so the bridges, at other radii and angles, drift apart for a while and
        together again in the steady state (docs/PHYSICS.md sec. 5.4) [choice: minutes,
        a collar's conduction; no measurement found].
    collar_weights : list of float
        With a two-node joint (:class:`swgsim.gear.thermal.ThermalNetwork`), each bridge's
        place between the housing (0) and the wave generator's grease (1): its temperature
        is T_h + w (T_g − T_h), w drawn per gear and bridge uniformly in ``[lo, hi]``
        within [0, 1] ([0.2, 0.8]) [choice: gauges on the collar, between the two].

    :meth:`check` refuses a negative spread, a gauge factor or arm count out of range, a
    non-finite value.
    """

    zero_mean_mvv_per_k: float = 0.0
    gauge_mismatch_ue_per_k: float = 0.2
    gauge_factor: float = 2.0
    active_arms: list[int] = field(default_factory=lambda: [4, 2, 2, 2, 2])
    span_mean_per_k: float = (-MODULUS_TC_PER_K + GAUGE_FACTOR_TC_PER_K
                              - 3 * STEEL_EXPANSION_PER_K)
    span_sd_per_k: float = 5e-5
    ref_c: float = REF_TEMP_C
    lag_spread_min: float = field(default=0.0, metadata={LATER: "bridges' own temperatures"})
    collar_weights: list[float] = field(default_factory=lambda: [0.2, 0.8],
                                        metadata={LATER: "a thermal network"})

    def check(self, key: str = "BridgeDrift") -> None:
        """Refuse a field outside its range in one line naming ``<key>.<field>``.

        Raises
        ------
        ValueError
        """
        for name in ("zero_mean_mvv_per_k", "span_mean_per_k", "ref_c"):
            if not np.isfinite(getattr(self, name)):
                raise ValueError(f"{key}.{name} must be finite, got {getattr(self, name)}")
        for name in ("gauge_mismatch_ue_per_k", "span_sd_per_k"):
            check_range(getattr(self, name), 0.0, np.inf, f"{key}.{name}")
        check_range(self.gauge_factor, 1.0, 5.0, f"{key}.gauge_factor")
        check_range(self.lag_spread_min, 0.0, 600.0, f"{key}.lag_spread_min", "min",
                    why="a bridge behind the joint's temperature, up to 10 h")
        w = list(self.collar_weights)
        if len(w) != 2 or not (0.0 <= w[0] <= w[1] <= 1.0):
            raise ValueError(f"{key}.collar_weights must be [lo, hi] with 0 <= lo <= hi <= 1, "
                             f"got {w}")
        arms = list(self.active_arms)
        if len(arms) != N_BRIDGES or any(a not in (1, 2, 4) for a in arms):
            raise ValueError(f"{key}.active_arms must be {N_BRIDGES} values of 1, 2 or 4, "
                             f"got {arms}")

    @property
    def zero_sd_mvv_per_k(self) -> np.ndarray:
        """Sd of each bridge's zero drift, 1e3 · GF/4 · √n · σ [mV/V per K], shape (5,)."""
        n = np.asarray(self.active_arms, dtype=float)
        return 1e3 * self.gauge_factor / 4 * np.sqrt(n) * self.gauge_mismatch_ue_per_k * 1e-6


def draw_bridge_drift(cfg: BridgeDrift, rng: np.random.Generator
                      ) -> tuple[np.ndarray, np.ndarray]:
    """One gear's drift coefficients: normal draws about the means.

    Parameters
    ----------
    cfg : BridgeDrift
    rng : numpy.random.Generator
        Seeded by the caller (one per gear); draws 10 standard normals, zeros first.

    Returns
    -------
    zero_mvv_per_k : ndarray, shape (5,)
        Zero drift of s0..s4 [mV/V per K].
    span_per_k : ndarray, shape (5,)
        Relative gain change of s0..s4 [1/K].

    Raises
    ------
    TypeError
        ``rng`` is not a Generator.
    """
    if not isinstance(rng, np.random.Generator):
        raise TypeError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    z = rng.standard_normal((2, N_BRIDGES))  # (zero, span) x bridge
    zero = cfg.zero_mean_mvv_per_k + cfg.zero_sd_mvv_per_k * z[0]
    span = cfg.span_mean_per_k + cfg.span_sd_per_k * z[1]
    return zero, span


def bridge_temperatures(temp_c: np.ndarray, wall_h: np.ndarray, cfg: BridgeDrift,
                        rng: np.random.Generator, housing_c: np.ndarray | None = None
                        ) -> np.ndarray | None:
    """Each bridge's temperature: the joint's (or, with ``housing_c``, its place between
    the housing and the grease, :attr:`BridgeDrift.collar_weights`) lagged by the bridge's
    own time constant (:attr:`BridgeDrift.lag_spread_min`); None where the spread is 0 and
    there is no housing (every bridge at the joint's temperature). Draws five uniform
    numbers for the lags (spread > 0), then five for the places (``housing_c`` given).

    Parameters
    ----------
    temp_c : ndarray, shape (W,)
        The joint's temperature at each window (the grease's, with ``housing_c``) [°C].
    wall_h : ndarray, shape (W,)
        The windows' wall-clock hours, increasing [h] (the lag runs over the stops too).
    cfg : BridgeDrift
    rng : numpy.random.Generator
        The gear's, after :func:`draw_bridge_drift`'s draws.
    housing_c : ndarray, shape (W,), optional
        The housing's temperature of a two-node joint [°C].

    Returns
    -------
    ndarray, shape (W, 5), or None
    """
    if cfg.lag_spread_min <= 0 and housing_c is None:
        return None
    tau_h = (cfg.lag_spread_min / 60.0 * rng.uniform(size=N_BRIDGES)
             if cfg.lag_spread_min > 0 else np.zeros(N_BRIDGES))
    if housing_c is None:
        base = [temp_c] * N_BRIDGES
    else:
        lo, hi = cfg.collar_weights
        w = lo + (hi - lo) * rng.uniform(size=N_BRIDGES)
        base = [housing_c + wk * (temp_c - housing_c) for wk in w]
    return np.column_stack([b if t <= 0 else first_order_lag(b, wall_h, t)
                            for b, t in zip(base, tau_h, strict=True)])


#: Why the sensor's later fields are :data:`swgsim.base.typed.LATER`.
_SENSOR = "sensor faults, lag, offset, ageing"
#: Faults of :class:`TemperatureSensor` (its docstring).
TEMPERATURE_SENSOR_FAULTS = ("none", "stuck", "drift", "dropout")


@dataclass
class TemperatureSensor:
    """The joint's temperature channel (an NTC or PT1000 on the joint's housing).

    Attributes
    ----------
    resolution_k : float
        Quantisation step of the reading [K] (0.1), >= 0 (0: none) [choice: a common
        resolution of joint temperature readouts].
    noise_sd_k : float
        Sd of the reading's white noise [K] (0.05), >= 0 [choice].
    lag_min : float
        Time constant by which the reading lags the joint's (the grease's) temperature
        [min], >= 0 (0: none, the reading follows at once). A sensor on the housing or
        the drive board sits behind thermal masses: minutes to tens of minutes
        (docs/PHYSICS.md sec. 5.4). First order along the operating hours.
    offset_k : float
        The sensor's calibration offset [K], finite (0: none); a PT1000 of class B is
        within ``±(0.3 + 0.005 |T|)`` K (IEC 60751 [unverified]).
    ageing_k_per_h : float
        A slow drift of the reading from hour 0 [K per operating h], finite (0: none): a
        sound sensor's ageing, some 1e-5 K/h (``drift_k_per_h``'s note), unlike the
        ``drift`` fault.
    fault : {"none", "stuck", "drift", "dropout"}
        The channel's fault from operating hour ``fault_hour`` on
        (:data:`TEMPERATURE_SENSOR_FAULTS`):

        * ``none``: a working sensor;
        * ``stuck``: the reading holds the last reading before ``fault_hour`` (the first
          reading when ``fault_hour`` is at or before the first one): a frozen converter
          or a bus that repeats its last value;
        * ``drift``: the reading gains ``drift_k_per_h`` · (h − ``fault_hour``) K, before the
          quantisation: a thermistor ageing or a sensor come loose from the housing
          (reading towards the hall, a negative rate);
        * ``dropout``: NaN (a broken wire, a lost channel); the true temperature, and all
          that it drives, stays.
    fault_hour : float
        Operating hour from which the fault acts, >= 0 [h] (0).
    drift_k_per_h : float
        Rate of the ``drift`` fault, finite, either sign [K per operating h] (0). Typical
        [choice]: an NTC ages by about 1 % of its resistance in its first year, 0.1 % a
        year after [unverified, a vendor's note], about 0.2 K at its 4-5 %/K, so some
        1e-5 K/h in continuous service, invisible over a life; a failing or loosened
        sensor 0.01-0.5 K/h (a few K to tens of K over a week), the range a monitor is
        meant to notice.

    :meth:`check` refuses a negative or non-finite value, an unknown fault.
    """

    resolution_k: float = 0.1
    noise_sd_k: float = 0.05
    fault: str = field(default="none", metadata={LATER: _SENSOR})
    fault_hour: float = field(default=0.0, metadata={LATER: _SENSOR})
    drift_k_per_h: float = field(default=0.0, metadata={LATER: _SENSOR})
    lag_min: float = field(default=0.0, metadata={LATER: _SENSOR})
    offset_k: float = field(default=0.0, metadata={LATER: _SENSOR})
    ageing_k_per_h: float = field(default=0.0, metadata={LATER: _SENSOR})

    def check(self, key: str = "TemperatureSensor") -> None:
        """Refuse a field outside its range in one line naming ``<key>.<field>``.

        Raises
        ------
        ValueError
        """
        for name in ("resolution_k", "noise_sd_k"):
            check_range(getattr(self, name), 0.0, np.inf, f"{key}.{name}", "K")
        if self.fault not in TEMPERATURE_SENSOR_FAULTS:
            raise ValueError(f"{key}.fault: {self.fault!r}; allowed: "
                             f"{', '.join(TEMPERATURE_SENSOR_FAULTS)}")
        check_range(self.fault_hour, 0.0, np.inf, f"{key}.fault_hour", "h")
        check_range(self.lag_min, 0.0, 600.0, f"{key}.lag_min", "min",
                    why="a sensor behind the joint's thermal masses, up to 10 h")
        for name, unit in (("drift_k_per_h", "K per h"), ("offset_k", "K"),
                           ("ageing_k_per_h", "K per h")):
            if not np.isfinite(getattr(self, name)):
                raise ValueError(f"{key}.{name} must be a finite number of {unit}, "
                                 f"got {getattr(self, name)}")

    @property
    def needs_hours(self) -> bool:
        """Whether its readings depend on their operating hours (a fault, a lag, ageing)."""
        return self.fault != "none" or self.lag_min > 0 or self.ageing_k_per_h != 0


def measure_temperature(true_c, sensor: TemperatureSensor, rng: np.random.Generator, *,
                        hours=None, wall_h=None) -> np.ndarray:
    """Readings of the temperature channel (:class:`TemperatureSensor`): the true
    temperature lagged by the sensor's time constant, its offset and ageing added, noisy,
    then quantised to the resolution, and the sensor's fault from its hour on.

    The lag is first order in wall-clock time, exact for a temperature held between
    readings: y_k = y_(k-1) + (1 − exp(−Δt / τ)) (T_k − y_(k-1)), y_0 = T_0 (the sensor
    starts at the joint's temperature); over a daily stop the sensor cools with the joint.
    Off (τ = 0, no offset, no ageing) the readings are those of a sensor without the
    options, bit for bit.

    Parameters
    ----------
    true_c : array_like, shape (W,)
        True temperatures [°C].
    sensor : TemperatureSensor
    rng : numpy.random.Generator
        Seeded by the caller; one standard normal per reading, whatever the fault (a
        faultless sensor's readings are those of a faulty one before its hour).
    hours : array_like, shape of ``true_c``, optional
        Operating hours of the readings [h], increasing; needed when
        :attr:`TemperatureSensor.needs_hours`.
    wall_h : array_like, shape of ``true_c``, optional
        Wall-clock hours of the readings [h], increasing (the stops included:
        :func:`swgsim.gear.thermal.wall_clock_h`): the lag's time; default ``hours``.

    Returns
    -------
    ndarray, shape of ``true_c``
        Readings [°C], float64, multiples of ``resolution_k`` (``drift`` included); NaN
        from ``fault_hour`` on under ``dropout``.

    Raises
    ------
    ValueError
        A non-finite true temperature; a fault without ``hours`` (naming
        ``TemperatureSensor.fault``), ``hours`` of another shape or not finite.
    TypeError
        ``rng`` is not a Generator.
    """
    if not isinstance(rng, np.random.Generator):
        raise TypeError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    t = np.asarray(true_c, dtype=np.float64)
    if not np.all(np.isfinite(t)):
        raise ValueError("true_c must be finite")
    h = _fault_hours(hours, t.shape, sensor)
    if h is not None and sensor.lag_min > 0:
        wall = h if wall_h is None else np.asarray(wall_h, dtype=np.float64)
        if wall.shape != h.shape or not np.all(np.isfinite(wall)) or np.any(np.diff(wall) < 0):
            raise ValueError(f"wall_h must be finite and increasing, of the readings' shape "
                             f"{h.shape}, got shape {wall.shape}")
        t = first_order_lag(t, wall, sensor.lag_min / 60.0)
    if sensor.offset_k != 0:
        t = t + sensor.offset_k
    if h is not None and sensor.ageing_k_per_h != 0:
        t = t + sensor.ageing_k_per_h * h
    r = t + sensor.noise_sd_k * rng.standard_normal(t.shape)
    if h is not None and sensor.fault == "drift":
        r = r + sensor.drift_k_per_h * np.maximum(h - sensor.fault_hour, 0.0)
    if sensor.resolution_k > 0:
        r = np.round(r / sensor.resolution_k) * sensor.resolution_k
    if sensor.fault in ("none", "drift"):
        return r
    on = h >= sensor.fault_hour
    if sensor.fault == "dropout":
        r[on] = np.nan
    elif on.any():  # stuck: the last reading before the hour, else the first
        before = np.flatnonzero(~on)
        held = before[np.argmax(h[before])] if before.size else int(np.argmin(h))
        r[on] = r[held]
    return r


def first_order_lag(x: np.ndarray, hours: np.ndarray, tau_h: float) -> np.ndarray:
    """A first-order lag of ``x`` along ``hours`` with time constant ``tau_h`` [h], exact
    for ``x`` held between samples, starting at ``x[0]`` (:func:`measure_temperature`).

    Parameters
    ----------
    x : ndarray, shape (W,)
    hours : ndarray, shape (W,)
        Increasing [h].
    tau_h : float
        > 0 [h].

    Returns
    -------
    ndarray, shape (W,)
    """
    a = 1.0 - np.exp(-np.diff(hours, prepend=hours[:1]) / tau_h)
    y = np.empty_like(x)
    prev = x[0]
    for k in range(x.size):  # a recursion: W readings of a life, a few hundred thousand
        prev = prev + a[k] * (x[k] - prev)
        y[k] = prev
    return y


def _fault_hours(hours, shape: tuple, sensor: TemperatureSensor) -> np.ndarray | None:
    """The readings' hours as float64 when the sensor's readings depend on them, else
    None; refuse them missing, of another shape or not finite."""
    if not sensor.needs_hours:
        return None
    if hours is None:
        raise ValueError(f"TemperatureSensor (fault {sensor.fault!r}, lag_min "
                         f"{sensor.lag_min:g}, ageing_k_per_h {sensor.ageing_k_per_h:g}) "
                         "needs the readings' operating hours: "
                         "measure_temperature(..., hours=...)")
    h = np.asarray(hours, dtype=np.float64)
    if h.shape != shape or not np.all(np.isfinite(h)):
        raise ValueError(f"hours must be finite, of the readings' shape {shape}, got shape "
                         f"{h.shape}")
    return h
