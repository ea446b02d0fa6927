"""Accepted friction effects as an option of the simulation chain.

A calibration writes its accepted effects as a list (``summary.json`` key
``friction_effects``, or ``friction_effects.yaml``)::

    friction_effects:
      - {kind: stribeck, params: {f_s: 0.12, v_st: 0.02}}
      - {kind: presliding, params: {f_d: 0.1, q_c: 4.6e-4}}

:class:`FrictionEffects` turns such a list into an extra friction torque of
(t, q, q̇, q̈) [s, rad, rad/s, rad/s²] -> τ [N m], in the joint coordinate (gear output
angle, τ positive along q̇), which the dynamics add to the paper-law friction:

* :meth:`FrictionEffects.__call__` evaluates a whole trajectory (1-D arrays in time
  order); states (presliding, lag) are integrated exactly along it.
* :meth:`FrictionEffects.torque` evaluates one time step for any array shape (e.g. one
  value per variant), with the states passed in; :meth:`FrictionEffects.state_derivative`
  gives their time derivatives for an ODE integrator (python-control style ``rhs``).

Effects that act *through* the friction law (``velocity_lag``) need the base model
(paper-law) parameters: the extra torque is then friction law with the effects minus
friction law without them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from swgsim.gear.friction.effects import (
    MeasuredVariable,
    Presliding,
    TemperatureFriction,
    VelocityLag,
    make_effect,
)
from swgsim.gear.friction.signals import FrictionSignals, PaperLaw, Scales
from swgsim.gear.terms import Term, evaluate_terms

__all__ = ["FrictionEffects", "friction_effects_from_config", "parse_effects"]


def parse_effects(effects: Sequence[Mapping[str, Any]]) -> list[tuple[Term, np.ndarray,
                                                                        np.ndarray]]:
    """Validate an effect list and build (term, coef, theta) triples.

    Parameters
    ----------
    effects : sequence of mapping
        Entries ``{"kind": key, "params": {raw name: value}}``; optional ``"name"``
        (``"kind"`` defaults to it without a ``#k`` suffix) and ``"options"`` (e.g.
        ``{"use_load": true}`` for ``load_coulomb``).

    Returns
    -------
    list of (Term, ndarray, ndarray)

    Raises
    ------
    KeyError
        Unknown effect or wrong parameter names (the message lists the right ones).
    ValueError
        A log-scaled parameter (time constant, period, ...) that is not positive.
    """
    out = []
    for i, e in enumerate(effects):
        if not isinstance(e, Mapping):
            raise ValueError(f"effect {i} must be a mapping with kind and params, got {e!r}")
        kind = e.get("kind") or str(e.get("name", "")).split("#")[0]
        name = e.get("name") or kind
        options = dict(e.get("options") or {})
        try:
            term = make_effect(kind, name, **options)
        except TypeError as err:
            raise KeyError(f"effect {name!r}: bad options {options}: {err}") from None
        missing = [o for o in term.required_options() if o not in options]
        if missing:
            raise KeyError(f"effect {name!r} ({kind}) needs options {missing} (the calibrated "
                           "range of q; summary.json and friction_effects.yaml carry them)")
        coef, theta = term.from_params(dict(e.get("params", {})))
        for p, v in zip(term.nonlinear, theta, strict=True):
            if p.log and not v > 0:
                raise ValueError(f"effect {name!r}: parameter {p.name} must be > 0 "
                                 f"[{p.unit}], got {v}")
        out.append((term, coef, theta))
    return out


class FrictionEffects:
    """Extra friction torque of a list of library effects.

    Parameters
    ----------
    effects : sequence of mapping
        See :func:`parse_effects`.
    v_s : float
        Smooth-sign velocity tanh(q̇ / v_s) [rad/s] (``v_s_rad_s`` in summary.json);
        may be None when ``effects`` is empty (the torque is then zero).
    base model : mapping, optional
        Paper-law parameters ``{b0, b1, b2, b3, theta_b}`` [N m, N m s/rad, N m s³/rad³,
        N m, rad]; required when an effect acts through the friction law
        (``velocity_lag``).
    t0 : float, default 0
        Time origin of the drift effects [s] (``t0_s`` in summary.json).

    Raises
    ------
    ValueError
        ``v_s`` not positive (with effects), a transform (``velocity_lag``,
        ``transport_delay``) without ``base model``, or ``temperature_friction`` (the
        simulation's friction effects see t, q, q̇, q̈, not the joint's temperature).

    Examples
    --------
    >>> fx = FrictionEffects([{"kind": "stribeck", "params": {"f_s": 0.1, "v_st": 0.02}}],
    ...                      v_s=1e-3)
    >>> tau = fx(t, q, dq, ddq)            # whole trajectory, shape (n,)
    >>> z = fx.initial_state(shape=(V,))   # per-step use inside an integrator
    >>> tau_k = fx.torque(t_k, q_k, dq_k, ddq_k, z)
    >>> dz = fx.state_derivative(t_k, q_k, dq_k, z)
    """

    def __init__(self, effects: Sequence[Mapping[str, Any]], v_s: float | None,
                 base_model: Mapping[str, float] | None = None, t0: float | None = 0.0) -> None:
        self.items = parse_effects(effects or [])
        for t, _, _ in self.items:
            if isinstance(t, (TemperatureFriction, MeasuredVariable)):
                raise ValueError(f"friction_effects: {t.kind} needs a measured variable of "
                                 "the recording (the joint's temperature, a column), which "
                                 "the simulation's friction effects do not see (t, q, q̇, q̈ "
                                 "only): leave it out")
        if self.items and not (v_s is not None and v_s > 0):
            raise ValueError(f"v_s must be > 0 [rad/s], got {v_s}")
        self.v_s = float(v_s) if v_s is not None else 1.0
        self.t0 = float(t0 or 0.0)
        self.has_transform = any(t.is_transform for t, _, _ in self.items)
        if self.has_transform and base_model is None:
            raise ValueError("a transform (velocity_lag, transport_delay) acts through the "
                             "friction law: pass base_model={b0, b1, b2, b3, theta_b}")
        self.base_coef = (PaperLaw().from_derived(**{k: float(base_model[k]) for k in (
            "b0", "b1", "b2", "b3", "theta_b")}) if base_model is not None else None)
        # state layout: one per presliding or lag effect
        self.state_names = [t.name for t, _, _ in self.items
                            if isinstance(t, (Presliding, VelocityLag))]

    @property
    def n_states(self) -> int:
        """Number of internal states (presliding z, lagged velocity)."""
        return len(self.state_names)

    def initial_state(self, shape: tuple[int, ...] = (), dq0: Any = 0.0) -> np.ndarray:
        """States at rest: z = 0, lagged velocity = q̇0. Shape ``(n_states, *shape)``."""
        z = np.zeros((self.n_states, *shape))
        for i, (t, _, _) in enumerate(x for x in self.items
                                      if isinstance(x[0], (Presliding, VelocityLag))):
            if isinstance(t, VelocityLag):
                z[i] = dq0
        return z

    def _signals(self, t, q, dq, ddq, states: dict[str, np.ndarray] | None) -> FrictionSignals:
        t = np.atleast_1d(np.asarray(t, float))
        q = np.atleast_1d(np.asarray(q, float))
        n = q.size
        t = np.broadcast_to(t, q.shape).ravel() if t.size != n else t.ravel()
        dq_ = np.broadcast_to(np.asarray(dq, float), q.shape).ravel()
        ddq_ = np.broadcast_to(np.asarray(ddq, float), q.shape).ravel()
        sc = Scales(v_ref=1.0, q_span=1.0, t0=self.t0, t_span=1.0, dt_med=1.0, dq_med=1.0)
        return FrictionSignals(t_s=t, q_rad=q.ravel(), dq_rad_s=dq_, ddq_rad_s2=ddq_,
                               load_nm=None, v_eff=dq_, v_s=self.v_s, scales=sc,
                               extra={"states": states} if states is not None else {})

    def _evaluate(self, sig: FrictionSignals) -> np.ndarray:
        if not self.items:
            return np.zeros(sig.n)
        terms = [t for t, _, _ in self.items]
        coefs = [c for _, c, _ in self.items]
        thetas = [th for _, _, th in self.items]
        if self.has_transform:
            base = PaperLaw()
            terms_all = [t for t in terms if t.is_transform] + [base] + [
                t for t in terms if not t.is_transform]
            pos = {id(t): i for i, t in enumerate(terms)}
            c_all = [coefs[pos[id(t)]] if t is not base else self.base_coef for t in terms_all]
            th_all = [thetas[pos[id(t)]] if t is not base else np.empty(0) for t in terms_all]
            with_fx = evaluate_terms(terms_all, sig, c_all, th_all)
            without = evaluate_terms([base], sig, [self.base_coef], [np.empty(0)])
            return with_fx - without
        return evaluate_terms(terms, sig, coefs, thetas)

    def __call__(self, t: np.ndarray, q: np.ndarray, dq: np.ndarray,
                 ddq: np.ndarray) -> np.ndarray:
        """Extra friction torque along a trajectory.

        Parameters
        ----------
        t, q, dq, ddq : ndarray, shape (n,)
            Time [s] (increasing), angle [rad], velocity [rad/s], acceleration [rad/s²].

        Returns
        -------
        ndarray, shape (n,)
            Extra torque [N m].
        """
        q = np.asarray(q, float)
        if q.ndim != 1:
            raise ValueError(f"trajectory arrays must be 1-D, got shape {q.shape}")
        return self._evaluate(self._signals(t, q, dq, ddq, None))

    def torque(self, t: Any, q: Any, dq: Any, ddq: Any, state: np.ndarray | None = None
               ) -> np.ndarray:
        """Extra friction torque at one time step, elementwise over any shape.

        Parameters
        ----------
        t : float
            Time [s].
        q, dq, ddq : array_like, same shape S
            Angle [rad], velocity [rad/s], acceleration [rad/s²] (q̈ of the previous
            step is adequate for the ``inertia`` effect; better add J_a to the output
            inertia).
        state : ndarray, shape ``(n_states, *S)``, optional
            From :meth:`initial_state` / integration of :meth:`state_derivative`.

        Returns
        -------
        ndarray, shape S
        """
        q = np.asarray(q, float)
        if self.n_states and state is None:
            raise ValueError(f"these effects have states {self.state_names}: pass state")
        states = ({n: np.asarray(state[i], float).ravel() for i, n in
                   enumerate(self.state_names)} if self.n_states else None)
        return self._evaluate(self._signals(t, q, dq, ddq, states)).reshape(q.shape)

    def state_derivative(self, t: Any, q: Any, dq: Any, state: np.ndarray) -> np.ndarray:
        """Time derivative of the states: Dahl ``dz/dt = (q̇ − |q̇| z) / q_c``, lag
        dv/dt = (q̇ − v) / T_L. Shape ``(n_states, *S)``."""
        dq = np.asarray(dq, float)
        out = np.zeros_like(np.asarray(state, float))
        i = 0
        for term, _, th in self.items:
            if isinstance(term, Presliding):
                out[i] = (dq - np.abs(dq) * state[i]) / th[0]
                i += 1
            elif isinstance(term, VelocityLag):
                out[i] = (dq - state[i]) / th[0]
                i += 1
        return out


@dataclass
class FrictionEffectsConfig:
    """The data-set option ``friction_effects``: what a calibration writes to
    ``friction_effects.yaml`` (``conf/friction_effects/*.yaml``).

    Attributes
    ----------
    v_s : float or None
        Smooth-sign velocity the effects were fitted with [rad/s], > 0 when there are
        effects.
    t0_s : float
        Time origin of drift effects [s].
    base model : dict or None
        Paper-law parameters ``{b0, b1, b2, b3, theta_b}``, needed by ``velocity_lag``.
    effects : list
        The effects, ``{kind, params}`` each (:func:`parse_effects`).
    """

    v_s: float | None = None
    t0_s: float = 0.0
    base_model: dict[str, float] | None = None
    effects: list[Any] = field(default_factory=list)


def _as_config(spec: Any, where: str) -> FrictionEffectsConfig:
    """A plain mapping (e.g. a calibration's file read as YAML) as the typed option."""
    if isinstance(spec, FrictionEffectsConfig):
        return spec
    if not isinstance(spec, Mapping):
        raise ValueError(f"{where} must be null or a mapping {{v_s, t0_s, base model, effects}} "
                         "(the friction_effects.yaml a calibration writes), got "
                         f"{type(spec).__name__}")
    keys = {f.name for f in fields(FrictionEffectsConfig)}
    unknown = set(spec) - keys
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {sorted(unknown)}; allowed: {sorted(keys)}")
    return FrictionEffectsConfig(v_s=spec.get("v_s"), t0_s=spec.get("t0_s") or 0.0,
                                 base_model=spec.get("base_model"),
                                 effects=spec.get("effects") or [])


def friction_effects_from_config(spec: FrictionEffectsConfig | Mapping[str, Any] | None,
                                 where: str = "dataset.friction_effects"
                                 ) -> FrictionEffects | None:
    """Build the extra friction of a data-set config (``conf/friction_effects/*.yaml``).

    Parameters
    ----------
    spec : FrictionEffectsConfig, mapping or None
        None, an empty mapping or empty list (the paper law alone), or the typed option
        (a mapping of its fields is taken as one, e.g. ``friction_effects.yaml`` read
        with a YAML parser).
    where : str
        Name of the config key, used in error messages.

    Returns
    -------
    FrictionEffects or None
        None when there are no effects.

    Raises
    ------
    ValueError
        ``spec`` of the wrong type, unknown keys, missing or non-positive ``v_s``, or an
        invalid effect (the message names ``where`` and the effect).
    """
    if spec is None or (isinstance(spec, (list, tuple, Mapping)) and len(spec) == 0):
        return None
    cfg = _as_config(spec, where)
    if not isinstance(cfg.effects, (list, tuple)):
        raise ValueError(f"{where}.effects must be a list, got {type(cfg.effects).__name__}")
    if not cfg.effects:
        return None
    if cfg.v_s is None or not float(cfg.v_s) > 0:
        raise ValueError(f"{where}.v_s must be > 0 [rad/s] (the smooth-sign velocity the "
                         f"effects were fitted with), got {cfg.v_s}")
    try:
        return FrictionEffects(cfg.effects, v_s=float(cfg.v_s), base_model=cfg.base_model,
                               t0=float(cfg.t0_s or 0.0))
    except (KeyError, ValueError) as e:
        msg = e.args[0] if e.args else str(e)
        raise ValueError(f"{where}: {msg}") from None
