"""Inference latency per window of the transfer comparison's runs (CPU, batch 1).

``python scripts/bench_inference.py`` prints it for a data set; the transfer report
holds it too.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from learn.inputs.signals import ResidualSettings
from learn.studies.runs import RunSpec, final_step, make_estimator
from swgsim.base.lazy import lazy_module

pd = lazy_module("pandas")


def measure_latency(ds, specs: Sequence[RunSpec], model_cfgs: Mapping[str, Any],
                    inputs: Mapping[str, Any], *, aux: Sequence[str] = ("eta2_rel", "eta_rel"),
                    feature_kwargs: Mapping[str, Any] | None = None,
                    residual: ResidualSettings | None = None, repeats: int = 100,
                    n_fit: int = 600) -> pd.DataFrame:
    """Inference latency per window, batch 1, one CPU thread, of every (model, input).

    Each model is fitted on at most ``n_fit`` windows with a budget of one epoch (the
    cost of ``predict`` does not depend on how well it was trained), then timed on
    ``repeats`` single windows (median). ``input_ms`` is the median time to build the
    input of one window from a two-window data set (the window and its reference).

    Parameters
    ----------
    ds : xarray.Dataset
        The data set the inputs were built from (schema v1, with reference windows).
    specs : sequence of RunSpec
        The runs; each (model, input) is timed once.
    model_cfgs : mapping of str to mapping
        Model name -> ``_target_`` config (``transfer.models``).
    inputs : mapping of str to InputSet
        Input kind -> :class:`learn.inputs.signals.InputSet` built from ``ds``.
    aux, feature_kwargs, residual
        As for :func:`learn.inputs.signals.build_input`.
    repeats : int
        Timed windows per model.
    n_fit : int
        Most windows a model is fitted on.

    Returns
    -------
    pandas.DataFrame
        Columns model, input, input_ms, model_ms [ms].
    """
    import torch

    from learn.inputs.features import reference_index
    from learn.inputs.signals import build_input

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    rows = []
    try:
        seen = set()
        for spec in specs:
            if (spec.model, spec.input) in seen:
                continue
            seen.add((spec.model, spec.input))
            inp = inputs[spec.input]
            rng = np.random.default_rng(0)
            idx = np.sort(rng.choice(len(inp.y), size=min(n_fit, len(inp.y)), replace=False))
            est = make_estimator(model_cfgs[spec.model], 0, inp.n_aux, spec.params)
            if "max_epochs" in final_step(est).get_params():
                final_step(est).set_params(max_epochs=1)
            est.fit(inp.X[idx], inp.y[idx])
            s_all, r_all = reference_index(ds)
            smp = int(inp.meta["sample"].iloc[0])
            one = ds.isel(sample=[smp, int(r_all[np.searchsorted(s_all, smp)])])
            t_in = []
            for _ in range(max(3, repeats // 10)):
                t0 = time.perf_counter()
                build_input(one, spec.input, aux=tuple(aux),
                            feature_kwargs=dict(feature_kwargs or {}),
                            residual=residual)
                t_in.append(time.perf_counter() - t0)
            est.predict(inp.X[:1])  # warm-up
            t_m = []
            for r in range(repeats):
                x = inp.X[r % len(inp.y)][None]
                t0 = time.perf_counter()
                est.predict(x)
                t_m.append(time.perf_counter() - t0)
            rows.append({"model": spec.model, "input": spec.input,
                         "input_ms": 1e3 * float(np.median(t_in)),
                         "model_ms": 1e3 * float(np.median(t_m))})
    finally:
        torch.set_num_threads(threads)
    return pd.DataFrame(rows)
