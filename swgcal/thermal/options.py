"""The thermal problem's options (data kind 3, a joint log), each default and range
written once; ``swgsim-calibrate`` builds its ``thermal`` keys from
:class:`ThermalOptions`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from swgsim.base.typed import allowed, check_ranges

from .library import AMBIENT_RANGE_C

__all__ = ["ThermalKindOptions", "ThermalOptions", "TORQUE_PER_AMP_NM", "GEAR_EFFICIENCY",
           "STANDSTILL_RAD_S", "POWERED_A"]

#: Output torque per motor ampere of a UR3 joint [N m/A]: a strain wave gear of ratio
#: 101 times a motor constant of about 0.1 N m/A [unverified: no UR data sheet gives it;
#: it only scales the fitted R_th, the shape of the fit does not depend on it].
TORQUE_PER_AMP_NM = 10.0
#: The gear's efficiency in the loss proxy P = (1 − η) k_τ |I| |ω| [-] (0.7) [choice: the
#: rated point of :func:`swgsim.gear.dynamics.rt1_size20` is 77 % at 20 °C; a small gear
#: at a cobot's low speeds is lower].
GEAR_EFFICIENCY = 0.7
#: A joint slower than this stands still [rad/s] [choice: 0.3 °/s, the log's speed noise
#: at rest is below 1e-3 rad/s].
STANDSTILL_RAD_S = 0.005
#: The arm is powered where its six motor currents' magnitudes sum above this [A]
#: [choice: an arm holding itself draws more (the UR3 day's smallest sum over a row with
#: readings is 1.0 A); one powered off reads 0].
POWERED_A = 0.1


@dataclass(frozen=True)
class ThermalOptions:
    """Every option of a thermal problem but the candidates (``selection.candidates``).

    Attributes
    ----------
    joint : int
        The joint fitted, 0-5 (1, the shoulder: the UR3 day's largest current).
    torque_per_amp_nm : float
        k_τ of the loss proxy [N m/A] (:data:`TORQUE_PER_AMP_NM`).
    gear_efficiency : float
        η of the loss proxy, in (0, 1) (:data:`GEAR_EFFICIENCY`).
    fit_frac : float
        Without a gap in the log: the first fraction of it fitted, in (0, 1) (0.6)
        [choice]; with one, the part before the first gap is fitted.
    room_c : float or None
        The room's measured temperature [°C], 0-50: the base's ambient held at it; None: the
        ambient fitted between 0 °C and the coolest joint's first reading (a log starting
        after a long stop leaves it on that bound: unphysical, not scored).
    """

    joint: int = field(default=1, metadata=allowed(0, 5))
    torque_per_amp_nm: float = field(default=TORQUE_PER_AMP_NM,
                                     metadata=allowed(0, None, "N m/A", lo_open=True))
    gear_efficiency: float = field(default=GEAR_EFFICIENCY,
                                   metadata=allowed(0, 1, lo_open=True, hi_open=True))
    fit_frac: float = field(default=0.6, metadata=allowed(0, 1, lo_open=True, hi_open=True))
    room_c: float | None = field(default=None, metadata=allowed(*AMBIENT_RANGE_C, unit="°C"))

    def __post_init__(self) -> None:
        check_ranges(self)

    def problem_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :func:`swgcal.thermal.build_problem`."""
        return dict(joint=self.joint, torque_per_amp_nm=self.torque_per_amp_nm,
                    gear_efficiency=self.gear_efficiency, fit_frac=self.fit_frac,
                    room_c=self.room_c)


@dataclass(frozen=True)
class ThermalKindOptions:
    """The thermal kind's keys of ``swgsim-calibrate``: one group, ``thermal``
    (:class:`ThermalOptions`)."""

    thermal: ThermalOptions = field(default_factory=ThermalOptions)

    def problem_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :func:`swgcal.thermal.build_problem`."""
        return self.thermal.problem_kwargs()
