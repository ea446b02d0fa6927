"""Is one bridge's fault enough to explain an alarm? The test that keeps sensor faults
from being named as gear faults.

A sensor fault acts on one bridge only and in one of two shapes
(:mod:`swgsim.sensing.sensor_faults`): an offset step moves that bridge's offset c0 by δ [mV/V]
and nothing else; a gain drift multiplies its whole output by g = 1 − severity, i.e.
its offset and every harmonic amplitude by g (its residual's RMS, which also holds the
converter's noise, is left free). A gear fault is seen by every bridge through the
flexspline (an eccentric WG moves the offsets of s1 and s3 by equal and opposite
amounts, and s0's; a crack changes the harmonics of several bridges, not in proportion).
This is the analytical redundancy of sensor fault isolation: each hypothesis "bridge c
has fault f" is fitted to the windows since the alarm by its one parameter (least
squares in the z-scores against the gear's normal behaviour), the fitted effect is taken out,
and what is left is judged twice, where the fit is plausible (significant, and a gain
that falls, not rises):

* window by window, as the alarm was: the diagnosis model's score and the novelty Σ z²,
  as conformal p-values against the gear's calibration windows
  (:meth:`learn.monitor.gear_monitor.GearMonitor.p_values`), whose median must be at least
  :data:`SENSOR_P_MIN` (the windows look as healthy as the gear's own healthy ones);
* over all the windows together, on the other bridges and the efficiency, which a
  sensor fault leaves alone: their mean z-scores over the n windows, as
  ``n · mean_j(mean_i z_ij)²`` (:attr:`SensorFit.rest`; about 1 where nothing else
  moved, growing with n where something did), must be at most :data:`REST_MAX`. A gear
  fault that one bridge explains window by window, because its share on the other
  bridges is inside their window-to-window spread (an eccentric WG's s3 on the robot
  link), still moves their mean: an hour of windows sees it.

A hypothesis that passes both explains the alarm; of those, the one that leaves the
windows most healthy is the sensor fault named.

Source: the structured-residual idea of sensor fault isolation (P. M. Frank, "Fault
diagnosis in dynamic systems using analytical and knowledge-based redundancy",
Automatica 26(3), 1990, sec. 4: one residual per sensor, insensitive to that sensor);
here the "observer" is the gear's own normal behaviour and the fault model is
parametric.
"""

from __future__ import annotations

from dataclasses import dataclass
from statistics import NormalDist

import numpy as np

from swgsim.sensing.sensor_faults import SENSOR_FAULTS

from .features import N_HARMONICS

#: Per-bridge block of health features: offset, H amplitudes, log RMS of the rest.
BLOCK = N_HARMONICS + 2
#: Median conformal p-value of the corrected windows from which on a sensor fault explains
#: the alarm. Chosen on the training gears (``scripts/naming_study.py``, bench, trained on
#: gear 1, judged on gear 2, an hour of windows): the right fit of every sensor fault on
#: every bridge from 0.005 to 0.05 mV/V and from 2 to 10 % gain left 0.43-0.76; the best
#: plausible one-bridge fit of a gear fault at most 0.19 (a tip crack of 0.5 fitted as a
#: 0.03 % gain loss; a mild eccentric WG with its s1 offset alone taken out: 0.14).
SENSOR_P_MIN = 0.3
#: Largest mean shift left on the other bridges (:attr:`SensorFit.rest`) for a one-bridge
#: fit to explain an alarm. Chosen on the training gears of both presets
#: (``scripts/naming_study.py --dataset bench|robot_joint``, trained on gear 1, judged on
#: gear 2, an hour of windows): the right fit of each of the 100 sensor-fault lives per
#: preset left 0.51-1.82 (the healthy hour 0.96-1.29); of the gear-fault lives whose
#: best plausible one-bridge fit left a median p-value above 0.2 (robot_joint root and
#: tip cracks of 0.5 and 0.7) it left 3.33-9.48, every other gear fault's 10-5657.
#: 2.5 is about the geometric middle of the gap.
REST_MAX = 2.5
#: Smallest reduction of Σ z² for a fit to count: the χ² (one degree of freedom) quantile
#: 0.999, so that a bridge without a fault is fitted one in a thousand times: the square of
#: the standard normal quantile 0.9995 (χ²₁ is the square of a standard normal variable).
FIT_MIN = NormalDist().inv_cdf(0.9995) ** 2


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
        where the bridge has no such fault).
    """

    fault: str
    bridge: int
    severity: float
    z: np.ndarray
    reduction: float

    @property
    def rest(self) -> float:
        """``n · mean_j(mean_i z_ij)²`` over the n windows and the features j outside
        the fitted bridge (the other bridges, the efficiency and the twist): the χ² per degree of
        freedom of their mean shift where the windows are independent and nothing but
        this bridge moved (module docstring)."""
        keep = np.ones(self.z.shape[1], bool)
        keep[self.bridge * BLOCK:(self.bridge + 1) * BLOCK] = False
        m = self.z[:, keep].mean(axis=0)
        return float(len(self.z) * np.mean(m ** 2))

    def plausible(self) -> bool:
        """Significant (:data:`FIT_MIN`) and within the fault's severity range (a gain
        only falls: :data:`swgsim.sensing.sensor_faults.SENSOR_FAULTS`)."""
        lo, hi = SENSOR_FAULTS[self.fault].severity_range
        return self.reduction >= FIT_MIN and lo <= self.severity <= hi


def fit_sensor_faults(z: np.ndarray, mean: np.ndarray, std: np.ndarray) -> list[SensorFit]:
    """Fit every one-bridge sensor fault to windows (module docstring).

    Parameters
    ----------
    z : ndarray, shape (n, F)
        z-scores of the windows since the alarm against the gear's normal behaviour,
        F = 5 (H + 2) + 1, or more (:func:`learn.monitor.features.feature_names`: the
        twist features of an output encoder come after the bridges' and efficiency).
    mean, std : ndarray, shape (n, F)
        The normal behaviour's mean and standard deviation at each window's operating point.

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
        m = (mean[:, cols] / std[:, cols]).ravel()
        a = float(z[:, cols].ravel() @ m / (m @ m))
        zc = z.copy()
        zc[:, cols] -= a * mean[:, cols] / std[:, cols]
        zc[:, j0 + BLOCK - 1] = 0.0  # the residual's RMS holds the noise too: left free
        out.append(SensorFit("sensor_gain_drift", c, -a, zc, a * a * float(m @ m)))
    return out


__all__ = ["BLOCK", "FIT_MIN", "REST_MAX", "SENSOR_P_MIN", "SensorFit", "fit_sensor_faults"]
