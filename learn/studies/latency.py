"""Inference latency per window of the transfer comparison's runs (batch 1, one torch
thread), with what was timed in its columns: the device each model ran on, the batch
size and the torch threads in force while it was timed (:data:`LATENCY_COLUMNS`).

``python scripts/bench_inference.py`` prints it for a data set; the transfer report
holds it too, under a heading made from those columns (:func:`latency_heading`).

Torch's thread count is set again before each model is timed: fitting MiniRocket (aeon,
numba) puts the process's OpenMP threads, which torch shares, back to the number of
cores, so one setting before the first fit did not hold for the models after it.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from learn.inputs.features import reference_index
from learn.inputs.signals import ResidualSettings, build_input
from learn.learners.devices import device_label
from learn.studies.runs import RunSpec, final_step, make_estimator
from swgsim.base.lazy import lazy_module

pd = lazy_module("pandas")

#: Columns of :func:`measure_latency`: times [ms] and what was timed.
LATENCY_COLUMNS = ("model", "input", "input_ms", "model_ms", "device", "batch",
                   "torch_threads")
#: Windows per call of ``predict`` while timing.
LATENCY_BATCH = 1


def measure_latency(ds, specs: Sequence[RunSpec], model_cfgs: Mapping[str, Any],
                    inputs: Mapping[str, Any], *, aux: Sequence[str] = ("eta2_rel", "eta_rel"),
                    feature_kwargs: Mapping[str, Any] | None = None,
                    residual: ResidualSettings | None = None, repeats: int = 100,
                    n_fit: int = 600) -> pd.DataFrame:
    """Inference latency per window, batch 1, one torch thread, of every (model, input).

    Each model is fitted on at most ``n_fit`` windows with a budget of one epoch (the
    cost of ``predict`` does not depend on how well it was trained), then timed on
    ``repeats`` single windows (median), on the device its config names (a torch net's
    ``device``: a GPU where ``auto`` finds one; the other models on the CPU), with torch
    set to one thread just before (and the caller's thread count restored afterwards).
    ``input_ms`` is the median time to build the input of one window from a two-window
    data set (the window and its reference), on the CPU.

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
        :data:`LATENCY_COLUMNS`: model, input, input_ms, model_ms [ms], device
        (:func:`learn.learners.devices.device_label` of the model's device, ``cpu`` for a
        model without one), batch (windows per call) and torch_threads (torch's thread
        count read while the model was timed).
    """
    import torch

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
            torch.set_num_threads(1)  # again: a fit may have reset it (module docstring)
            est.predict(inp.X[:LATENCY_BATCH])  # warm-up
            n_threads = torch.get_num_threads()
            t_m = []
            for r in range(repeats):
                x = inp.X[np.arange(r, r + LATENCY_BATCH) % len(inp.y)]
                t0 = time.perf_counter()
                est.predict(x)
                t_m.append(time.perf_counter() - t0)
            rows.append({"model": spec.model, "input": spec.input,
                         "input_ms": 1e3 * float(np.median(t_in)),
                         "model_ms": 1e3 * float(np.median(t_m)),
                         "device": _device_of(est), "batch": LATENCY_BATCH,
                         "torch_threads": n_threads})
    finally:
        torch.set_num_threads(threads)
    return pd.DataFrame(rows, columns=list(LATENCY_COLUMNS))


def _device_of(est) -> str:
    """Where a fitted model's final step ran: its torch device, or ``cpu``."""
    dev = getattr(final_step(est), "device_", None)
    return "cpu" if dev is None else device_label(dev)


def latency_heading(latency: pd.DataFrame) -> str:
    """What a latency table timed, read from its columns (:data:`LATENCY_COLUMNS`).

    Parameters
    ----------
    latency : pandas.DataFrame
        Rows of :func:`measure_latency`; a table without the columns device, batch or
        torch_threads (written before they existed) says it does not know them.

    Returns
    -------
    str
        E.g. ``"cpu, batch 1, 1 torch thread"`` or ``"cpu and cuda:0 (NVIDIA H100),
        batch 1, 1 torch thread"``.
    """
    def values(col: str, unit: str) -> str:
        if col not in latency or not len(latency):
            return f"{unit} not recorded"
        seen = [str(v) for v in dict.fromkeys(latency[col].tolist())]
        return " and ".join(seen) + (f" {unit}" if unit else "")

    threads = values("torch_threads", "torch thread(s)")
    return f"{values('device', '')}, batch {values('batch', '')}, {threads}"
