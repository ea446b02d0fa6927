"""The friction problem's options (data kind 1), each default and range written once.

:func:`~swgcal.friction.problem.friction_problem` takes its defaults from here and checks
its arguments with these classes; ``swgsim-calibrate`` builds its ``base model``,
``gear_ratio``, ``accel_window`` and ``split`` keys from :class:`FrictionOptions`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from swgsim.base.typed import allowed, check_ranges

__all__ = ["BaseModelOptions", "SplitOptions", "FrictionOptions"]


@dataclass(frozen=True)
class BaseModelOptions:
    """Smooth sign tanh(q̇ / v_s) of the paper's friction law (paper eq. 5).

    Attributes
    ----------
    v_s : float or None
        Smooth-sign velocity [rad/s]; None: ``v_s_rel`` times the 99th percentile of ``|q̇|``.
    v_s_rel : float, default 0.01
        Fraction of the 99th percentile of ``|q̇|`` [-].
    """

    v_s: float | None = field(default=None, metadata=allowed(0, None, "rad/s", lo_open=True))
    v_s_rel: float = field(default=0.01, metadata=allowed(0, 1, lo_open=True))

    def __post_init__(self) -> None:
        check_ranges(self)


@dataclass(frozen=True)
class SplitOptions:
    """Held-out time blocks of a friction recording; the other blocks are fit blocks
    (:func:`~swgcal.split.time_block_split`).

    Attributes
    ----------
    n_blocks : int, default 10
        Equal time blocks of the recording.
    validation_blocks : tuple of int, default (3, 7)
        Blocks that choose the effects (negative: from the end).
    test_blocks : tuple of int, default (5, 9)
        Blocks for the errors before/after only; the last block extrapolates.
    guard_frac : float, default 0.05
        Samples dropped at role boundaries [blocks].
    """

    n_blocks: int = field(default=10, metadata=allowed(3, None))
    validation_blocks: tuple[int, ...] = (3, 7)
    test_blocks: tuple[int, ...] = (5, 9)
    guard_frac: float = field(default=0.05, metadata=allowed(0, 0.45))

    def __post_init__(self) -> None:
        check_ranges(self)
        n = self.n_blocks
        for key in ("validation_blocks", "test_blocks"):
            blocks = getattr(self, key)
            if not blocks or any(not -n <= int(b) < n for b in blocks):
                raise ValueError(f"{key} must list blocks in [{-n}, {n - 1}], got {list(blocks)}")


@dataclass(frozen=True)
class FrictionOptions:
    """Every option of a friction problem but the candidates (``selection.candidates``).

    Attributes
    ----------
    gear_ratio : float or None
        Reduction ratio N (wave-generator turns per output turn) when known: ripple
        periods are then reported and checked as wave-generator orders.
    accel_window : int, default 21
        Samples of the Savitzky-Golay estimate of q̈ when the CSV has none.
    """

    base_model: BaseModelOptions = field(default_factory=BaseModelOptions)
    gear_ratio: float | None = field(default=None, metadata=allowed(1, 10_000, lo_open=True))
    accel_window: int = field(default=21, metadata=allowed(5, 1001, "samples", odd=True))
    split: SplitOptions = field(default_factory=SplitOptions)

    def __post_init__(self) -> None:
        check_ranges(self)

    def problem_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :func:`swgcal.friction.build_problem`."""
        b, s = self.base_model, self.split
        return dict(v_s=b.v_s, v_s_rel=b.v_s_rel, n_blocks=s.n_blocks,
                    validation_blocks=list(s.validation_blocks),
                    test_blocks=list(s.test_blocks), guard_frac=s.guard_frac,
                    accel_window=self.accel_window, gear_ratio=self.gear_ratio)
