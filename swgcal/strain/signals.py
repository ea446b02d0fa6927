"""Signals of the strain side of the calibration: what strain terms and probes see.

The measured data are strain-gauge windows (data kind 2, schema v1). Every sample of
every window and channel is one entry of the target vector, in the order (window,
channel, time). The chain's prediction of a window (the nominal gear at the window's
operating point, aligned to the window's WG angle and input angle; :mod:`.problem`) is
split into *basis* signals, each of shape (n_windows, 5, n_ext) on a time grid that
extends ``n_lead`` samples before and ``n_tail`` samples after the window (filters
and shifts need the history):

==========  ==========================================================================
s_wg        w0 (A cos 2ψ + B sin 2ψ): the WG-deflection pattern [mV/V]
s_t         T_out(t) h(ψ): the torque pattern [mV/V]
dpsi        ∂(s_wg + s_t)/∂ψ at fixed torque [mV/V / rad]
==========  ==========================================================================

The effect library that maps and extends this basis is :mod:`.effects`.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from swgsim.gear.sensors import SENSORS

__all__ = ["SENSORS", "MappedBasis", "StrainSignals", "constraint_basis"]



# ---------------------------------------------------------------------------------------
# signals


class MappedBasis(Mapping):
    """Lazy view of a basis mapping with a function applied per entry, fn(key, array)."""

    def __init__(self, base: Mapping[str, np.ndarray],
                 fn: Callable[[str, np.ndarray], np.ndarray]) -> None:
        self._base, self._fn, self._cache = base, fn, {}

    def __getitem__(self, k: str) -> np.ndarray:
        if k not in self._cache:
            self._cache[k] = self._fn(k, self._base[k])
        return self._cache[k]

    def __iter__(self) -> Iterator[str]:
        return iter(self._base)

    def __len__(self) -> int:
        return len(self._base)


@dataclass(frozen=True)
class StrainSignals:
    """What strain terms and probes see. Per-sample arrays have shape (n,) with
    n = n_windows · 5 · n_t, ordered (window, channel, time).

    The basis signals are ``raw`` (the chain's prediction at the current alignment) with
    the ``maps`` of the transform terms applied in order (low-pass, bridge nonlinearity),
    lazily; a kinematic-error term replaces the raw torque pattern (``ripple``) and keeps
    the maps, so transforms compose in any order.

    Attributes
    ----------
    raw : mapping of str to ndarray, shape (n_windows, 5, n_lead + n_t + n_tail)
        Basis signals "s_wg", "s_t", "dpsi" (module docstring) on the extended grid.
    n_lead, n_t : int
        History samples before the window, samples in the window.
    fs : float
        Sample rate [Hz].
    window, channel, op : ndarray of int, shape (n,)
        Window index (0..n_windows−1), channel (0..4), operating-point index.
    t_s : ndarray, shape (n,)
        Time since the window start [s].
    t_seq_s : ndarray, shape (n,)
        Time since the start of the recording sequence [s] (thermal drift).
    phi_in_rad, psi_rad : ndarray, shape (n,)
        Input angle and WG angle relative to the flexspline of the aligned model [rad].
    psi_rate : ndarray, shape (n_windows,)
        ψ̇ of each window [rad/s].
    n_in_rpm, t_out_nm : ndarray, shape (n_windows,)
        Operating point of each window [rpm, N m].
    ops : tuple of (float, float)
        Distinct operating points (n_in [rpm], T_out [N m]), indexed by ``op``.
    w0_nom_m : float
        Nominal WG deflection of the model [m].
    weights : dict of str to ndarray, shape (5,)
        Constraint weights of the relative per-channel effects (``"gain"``,
        ``"misplacement"``).
    maps : tuple of callable
        Transforms of the basis, each ``Mapping -> Mapping``, applied in order.
    ripple : callable, optional
        ``ripple(ke) -> dict`` with the raw "s_t", "dpsi", "phi_in" (n_windows, m) and the
        re-aligned torque shifts for extra kinematic-error harmonics ``ke`` (tuple of
        (order, a_sin, a_cos)); ``ripple.unit(order)`` gives the unit responses at the
        current alignment, shape (2, n_windows, 5, m).
    ke : tuple of (int, float, float)
        Extra kinematic-error harmonics in the raw basis.
    ke_orders : tuple of int
        Orders with kinematic-error responses.
    ke_bound_rad : float
        Bound of the kinematic-error coefficients [rad].
    f_c_bounds : tuple of float
        Range searched for the low-pass cut-off [Hz].
    """

    raw: Mapping[str, np.ndarray]
    n_lead: int
    n_t: int
    fs: float
    window: np.ndarray
    channel: np.ndarray
    op: np.ndarray
    t_s: np.ndarray
    t_seq_s: np.ndarray
    phi_in_rad: np.ndarray
    psi_rad: np.ndarray
    psi_rate: np.ndarray
    n_in_rpm: np.ndarray
    t_out_nm: np.ndarray
    ops: tuple[tuple[float, float], ...]
    w0_nom_m: float
    weights: dict[str, np.ndarray] = field(default_factory=dict)
    maps: tuple[Callable[[Mapping[str, np.ndarray]], Mapping[str, np.ndarray]], ...] = ()
    ripple: Any = None
    ke: tuple[tuple[int, float, float], ...] = ()
    ke_orders: tuple[int, ...] = ()
    ke_bound_rad: float = 2e-3
    f_c_bounds: tuple[float, float] = (50.0, 4500.0)

    @property
    def n(self) -> int:
        return int(self.window.size)

    @property
    def n_windows(self) -> int:
        return int(self.psi_rate.size)

    @functools.cached_property
    def basis(self) -> Mapping[str, np.ndarray]:
        """Raw basis with the maps applied (lazily, cached per signals object)."""
        b: Mapping[str, np.ndarray] = self.raw
        for fn in self.maps:
            b = fn(b)
        return b

    def window_part(self, a: np.ndarray) -> np.ndarray:
        """Window samples of an extended array (..., m) -> (..., n_t)."""
        return a[..., self.n_lead:self.n_lead + self.n_t]

    def col(self, name: str) -> np.ndarray:
        """Window part of a basis signal, flattened to shape (n,)."""
        return np.ascontiguousarray(self.window_part(self.basis[name])).reshape(-1)

    def prediction(self) -> np.ndarray:
        """Nominal prediction s_wg + s_t, shape (n,) [mV/V]."""
        return self.col("s_wg") + self.col("s_t")

    @functools.cached_property
    def onehot(self) -> np.ndarray:
        """Channel indicators, shape (n, 5)."""
        return (self.channel[:, None] == np.arange(5)[None, :]).astype(float)

    def replace(self, **changes: Any) -> StrainSignals:
        return dataclasses.replace(self, **changes)


def constraint_basis(weights: np.ndarray, estimable: Any = None) -> tuple[np.ndarray, int]:
    """Basis of the per-channel values v with Σ w_c v_c = 0 over the estimable channels
    (the others are held at 0).

    Parameters
    ----------
    weights : ndarray, shape (5,)
        Positive weights.
    estimable : array of bool, shape (5,), optional
        Channels whose value is estimated (default all; at least two).

    Returns
    -------
    Q : ndarray, shape (5, n_estimable − 1)
        v = Q r for the free values r of the estimable channels other than ``ref``
        (rows of the other channels are zero).
    ref : int
        The estimable channel with the largest weight, whose value follows from the others.

    Raises
    ------
    ValueError
        Weights not 5 positive values, or fewer than two estimable channels.
    """
    w = np.asarray(weights, float)
    if w.shape != (5,) or np.any(~(w > 0)):
        raise ValueError(f"constraint weights must be 5 positive values, got {weights}")
    est = np.ones(5, bool) if estimable is None else np.asarray(estimable, bool)
    if est.shape != (5,) or est.sum() < 2:
        raise ValueError(f"estimable must flag at least 2 of the 5 channels, got {estimable}")
    ref = int(np.argmax(np.where(est, w, -np.inf)))
    free = [c for c in range(5) if c != ref and est[c]]
    q = np.zeros((5, len(free)))
    for j, c in enumerate(free):
        q[c, j] = 1.0
        q[ref, j] = -w[c] / w[ref]
    return q, ref
