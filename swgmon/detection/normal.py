"""The gear's normal behaviour: its health features as the operating conditions set them,
learnt at commissioning (a normal-behaviour model with the physics' shape).

:class:`NormalBehaviour` fits, per operating point, the bridges' span and zero drift with
the temperature, the loss torque's law of temperature and load, each feature's law of the
acting load and a tracked friction factor; :meth:`NormalBehaviour.reference` brings a
window's features to commissioning's condition, :meth:`NormalBehaviour.outside` flags a
condition commissioning did not see, :meth:`NormalBehaviour.recommission` relearns a point.
Design and sources: docs/monitor/detection.md, "The normal behaviour's laws" (and "A real day").
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field, replace

import numpy as np

from swgmon.detection.laws import (
    BLOCK,
    EFFICIENCY,
    LawFit,
    LossLaw,
    bridge_drift,
    feature_slopes,
    generic_inputs,
    generic_laws,
    load_curves,
    loss_model,
    warm_up_directions,
)
from swgsim.base.typed import check_range

#: The normal behaviour's laws (:class:`NormalConfig` ``laws``).
LAWS = ("physics", "generic")


class Outside(enum.IntFlag):
    """Bits of :meth:`NormalBehaviour.outside`: the condition commissioning did not see
    (temperature, load, friction), and ``UNJUDGED``: the window is not judged (its
    temperature is outside and no temperature law carries the normal behaviour there)."""

    TEMPERATURE = 1
    LOAD = 2
    FRICTION = 4
    UNJUDGED = 8


@dataclass
class NormalConfig:
    """How the normal behaviour follows the conditions
    (docs/monitor/detection.md, "The normal behaviour's laws").

    Attributes
    ----------
    friction_track_h : float
        Time constant of the friction factor's tracking [operating h], > 0; 0: not
        tracked (the factor stays 1).
    temperature_margin_k : float
        Where commissioning fitted the temperature terms, a window's temperature may
        exceed commissioning's range at its operating point by this much before it is
        outside [K], >= 0 (without them: by nothing,
        docs/monitor/detection.md, "The normal behaviour's laws").
    temperature_uncertainty_k : float
        The temperature reading's uncertainty [K], in [0, 10]: commissioning's range is
        its readings' widened by this on either side. 0.2, of the simulated sensor's
        resolution (0.1 K) and noise (0.05 K sd, :class:`swgsim.sensing.bridge_drift.
        TemperatureSensor`); a sensor's stated accuracy where it gives one.
    load_margin : float
        Relative margin on commissioning's acting load at the operating point [-], >= 0.
    friction_margin : float
        The friction factor may leave the range it was tracked in over commissioning
        (:attr:`NormalBehaviour.friction_range`) by this much before the condition is
        outside [-], > 0.
    extrapolation_uncertainty : float
        κ, the relative uncertainty of the correction that carries a feature (the
        bridges' and the efficiency) beyond the load and temperature commissioning saw at a point
        (:meth:`NormalBehaviour.z_and_spread`), >= 0; 0: the correction is trusted. 1, not
        tuned: an extrapolation known to its own order of magnitude. Behind a robot link
        (robot_joint, gear 3, seed 0) a 10 % heavier tool left the residual's RMS and the
        third harmonic 0.7-1.3 times the predicted correction away from it
        (docs/monitor/detection.md, "A real day").
    recommission_load : bool
        Where an operating point's acting load stays beyond what commissioning saw there
        for as many windows in a row, without an alarm, as commissioning gave the point's
        normal behaviour (a heavier tool), the monitor recommissions the point at its new load
        (:meth:`NormalBehaviour.recommission`, done by
        :class:`~swgmon.assessment.gear_monitor.GearMonitor`); False: it stays
        commissioning's, with the widened spread.
    regrease_settle_h : float
        After a re-greasing declared in the maintenance log
        (:class:`~swgmon.assessment.gear_monitor.MaintenanceEvent`), the friction factor follows
        the windows one by one for this many operating hours [h], >= 0, while the new
        grease runs in again: 72, three time constants of the slowest running-in assumed,
        24 h (4-24 h [choice; Harmonic Drive's manuals ask for a run-in after
        relubrication, unverified]; with 24 h of following, the bench's declared
        re-greasing at 41.7 h, +11 %, 12 h, gave a reduced-damping alarm at 66.9 h: the
        friction still fell faster than its tracking over ``friction_track_h``); the
        efficiency is not judged then, the bridges are. Also after an unexplained change.
    warm_up_components : int
        Without a temperature reading at commissioning: at most this many directions in
        which commissioning's z-scores at a point varied together beyond noise, and as
        many slow ones beside them (:func:`~.laws.warm_up_directions`), taken out of
        every window's z-scores within the range commissioning saw along them
        (:attr:`NormalBehaviour.warm_dir`), in [0, 5]; 0: none. 2 [choice]: on the
        bench's joint without a sensor (gear 3, family ``sensor``, design seed 100) one
        direction left the hour after each cold start at -1.1 to -1.6 σ on the second
        harmonic of bridges 1 and 3 and 5 alarms in 200 h; two left none, and both of
        each point's largest eigenvalues lay above the noise's edge.
    laws : str
        ``physics`` (the default): the laws above; ``generic``: their ablation, a generic
        regression of every feature on the acting load and the temperature per input
        speed (:func:`~.laws.generic_laws`), no friction factor (the benchmark of issue
        83 scores both).
    fit : LawFit
        The numbers the laws are fitted with (:class:`~.laws.LawFit`).
    """

    friction_track_h: float = 4.0
    temperature_margin_k: float = 2.0
    temperature_uncertainty_k: float = 0.2
    load_margin: float = 0.03
    friction_margin: float = 0.05
    extrapolation_uncertainty: float = 1.0
    recommission_load: bool = True
    regrease_settle_h: float = 72.0
    warm_up_components: int = 2
    laws: str = "physics"
    fit: LawFit = field(default_factory=LawFit)

    def check(self, key: str = "normal") -> None:
        """Refuse a field out of range in one line naming ``<key>.<field>``.

        Raises
        ------
        ValueError
        """
        check_range(self.friction_track_h, 0.0, 1e4, f"{key}.friction_track_h", "h")
        check_range(self.temperature_margin_k, 0.0, 100.0, f"{key}.temperature_margin_k",
                    "K")
        check_range(self.temperature_uncertainty_k, 0.0, 10.0,
                    f"{key}.temperature_uncertainty_k", "K",
                    why="the temperature reading's uncertainty")
        check_range(self.load_margin, 0.0, 1.0, f"{key}.load_margin")
        check_range(self.friction_margin, 0.0, 1.0, f"{key}.friction_margin", lo_open=True)
        check_range(self.extrapolation_uncertainty, 0.0, 10.0,
                    f"{key}.extrapolation_uncertainty")
        check_range(self.regrease_settle_h, 0.0, 1e4, f"{key}.regrease_settle_h", "h")
        if (isinstance(self.warm_up_components, bool)
                or not isinstance(self.warm_up_components, int)
                or not 0 <= self.warm_up_components <= 5):
            raise ValueError(f"{key}.warm_up_components must be an integer in [0, 5], got "
                             f"{self.warm_up_components!r}")
        if self.laws not in LAWS:
            raise ValueError(f"{key}.laws must be one of {', '.join(LAWS)}, got {self.laws!r}")


@dataclass
class Conditions:
    """A window's operating conditions as a real joint measures them.

    Attributes
    ----------
    torque_nm : ndarray, shape (n,)
        Acting output torque over the window (``t_out_mean_nm``) [N m].
    temperature_c : ndarray, shape (n,) or None
        The joint's temperature reading (``temperature_c``) [°C]; None: not measured.
    """

    torque_nm: np.ndarray
    temperature_c: np.ndarray | None = None

    def __getitem__(self, idx) -> Conditions:
        t = None if self.temperature_c is None else self.temperature_c[idx]
        return Conditions(self.torque_nm[idx], t)

    @classmethod
    def of(cls, meta: dict[str, np.ndarray]) -> Conditions:
        """From windows' metadata (``t_out_mean_nm``, optional ``temperature_c``)."""
        t = meta.get("temperature_c")
        return cls(np.asarray(meta["t_out_mean_nm"], float),
                   None if t is None else np.asarray(t, float))

    @classmethod
    def concat(cls, parts: list[Conditions]) -> Conditions:
        """Consecutive windows' conditions as one."""
        temps = [p.temperature_c for p in parts]
        t = None if any(x is None for x in temps) else np.concatenate(temps)
        return cls(np.concatenate([p.torque_nm for p in parts]), t)


@dataclass
class NormalBehaviour:
    """The gear's normal behaviour per operating point
    (docs/monitor/detection.md, "The normal behaviour's laws").

    Attributes
    ----------
    points : ndarray, shape (P, 2)
        (n_in_rpm, t_out_nm) of each operating point (commanded).
    mean, std : ndarray, shape (P, F)
        Commissioning's features brought to the reference condition: mean and spread.
    ref_torque, ref_temp : ndarray, shape (P,)
        Commissioning's mean acting load [N m] and temperature [°C] (NaN: no temperature
        terms, none measured or a spread below ``config.fit.min_spread_k``).
    torque_range, temp_range : ndarray, shape (P, 2)
        Commissioning's range of acting load [N m] and temperature [°C], the latter
        widened by ``temperature_uncertainty_k`` (NaN: none measured).
    gain, zero : ndarray, shape (5,)
        γ_c [1/K] and ζ_c [mV/V per K] of each bridge (0 without temperature).
    loss : LossLaw
        The loss torque's law at each point (:func:`~.laws.loss_model`).
    load : ndarray, shape (P, 3, F)
        Per point, the quadratic in τ of each feature's load curve at its speed (squared
        amplitudes, offsets, residual power; unused columns zero).
    config : NormalConfig
    count : ndarray of int, shape (P,), optional
        Commissioning's windows per point (a point recommissioned at a new load gathers
        as many).
    slope : ndarray, shape (P, F), optional
        Per point, each bridge feature's own change per K left after the bridges' gain
        and zero drift [unit per K] (0 without temperature;
        docs/monitor/detection.md, "The normal behaviour's laws").
    friction_range : ndarray, shape (2,)
        The friction factor's range over commissioning, as tracked there [-] (default
        [1, 1]). On the joint in motion the factor's own noise spans ±5 % over 1000 h
        (robot_joint_motion gear 1, seed 0: 0.94-1.03), which a margin about 1 alone
        advised as a friction change 11 times on a gear with none.
    loss_band : tuple or None
        Where commissioning did not cool (:func:`~.laws.cools`) and the loss law is only
        bounded, the laws at its bounds, two :class:`~.laws.LossLaw`
        (:func:`~.laws.loss_model`): the efficiency is judged in its spread widened by the
        difference they make at the window's condition (:meth:`_law_spread`). None where
        the law was learnt.
    warm_dir, warm_range : ndarray, shapes (P, K, F) and (P, K, 2), or None
        Without a temperature reading at commissioning: per point, the directions in
        which commissioning's z-scores varied together beyond noise (unit vectors; zero
        rows where fewer than K did) and the range of commissioning's windows along each
        (:func:`~.laws.warm_up_directions`). :meth:`z_and_spread` takes each window's
        part along them out, in σ, clipped to that range: a joint without a sensor warms
        up and cools down as commissioning saw, and a change beyond what its warm-ups did
        stays in the z-scores; at a load beyond commissioning's the part beyond is an
        extrapolation that widens the spread by its own size (:meth:`_in_spread`). None
        with a reading.
    warm_torque : ndarray, shape (P, 2), or None
        Without a reading: the load range at which each point's warm-ups were seen,
        commissioning's :attr:`torque_range`, kept when that range grows or the point is
        relearnt at a new load (the warm-ups are carried, not seen again): a heavier tool
        heats the joint beyond them for as long as it stays. None with a reading.
    generic : list or None
        With ``laws`` ``generic``: each point's generic regression
        (:func:`~.laws.generic_laws`), in place of the drift, loss and load laws; None
        with the physics' laws.
    """

    points: np.ndarray
    mean: np.ndarray
    std: np.ndarray
    ref_torque: np.ndarray
    ref_temp: np.ndarray
    torque_range: np.ndarray
    temp_range: np.ndarray
    gain: np.ndarray
    zero: np.ndarray
    loss: LossLaw
    load: np.ndarray
    config: NormalConfig = field(default_factory=NormalConfig)
    count: np.ndarray | None = None
    slope: np.ndarray | None = None
    friction_range: np.ndarray = field(default_factory=lambda: np.ones(2))
    loss_band: tuple | None = None
    warm_dir: np.ndarray | None = None
    warm_range: np.ndarray | None = None
    warm_torque: np.ndarray | None = None
    generic: list | None = None

    # ------------------------------------------------------------------ fitting
    @classmethod
    def fit(cls, feats: np.ndarray, points: np.ndarray, cond: Conditions,
            config: NormalConfig | None = None, friction: np.ndarray | float = 1.0
            ) -> NormalBehaviour:
        """From commissioning windows: features (n, F), operating points (n, 2) and
        conditions; ``friction``, the friction factor in force at each window, shape (n,)
        (:meth:`friction_ratio` tracked over commissioning; default 1), sets the
        efficiency's mean and spread at the reference condition (not its loss law).

        Raises
        ------
        ValueError
            If an operating point has fewer than two windows.
        """
        config = config or NormalConfig()
        ops, inv = np.unique(points, axis=0, return_inverse=True)
        inv = inv.ravel()
        if np.bincount(inv).min() < 2:
            raise ValueError("the normal behaviour needs at least two windows per operating "
                             "point")
        n_p, n_f = len(ops), feats.shape[1]
        tq = cond.torque_nm
        ref_torque = np.array([tq[inv == k].mean() for k in range(n_p)])
        torque_range = np.array([[tq[inv == k].min(), tq[inv == k].max()] for k in range(n_p)])
        temp = cond.temperature_c
        use_t = temp is not None and np.ptp(temp) >= config.fit.min_spread_k
        ref_temp = np.array([temp[inv == k].mean() if use_t else np.nan for k in range(n_p)])
        u = config.temperature_uncertainty_k
        temp_range = np.array([[temp[inv == k].min() - u, temp[inv == k].max() + u]
                               if temp is not None else [np.nan, np.nan] for k in range(n_p)])
        dt = temp - ref_temp[inv] if use_t else np.zeros(len(feats))
        gain, zero = (bridge_drift(feats, inv, dt, config.fit.significant_sd) if use_t
                      else (np.zeros(5), np.zeros(5)))
        loss, band = loss_model(feats[:, EFFICIENCY], tq, temp if use_t else None, ops, inv,
                                config.fit)
        nb = cls(ops, np.zeros((n_p, n_f)), np.ones((n_p, n_f)), ref_torque, ref_temp,
                 torque_range, temp_range, gain, zero, loss, np.zeros((n_p, 3, n_f)), config,
                 np.bincount(inv, minlength=n_p), loss_band=band)
        if config.laws == "generic":
            nb.generic, nb.loss_band = generic_laws(feats, inv, ops, tq,
                                                    temp if use_t else None, config.fit), None
        elif use_t:
            nb.slope = feature_slopes(nb._temperature_corrected(feats, inv, dt), inv, dt)
        if nb.generic is None:
            nb.load = load_curves(nb._temperature_corrected(feats, inv, dt), inv, ops,
                                  ref_torque)
        ref = nb._corrected(feats, inv, cond, np.broadcast_to(friction, (len(feats),)))
        nb.mean = np.stack([ref[inv == k].mean(axis=0) for k in range(n_p)])
        nb.std = np.maximum(np.stack([ref[inv == k].std(axis=0, ddof=1)
                                      for k in range(n_p)]), 1e-12)
        if temp is None and config.warm_up_components > 0:
            nb.warm_dir, nb.warm_range = warm_up_directions(
                (ref - nb.mean[inv]) / nb.std[inv], inv, config.warm_up_components,
                config.fit.warm_up_average)
            nb.warm_torque = torque_range.copy()
        return nb

    # ------------------------------------------------------------------ using it
    def index(self, points: np.ndarray) -> np.ndarray:
        """Row of each window's operating point; -1 where commissioning saw none."""
        idx = np.full(len(points), -1)
        for i, o in enumerate(self.points):
            idx[(points == o).all(axis=1)] = i
        return idx

    def _check(self, points: np.ndarray, index: np.ndarray | None) -> np.ndarray:
        i = self.index(points) if index is None else index
        if (i < 0).any():
            bad = points[np.flatnonzero(i < 0)[0]]
            raise ValueError(f"operating point {bad[0]:g} rpm, {bad[1]:g} N m was not seen at "
                             "commissioning; the normal behaviour has "
                             f"{[tuple(map(float, o)) for o in self.points]}")
        return i

    def reference(self, feats: np.ndarray, points: np.ndarray, cond: Conditions,
                  friction: np.ndarray | float = 1.0, index: np.ndarray | None = None
                  ) -> np.ndarray:
        """Windows' features brought to the reference condition of their operating point
        (docs/monitor/detection.md, "The normal behaviour's laws"), shape (n, F).

        Parameters
        ----------
        feats : ndarray, shape (n, F)
        points : ndarray, shape (n, 2)
        cond : Conditions
        friction : float or ndarray, shape (n,)
            The friction factor r of each window (:meth:`friction_ratio`).
        index : ndarray of int, shape (n,), optional
            :meth:`index` of ``points``, when known.

        Raises
        ------
        ValueError
            If a window's operating point was not seen at commissioning.
        """
        i = self._check(points, index)
        return self._corrected(feats, i, cond, np.broadcast_to(friction, (len(feats),)))

    def unwidened(self) -> NormalBehaviour:
        """This normal behaviour extrapolating beyond commissioning's range in
        commissioning's spread (``extrapolation_uncertainty`` 0): a fit over conditions
        would be pulled to its grid's ends by the widened spread, and a severity read in
        it shrinks (:meth:`~swgmon.assessment.gear_monitor.GearMonitor.inputs`)."""
        return replace(self, config=replace(self.config, extrapolation_uncertainty=0.0))

    def z(self, feats: np.ndarray, points: np.ndarray, cond: Conditions | None = None,
          friction: np.ndarray | float = 1.0, index: np.ndarray | None = None) -> np.ndarray:
        """z-scores of windows against the normal behaviour, shape (n, F); ``cond`` None:
        each window at its point's reference condition (no correction). Beyond the
        conditions commissioning saw, in the widened spread of :meth:`z_and_spread`.

        Raises
        ------
        ValueError
            If a window's operating point was not seen at commissioning.
        """
        return self.z_and_spread(feats, points, cond, friction, index)[0]

    def z_and_spread(self, feats: np.ndarray, points: np.ndarray,
                     cond: Conditions | None = None, friction: np.ndarray | float = 1.0,
                     index: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """z-scores of windows and the spread they are measured in, shapes (n, F) each.

        The spread is commissioning's σ at the window's operating point, widened where
        the window's load or temperature lies beyond commissioning's range there: the
        correction that carries a bridge's feature from the range's edge to the window's
        condition, ``u``, is an extrapolation of its load curve (a quadratic through the
        loads commissioning saw at the speed) and drift law, trusted to
        ``extrapolation_uncertainty`` (κ) times its own size, so the spread is
        ``sqrt(σ² + (κ u)²)``. Inside the range ``u`` is zero and the spread σ. The
        efficiency's correction (its loss law carried beyond the loads it was
        fitted at) widens its spread alike: behind a robot link a 10 % heavier tool left
        the efficiency 1.2 σ above the law's extrapolation (docs/monitor/detection.md, "A real
        day"). The widening lasts until the point is recommissioned at its new load
        (:meth:`recommission`). Where commissioning only bounded the friction's
        temperature law (:attr:`loss_band`), the efficiency's spread also holds the
        difference its bounds make (:meth:`_law_spread`).

        Raises
        ------
        ValueError
            If a window's operating point was not seen at commissioning.
        """
        i = self._check(points, index)
        if cond is None:
            cond = Conditions(self.ref_torque[i], None)
        return self._z_in(feats, i, cond, np.broadcast_to(friction, (len(feats),)))

    def _z_in(self, feats: np.ndarray, i: np.ndarray, cond: Conditions, fr: np.ndarray,
              load: tuple[np.ndarray, np.ndarray] | None = None
              ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`z_and_spread` of windows at point indices ``i``, with the friction
        factors ``fr`` (n,) and, when known, their :meth:`_load_terms` ``load``."""
        ref = self._corrected(feats, i, cond, fr, load)
        spread = self.std[i]
        edge, beyond = self._edge(i, cond)
        kappa = self.config.extrapolation_uncertainty
        if kappa > 0 and beyond.any():
            b, law = np.flatnonzero(beyond), slice(0, EFFICIENCY + 1)
            u = ref[b, law] - self._corrected(feats[b], i[b], edge[b], fr[b])[:, law]
            spread = spread.copy()
            spread[b, law] = np.sqrt(spread[b, law] ** 2 + (kappa * u) ** 2)
        w = self._law_spread(feats, i, cond, fr)
        if w is not None:
            spread = spread.copy()
            spread[:, EFFICIENCY] = np.sqrt(spread[:, EFFICIENCY] ** 2 + w ** 2)
        return self._in_spread(ref - self.mean[i], i, spread, self._heavier(i, cond))

    def z_over_friction(self, feats: np.ndarray, points: np.ndarray,
                        cond: Conditions | None, friction: np.ndarray,
                        index: np.ndarray | None = None) -> np.ndarray:
        """z-scores of the same windows at many friction factors, shape (m, n, F): equal to
        :meth:`z` of the windows repeated m times (``friction.ravel()`` the factor of each),
        at a fraction of its cost, for the friction fits
        (:func:`swgmon.assessment.unexplained.fit_friction`): a factor moves only the
        efficiency (its loss law, docs/monitor/detection.md, "The normal behaviour's laws") and,
        beyond commissioning's range, its spread, so every other feature is corrected once.

        Parameters
        ----------
        feats : ndarray, shape (n, F)
        points : ndarray, shape (n, 2)
        cond : Conditions or None
        friction : ndarray, shape (m, n)
            The friction factors tried, m per window.
        index : ndarray of int, shape (n,), optional

        Raises
        ------
        ValueError
            If a window's operating point was not seen at commissioning.
        """
        i = self._check(points, index)
        if cond is None:
            cond = Conditions(self.ref_torque[i], None)
        m, n, law, e = len(friction), len(feats), slice(0, EFFICIENCY + 1), EFFICIENCY
        ref = self._corrected(feats, i, cond, np.ones(n))  # (n, F): all but the efficiency
        ref_e = self._efficiency(feats, i, cond, friction)  # (m, n): the efficiency
        spread, spread_e = self.std[i].copy(), np.repeat(self.std[i, e][None], m, axis=0)
        edge, beyond = self._edge(i, cond)
        kappa = self.config.extrapolation_uncertainty
        if kappa > 0 and beyond.any():
            b = np.flatnonzero(beyond)
            at_edge = self._corrected(feats[b], i[b], edge[b], np.ones(len(b)))
            u = ref[b, law] - at_edge[:, law]
            spread[b, law] = np.sqrt(spread[b, law] ** 2 + (kappa * u) ** 2)
            u_e = ref_e[:, b] - self._efficiency(feats[b], i[b], edge[b], friction[:, b])
            spread_e[:, b] = np.sqrt(spread_e[:, b] ** 2 + (kappa * u_e) ** 2)
        w = self._law_spread(feats, i, cond, friction)
        if w is not None:
            spread_e = np.sqrt(spread_e ** 2 + w ** 2)
        dev, dev_e = ref - self.mean[i], ref_e - self.mean[i, e]
        if self.warm_dir is None:  # the columns do not mix: all but one are the same
            z = np.repeat((dev / spread)[None], m, axis=0)
            z[..., e] = dev_e / spread_e
            return z
        dev, spread = np.repeat(dev[None], m, axis=0), np.repeat(spread[None], m, axis=0)
        dev[..., e], spread[..., e] = dev_e, spread_e
        z, _ = self._in_spread(dev.reshape(m * n, -1), np.tile(i, m),
                               spread.reshape(m * n, -1), np.tile(self._heavier(i, cond), m))
        return z.reshape(m, n, -1)

    def z_over_temperature(self, feats: np.ndarray, points: np.ndarray,
                           torque_nm: np.ndarray, temps: np.ndarray, friction: np.ndarray,
                           index: np.ndarray | None = None) -> np.ndarray:
        """z-scores of the same windows at many temperatures, shape (n, G, F): equal to
        :meth:`z` of each window repeated G times (``temps[k]`` its temperatures) at a
        lower cost, for the fits of the temperature
        (:func:`swgmon.assessment.sensor_check.best_temperature`): the load curves' correction
        does not depend on the temperature, so it is computed once per window.

        Parameters
        ----------
        feats : ndarray, shape (n, F)
        points : ndarray, shape (n, 2)
        torque_nm : ndarray, shape (n,)
            Each window's load [N m].
        temps : ndarray, shape (n, G)
            The temperatures tried [°C], G per window.
        friction : ndarray, shape (n,)
            Each window's friction factor.
        index : ndarray of int, shape (n,), optional

        Raises
        ------
        ValueError
            If a window's operating point was not seen at commissioning.
        """
        i = self._check(points, index)
        n, g = temps.shape
        rep = np.repeat(np.arange(n), g)
        div, shift = self._load_terms(i, torque_nm)
        z, _ = self._z_in(feats[rep], i[rep], Conditions(torque_nm[rep], temps.ravel()),
                          np.asarray(friction, float)[rep], (div[rep], shift[rep]))
        return z.reshape(n, g, -1)

    def _in_spread(self, dev: np.ndarray, index: np.ndarray, spread: np.ndarray,
                   loaded: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """z-scores of deviations from the mean (n, F) in ``spread`` (n, F), and the spread,
        without a reading the warm-ups taken out (:meth:`without_warm_ups`) in σ, where
        their directions were learnt, before any widening: a cold start beyond the load
        range is taken out as commissioning saw it, not bent by the features' unequal
        widening. At a load beyond the one the warm-ups were seen at by more than
        ``load_margin`` (``loaded``, shape (n,) bool, :meth:`_heavier`: a heavier tool
        heats the joint beyond anything commissioning saw), the part beyond the range
        commissioning spanned along a direction is taken out too, as an extrapolation of
        the latent temperature's law trusted to ``extrapolation_uncertainty`` (κ) times
        its size, as a reading's drift law is beyond its range: the spread of each feature
        grows to ``sqrt(s² + (κ σ e)²)``, e its share of the part beyond [σ]. At
        commissioning's loads it stays in the z-scores (there a joint warms no further
        than commissioning saw, and a root crack's pattern lies along the bridges'
        warm-up: in the training lives of bench gear 1, 776 of 1,350 root-crack windows
        lay beyond the range)."""
        if self.warm_dir is None:
            return dev / spread, spread
        sd = self.std[index]
        zs = dev / sd
        d, u, inside = self._along_warm_ups(zs, index)
        z = zs - np.einsum("nk,nkf->nf", inside, d)
        kappa = self.config.extrapolation_uncertainty
        b = np.flatnonzero((u != inside).any(axis=1) & loaded) if kappa > 0 \
            else np.array([], int)
        if b.size:
            e = np.einsum("nk,nkf->nf", (u - inside)[b], d[b])
            z[b] -= e
            spread = spread.copy()
            spread[b] = np.sqrt(spread[b] ** 2 + (kappa * sd[b] * e) ** 2)
        return z * (sd / spread), spread

    def without_warm_ups(self, z: np.ndarray, index: np.ndarray) -> np.ndarray:
        """z-scores (n, F) of windows at the points ``index`` (n,) with their parts along
        commissioning's warm-up directions taken out, each clipped to the range
        commissioning saw (:attr:`warm_dir`); ``z`` itself where there are none (a
        temperature reading)."""
        if self.warm_dir is None:
            return z
        d, _, inside = self._along_warm_ups(z, index)
        return z - np.einsum("nk,nkf->nf", inside, d)

    def _along_warm_ups(self, z: np.ndarray, index: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The warm-up directions of windows at points ``index`` (n, K, F), the parts of
        their z-scores in σ (n, F) along them and those parts clipped to commissioning's
        range (n, K) each."""
        d, r = self.warm_dir[index], self.warm_range[index]  # (n, K, F), (n, K, 2)
        u = np.einsum("nf,nkf->nk", z, d)
        return d, u, np.clip(u, r[..., 0], r[..., 1])

    def recommission(self, k: int, ref: np.ndarray, torque_nm: np.ndarray) -> None:
        """Take windows of operating point ``k`` at a load commissioning did not see as
        its new normal: its mean, spread and load range become theirs; the load curves,
        drift and loss laws stay commissioning's, and so does the rule's calibration (the
        z-scores' distribution, standardised, is taken to keep its shape). For a
        persistent change of the acting load, e.g. a heavier tool (:class:`NormalConfig`
        ``recommission_load``): behind a robot link the bridges' ripple at the new load
        is not only shifted but wider than commissioning's (a mode near the excitation).
        Without a temperature reading the windows, as many as commissioning gave the point
        but gathered in about half its hours, need not span a cold start: the point keeps
        commissioning's warm-up directions and their range (:meth:`_warm_ups_at`) and a
        spread no smaller than commissioning's, which holds its daily cycle. Learnt from
        the windows alone, a point relearnt at a lighter tool's load from warm hours read
        every later cold start as a root crack (bench gear 3, family ``all``, design
        seed 101: 47 gear-fault alarms in 200 h).

        Parameters
        ----------
        k : int
            Row of the operating point.
        ref : ndarray, shape (m, F)
            The windows' features at the reference condition (:meth:`reference`), m >= 2.
        torque_nm : ndarray, shape (m,)
            Their acting load [N m].

        Raises
        ------
        ValueError
            If fewer than two windows are given.
        """
        if len(ref) < 2:
            raise ValueError("recommissioning a point needs at least two windows")
        ref = np.asarray(ref, float)
        mean, std = ref.mean(axis=0), np.maximum(ref.std(axis=0, ddof=1), 1e-12)
        if self.warm_dir is not None:  # no reading: the daily cycle's spread kept
            std = np.maximum(std, self.std[k])
            self.warm_dir[k], self.warm_range[k] = self._warm_ups_at(k, ref, mean, std)
        self.mean[k], self.std[k] = mean, std
        self.torque_range[k] = [float(np.min(torque_nm)), float(np.max(torque_nm))]

    def _warm_ups_at(self, k: int, ref: np.ndarray, mean: np.ndarray, std: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
        """Commissioning's warm-up directions of point ``k`` and their range, carried to
        its new normal (mean, std (F,)) from windows ``ref`` (m, F) that need not span a
        cold start (a point relearns from as many windows as commissioning gave it, about
        half of commissioning's hours): each direction in physical units, ``d σ_old``, in
        the new spread; its range commissioning's, in the new spread about the new mean,
        grown to hold the windows. Shapes (K, F), (K, 2)."""
        d_old, r_old = self.warm_dir[k], self.warm_range[k]
        phys = d_old * (self.std[k] / std)
        scale = np.linalg.norm(phys, axis=1)  # 0 where commissioning had no direction
        d = np.divide(phys, scale[:, None], out=np.zeros_like(phys), where=scale[:, None] > 0)
        shift = ((mean - self.mean[k]) / std) @ d.T  # (K,): the new mean, in the new frame
        u = ((ref - mean) / std) @ d.T  # (m, K)
        lo = np.minimum(scale * r_old[:, 0] - shift, u.min(axis=0))
        hi = np.maximum(scale * r_old[:, 1] - shift, u.max(axis=0))
        return d, np.where(scale[:, None] > 0, np.stack([lo, hi], axis=1), 0.0)

    def extend_load_range(self, k: int, torque_nm: np.ndarray) -> None:
        """Grow operating point ``k``'s load range to cover ``torque_nm`` [N m] (where
        commissioning's laws were found to hold there; mean and spread unchanged)."""
        self.torque_range[k] = [min(self.torque_range[k, 0], float(np.min(torque_nm))),
                                max(self.torque_range[k, 1], float(np.max(torque_nm)))]

    def _loaded(self, i: np.ndarray, cond: Conditions,
                ranges: np.ndarray | None = None) -> np.ndarray:
        """Windows whose acting load lies beyond ``ranges`` (P, 2) at their point, by default
        the point's load range (the advisory's :attr:`Outside.LOAD`), by more than
        ``load_margin``, shape (n,) bool."""
        r = self.torque_range if ranges is None else ranges
        span = self.config.load_margin * np.abs(self.ref_torque[i])
        return (cond.torque_nm < r[i, 0] - span) | (cond.torque_nm > r[i, 1] + span)

    def _heavier(self, i: np.ndarray, cond: Conditions) -> np.ndarray:
        """Windows at a load beyond the one their point's warm-ups were seen at
        (:attr:`warm_torque`; without it the load range), shape (n,) bool."""
        return self._loaded(i, cond, self.warm_torque)

    def _edge(self, i: np.ndarray, cond: Conditions) -> tuple[Conditions, np.ndarray]:
        """Each window's conditions clipped into commissioning's range at its point, and
        which windows were clipped, shape (n,) bool."""
        tq = np.clip(cond.torque_nm, self.torque_range[i, 0], self.torque_range[i, 1])
        beyond = tq != cond.torque_nm
        temp = cond.temperature_c
        if temp is not None and np.isfinite(self.ref_temp).all():
            temp = np.clip(temp, self.temp_range[i, 0], self.temp_range[i, 1])
            beyond |= temp != cond.temperature_c
        return Conditions(tq, temp), beyond

    def friction_ratio(self, feats: np.ndarray, points: np.ndarray, cond: Conditions,
                       index: np.ndarray | None = None) -> np.ndarray:
        """Each window's loss torque over the model's prediction at its load and
        temperature (the friction factor's evidence), shape (n,)."""
        i = self._check(points, index)
        if self.generic is not None:  # the ablation tracks no friction factor
            return np.ones(len(i))
        tq = np.maximum(np.abs(cond.torque_nm), 1e-9)
        eta = np.clip(feats[:, EFFICIENCY], 1e-6, 1.0)
        pred = self._loss(i, cond)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(pred > 0, tq * (1.0 / eta - 1.0) / pred, 1.0)

    @property
    def temperature_law(self) -> bool:
        """Whether commissioning fitted the temperature terms
        (docs/monitor/detection.md, "The normal behaviour's laws")."""
        return bool(np.isfinite(self.ref_temp).all())

    def outside(self, points: np.ndarray, cond: Conditions, friction: np.ndarray | float,
                index: np.ndarray | None = None) -> np.ndarray:
        """Which condition each window has that commissioning did not see: a bit field,
        :attr:`Outside.TEMPERATURE` (1), :attr:`Outside.LOAD` (2), :attr:`Outside.FRICTION`
        (4), and :attr:`Outside.UNJUDGED` (8) where the temperature is outside with no
        temperature law (docs/monitor/detection.md, "The normal behaviour's laws"); 0: none;
        shape (n,) int."""
        i = self._check(points, index)
        c = self.config
        out = np.zeros(len(points), np.int64)
        if cond.temperature_c is not None and np.isfinite(self.temp_range[i]).all():
            t = cond.temperature_c
            law = self.temperature_law
            margin = c.temperature_margin_k if law else 0.0
            lo, hi = self.temp_range[i, 0], self.temp_range[i, 1]
            beyond = (t < lo - margin) | (t > hi + margin)
            out |= beyond * (Outside.TEMPERATURE if law
                             else Outside.TEMPERATURE | Outside.UNJUDGED)
        out |= self._loaded(i, cond) * Outside.LOAD
        fr = np.broadcast_to(np.asarray(friction, float), (len(points),))
        out |= self.beyond_friction(fr) * Outside.FRICTION
        return out

    def beyond_friction(self, friction: np.ndarray | float) -> np.ndarray:
        """Whether each friction factor lies beyond commissioning's range
        (:attr:`friction_range`) by more than ``friction_margin``: a friction commissioning
        did not see; bool, the shape of ``friction``."""
        lo, hi = self.friction_range
        fr, m = np.asarray(friction, float), self.config.friction_margin
        return (fr < lo - m) | (fr > hi + m)

    # ------------------------------------------------------------------ internals
    def _gain(self, dt: np.ndarray) -> np.ndarray:
        """Each window's bridge gain relative to the reference, shape (n, 5)."""
        return 1.0 + self.gain[None, :] * dt[:, None]

    def _dt(self, i: np.ndarray, cond: Conditions) -> np.ndarray:
        if cond.temperature_c is None or not np.isfinite(self.ref_temp).all():
            return np.zeros(len(i))
        return cond.temperature_c - self.ref_temp[i]

    def _temperature_corrected(self, feats: np.ndarray, i: np.ndarray, dt: np.ndarray
                               ) -> np.ndarray:
        """Features with the bridges' temperature drift taken out (the efficiency's is in
        the loss model)."""
        out = np.array(feats, float)
        g = self._gain(dt)
        for c in range(5):
            j0 = c * BLOCK
            out[:, j0] = (out[:, j0] - self.zero[c] * dt) / g[:, c]
            out[:, j0 + 1:j0 + BLOCK - 1] /= g[:, c:c + 1]
            out[:, j0 + BLOCK - 1] -= np.log10(g[:, c])
        if self.slope is not None:
            out[:, :EFFICIENCY] -= self.slope[i, :EFFICIENCY] * dt[:, None]
        return out

    def _loss(self, i: np.ndarray, cond: Conditions,
              law: LossLaw | None = None) -> np.ndarray:
        """Predicted loss torque at each window's load and temperature [N m], by the
        loss law ``law`` (None: commissioning's)."""
        temp = cond.temperature_c if np.isfinite(self.ref_temp).all() else None
        return (self.loss if law is None else law).predict(i, np.abs(cond.torque_nm), temp)

    def _corrected(self, feats: np.ndarray, i: np.ndarray, cond: Conditions,
                   friction: np.ndarray,
                   load: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
        """Features at the reference condition of their point
        (docs/monitor/detection.md, "The normal behaviour's laws"); ``load``: :meth:`_load_terms` of
        the windows' loads, when known."""
        if self.generic is not None:
            return np.asarray(feats, float) - self._generic_shift(i, cond)
        div, shift = self._load_terms(i, cond.torque_nm) if load is None else load
        out = self._temperature_corrected(feats, i, self._dt(i, cond))
        out /= div
        out += shift
        out[:, EFFICIENCY] = self._efficiency(feats, i, cond, friction)
        return out

    def _load_terms(self, i: np.ndarray, torque_nm: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
        """The load curves' correction of features at loads ``torque_nm`` to their point's
        reference load, as a divisor and a shift (n, F) each, ``x / div + shift``: the
        offset's line taken out, the harmonics' amplitudes divided by the square root of
        the curve's ratio, the residual's log10 shifted by half its log10 (the
        efficiency's correction is in its loss law: divisor 1, shift 0). It does not
        depend on the temperature, so a fit over temperatures computes it once."""
        tq = np.abs(torque_nm)
        t0 = np.abs(self.ref_torque[i])
        q = self.load[i]  # (n, 3, F)

        def curve(tau):  # (n, F)
            return q[:, 0] + q[:, 1] * tau[:, None] + q[:, 2] * tau[:, None] ** 2

        at, at0 = curve(tq), curve(t0)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where((at > 0) & (at0 > 0), at / at0, 1.0)
        div, shift = np.ones_like(at), np.zeros_like(at)
        for c in range(5):
            j0 = c * BLOCK
            shift[:, j0] = -(at - at0)[:, j0]  # the offset's line
            div[:, j0 + 1:j0 + BLOCK - 1] = np.sqrt(ratio[:, j0 + 1:j0 + BLOCK - 1])
            shift[:, j0 + BLOCK - 1] = -0.5 * np.log10(ratio[:, j0 + BLOCK - 1])
        return div, shift

    def _efficiency(self, feats: np.ndarray, i: np.ndarray, cond: Conditions,
                    friction: np.ndarray, law: LossLaw | None = None
                    ) -> np.ndarray:
        """The efficiency at the reference condition of its point with friction factors
        ``friction`` (n,) or (m, n): its loss law's prediction (``law``, :meth:`_loss`) at
        the window's load and temperature taken out, the reference's put in; the shape of
        ``friction`` (the ablation's generic regression, which has no friction factor,
        the same for every factor)."""
        if self.generic is not None:
            eta = feats[:, EFFICIENCY] - self._generic_shift(i, cond)[:, EFFICIENCY]
            return np.broadcast_to(eta, np.shape(friction)).copy()
        tq, t0 = np.abs(cond.torque_nm), np.abs(self.ref_torque[i])
        ref_cond = Conditions(t0, None if cond.temperature_c is None
                              else self.ref_temp[i])
        pred = friction * self._loss(i, cond, law)
        pred0 = self._loss(i, ref_cond, law)
        with np.errstate(divide="ignore", invalid="ignore"):
            eta_pred = np.where(tq > 0, tq / (tq + pred), 0.0)
            eta_ref = np.where(t0 > 0, t0 / (t0 + pred0), 0.0)
        return feats[:, EFFICIENCY] - eta_pred + eta_ref

    def _generic_shift(self, i: np.ndarray, cond: Conditions) -> np.ndarray:
        """What the generic regression (:attr:`generic`) says the windows' conditions add
        to their features over their point's reference condition, shape (n, F): without
        a temperature the reference's taken, a NaN reading gives NaN (as the laws do)."""
        law_t = self.temperature_law
        out = np.full((len(i), self.mean.shape[1]), np.nan)
        for k in np.unique(i):
            m = np.flatnonzero(i == k)
            t_ref = np.full(m.size, self.ref_temp[k]) if law_t else None
            t = t_ref if t_ref is None or cond.temperature_c is None else cond.temperature_c[m]
            at = generic_inputs(cond.torque_nm[m], t)
            ok = np.isfinite(at).all(axis=1)
            if not ok.any():
                continue
            ref = generic_inputs(np.full(m.size, self.ref_torque[k]), t_ref)[ok]
            out[m[ok]] = self.generic[k].predict(at[ok]) - self.generic[k].predict(ref)
        return out

    def _law_spread(self, feats: np.ndarray, i: np.ndarray, cond: Conditions,
                    friction: np.ndarray) -> np.ndarray | None:
        """The difference the laws at its bounds (:attr:`loss_band`) make to the
        efficiency at the reference condition, with friction factors ``friction`` (n,) or
        (m, n): what commissioning could not learn, in the efficiency's spread; the shape
        of ``friction``. None where the law was learnt or the windows have no temperature."""
        if self.loss_band is None or cond.temperature_c is None:
            return None
        lo, hi = (self._efficiency(feats, i, cond, friction, law) for law in self.loss_band)
        return np.abs(lo - hi)


__all__ = ["BLOCK", "Conditions", "EFFICIENCY", "LAWS", "NormalBehaviour", "NormalConfig",
           "Outside"]
