"""Inference latency per window (CPU, batch 1, one thread) of every model of the transfer
comparison, and the time to build its input from the window and its reference.

Models and inputs are those of ``conf/experiment/transfer.yaml`` (``transfer.runs``);
each model is fitted briefly (latency does not depend on how well it was trained), then
``predict`` is timed on single windows. Run from the repository root::

    python scripts/bench_inference.py data/paper
    python scripts/bench_inference.py data/tiny/paper --repeats 50 --out /tmp/latency.csv \\
        transfer.models.minirocket.estimator.n_kernels=1000
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

CONF = Path(__file__).resolve().parents[1] / "conf"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("data", help="data-set directory (schema v1)")
    parser.add_argument("--repeats", type=int, default=200, help="timed windows per model")
    parser.add_argument("--out", default=None, help="write the table as CSV here")
    parser.add_argument("overrides", nargs="*",
                        help="Hydra overrides of train.yaml with experiment=transfer")
    args = parser.parse_intermixed_args(argv)
    logging.basicConfig(level=logging.WARNING)

    import torch
    from hydra import compose, initialize_config_dir
    from omegaconf import OmegaConf

    from learn.inputs.signals import build_input
    from learn.studies.latency import measure_latency
    from swgsim.datasets.schema import load

    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        cfg = compose("train", overrides=["experiment=transfer", *args.overrides])
    app = OmegaConf.to_object(cfg)  # swgcli.schema.TrainApp, every group typed
    tc = app.transfer
    specs, models = tc.runs, tc.models
    residual = tc.residual
    fk = app.features.kwargs()
    ds = load(args.data)
    flag = bool(ds["disturbed"].values.any())
    inputs = {k: build_input(ds, k, aux=tuple(tc.aux), disturbed=flag, feature_kwargs=fk,
                             residual=residual) for k in sorted({s.input for s in specs})}
    torch.set_num_threads(1)
    table = measure_latency(ds, specs, models, inputs, aux=tuple(tc.aux), feature_kwargs=fk,
                            residual=residual, repeats=args.repeats)
    table["total_ms"] = table["input_ms"] + table["model_ms"]
    print(table.to_string(index=False, float_format=lambda v: f"{v:.3f}"))
    if args.out:
        table.to_csv(args.out, index=False)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
