"""Is one sensor's fault enough to explain an alarm? The test that keeps sensor faults
from being named as gear faults (the analytical redundancy of sensor fault isolation).

:func:`fit_bridge_faults` and :func:`fit_sensor_faults` fit each one-bridge fault to the
windows since the alarm (:class:`SensorFit`), judged window by window
(:func:`~.hypotheses.log_odds`) and on the other bridges together
(:attr:`NamingConfig.rest_max`);
:func:`fit_temperature`, :func:`fit_temperature_drift` and :func:`still_reading` test the
joint's temperature sensor, :func:`virtual_temperature` replaces a failed one (an even
change of friction, the other hypothesis: :mod:`.unexplained`). Design and source (Frank
1990): docs/monitor/assessment.md, "Naming a sensor fault" and
"The monitor checks its temperature sensor".
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field

import numpy as np

from swgmon.detection.normal import BLOCK, Conditions, NormalBehaviour
from swgsim.base.lazy import lazy_module
from swgsim.base.typed import allowed
from swgsim.sensing.sensor_faults import SENSOR_FAULTS

stats = lazy_module("scipy.stats")  # at the first naming, not at an app's start


@dataclass
class NamingConfig:
    """The numbers the naming of an alarm was tuned or chosen with (issue 84: every
    constant on record), one typed object: ``monitor.study.naming`` of the evaluation,
    ``naming`` of ``swgsim-monitor``, logged with every run. Design and sources:
    docs/monitor/assessment.md.

    Attributes
    ----------
    prior_odds : float
        Prior odds of a hypothesis that fitted (significant at ``fit_level``, the other
        bridges within ``rest_max``) against its windows staying abnormal, in
        [10^-6, 10^6] (1.0 [declared, not tuned]: even odds; the rule,
        :func:`~.hypotheses.log_odds`, names it where the posterior odds exceed 1).
    right_median_p, wrong_median_p : float
        The least median conformal p-value a hypothesis that explains an alarm leaves its
        windows at (0.43), and the largest one that does not (0.23), in (0, 0.5), the
        second below the first: the priors of :func:`~.hypotheses.log_odds` (Beta(ξ, 1)
        p-values, ξ uniform over the exponents of medians above the first, or below the
        second). Read on the training gears (``scripts/naming_study.py``, trained on gear
        1, judged on gear 2, an hour of windows): the right fit of every sensor fault on
        every bridge left 0.43-0.76 (bench; robot_joint from 0.438); the best plausible
        one-bridge fit of a gear fault at most 0.231 (bench) and 0.223 (robot_joint).
    rest_max : float
        Largest mean shift left on the other bridges (:attr:`SensorFit.rest`) for a
        one-bridge fit to explain an alarm, > 0 (2.5). Chosen on the training gears of both
        presets (``scripts/naming_study.py --dataset bench|robot_joint``): the right fit of
        each of the 100 sensor-fault lives per preset left 0.51-1.82, the gear-fault lives
        with a median p-value above 0.2 3.33-9.48; about the geometric middle of the gap.
    temperature_step_k : float
        Step of the temperatures :func:`fit_temperature` tries, in (0, 5] [K] (0.25).
    temperature_min_k : float
        Least median distance (unsigned) of the fitted temperature from the reading for the
        reading to be wrong, in [0, 50] [K] (2.0: ten times the reading's uncertainty of
        0.2 K, ``NormalConfig.temperature_uncertainty_k``; unsigned: a reading stuck at a
        warm joint's temperature lies above the true one in the cool phases and below it in
        the hot ones, bench gear 3, family ``sensor_stuck``, design seed 100).
    drift_min_k : float
        Least median distance of a drift's fitted temperature from the reading
        (:func:`fit_temperature_drift`), in [0, 50] [K] (0.4: twice the reading's
        uncertainty [choice]).
    drift_rate_k_per_h : float
        Largest rate of a drifting reading :func:`fit_temperature_drift` tries first, on
        ``drift_rate_points`` rates from minus it, in (0, 10] [K/h] (0.6: the families'
        ±0.5 K/h and a little beyond).
    drift_rate_points : int
        Rates it tries first, odd (zero among them), in [3, 999] (13 [choice]: a step of
        0.1 K/h at 0.6).
    drift_offset_step_k : float
        Step of the offsets it tries first, over ±``temperature_beyond_k``, in (0, 20] [K]
        (1.0 [choice]).
    drift_fine_k, drift_fine_k_per_h : float
        Steps of its second grid, over half a first step on either side of the first
        grid's best offset and rate, in (0, 5] [K] and (0, 1] [K/h] (0.125 and 0.01
        [choice]: an eighth and a tenth of the first steps).
    coarse_step_k : float
        Step of the coarse grid :func:`best_temperature` starts from, in (0, 20] [K] (2.0).
    coarse_steps : int
        Fine steps it then tries on either side of the coarse best, in [1, 100] (6: to half
        a coarse step beyond).
    temperature_beyond_k : float
        How far beyond commissioning's temperature range the fits look, in [0, 100] [K]
        (20: the hall's drift over a season, 10-20 K).
    virtual_windows : int
        Windows of the running median of :func:`virtual_temperature`, odd, in [1, 999] (7).
    still_h : float
        Least time a temperature reading stays the same, to the bit, for
        :func:`still_reading` to judge it, in (0, 100] [h] (0.25 [choice]: the UR3's six
        joint readings over a working day, UR3 CobotOps, Tyrovolas et al. 2024, CC BY 4.0,
        held one value for at most 1.4 min).
    still_moved_k : float
        Least range of the virtual temperature over such a run for the reading to be stuck,
        in [0, 100] [K] (4.0: twice ``temperature_min_k`` [choice]; at once
        ``temperature_min_k`` the tiny real day's whole-kelvin readings were taken for
        stuck).
    friction_refine : int
        Factors and rates :func:`~.unexplained.fit_friction` refines its grid's best with,
        over one grid step on either side, odd, in [3, 99] (9).
    law_level : float
        One-sided level of the test whether commissioning's laws hold at a point's new
        load (:meth:`~.gear_monitor.GearMonitor.commission` after a tool change), in
        (0, 0.5) (0.01: declared, not tuned).
    recur_h : float
        How far back an earlier unexplained change makes the next one recurring
        (:func:`swgmon.advisories.stream.run_stream`), in [0, 10^4] [h] (24: a day, in
        which a drifting reading's ±0.5 K/h reach 12 K [choice]).
    virtual_passes : int
        Passes of the virtual temperature and the friction factor after a lost reading
        (:func:`swgmon.advisories.stream.read_without`), in [0, 10] (2 [choice, on design
        seeds: family lost_running_in, seeds 100-104, after 0, 1 and 2 passes gear-fault
        alarms 140, 0, 0 per 1000 h on bench gear 3, 152, 3, 0 on robot_joint gear 2]).
    fit_level : float
        How often a hypothesis's fit may count where its effect is absent, in (0, 0.5)
        (0.001 [choice]: a bridge without a fault fitted one in a thousand times): a fit
        of k parameters counts where it lowers Σ z² by the χ²_k quantile 1 − ``fit_level``
        (:meth:`least_reduction`; Wilks' theorem, twice the log-likelihood ratio).
    hypotheses : list of str or None
        The hypotheses an alarm is weighed against, and the checks the stream asks
        (:class:`~.hypotheses.ReadingCheck`), in order: names registered in
        :data:`~.hypotheses.HYPOTHESES`; None: every registered one.
    windows_at_once : int
        Windows the temperature fits take at once, in [16, 10^5] (512 [choice]: about
        10 MB an array); memory only, no result changes.
    """

    prior_odds: float = field(default=1.0, metadata=allowed(1e-6, 1e6))
    right_median_p: float = field(default=0.43, metadata=allowed(0.0, 0.5, lo_open=True,
                                                                 hi_open=True))
    wrong_median_p: float = field(default=0.23, metadata=allowed(0.0, 0.5, lo_open=True,
                                                                 hi_open=True))
    rest_max: float = field(default=2.5, metadata=allowed(0.0, 1e4, lo_open=True))
    temperature_step_k: float = field(default=0.25, metadata=allowed(0.0, 5.0, lo_open=True,
                                                                     unit="K"))
    temperature_min_k: float = field(default=2.0, metadata=allowed(0.0, 50.0, unit="K"))
    drift_min_k: float = field(default=0.4, metadata=allowed(0.0, 50.0, unit="K"))
    drift_rate_k_per_h: float = field(default=0.6, metadata=allowed(0.0, 10.0, lo_open=True,
                                                                    unit="K/h"))
    drift_rate_points: int = field(default=13, metadata=allowed(3, 999))
    drift_offset_step_k: float = field(default=1.0, metadata=allowed(0.0, 20.0, lo_open=True,
                                                                     unit="K"))
    drift_fine_k: float = field(default=0.125, metadata=allowed(0.0, 5.0, lo_open=True,
                                                                unit="K"))
    drift_fine_k_per_h: float = field(default=0.01, metadata=allowed(0.0, 1.0, lo_open=True,
                                                                     unit="K/h"))
    coarse_step_k: float = field(default=2.0, metadata=allowed(0.0, 20.0, lo_open=True,
                                                               unit="K"))
    coarse_steps: int = field(default=6, metadata=allowed(1, 100))
    temperature_beyond_k: float = field(default=20.0, metadata=allowed(0.0, 100.0, unit="K"))
    virtual_windows: int = field(default=7, metadata=allowed(1, 999))
    still_h: float = field(default=0.25, metadata=allowed(0.0, 100.0, lo_open=True, unit="h"))
    still_moved_k: float = field(default=4.0, metadata=allowed(0.0, 100.0, unit="K"))
    friction_refine: int = field(default=9, metadata=allowed(3, 99))
    law_level: float = field(default=0.01, metadata=allowed(0.0, 0.5, lo_open=True,
                                                            hi_open=True))
    recur_h: float = field(default=24.0, metadata=allowed(0.0, 1e4, unit="h"))
    virtual_passes: int = field(default=2, metadata=allowed(0, 10))
    fit_level: float = field(default=0.001, metadata=allowed(0.0, 0.5, lo_open=True,
                                                             hi_open=True))
    hypotheses: list[str] | None = None
    windows_at_once: int = field(default=512, metadata=allowed(16, 10**5))

    def check(self, where: str = "naming") -> None:
        """Refuse an even window count where an odd one is needed, in one line naming the
        key (the ranges are the fields' metadata, :func:`swgsim.base.typed.check_tree`).

        Raises
        ------
        ValueError
            ``virtual_windows``, ``friction_refine`` or ``drift_rate_points`` even;
            ``wrong_median_p`` not below ``right_median_p``.
        """
        if self.wrong_median_p >= self.right_median_p:
            raise ValueError(f"{where}.wrong_median_p must lie below {where}.right_median_p "
                             f"({self.right_median_p}), got {self.wrong_median_p}")
        for name in ("virtual_windows", "friction_refine", "drift_rate_points"):
            if getattr(self, name) % 2 == 0:
                raise ValueError(f"{where}.{name} must be odd (its own window in the "
                                 f"middle), got {getattr(self, name)}")

    def least_reduction(self, dof: int) -> float:
        """Smallest reduction of Σ z² for a fit of ``dof`` parameters to count: the χ²
        quantile 1 − :attr:`fit_level` with ``dof`` degrees of freedom [-] (1: a sensor's
        step or a temperature per window; 2: a gain drift's level and rate; 3: a
        friction or temperature drift's step, factor and rate)."""
        return _chi2_isf(self.fit_level, dof)

    @property
    def drift_rates(self) -> np.ndarray:
        """The rates :func:`fit_temperature_drift` tries first, shape
        (``drift_rate_points``,) [K/h]."""
        return np.linspace(-self.drift_rate_k_per_h, self.drift_rate_k_per_h,
                           self.drift_rate_points)


@functools.lru_cache(maxsize=64)
def _chi2_isf(level: float, dof: int) -> float:
    """``scipy.stats.chi2.isf(level, dof)``, once per level and degrees of freedom."""
    return float(stats.chi2.isf(level, dof))


@dataclass(frozen=True)
class SensorFit:
    """One hypothesis fitted to the windows since an alarm.

    Attributes
    ----------
    fault : str
        ``sensor_offset_step`` or ``sensor_gain_drift``.
    bridge : int
        0..4 (s0..s4).
    severity : float
        δ [mV/V] of an offset step, 1 − g of a gain drift [-].
    z : ndarray, shape (n, F)
        The windows' z-scores with the fitted effect taken out.
    reduction : float
        How much the fit lowers Σ z² over the windows (χ² with one degree of freedom
        where the bridge has no such fault, two with a rate).
    rate_per_h : float or None
        A gain drift's fitted rate of 1 − g [1/h]; None: not fitted.
    """

    fault: str
    bridge: int
    severity: float
    z: np.ndarray
    reduction: float
    rate_per_h: float | None = None

    @property
    def rest(self) -> float:
        """``n · mean_j(mean_i z_ij)²`` over the n windows and the features j outside
        the fitted bridge (the other bridges, the efficiency and the twist): the χ² per degree of
        freedom of their mean shift where the windows are independent and nothing but
        this bridge moved (docs/monitor/assessment.md, "Naming a sensor fault")."""
        keep = np.ones(self.z.shape[1], bool)
        keep[self.bridge * BLOCK:(self.bridge + 1) * BLOCK] = False
        m = self.z[:, keep].mean(axis=0)
        return float(len(self.z) * np.mean(m ** 2))

    def plausible(self, naming: NamingConfig | None = None) -> bool:
        """Significant (:meth:`NamingConfig.least_reduction` of one parameter, two with a
        rate) and within the fault's severity range (a gain only falls:
        :data:`swgsim.sensing.sensor_faults.SENSOR_FAULTS`)."""
        lo, hi = SENSOR_FAULTS[self.fault].severity_range
        least = (naming or NamingConfig()).least_reduction(
            1 if self.rate_per_h is None else 2)
        return self.reduction >= least and lo <= self.severity <= hi


def fit_sensor_faults(z: np.ndarray, mean: np.ndarray, std: np.ndarray,
                      hours: np.ndarray | None = None) -> list[SensorFit]:
    """Fit every one-bridge sensor fault to windows (docs/monitor/assessment.md, "Naming a sensor
    fault").

    Parameters
    ----------
    z : ndarray, shape (n, F)
        z-scores of the windows since the alarm against the gear's normal behaviour,
        F = 5 (H + 2) + 1, or more (:func:`learn.inputs.health.feature_names`: the
        twist features of an output encoder come after the bridges' and efficiency).
    mean, std : ndarray, shape (n, F)
        The normal behaviour's mean and standard deviation at each window's operating point.
    hours : ndarray, shape (n,), optional
        The windows' operating hours [h]: the gain drifts, 1 − g = s + r (h − h_last),
        its level s at the last window and its rate r [1/h] fitted together (linear
        least squares; :attr:`SensorFit.rate_per_h`). A drift that moves the gain by a
        few tenths of a percent in the hour after an alarm moves a harmonic's amplitude
        by many σ (robot_joint s3_h2: 0.02 of gain is 41 σ), which one level leaves
        behind. None: one level (a step).

    Returns
    -------
    list of SensorFit
        Ten: both faults on each of the five bridges.

    Raises
    ------
    ValueError
        If the shapes disagree with five bridges of H + 2 features.
    """
    n, f = z.shape
    if f < 5 * BLOCK + 1 or mean.shape != z.shape or std.shape != z.shape:
        raise ValueError(f"z, mean and std must be (n, >= {5 * BLOCK + 1}), got {z.shape}, "
                         f"{mean.shape}, {std.shape}")
    out = []
    for c in range(5):
        j0 = c * BLOCK
        # offset step: z of the offset rises by δ / σ
        m = 1.0 / std[:, j0]
        d = float(z[:, j0] @ m / (m @ m))
        zc = z.copy()
        zc[:, j0] -= d * m
        out.append(SensorFit("sensor_offset_step", c, d, zc, d * d * float(m @ m)))
        # gain drift: offset and amplitudes f -> g f, so z rises by (g - 1) μ / σ
        cols = slice(j0, j0 + BLOCK - 1)
        m = mean[:, cols] / std[:, cols]
        x = m.reshape(-1, 1) if hours is None else np.stack(
            [m.ravel(), (m * (np.asarray(hours, float) - hours[-1])[:, None]).ravel()], 1)
        a = np.linalg.lstsq(x, z[:, cols].ravel(), rcond=None)[0]
        fitted = x @ a
        zc = z.copy()
        zc[:, cols] -= fitted.reshape(n, -1)
        zc[:, j0 + BLOCK - 1] = 0.0  # the residual's RMS holds the noise too: left free
        out.append(SensorFit("sensor_gain_drift", c, -float(a[0]), zc,
                             float(fitted @ fitted), None if hours is None else -float(a[1])))
    return out


def fit_bridge_faults(normal: NormalBehaviour, feats: np.ndarray, points: np.ndarray,
                      cond: Conditions | None, friction: np.ndarray, index: np.ndarray,
                      z: np.ndarray, spread: np.ndarray, hours: np.ndarray | None = None
                      ) -> list[SensorFit]:
    """Every one-bridge sensor fault fitted to windows since an alarm
    (:func:`fit_sensor_faults`), and where the joint has no reading (``normal.warm_dir``)
    also fitted before its latent temperature is taken out: a bridge's gain drift moves
    its features in a direction that may share a part with a warm-up direction, which the
    clipped projection takes out in part and bends the rest of; fitted with the warm-ups
    left in and the warm-ups then taken out of what is left, the hypothesis is "this
    bridge's fault, and the joint warmed as commissioning saw". Without it the default
    evaluation at 2a3c421 named 9 of robot_joint's 37 detected gain drifts of s3 a gear
    fault (root crack 7, eccentric WG 2; gears 2-3); none before ae2a28d learnt the
    warm-up directions (found by bisection on gear 2, seed 1).

    Parameters
    ----------
    normal : NormalBehaviour
    feats, points, cond, friction, index
        The windows, as :meth:`NormalBehaviour.z_and_spread` takes them.
    z, spread : ndarray, shape (n, F)
        Their z-scores and spread (:meth:`NormalBehaviour.z_and_spread`).
    hours : ndarray, shape (n,), optional
        Their operating hours [h]: a gain drift with a rate (:func:`fit_sensor_faults`).

    Returns
    -------
    list of SensorFit
        Ten, or twenty without a reading (the second ten with the warm-ups left in at
        the fit).
    """
    fits = fit_sensor_faults(z, normal.mean[index], spread, hours)
    if normal.warm_dir is None:
        return fits
    bare = dataclasses.replace(normal, warm_dir=None, warm_range=None, warm_torque=None)
    raw, _ = bare.z_and_spread(feats, points, cond, friction, index)
    return fits + [dataclasses.replace(f, z=normal.without_warm_ups(f.z, index))
                   for f in fit_sensor_faults(raw, normal.mean[index], spread, hours)]


@dataclass(frozen=True)
class TemperatureFit:
    """The hypothesis "the temperature reading is wrong" fitted to the windows since an
    alarm (:func:`fit_temperature`).

    Attributes
    ----------
    temperature_c : ndarray, shape (n,)
        Each window's temperature that leaves its z-scores smallest [°C].
    reading_c : ndarray, shape (n,)
        The sensor's readings [°C].
    z : ndarray, shape (n, F)
        The windows' z-scores at the fitted temperatures.
    reduction : float
        How much the fit lowers Σ z² over the windows.
    """

    temperature_c: np.ndarray
    reading_c: np.ndarray
    z: np.ndarray
    reduction: float
    rate_k_per_h: float | None = None

    @property
    def offset_k(self) -> float:
        """Median of the fitted temperature minus the reading [K]."""
        return float(np.median(self.temperature_c - self.reading_c))

    @property
    def error_k(self) -> float:
        """Median distance of the fitted temperature from the reading [K]."""
        return float(np.median(np.abs(self.temperature_c - self.reading_c)))

    def plausible(self, naming: NamingConfig | None = None) -> bool:
        """Window by window (``rate_k_per_h`` None): the fit moved the temperature by at
        least ``naming.temperature_min_k``, either way, at the median window and lowered
        Σ z² by at least ``naming.least_reduction(1)`` per window (each window has its
        own temperature: one degree of freedom each). A drift (an offset and a rate): by
        at least ``naming.drift_min_k`` and Σ z² by ``naming.least_reduction(3)`` over all
        windows."""
        nc = naming or NamingConfig()
        if self.rate_k_per_h is None:
            return (self.error_k >= nc.temperature_min_k
                    and self.reduction >= nc.least_reduction(1) * len(self.z))
        return self.error_k >= nc.drift_min_k and self.reduction >= nc.least_reduction(3)


def fit_temperature(normal: NormalBehaviour, feats: np.ndarray, points: np.ndarray,
                    cond: Conditions, friction: np.ndarray, index: np.ndarray,
                    naming: NamingConfig | None = None) -> TemperatureFit | None:
    """Fit the hypothesis "the temperature reading is wrong" (stuck, drifting, off):
    each window's temperature chosen to leave Σ z² smallest (:func:`best_temperature`),
    where that beats the reading. The
    bridges' span and zero drift, their features' own slopes and the friction's law
    learnt at commissioning (:mod:`swgmon.detection.normal`) together say what temperature each
    window was at; a gear fault moves them in a pattern no temperature gives.

    Parameters
    ----------
    normal : NormalBehaviour
        With temperature terms (:attr:`NormalBehaviour.temperature_law`).
    feats : ndarray, shape (n, F)
    points : ndarray, shape (n, 2)
    cond : Conditions
        With the readings.
    friction : ndarray, shape (n,)
        The friction factor in force at each window.
    index : ndarray of int, shape (n,)
        Each window's operating point's row in ``normal``.

    Returns
    -------
    TemperatureFit or None
        None where the normal behaviour has no temperature terms or the stream no
        reading.
    """
    if cond.temperature_c is None or not normal.temperature_law:
        return None
    z0 = normal.z(feats, points, cond, friction, index)
    temp, z = best_temperature(normal, feats, points, cond.torque_nm, friction, index,
                               naming)
    s0, s = np.sum(z0 ** 2, axis=1), np.sum(z ** 2, axis=1)
    worse = s0 <= s  # the reading is as good: kept
    temp[worse], z[worse] = cond.temperature_c[worse], z0[worse]
    return TemperatureFit(temp, cond.temperature_c, z, float(np.sum(s0 - np.minimum(s, s0))))


def fit_temperature_drift(normal: NormalBehaviour, feats: np.ndarray, points: np.ndarray,
                          cond: Conditions, friction: np.ndarray, index: np.ndarray,
                          hours: np.ndarray | None, naming: NamingConfig | None = None
                          ) -> TemperatureFit | None:
    """Fit the hypothesis "the temperature reading drifts" (a loosened or ageing sensor:
    :class:`~swgsim.sensing.bridge_drift.TemperatureSensor` ``drift``): the true
    temperature is the reading plus an offset and a rate, a + r (t − t₀), the same for
    every window since the alarm (two parameters in all, where :func:`fit_temperature`
    gives each window its own: a drift is named while its error is still small, before
    a gear-fault alarm has fired on the features it moves). Offsets within
    ``naming.temperature_beyond_k``, rates within ``naming.drift_rates`` (the families' ±0.5
    K/h), on a grid (``naming.drift_offset_step_k``) refined about its best
    (``drift_fine_k``, ``drift_fine_k_per_h``); the z-scores by the laws commissioning
    learnt, unwidened beyond its range (as :func:`best_temperature`).

    Returns
    -------
    TemperatureFit or None
        ``rate_k_per_h`` the fitted rate; None where the normal behaviour has no
        temperature terms, the stream no reading (or a missing one among these windows)
        or no hours are given.
    """
    if (cond.temperature_c is None or not normal.temperature_law or hours is None
            or not np.all(np.isfinite(cond.temperature_c))):
        return None
    z0 = normal.z(feats, points, cond, friction, index)
    flat = normal.unwidened()
    dt = np.asarray(hours, float) - float(hours[0])
    args = (flat, feats, points, cond.torque_nm, friction, index)

    def best(offsets: np.ndarray, rates: np.ndarray) -> tuple[float, float]:
        tot = [_sum_z2(*args, (cond.temperature_c + r * dt)[:, None] + offsets[None, :])[0]
               .sum(axis=0) for r in rates]  # (R, G)
        i, j = np.unravel_index(int(np.argmin(tot)), (len(rates), len(offsets)))
        return float(offsets[j]), float(rates[i])

    nc = naming or NamingConfig()
    beyond, step = nc.temperature_beyond_k, nc.drift_offset_step_k
    rates = nc.drift_rates
    a, r = best(np.arange(-beyond, beyond + step / 2, step), rates)
    half_a, half_r = step / 2, (rates[1] - rates[0]) / 2  # half a first step
    a, r = best(a + np.arange(-half_a, half_a + nc.drift_fine_k / 2, nc.drift_fine_k),
                r + np.arange(-half_r, half_r + nc.drift_fine_k_per_h / 2,
                              nc.drift_fine_k_per_h))
    temp = cond.temperature_c + a + r * dt
    s, z = _sum_z2(*args, temp[:, None])
    return TemperatureFit(temp, cond.temperature_c, z[:, 0],
                          float(np.sum(z0 ** 2) - s.sum()), r)


def best_temperature(normal: NormalBehaviour, feats: np.ndarray, points: np.ndarray,
                     torque_nm: np.ndarray, friction: np.ndarray, index: np.ndarray,
                     naming: NamingConfig | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Each window's temperature that leaves its z-scores smallest (Σ z²), on a grid of
    ``naming.coarse_step_k`` refined to ``naming.temperature_step_k`` about its best, over the
    range commissioning saw widened by ``naming.temperature_beyond_k`` on either side, and
    the z-scores there; shapes (n,) [°C] and (n, F). Beyond commissioning's range the
    laws are extrapolated in commissioning's spread (not
    :meth:`~swgmon.detection.normal.NormalBehaviour.z_and_spread`'s widened one, which would
    pull every fit to the grid's ends)."""
    nc = naming or NamingConfig()
    lo = float(np.min(normal.temp_range[:, 0])) - nc.temperature_beyond_k
    hi = float(np.max(normal.temp_range[:, 1])) + nc.temperature_beyond_k
    normal = normal.unwidened()  # no pull to the ends
    fine = nc.temperature_step_k * np.arange(-nc.coarse_steps, nc.coarse_steps + 1)
    grid = np.arange(lo, hi + nc.coarse_step_k, nc.coarse_step_k)  # coarse, then fine
    temp, zb = np.empty(len(feats)), np.empty(feats.shape)
    for a in range(0, len(feats), nc.windows_at_once):  # a bounded memory
        w = slice(a, a + nc.windows_at_once)
        args = (normal, feats[w], points[w], torque_nm[w], friction[w], index[w])
        n = len(args[1])
        best = grid[np.argmin(_sum_z2(*args, np.broadcast_to(grid, (n, len(grid))))[0],
                              axis=1)]
        cand = best[:, None] + fine[None, :]  # (n, G)
        s, z = _sum_z2(*args, cand)
        k = np.argmin(s, axis=1)
        temp[w], zb[w] = cand[np.arange(n), k], z[np.arange(n), k]
    return temp, zb


def _sum_z2(normal: NormalBehaviour, feats, points, torque_nm, friction, index,
            temps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Σ z² and z of each window (n) at each of its temperatures ``temps`` (n, G), in one
    evaluation of the normal behaviour; shapes (n, G) and (n, G, F)."""
    z = normal.z_over_temperature(feats, points, torque_nm, temps, friction, index)
    return np.sum(z ** 2, axis=2), z


def virtual_temperature(normal: NormalBehaviour, feats: np.ndarray, points: np.ndarray,
                        torque_nm: np.ndarray, friction: float | np.ndarray,
                        index: np.ndarray, naming: NamingConfig | None = None) -> np.ndarray:
    """The temperature the bridges and the efficiency say each window was at, by the
    laws learnt at commissioning (:func:`best_temperature`), as a running median over
    ``naming.virtual_windows`` windows (a joint's temperature moves with a time constant of
    tens of minutes, docs/DATASET.md, "Gear lives"); the monitor's reading where its
    temperature sensor has failed (:func:`swgmon.advisories.stream.run_stream`). Shape (n,) [°C].
    ``friction``: the friction factor in force, one for every window or one each (n,).

    Raises
    ------
    ValueError
        If the normal behaviour has no temperature terms.
    """
    if not normal.temperature_law:
        raise ValueError("virtual_temperature: the normal behaviour has no temperature law "
                         "(commissioning without a temperature reading or without its "
                         "spread)")
    nc = naming or NamingConfig()
    temp, _ = best_temperature(normal, feats, points, torque_nm,
                               np.broadcast_to(np.asarray(friction, float), (len(feats),)),
                               index, nc)
    half = nc.virtual_windows // 2
    padded = np.pad(temp, half, mode="edge")
    return np.median(np.lib.stride_tricks.sliding_window_view(padded, 2 * half + 1), axis=1)


def still_reading(normal: NormalBehaviour, feats: np.ndarray, points: np.ndarray,
                  cond: Conditions, friction: float, hours: np.ndarray,
                  naming: NamingConfig | None = None) -> tuple[int, int] | None:
    """The first window at which the temperature reading is stuck: it has stayed the same,
    to the bit, for at least ``naming.still_h`` while the temperature the bridges and the
    efficiency say (:func:`virtual_temperature`, at friction factor ``friction``) moved by
    at least ``naming.still_moved_k`` since the run began (a frozen converter, a bus that
    repeats its last value: a flat-line test, with the bridges telling a stuck reading from
    a joint at a steady temperature read without noise). Judged without an alarm and
    without the spreads: a reading stuck beyond commissioning's range is cheap in the
    spread widened there (docs/monitor/assessment.md, "The monitor checks its temperature sensor").

    Parameters
    ----------
    normal : NormalBehaviour
    feats, points : ndarray, shapes (n, F), (n, 2)
    cond : Conditions
        The readings [°C] (NaN: none).
    friction : float
        The friction factor in force.
    hours : ndarray, shape (n,)
        Operating hours, increasing [h].

    Returns
    -------
    (int, int) or None
        The first window of the run of one reading, and the window at which it is found
        stuck (the running median's half-width after the first whose virtual temperature
        has moved enough, within the run); None where no reading is stuck, or the stream
        has no reading or the normal behaviour no temperature law.
    """
    t = cond.temperature_c
    if t is None or not normal.temperature_law or not len(t):
        return None
    starts = np.flatnonzero(np.r_[True, t[1:] != t[:-1]])  # NaN: a run of its own
    ends = np.r_[starts[1:], len(t)]
    nc = naming or NamingConfig()
    long = hours[ends - 1] - hours[starts] >= nc.still_h
    half = nc.virtual_windows // 2
    for s, e in zip(starts[long], ends[long], strict=True):
        judged = s + int(np.searchsorted(hours[s:e], hours[s] + nc.still_h))
        lo, hi = np.inf, -np.inf
        for a in range(s, e, nc.windows_at_once):
            b = min(e, a + nc.windows_at_once)
            w = slice(max(s, a - half), min(e, b + half))  # the running median's edges
            v = virtual_temperature(normal, feats[w], points[w], cond.torque_nm[w], friction,
                                    normal.index(points[w]), nc)[a - w.start:b - w.start]
            moved = (np.maximum.accumulate(np.maximum(v, hi))
                     - np.minimum.accumulate(np.minimum(v, lo)))
            hit = (moved >= nc.still_moved_k) & (np.arange(a, b) >= judged)
            if hit.any():
                return int(s), min(int(e) - 1, a + int(np.argmax(hit)) + half)
            lo, hi = min(lo, float(v.min())), max(hi, float(v.max()))
    return None


__all__ = ["BLOCK", "NamingConfig", "SensorFit", "TemperatureFit", "best_temperature",
           "fit_bridge_faults", "fit_sensor_faults", "fit_temperature", "fit_temperature_drift",
           "still_reading", "virtual_temperature"]
