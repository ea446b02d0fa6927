"""Faults of the sensors themselves: classes of their own, named ``sensor_*``.

A gauge or its bridge can fail while the gear is sound; a monitor must name that a sensor
fault, never a gear fault, so the gear lives (:mod:`swgsim.datasets.life`) carry them as
classes of their own. Each (:class:`SensorFault`, in :data:`SENSOR_FAULTS`; add one with
:func:`register_sensor_fault`) acts on one bridge's strain signal s (its output less its
zero offset z, which a fault of the strain's transfer leaves) before the converter's
noise: ``sensor_gain_drift`` z + (1 − severity) s, ``sensor_offset_step`` z + s + severity.
Effects, causes, magnitudes and their sources: docs/PHYSICS.md sec. 8.2.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from swgsim.base.registry import Registry


@dataclass(frozen=True)
class SensorFault:
    """A fault of one bridge.

    Attributes
    ----------
    name : str
        ``sensor_*``.
    severity_range : tuple of float
        Allowed closed range.
    unit : str
        Unit of the severity.
    apply : callable
        ``apply(x, severity)`` on one bridge's strain signals ``x`` [mV/V] (its output
        less its zero offset), shape (n, n_t), with ``severity`` of shape (n, 1); returns
        the faulty ones.
    display : str
        Name in reports and figures.
    """

    name: str
    severity_range: tuple[float, float]
    unit: str
    apply: Callable[[np.ndarray, np.ndarray], np.ndarray]
    display: str


SENSOR_FAULTS: Registry[SensorFault] = Registry("sensor fault", __name__, "SENSOR_FAULTS", (
    (f.name, f) for f in (
        SensorFault("sensor_gain_drift", (0.0, 0.5), "-", lambda x, s: x * (1.0 - s),
                    "sensor gain drift"),
        SensorFault("sensor_offset_step", (-0.5, 0.5), "mV/V", lambda x, s: x + s,
                    "sensor offset step"),
    )
))

#: Severities of the evaluation: mild and severe. Gain: 2 %, twice the worst sound
#: installation's drift over a year (0.2 % to a little over 1 %, Espion and Halleux, HBM RAM
#: 2000/1), 10 % a gauge partly debonded [choice]. Offset: 0.05 mV/V, GF ε / 4 of fatigue's
#: failure criterion of about 100 µε (Vishay TN-508-1; ASTM E1949 sec. 4.4), a tenth of it
#: mild (docs/PHYSICS.md sec. 8.2).
SEVERITIES: Registry[tuple[float, ...]] = Registry("sensor fault severities", __name__,
                                                   "SEVERITIES", {
    "sensor_gain_drift": (0.02, 0.10),
    "sensor_offset_step": (0.005, 0.05),
}.items())


def register_sensor_fault(fault: SensorFault, severities: tuple[float, float]) -> SensorFault:
    """Add a sensor fault to :data:`SENSOR_FAULTS`, with its mild and severe severity of
    the monitor's evaluation (:data:`SEVERITIES`).

    Parameters
    ----------
    fault : SensorFault
        Named ``sensor_<...>``; ``apply(x, severity)`` acts on one bridge's samples.
    severities : (float, float)
        Mild and severe, inside ``fault.severity_range``.

    Returns
    -------
    SensorFault

    Raises
    ------
    ValueError
        A name taken or not starting with ``sensor_``, or severities outside the range.
    """
    if fault.name in SENSOR_FAULTS or not fault.name.startswith("sensor_"):
        raise ValueError(f"sensor fault {fault.name!r}: the name must start with 'sensor_' "
                         "and not be registered yet")
    lo, hi = fault.severity_range
    if len(severities) != 2 or not all(lo <= s <= hi for s in severities):
        raise ValueError(f"sensor fault {fault.name!r}: severities {severities} must be two "
                         f"values in [{lo}, {hi}]")
    SEVERITIES.add(fault.name, tuple(float(s) for s in severities))
    return SENSOR_FAULTS.add(fault.name, fault)


def is_sensor_fault(name: str) -> bool:
    """Whether ``name`` is a registered sensor fault."""
    return name in SENSOR_FAULTS


def apply_sensor_fault(x: np.ndarray, name: str, severity: np.ndarray | float,
                       sensor: int, zero_offset_mvv: float = 0.0) -> np.ndarray:
    """One bridge's fault on a batch of windows (a copy; the input is left as it is).

    The fault acts on the bridge's strain signal, x − z; the zero offset z (its arms'
    imbalance, docs/PHYSICS.md sec. 4.4) stays: a gauge that debonds passes less strain,
    not less imbalance.

    Parameters
    ----------
    x : ndarray, shape (n, 5, n_t)
        Sampled bridge outputs [mV/V].
    name : str
        A key of :data:`SENSOR_FAULTS`.
    severity : float or ndarray, shape (n,)
        In the fault's unit.
    sensor : int
        Index of the faulty bridge, 0..4.
    zero_offset_mvv : float
        The faulty bridge's zero offset z [mV/V] (the gear's
        :attr:`swgsim.gear.sensors.SensorLayout.zero_offsets_mvv`); 0: a balanced bridge.

    Returns
    -------
    ndarray, shape (n, 5, n_t)

    Raises
    ------
    KeyError
        For an unknown name.
    """
    f = SENSOR_FAULTS[name]
    out = np.array(x, copy=True)
    sev = np.broadcast_to(np.asarray(severity, float), (x.shape[0],))[:, None]
    z = float(zero_offset_mvv)
    out[:, sensor] = f.apply(out[:, sensor] - z, sev) + z
    return out


__all__ = ["SENSOR_FAULTS", "SEVERITIES", "SensorFault", "apply_sensor_fault",
           "register_sensor_fault",
           "is_sensor_fault"]
