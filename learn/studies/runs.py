"""One (model, input) run of the transfer comparison: its spec, estimator and scoring.

A run names a model config (``transfer.models.<name>``, a ``_target_`` mapping as in
``conf/model/``) and an input of :data:`learn.inputs.signals.INPUTS`, and says which target-gear
adaptations it gets (:mod:`learn.studies.transfer`).
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

ADAPT = ("adabn", "coral")


@dataclass
class RunRef:
    """A (model, input) pair named by the config, e.g. ``transfer.primary``.

    Attributes
    ----------
    model : str
        Key into the model configs (``transfer.models``).
    input : str
        One of :data:`learn.inputs.signals.INPUTS`.
    """

    model: str
    input: str

    @property
    def label(self) -> str:
        return f"{self.model}/{self.input}"


@dataclass
class RunSpec(RunRef):
    """One (model, input) run of the comparison, an entry of ``transfer.runs``.

    Attributes
    ----------
    model : str
        Key into the model configs (``transfer.models``).
    input : str
        One of :data:`learn.inputs.signals.INPUTS`.
    finetune : bool
        Adapt with k labelled target windows per class (leave-one-gear-out protocols):
        torch nets are fine-tuned, MiniRocket's ridge is refitted.
    adapt : str or None
        ``adabn`` (torch nets) or ``coral`` (feature inputs), unsupervised
        (:data:`ADAPT`).
    params : dict of str to value
        Parameters set on the model for this input (e.g. ``padding_mode``).
    """

    finetune: bool = False
    adapt: str | None = None
    params: dict[str, Any] = field(default_factory=dict)


def final_step(est):
    """The classifier of a pipeline (or the estimator itself)."""
    from sklearn.pipeline import Pipeline

    return est[-1] if isinstance(est, Pipeline) else est


def pre_transform(est, X):
    """``X`` through every step of a fitted pipeline but the last."""
    from sklearn.pipeline import Pipeline

    return est[:-1].transform(X) if isinstance(est, Pipeline) and len(est) > 1 else X


def make_estimator(model_cfg: Mapping[str, Any], seed: int, n_aux: int,
                   params: Mapping[str, Any] | None = None):
    """Instantiate a model config (``_target_``) and set its seed, ``n_aux`` and ``params``.

    Every parameter named ``random_state`` or ``*__random_state`` is set to ``seed``,
    every ``n_aux`` to ``n_aux`` (the scalar channels of a signal input); ``params`` are
    set on the final estimator of a pipeline.
    """
    from hydra.utils import instantiate

    est = instantiate(model_cfg, _convert_="all")
    keys = est.get_params(deep=True)
    upd = {k: seed for k in keys if k == "random_state" or k.endswith("__random_state")}
    upd.update({k: n_aux for k in keys if k == "n_aux" or k.endswith("__n_aux")})
    est.set_params(**upd)
    if params:
        final_step(est).set_params(**dict(params))
    return est


def fit_with_groups(est, X, y, groups):
    """``est.fit``, passing ``groups`` (for a source-only early-stopping split) to an
    estimator whose ``fit`` takes them."""
    from sklearn.pipeline import Pipeline

    final = final_step(est)
    if "groups" not in inspect.signature(final.fit).parameters:
        return est.fit(X, y)
    if isinstance(est, Pipeline):
        return est.fit(X, y, **{f"{est.steps[-1][0]}__groups": groups})
    return est.fit(X, y, groups=groups)


def score(est, X, y, pred=None) -> tuple[float, list[tuple[str, str, int]]]:
    """Accuracy and the confusion as (true, predicted, count) triples.

    ``pred``, when given, are the estimator's predictions for ``X`` computed elsewhere
    (e.g. from cached features); ``est.predict`` is then not called.
    """
    pred = np.asarray(est.predict(X) if pred is None else pred).astype(str)
    y = np.asarray(y).astype(str)
    pairs = pd.Series(list(zip(y, pred, strict=True))).value_counts()
    return float(np.mean(pred == y)), [(t, p, int(c)) for (t, p), c in pairs.items()]
