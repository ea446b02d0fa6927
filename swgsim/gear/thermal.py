"""Temperature of a joint over a gear life, and what it does to the gear's friction.

A joint warms while it runs and cools while it stands, its friction falls as the grease
warms: a benign change a monitor must not call a fault. Here: the joint temperature with a
cold start every operating day (:func:`joint_temperature`), the gear's friction at a
temperature and run-in state (:func:`gear_at_temperature`), the model's steady efficiency
and loss. SI except temperatures in °C (differences in K), life times in hours (``_h``),
the time constant in minutes (``tau_min``), speeds in rpm.

Sources. Harmonic Drive AG, *Engineering Data CSD-2A Component Sets* (1019659 11/2014)
and *HFUS-2A* (1019658): efficiency "varies depending on" ratio, input speed, load torque,
temperature and lubrication; no-load running torque as curves over −10..+40 °C at 500 to
3500 rpm (CSD-2A illustration 26.1); grease change after about 8.5e8 input revolutions at
40 °C grease temperature (SK-1A, SK-2) **[src]**. The curves are graphs we could not read:
the temperature law is anchored on the issue's figures instead **[unverified]**. Universal
Robots, *Robot start-up in cold environments*: sealed strain wave gear joints whose grease
viscosity and friction depend on temperature, 21 °C internal joint temperature as the
reference before full speed, ambient 0-50 °C **[src]**. Nevmerzhitskiy et al., *Friction
model of industrial robot joint with temperature correction by example of KUKA KR10*,
J. Robotics 2019, 6931563: a joint heated by intensive motion to 65 °C motor temperature,
cooled to 25 °C, its friction re-identified along the way **[src]**.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from itertools import accumulate

import numpy as np

from swgsim.base.typed import LATER
from swgsim.gear.dynamics import RPM, GearParams

#: Reference temperature of the catalogue and so of :func:`swgsim.gear.dynamics.rt1_size20`
#: [°C] (efficiency at 20 °C, docs/PHYSICS.md sec. 2).
REF_TEMP_C = 20.0
#: Temperatures the viscosity law accepts [°C] (the issue's range; anchored on 0..40 °C).
TEMP_RANGE_C = (-40.0, 150.0)
#: k of ν(T) = ν(T_ref) exp(−k (T − T_ref)) [1/K] [choice; :func:`viscosity_ratio`].
VISCOSITY_COEFF_PER_K = 0.035
#: Exponent m of the viscosity in the load-independent friction [-]: 2/3 as in Palmgren's
#: viscous friction moment of rolling bearings, M0 ∝ (ν n)^(2/3) (the wave generator runs
#: on a thin ball bearing) [recall, Palmgren 1959 / Harris & Kotzalas, not re-read].
FRICTION_EXPONENT = 2.0 / 3.0
#: Run-in: excess friction of a new gear [-], time constant [operating h] [choice: the
#: issue's "+3 points over about 30 h"; 74.0 -> 77.0 % at the rated point, the tests].
RUN_IN_DROP = 0.16
RUN_IN_TAU_H = 30.0

#: Re-greasing in service: excess friction just after fresh grease [-] and the time
#: constant of running in again [operating h] [choice: fresh grease churns until it has
#: redistributed, and Harmonic Drive's manuals ask for a run-in after relubrication
#: [unverified]; no measured curve: +30 % falling over about a day (3 τ = 24 h)].
REGREASE_DROP = 0.3
REGREASE_TAU_H = 8.0
_HOURS_PER_DAY = 24.0


def _fail(name: str, rng: str, value) -> None:
    raise ValueError(f"{name} must lie in {rng}, got {value}")  # one line, naming the key


def _positive(x, name: str, unit: str, hi: float = np.inf) -> float:
    """``x`` as a float, refused unless in (0, hi]."""
    if np.ndim(x) or not (np.isfinite(float(x)) and 0 < float(x) <= hi):
        _fail(name, f"(0, {hi:g}] {unit}".replace(", inf]", ", inf)").strip(), x)
    return float(x)


def _finite(x, name: str, lo: float = -np.inf, hi: float = np.inf, rng: str = ""):
    """``x`` as a float array, refused unless finite and within [lo, hi]."""
    a = np.asarray(x, dtype=float)
    if a.size and not (np.all(np.isfinite(a)) and a.min() >= lo and a.max() <= hi):
        bad = a[~(np.isfinite(a) & (a >= lo) & (a <= hi))]
        _fail(name, rng or f"[{lo}, {hi}]", bad.flat[0])
    return a


#: Why the network's fields are :data:`swgsim.base.typed.LATER`.
_NETWORK = "a thermal network"


@dataclass
class ThermalNetwork:
    """A joint's heat in two nodes (:func:`network_temperatures`): the wave generator with
    its bearing, the flexspline's teeth and the grease (*grease*), and the housing with the
    flexspline's collar, the circular spline and the motor's stator (*housing*).

    The gear's loss heats the grease; the motor's copper loss and its drive's electronics
    heat the housing; the grease gives its heat to the housing through ``grease_r_k_per_w``
    while the gear turns and through ``standstill_factor`` times that at a stop (no
    churning: conduction alone) [choice]; the housing to the hall through the rest of the
    joint's resistance, r_th − ``grease_r_k_per_w`` (:class:`JointThermal`), with the time
    constant ``tau_min`` of :class:`JointThermal`. So at steady duty the grease sits
    ``grease_r_k_per_w`` · P_loss above the housing, and the whole joint at the gear's loss
    warms as the one-node model's. The drive is off over the daily stops.

    Attributes
    ----------
    grease_r_k_per_w : float
        Resistance grease -> housing while running [K/W], in (0, r_th): 0.06, a fifth of
        the joint's 0.3 K/W [choice: no measured split found].
    grease_c_j_per_k : float
        Heat capacity of the grease node [J/K], > 0: 300, about 0.6 kg of steel (wave
        generator, bearing, flexspline) at 460 J/(kg K) and 20 g of grease [derived from a
        size-20 component set's mass of some 0.6 kg, recall]; τ = 18 s running.
    standstill_factor : float
        The grease's resistance at a stop over that while running, >= 1 (4) [choice].
    motor_km_nm_per_sqrt_w : float
        The motor's constant K_m = T / √P_cu [N m/√W], > 0: 0.2, so the rated point (0.68
        N m at the input) loses 11 W in the copper against the gear's 32.5 W [choice: a
        frameless motor of this torque; a 2.2 N m servo motor of 0.49 N m/A and 3.07 Ω has
        0.28, derived from its data]. P_cu = (T_in / K_m)², T_in = T_load / N + P_loss / ω_in.
    drive_w : float
        The drive's electronics while powered [W], >= 0 (5) [choice].
    """

    grease_r_k_per_w: float = 0.06
    grease_c_j_per_k: float = 300.0
    standstill_factor: float = 4.0
    motor_km_nm_per_sqrt_w: float = 0.2
    drive_w: float = 5.0

    def check(self, key: str = "ThermalNetwork") -> None:
        """Refuse a field outside its range in one line naming ``<key>.<field>``.

        Raises
        ------
        ValueError
        """
        for name, unit in (("grease_r_k_per_w", "K/W"), ("grease_c_j_per_k", "J/K"),
                           ("motor_km_nm_per_sqrt_w", "N m/√W")):
            _positive(getattr(self, name), f"{key}.{name}", unit)
        _finite(self.standstill_factor, f"{key}.standstill_factor", 1.0, 1e3, "[1, 1000]")
        _finite(self.drive_w, f"{key}.drive_w", 0.0, 1e3, "[0, 1000] W")


@dataclass
class JointThermal:
    """Thermal model of a joint and its day (:func:`joint_temperature`); :meth:`check`
    refuses a field outside its range, naming it.

    Attributes
    ----------
    r_th_k_per_w : float
        Thermal resistance joint -> ambient (0.3) [K/W]: the paper's six operating points
        lose 23-122 W (mean 69 W, :func:`loss_power_w`), so its duty cycle warms the joint
        by about 21 K, the issue's "about 20 K" [choice]; the rated point alone (2000 rpm,
        52 N m, 32.5 W) by about 10 K [derived].
    tau_min : float
        Thermal time constant R_th C [min]: 30 [choice, an industrial joint]; measured on
        a UR3's six joints 32-46 min (docs/calibration.md, "A joint's warm-up"; preset
        ``small_cobot``, :data:`SMALL_COBOT_TAU_MIN`); C = 3000 J/K, e.g. 3.3 kg of
        aluminium at 900 J/(kg K) [derived]. Kept: the day could not calibrate R_th (its
        duty steady).
    ambient_c : float
        Hall temperature at the first start (20, the catalogue's reference) [°C].
    ambient_swing_k : float
        Day/night amplitude (3, a heated hall) [K] [choice], phase ``sin(2π t / 24 h)``,
        t the wall-clock hours since the first start, taken as 08:00: warmest at 14:00,
        coldest at 02:00, ``ambient_c`` at each day's start.
    ambient_points : list of [float, float]
        Slow offsets of the hall, ``[wall-clock hour, offset K]`` pairs, hours >= 0 and
        strictly increasing, linear in between, held outside (default none); the hall
        warming by 10 K over two days: ``[[0, 0], [48, 10]]``.
    run_h_per_day : float
        Operating hours per day before a stop, in (0, 24] (16: two shifts) [h] [choice].
        The stop lasts 24 − run_h_per_day wall-clock hours (8 h = 16 time constants: a
        cold start every day); 24 never stops. The life starts cold, at ambient.
    network : ThermalNetwork or None
        Two nodes instead of one (:func:`network_temperatures`): the grease, which the
        friction follows, and the housing, which the sensor and the bridges read; with it
        ``r_th_k_per_w`` is the grease's resistance to the hall while running and
        ``tau_min`` the housing's time constant. None: one node (:func:`joint_temperature`).
    """

    r_th_k_per_w: float = 0.3
    tau_min: float = 30.0
    ambient_c: float = 20.0
    ambient_swing_k: float = 3.0
    ambient_points: list[list[float]] = field(default_factory=list)
    run_h_per_day: float = 16.0
    network: ThermalNetwork | None = field(default=None, metadata={LATER: _NETWORK})

    @classmethod
    def preset(cls, name: str, **changes) -> JointThermal:
        """A named joint (:data:`THERMAL_PRESETS`), fields replaced by ``changes``.

        Raises
        ------
        ValueError
            One line listing the allowed names, for a name not in :data:`THERMAL_PRESETS`.
        """
        if name not in THERMAL_PRESETS:
            raise ValueError(f"thermal preset must be one of {', '.join(THERMAL_PRESETS)}, "
                             f"got {name!r}")
        return cls(**{**THERMAL_PRESETS[name], **changes})

    def check(self, key: str = "JointThermal") -> None:
        """Refuse a field outside its range in one line naming ``<key>.<field>``.

        Raises
        ------
        ValueError
        """
        for name, unit in (("r_th_k_per_w", "K/W"), ("tau_min", "min")):
            _positive(getattr(self, name), f"{key}.{name}", unit)
        _finite(self.ambient_c, f"{key}.ambient_c", -273.15, np.inf, "[-273.15, inf) °C")
        _finite(self.ambient_swing_k, f"{key}.ambient_swing_k", 0, np.inf, "[0, inf) K")
        _positive(self.run_h_per_day, f"{key}.run_h_per_day", "h", _HOURS_PER_DAY)
        try:
            pts = np.asarray(self.ambient_points, dtype=float).reshape(-1, 2)  # (n, 2)
        except ValueError:
            raise ValueError(f"{key}.ambient_points must be [hour, offset K] pairs, got "
                             f"{self.ambient_points}") from None
        _finite(pts[:, 0], f"{key}.ambient_points hours", 0.0, np.inf, "[0, inf) h")
        _finite(pts[:, 1], f"{key}.ambient_points offsets", rng="finite K")
        if np.any(np.diff(pts[:, 0]) <= 0):
            raise ValueError(f"{key}.ambient_points hours must increase strictly, got "
                             f"{pts[:, 0].tolist()}")
        if self.network is not None and not self.network.grease_r_k_per_w < self.r_th_k_per_w:
            raise ValueError(f"{key}.network.grease_r_k_per_w must lie below "
                             f"{key}.r_th_k_per_w ({self.r_th_k_per_w:g} K/W: the housing's "
                             f"own resistance is the rest), got {self.network.grease_r_k_per_w:g}")
        offsets = np.concatenate([[0.0], pts[:, 1]])
        lo = self.ambient_c - self.ambient_swing_k + offsets.min()
        hi = self.ambient_c + self.ambient_swing_k + offsets.max()
        if lo < TEMP_RANGE_C[0] or hi > TEMP_RANGE_C[1]:
            raise ValueError(f"{key}: the hall reaches {lo:g}..{hi:g} °C (ambient_c ± "
                             "ambient_swing_k + ambient_points offsets); it must stay within "
                             f"[{TEMP_RANGE_C[0]:g}, {TEMP_RANGE_C[1]:g}] °C, the viscosity "
                             "law's range")


#: The small cobot joint's time constant [min]: the median of a UR3's six joints, 32.1-45.9
#: min (docs/calibration.md, "A joint's warm-up": the Universal Robots UR3 CobotOps day,
#: one first-order fit per joint) [derived].
SMALL_COBOT_TAU_MIN = 35.45
#: Named joints, the fields each changes from :class:`JointThermal`'s defaults, selected
#: with :meth:`JointThermal.preset` or the config group ``thermal`` (``+thermal@dataset.
#: life.conditions.thermal=small_cobot``):
#:
#: * ``industrial``: the defaults (an industrial robot's joint, the paper's gear's duty);
#: * ``small_cobot``: a UR3-size joint, ``tau_min`` :data:`SMALL_COBOT_TAU_MIN`;
#:   ``r_th_k_per_w`` stays 0.3 K/W **[unverified]**: on one steady duty R_th is not
#:   separable from the hall's temperature (the fits give −9.6 to 26 K/W; J1's 2.2 ± 0.7
#:   K/W holds only with its copper term, whose gain follows the hall at r = −1.00), and
#:   2.2 K/W on this model's gear loss (mean 69 W) would warm the joint by about 150 K
#:   [derived].
#:
#: The defaults stay the industrial joint's: changing them would move every data set and
#: the monitor's figures, and the small cobot's τ lies inside the families' drawn 20-60 min.
THERMAL_PRESETS: dict[str, dict[str, float]] = {
    "industrial": {},
    "small_cobot": {"tau_min": SMALL_COBOT_TAU_MIN},
}


def wall_clock_h(operating_h, run_h_per_day: float) -> np.ndarray:
    """Wall-clock hours of operating hours, with the daily stops inserted.

    Day d runs from wall-clock hour 24 d for ``run_h_per_day`` hours, then stands until
    24 (d + 1); an operating hour on a day's boundary starts the next day, after the stop.

    Parameters
    ----------
    operating_h, run_h_per_day : array_like, shape (W,); float
        Operating hours since the first start, >= 0; hours per day, in (0, 24] [h].

    Returns
    -------
    ndarray, shape (W,)
        Wall-clock hours since the first start [h]; ValueError for values out of range.
    """
    run = _positive(run_h_per_day, "run_h_per_day", "h", _HOURS_PER_DAY)
    h = _finite(operating_h, "operating_h", 0.0, np.inf, "[0, inf) h")
    if run == _HOURS_PER_DAY:
        return h.copy()
    day = np.floor(h / run)
    return day * _HOURS_PER_DAY + (h - day * run)


def _offset_k(wall_h: np.ndarray, cfg: JointThermal) -> np.ndarray:
    """Piecewise-linear offset of the hall at wall-clock hours [K]."""
    pts = np.asarray(cfg.ambient_points).reshape(-1, 2)  # (n_points, 2)
    return np.interp(wall_h, pts[:, 0], pts[:, 1]) if len(pts) else np.zeros_like(wall_h)


def ambient_temperature(wall_h, cfg: JointThermal) -> np.ndarray:
    """Hall temperature ambient_c + swing sin(2π t / 24 h) + offset(t) [°C], shape of
    ``wall_h`` (wall-clock hours since the first start [h])."""
    t = np.asarray(wall_h, dtype=float)
    return (cfg.ambient_c + cfg.ambient_swing_k * np.sin(2 * np.pi * t / _HOURS_PER_DAY)
            + _offset_k(t, cfg))


def _grid(wall: np.ndarray, cfg: JointThermal) -> np.ndarray:
    """Event times [wall-clock h]: start, windows, stop starts and ends, ambient points."""
    last, run = wall[-1], cfg.run_h_per_day
    ev = [np.zeros(1), wall]
    if run < _HOURS_PER_DAY:
        days = np.arange(np.floor(last / _HOURS_PER_DAY))  # days that ended before `last`
        ev += [days * _HOURS_PER_DAY + run, (days + 1) * _HOURS_PER_DAY]
    if cfg.ambient_points:
        hrs = np.asarray(cfg.ambient_points)[:, 0]
        ev.append(hrs[(hrs > 0) & (hrs < last)])
    return np.unique(np.concatenate(ev))


def _forced_response(t, heat_k, offset, slope, cfg: JointThermal) -> np.ndarray:
    """Particular solution of τ T' + T = R P + T_amb(t) at times t [°C], for a constant
    heat R P (``heat_k`` [K]) and an offset of slope ``slope`` [K/h], ``offset`` at t:
    R P + ambient_c + offset − slope τ + S (sin ωt − ωτ cos ωt) / (1 + (ωτ)²), ω = 2π/24 h
    [derived: substitute]."""
    tau, w = cfg.tau_min / 60.0, 2 * np.pi / _HOURS_PER_DAY
    wt = w * tau
    swing = cfg.ambient_swing_k / (1.0 + wt * wt) * (np.sin(w * t) - wt * np.cos(w * t))
    return heat_k + cfg.ambient_c + offset - slope * tau + swing


def joint_temperature(operating_h, loss_w, cfg: JointThermal | None = None) -> np.ndarray:
    """Joint temperature at each window of a life: exact first-order response.

    C dT/dt = P(t) − (T − T_amb(t)) / R_th, τ = R_th C, from T = T_amb at the first start.
    Window i's loss holds from its operating hour to the next window's (window 0's from
    hour 0), and is 0 during the daily stops. Between events (windows, stop starts and
    ends, ambient breakpoints) the loss is constant and the ambient a sine plus a line, so
    each step is exact, T(t1) = T_p(t1) + (T(t0) − T_p(t0)) e^{−(t1−t0)/τ} with the
    particular solution T_p (:func:`_forced_response`); a loop over events, O(W).

    Parameters
    ----------
    operating_h : array_like, shape (W,)
        Operating hours of the windows since the first start, >= 0, non-decreasing [h].
    loss_w : array_like, shape (W,)
        Power loss of each window's operating point, >= 0 (:func:`loss_power_w`) [W].
    cfg : JointThermal, optional

    Returns
    -------
    ndarray, shape (W,)
        Joint temperature at the start of each window [°C]. ValueError for shapes not
        (W,) alike, hours negative or decreasing, losses negative, non-finite values.
    """
    cfg = cfg or JointThermal()
    cfg.check()
    h = _finite(operating_h, "operating_h", 0.0, np.inf, "[0, inf) h")
    p = _finite(loss_w, "loss_w", 0.0, np.inf, "[0, inf) W")
    if h.ndim != 1 or h.size == 0 or p.shape != h.shape:
        raise ValueError(f"operating_h, loss_w must share a shape (W,), got {h.shape}, {p.shape}")
    if np.any(np.diff(h) < 0):
        raise ValueError("operating_h must not decrease (windows in time order)")
    wall = wall_clock_h(h, cfg.run_h_per_day)
    g = _grid(wall, cfg)  # (K,) events; intervals (K - 1,)
    t0, t1 = g[:-1], g[1:]
    running = np.mod(0.5 * (t0 + t1), _HOURS_PER_DAY) < cfg.run_h_per_day
    i = np.maximum(np.searchsorted(wall, t0, side="right") - 1, 0)  # window of interval
    heat = np.where(running, cfg.r_th_k_per_w * p[i], 0.0)  # R P [K]
    off = _offset_k(g, cfg)
    slope = np.diff(off) / (t1 - t0)
    e = np.exp(-(t1 - t0) * 60.0 / cfg.tau_min)
    c = (_forced_response(t1, heat, off[1:], slope, cfg)
         - e * _forced_response(t0, heat, off[:-1], slope, cfg))
    t_start = float(ambient_temperature(0.0, cfg))
    temps = accumulate(zip(e.tolist(), c.tolist(), strict=True),  # T_k+1 = e_k T_k + c_k
                       lambda tk, ec: ec[0] * tk + ec[1], initial=t_start)
    return np.fromiter(temps, float, g.size)[np.searchsorted(g, wall)]


#: Longest step of :func:`network_temperatures` [h]: the hall's temperature is held at an
#: interval's midpoint value, so a stop is cut into steps of at most this; a 3-K day/night
#: swing moves by at most 0.2 K within one [derived].
NETWORK_STEP_H = 0.25


def network_temperatures(operating_h, loss_w, input_torque_nm, cfg: JointThermal
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Grease and housing temperatures at each window of a life, by the joint's two-node
    network (:class:`ThermalNetwork`).

    C_g dT_g/dt = P_loss − G (T_g − T_h), C_h dT_h/dt = P_cu + P_drive + G (T_g − T_h)
    − (T_h − T_amb) / R_ha, G = 1 / R_gh (R_gh times ``standstill_factor`` at a stop, when
    P_loss, P_cu and P_drive are 0), from T_g = T_h = T_amb at the first start. Each interval
    between events (windows, stops, the hall's breakpoints, at most :data:`NETWORK_STEP_H`
    long) holds its window's heat and the hall at its midpoint, and is stepped exactly,
    x1 = Φ x0 + Γ u, from the matrix exponential of [[A, B], [0, 0]] Δt (zero-order hold;
    Φ and Γ computed once per interval length and state) [derived].

    Parameters
    ----------
    operating_h : array_like, shape (W,)
        Operating hours of the windows, >= 0, non-decreasing [h].
    loss_w : array_like, shape (W,)
        The gear's loss at each window, >= 0 [W] (:func:`loss_power_w`).
    input_torque_nm : array_like, shape (W,)
        The motor's torque at each window [N m] (its copper loss, ``(T / K_m)²``).
    cfg : JointThermal
        With ``network`` set.

    Returns
    -------
    grease_c, housing_c : ndarray, shape (W,)
        Temperatures at the start of each window [°C].

    Raises
    ------
    ValueError
        ``cfg.network`` None, a field out of range, shapes not (W,) alike, hours negative
        or decreasing, a loss negative, non-finite values.
    """
    from scipy.linalg import expm

    cfg.check()
    net = cfg.network
    if net is None:
        raise ValueError("network_temperatures needs JointThermal.network (two nodes), got None")
    net.check("JointThermal.network")
    h = _finite(operating_h, "operating_h", 0.0, np.inf, "[0, inf) h")
    p = _finite(loss_w, "loss_w", 0.0, np.inf, "[0, inf) W")
    tq = _finite(input_torque_nm, "input_torque_nm", rng="finite N m")
    if h.ndim != 1 or h.size == 0 or p.shape != h.shape or tq.shape != h.shape:
        raise ValueError(f"operating_h, loss_w, input_torque_nm must share a shape (W,), got "
                         f"{h.shape}, {p.shape}, {tq.shape}")
    if np.any(np.diff(h) < 0):
        raise ValueError("operating_h must not decrease (windows in time order)")
    wall = wall_clock_h(h, cfg.run_h_per_day)
    g = _grid(wall, cfg)
    pieces = np.maximum(np.ceil(np.diff(g) / NETWORK_STEP_H), 1).astype(int)
    seg = np.repeat(np.arange(pieces.size), pieces)  # each interval in equal steps, as
    j = np.arange(seg.size) - np.repeat(np.cumsum(pieces) - pieces, pieces)  # linspace
    g = np.concatenate([j * (np.diff(g) / pieces)[seg] + g[:-1][seg], g[-1:]])
    t0, t1 = g[:-1], g[1:]
    mid = 0.5 * (t0 + t1)
    running = np.mod(mid, _HOURS_PER_DAY) < cfg.run_h_per_day
    i = np.maximum(np.searchsorted(wall, t0, side="right") - 1, 0)
    heat_h = p[i]
    heat_c = (tq[i] / net.motor_km_nm_per_sqrt_w) ** 2 + net.drive_w
    u = np.column_stack([np.where(running, heat_h, 0.0), np.where(running, heat_c, 0.0),
                         ambient_temperature(mid, cfg)])  # (K - 1, 3)
    r_ha = cfg.r_th_k_per_w - net.grease_r_k_per_w
    c_h = cfg.tau_min * 60.0 / r_ha
    step: dict[tuple[bool, float], tuple[np.ndarray, np.ndarray]] = {}
    x = np.full(2, float(ambient_temperature(0.0, cfg)))
    out = np.empty((g.size, 2))
    out[0] = x
    for k, (run, dt) in enumerate(zip(running.tolist(), np.round(t1 - t0, 12).tolist(),
                                      strict=True)):
        if (run, dt) not in step:
            gg = 1.0 / (net.grease_r_k_per_w * (1.0 if run else net.standstill_factor))
            m = np.zeros((5, 5))
            m[:2, :2] = [[-gg / net.grease_c_j_per_k, gg / net.grease_c_j_per_k],
                         [gg / c_h, -(gg + 1.0 / r_ha) / c_h]]
            m[:2, 2:] = [[1.0 / net.grease_c_j_per_k, 0.0, 0.0],
                         [0.0, 1.0 / c_h, 1.0 / (r_ha * c_h)]]
            e = expm(m * dt * 3600.0)
            step[(run, dt)] = e[:2, :2], e[:2, 2:]
        phi, gamma = step[(run, dt)]
        x = phi @ x + gamma @ u[k]
        out[k + 1] = x
    at = out[np.searchsorted(g, wall)]
    return at[:, 0], at[:, 1]


def traced_temperature(operating_h, trace_h, rise_k, cfg: JointThermal | None = None,
                       scale: float = 1.0) -> np.ndarray:
    """Joint temperature at each window of a life that follows a measured warm-up: the
    hall's temperature plus ``scale`` times the measured rise since the day's cold start.

    Every operating day of ``cfg`` starts cold (the stops of ``run_h_per_day``; a day of 24
    h never stops: one start, at hour 0); at t operating hours since it the joint is
    ``ambient_temperature(wall) + scale · rise(t)``, the rise linear between the trace's
    points and held at its last beyond them. Held constant against
    :func:`joint_temperature`: the rise does not depend on the life's operating point or
    payload (it is the measured joint's, at its own duty), ``r_th_k_per_w`` and ``tau_min``
    do not enter, a stop cools the joint completely, and the rise rides on the hall's
    swing and drift as they are at each window.

    Parameters
    ----------
    operating_h : array_like, shape (W,)
        Operating hours of the windows since the first start, >= 0 [h].
    trace_h : array_like, shape (N,)
        Hours of the measured rise since its start, 0 first, increasing [h].
    rise_k : array_like, shape (N,)
        Measured temperature minus its first reading [K] (0 first).
    cfg : JointThermal, optional
        The hall and the operating day (``r_th_k_per_w``, ``tau_min`` unused).
    scale : float
        Factor on the rise, in [0, 10] [-].

    Returns
    -------
    ndarray, shape (W,)
        Joint temperature [°C].

    Raises
    ------
    ValueError
        A value out of its range, shapes not as above, ``trace_h`` not increasing from 0.
    """
    cfg = cfg or JointThermal()
    cfg.check()
    h = _finite(operating_h, "operating_h", 0.0, np.inf, "[0, inf) h")
    t = _finite(trace_h, "trace_h", 0.0, np.inf, "[0, inf) h")
    r = _finite(rise_k, "rise_k", rng="finite K")
    if t.ndim != 1 or t.size == 0 or r.shape != t.shape or t[0] != 0.0 \
            or np.any(np.diff(t) <= 0):
        raise ValueError(f"trace_h, rise_k must share a shape (N,), trace_h increasing from "
                         f"0 h, got {t.shape}, {r.shape}")
    k = float(_finite(scale, "scale", 0.0, 10.0, "[0, 10]"))
    run = cfg.run_h_per_day
    since = h if run >= _HOURS_PER_DAY else h - np.floor(h / run) * run
    return ambient_temperature(wall_clock_h(h, run), cfg) + k * np.interp(since, t, r)


def steady_rise_k(loss_w, cfg: JointThermal | None = None) -> np.ndarray:
    """Steady rise over ambient, R_th P_loss [K], shape of ``loss_w`` (loss [W])."""
    cfg = cfg or JointThermal()
    return cfg.r_th_k_per_w * np.asarray(loss_w, dtype=float)


def viscosity_ratio(temp_c, ref_c: float = REF_TEMP_C) -> np.ndarray:
    """Viscosity of the grease relative to the reference, ν(T) / ν(T_ref) [-].

    Reynolds' exponential law ν ∝ exp(−k T), the classic viscosity-temperature relation
    of lubricants over a limited range, k = 0.035 1/K [choice: the issue's value]. The
    grease's base-oil viscosities, to anchor the Walther law (ASTM D341), were not found;
    through typical mineral oils (ISO VG 32-100) Walther gives 0.058-0.071 1/K at 20 °C
    [derived]: 0.035 is an effective coefficient, anchored at 0..40 °C on the issue's
    no-load torque factors (:func:`friction_scale`) [unverified]; −40..150 °C accepted.

    Parameters
    ----------
    temp_c, ref_c : array_like; float
        Grease temperature; reference temperature (20) [°C].

    Returns
    -------
    ndarray, shape of ``temp_c``
        ν(T) / ν(ref) [-]. ValueError for a temperature outside [−40, 150] °C.
    """
    rng = f"[{TEMP_RANGE_C[0]:g}, {TEMP_RANGE_C[1]:g}] °C"
    t = _finite(temp_c, "temp_c", *TEMP_RANGE_C, rng)
    r = _finite(ref_c, "ref_c", *TEMP_RANGE_C, rng)
    return np.exp(-VISCOSITY_COEFF_PER_K * (t - r))


def friction_scale(temp_c, ref_c: float = REF_TEMP_C,
                   exponent: float = FRICTION_EXPONENT) -> np.ndarray:
    """Factor on the load-independent friction at a temperature, (ν(T)/ν(ref))^m [-].

    For b0_nm, b1_nms, b2_nms3, b3_nm of :class:`swgsim.gear.dynamics.GearParams` (churning,
    the wave generator's bearing, seals); μ, the mesh's load-proportional term, is kept
    [choice: boundary friction taken as independent of temperature]. The no-load running
    torque scales by the factor exactly: ×1.595 at 0 °C, ×0.627 at 40 °C, the issue's ×1.6
    and ×0.63 [unverified: the catalogue curves could not be read]; rated-point efficiency
    of :func:`swgsim.gear.dynamics.rt1_size20` 70.5 / 77.0 / 81.7 % at 0 / 20 / 40 °C, the
    issue's roughly 69 / 77 / 82 % (tests/swgsim/test_thermal.py).

    Parameters
    ----------
    temp_c, ref_c : array_like; float
        Joint temperature, in [−40, 150]; that of the nominal coefficients (20) [°C].
    exponent : float
        m (:data:`FRICTION_EXPONENT`, 2/3) [-].

    Returns
    -------
    ndarray, shape of ``temp_c``
        Factor, 1 at ``ref_c`` [-]; refusals as :func:`viscosity_ratio`.
    """
    return viscosity_ratio(temp_c, ref_c) ** exponent


#: Forms of :class:`FrictionLaw` that fall monotonically as the joint warms.
MONOTONE_FORMS = ("exponential", "linear", "saturating")
#: Forms of :class:`FrictionLaw` (how friction follows temperature): the monotone ones and
#: one whose slope changes sign.
FRICTION_FORMS = (*MONOTONE_FORMS, "u_shaped")
#: Temperatures the ``u_shaped`` form's minimum may take [°C]: inside ABB's joint friction
#: map, 30-80 °C (Bittencourt and Axelsson 2014) [src: that range], and from 45 up, so that
#: the rise beyond stays moderate (×1.7 at 80 °C at the steepest, r = 0.3, T_m = 45)
#: [choice; at 30 the 20 and 40 °C points sit symmetric about the minimum].
U_MINIMUM_RANGE_C = (45.0, 80.0)
#: Lowest factor any form gives [-]: friction does not vanish [choice].
FACTOR_FLOOR = 0.2
#: Width of the saturating form's tanh [K] [choice: it saturates over the −40..80 °C of a
#: joint's life].
SATURATING_WIDTH_K = 20.0


@dataclass
class FrictionLaw:
    """How a joint's load-independent friction follows its temperature: a family of smooth
    monotone laws, so that an evaluation can draw a joint's law instead of sharing one with
    the method it scores (docs/PHYSICS.md; issue 44).

    Every form gives the factor φ(T) on the load-independent friction, 1 at
    :data:`REF_TEMP_C` and ``ratio_40c`` at 40 °C, the one point the sources fix (the
    no-load running torque about ×0.63 at 40 °C against 20 °C, the issue's figure derived
    from the grease's viscosity, :func:`friction_scale`) **[derived]**; they differ away
    from it, where no source fixes the law:

    * ``exponential``: φ = r^((T − 20)/20), the viscosity law's form (with ``ratio_40c``
      None exactly :func:`friction_scale`): ×1.6 at 0 °C;
    * ``linear``: φ = 1 + (r − 1)(T − 20)/20, floored at 0.2 (friction does not vanish):
      ×1.37 at 0 °C;
    * ``saturating``: φ = 1 − A tanh((T − 20)/w), A = (1 − r)/tanh(20/w), w =
      :data:`SATURATING_WIDTH_K`: ×1.37 at 0 °C as the linear, ×0.51 at 80 °C (linear 0.2),
      bounded by 1 ± A;
    * ``u_shaped``: φ = 1 + c ((T − T_m)² − (20 − T_m)²), c = (r − 1) / (20 (60 − 2 T_m)),
      its slope changing sign at T_m = ``minimum_c``: friction that falls as the film
      thickens and rises again as a thin, hot grease lets the surfaces touch (mixed
      lubrication; static friction rising above a grease's working range [recall, REAL-DAY
      background: Bittencourt et al.]), for the Coulomb term (``coulomb_law`` of the
      conditions); with r = 0.63 and T_m = 50 °C: ×1.74 at 0 °C, ×0.58 at 50, ×1.00 at 80.

    The linear and the u-shaped forms are floored at :data:`FACTOR_FLOOR`.

    Attributes
    ----------
    form : {"exponential", "linear", "saturating", "u_shaped"}
    ratio_40c : float or None
        r = φ(40 °C), in [0.3, 1]; None: the catalogue-anchored value of
        :func:`friction_scale` (0.627).
    minimum_c : float
        T_m of the ``u_shaped`` form, in :data:`U_MINIMUM_RANGE_C` [°C] (50); the other
        forms do not read it.
    """

    form: str = "exponential"
    ratio_40c: float | None = None
    minimum_c: float = field(default=50.0, metadata={LATER: "u-shaped laws"})

    def check(self, key: str = "FrictionLaw") -> None:
        """Refuse an unknown form or a ratio outside [0.3, 1], naming ``<key>.<field>``.

        Raises
        ------
        ValueError
        """
        if self.form not in FRICTION_FORMS:
            raise ValueError(f"{key}.form: {self.form!r}; allowed: {', '.join(FRICTION_FORMS)}")
        if self.ratio_40c is not None:
            _finite(self.ratio_40c, f"{key}.ratio_40c", 0.3, 1.0, "[0.3, 1]")
        lo, hi = U_MINIMUM_RANGE_C
        _finite(self.minimum_c, f"{key}.minimum_c", lo, hi, f"[{lo:g}, {hi:g}] °C")

    def factor(self, temp_c) -> np.ndarray:
        """φ(T) on the load-independent friction [-].

        Parameters
        ----------
        temp_c : array_like
            Joint temperature, in [−40, 150] [°C].

        Returns
        -------
        ndarray, shape of ``temp_c``
            1 at 20 °C, ``ratio_40c`` at 40 °C; ValueError outside the temperature range.
        """
        if self.form == "exponential" and self.ratio_40c is None:
            return friction_scale(temp_c)
        t = _finite(temp_c, "temp_c", *TEMP_RANGE_C,
                    f"[{TEMP_RANGE_C[0]:g}, {TEMP_RANGE_C[1]:g}] °C")
        r = float(friction_scale(40.0)) if self.ratio_40c is None else float(self.ratio_40c)
        x = (t - REF_TEMP_C) / 20.0
        if self.form == "exponential":
            return r ** x
        if self.form == "linear":
            return np.maximum(1.0 + (r - 1.0) * x, FACTOR_FLOOR)
        if self.form == "u_shaped":
            tm = self.minimum_c
            c = (r - 1.0) / (20.0 * (60.0 - 2.0 * tm))
            return np.maximum(1.0 + c * ((t - tm) ** 2 - (REF_TEMP_C - tm) ** 2), FACTOR_FLOOR)
        a = (1.0 - r) / np.tanh(20.0 / SATURATING_WIDTH_K)
        return 1.0 - a * np.tanh((t - REF_TEMP_C) / SATURATING_WIDTH_K)


def run_in_factor(operating_h, drop: float = RUN_IN_DROP,
                  tau_h: float = RUN_IN_TAU_H) -> np.ndarray:
    """Friction multiplier of a gear running in, 1 + drop · exp(−h / τ) [-].

    Convention: the nominal friction (the catalogue fit) is the run-in state; the factor
    tends to 1, a new gear starts at 1 + drop. Lubricant redistribution while running is
    the mechanism (Universal Robots, module docstring) [src]; no measured curve: 0.16 and
    30 h give the issue's +3 points of rated-point efficiency over about 30 h [choice].

    Parameters
    ----------
    operating_h, tau_h : array_like; float
        Operating hours since the first start, >= 0; time constant, > 0 [h].
    drop : float
        Relative excess friction of a new gear, in [0, 1] [-].

    Returns
    -------
    ndarray, shape of ``operating_h``
        Multiplier on all friction (:func:`gear_at_temperature`) [-]; ValueError if out
        of range.
    """
    h = _finite(operating_h, "operating_h", 0.0, np.inf, "[0, inf) h")
    d = float(_finite(drop, "drop", 0.0, 1.0, "[0, 1]"))
    return 1.0 + d * np.exp(-h / _positive(tau_h, "tau_h", "h"))


def regrease_factor(operating_h, at_h, drop: float = REGREASE_DROP,
                    tau_h: float = REGREASE_TAU_H) -> np.ndarray:
    """Friction multiplier of a gear re-greased in service, 1 + drop · exp(−(h − h_r) / τ)
    from the latest re-greasing h_r <= h on, 1 before the first [-].

    The latest re-greasing alone counts (not the product over all): fresh grease replaces
    the old, and the churning starts again from the new fill whatever was left of the last
    one [choice]. Like :func:`run_in_factor`, the nominal friction is the settled state.

    Parameters
    ----------
    operating_h : array_like
        Operating hours, >= 0 [h].
    at_h : array_like, shape (R,)
        Operating hours of the re-greasings, increasing, >= 0 [h].
    drop : float
        Relative excess friction just after a re-greasing, in [0, 1] [-]
        (:data:`REGREASE_DROP`).
    tau_h : float
        Time constant of running in again, > 0 [operating h] (:data:`REGREASE_TAU_H`).

    Returns
    -------
    ndarray, shape of ``operating_h``
        Multiplier on all friction (:func:`gear_at_temperature`) [-]; 1 + drop at each
        re-greasing, back towards 1 with τ.

    Raises
    ------
    ValueError
        A value out of its range, ``at_h`` not increasing.
    """
    h = _finite(operating_h, "operating_h", 0.0, np.inf, "[0, inf) h")
    at = np.atleast_1d(_finite(at_h, "at_h", 0.0, np.inf, "[0, inf) h"))
    if at.ndim != 1 or np.any(np.diff(at) <= 0):
        raise ValueError(f"at_h must be increasing operating hours, got {at.tolist()}")
    d = float(_finite(drop, "drop", 0.0, 1.0, "[0, 1]"))
    tau = _positive(tau_h, "tau_h", "h")
    k = np.searchsorted(at, h, side="right") - 1  # the latest re-greasing, -1: none yet
    since = h - at[np.maximum(k, 0)] if at.size else np.zeros_like(h)
    return np.where(k >= 0, 1.0 + d * np.exp(-np.maximum(since, 0.0) / tau), 1.0)


def gear_at_temperature(gear: GearParams, temp_c: float, run_in: float = 1.0) -> GearParams:
    """The gear's friction coefficients at a temperature and a run-in state.

    b0, b1, b2, b3 times ``friction_scale(temp_c) · run_in`` (b3 with b0, whose 6 % it
    is, docs/PHYSICS.md sec. 1.4), μ times ``run_in``; all else kept. 20 °C and
    ``run_in`` = 1 return a gear equal to the input (factors exactly 1).

    Parameters
    ----------
    gear : GearParams
        Nominal gear, run in, at 20 °C (:func:`swgsim.gear.dynamics.rt1_size20`).
    temp_c, run_in : float
        Joint temperature, in [−40, 150] [°C]; run-in multiplier, > 0
        (:func:`run_in_factor`) [-].

    Returns
    -------
    GearParams
        ValueError for a temperature outside its range, ``run_in`` <= 0, or an array.
    """
    if np.ndim(temp_c):
        raise ValueError("gear_at_temperature takes a scalar temp_c")
    r = _positive(run_in, "run_in", "")
    f = float(friction_scale(temp_c)) * r
    return dataclasses.replace(gear, b0_nm=gear.b0_nm * f, b1_nms=gear.b1_nms * f,
                               b2_nms3=gear.b2_nms3 * f, b3_nm=gear.b3_nm * f,
                               mu=gear.mu * r)


def _steady_friction(gear: GearParams, n_in_rpm, t_out_nm, friction=1.0, mu_factor=1.0,
                     coulomb=None):
    """Steady friction torque T_fric [N m] and flank speed v [rad/s], broadcast: with
    v = ω_in / (N sin α) and c T_stiff = T_load + T_fric / sin α, eq. (5) (b3 averaging
    out) gives T_fric = (f_c b0 s + f (b1 v + b2 v³) + m μ s T_load / cos α) / (1 − m μ s /
    (sin α cos α)), s = tanh(v / v_s), f, f_c and m the factors on the viscous terms, on
    the Coulomb term (``coulomb``; None: f) and on μ (:func:`gear_at_temperature`;
    docs/PHYSICS.md sec. 1.4, as in ``fit_friction``)."""
    n = _finite(n_in_rpm, "n_in_rpm", 0.0, np.inf, "(0, inf) rpm")
    t = _finite(t_out_nm, "t_out_nm", 0.0, np.inf, "[0, inf) N m")
    if np.any(n <= 0):
        _fail("n_in_rpm", "(0, inf) rpm", n[n <= 0].flat[0])
    f = _finite(friction, "friction", 0.0, np.inf, "(0, inf)")
    m = _finite(mu_factor, "mu_factor", 0.0, np.inf, "(0, inf)")
    sa, ca = np.sin(gear.alpha_tooth_rad), np.cos(gear.alpha_tooth_rad)
    v = n * RPM / (gear.ratio * sa)
    s = np.tanh(v / gear.v_smooth_rad_s)
    mu = gear.mu * m
    if coulomb is None:  # one factor on every load-independent term (the same bits as ever)
        free = f * (gear.b0_nm * s + gear.b1_nms * v + gear.b2_nms3 * v**3)
    else:
        fc = _finite(coulomb, "coulomb", 0.0, np.inf, "(0, inf)")
        free = fc * gear.b0_nm * s + f * (gear.b1_nms * v + gear.b2_nms3 * v**3)
    num = free + mu * s * t / ca
    return num / (1.0 - mu * s / (sa * ca)), v, t


def steady_efficiency(gear: GearParams, n_in_rpm, t_out_nm, friction=1.0,
                      mu_factor=1.0, coulomb=None) -> np.ndarray:
    """Efficiency of the model in steady state, T_load / (T_load + T_fric / sin α) [-].

    The energy balance of :mod:`swgsim.gear.dynamics` (docs/PHYSICS.md sec. 1.5), which
    has no function for it (:func:`swgsim.gear.dynamics.fit_friction` solves it for b1
    and μ).

    Parameters
    ----------
    gear : GearParams
    n_in_rpm, t_out_nm : array_like
        Input speed, > 0 [rpm]; load torque, >= 0 [N m]; broadcast together.
    friction, mu_factor : array_like
        Factors on the load-independent friction (b0, b1, b2; the temperature's and the
        run-in's, :func:`gear_at_temperature`) and on μ (the run-in's), > 0 [-];
        broadcast with the speeds.
    coulomb : array_like, optional
        Factor on the Coulomb term b0 alone, > 0 [-]; ``friction`` then acts on the
        viscous terms b1, b2 only (viscous and Coulomb friction following their own laws,
        :class:`swgsim.datasets.conditions.ConditionsConfig`); None: ``friction`` on all.

    Returns
    -------
    ndarray, broadcast shape
        Efficiency, 0 at no load [-]; ValueError for a speed <= 0, a negative torque.
    """
    tf, _, t = _steady_friction(gear, n_in_rpm, t_out_nm, friction, mu_factor, coulomb)
    return t / (t + tf / np.sin(gear.alpha_tooth_rad))


def loss_power_w(gear: GearParams, n_in_rpm, t_out_nm) -> np.ndarray:
    """Power lost in the gear in steady state, P_in − P_out = T_fric φ̇_b [W], broadcast
    over ``n_in_rpm`` [rpm] and ``t_out_nm`` [N m] as :func:`steady_efficiency`."""
    tf, v, _ = _steady_friction(gear, n_in_rpm, t_out_nm)
    return tf * v


def no_load_torque_nm(gear: GearParams, n_in_rpm) -> np.ndarray:
    """No-load running torque at the input, P_in / ω_in at zero load [N m], shape of
    ``n_in_rpm`` [rpm]: the catalogue's 0.105 N m at 2000 rpm (docs/PHYSICS.md sec. 2)."""
    n = np.asarray(n_in_rpm, dtype=float)
    return loss_power_w(gear, n, 0.0) / (n * RPM)
