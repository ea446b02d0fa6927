"""swgsim-paper: the main job — the paper's data sets and its whole study, end to end.

Stages: (1) generate ``data_dir`` (shards already there and valid are skipped; a data
set of another config there is replaced),
(2) the study of Tables VII-X (:func:`learn.study.run_paper_study`), every job logged to
MLflow, (3) the report in ``report_dir``. Prints where it wrote and how long each stage
took. Config: ``conf/paper.yaml``.
"""

from __future__ import annotations

import logging
import sys
import time

import hydra
from hydra.utils import to_absolute_path
from omegaconf import DictConfig, OmegaConf

from swgcli import CONF_DIR

log = logging.getLogger(__name__)


def _abs(path: str) -> str:
    try:
        return to_absolute_path(path)
    except ValueError:  # outside a Hydra run
        return path


def run_paper(cfg: DictConfig) -> dict:
    """Run the main job from a composed ``paper`` config (task function).

    Returns
    -------
    dict
        ``stages_s`` (wall time of each stage [s]), ``data_dir``, ``report_dir``,
        ``generate`` (generation summary), ``study`` (timings and files of the study).
    """
    from swgsim.generate import generate

    stages: dict[str, float] = {}
    t0 = time.perf_counter()
    data_dir, report_dir = _abs(str(cfg.data_dir)), _abs(str(cfg.report_dir))
    # data_dir is this job's own output: a data set of another config there is replaced
    gen = generate(OmegaConf.to_container(cfg.dataset, resolve=True), data_dir,
                   n_jobs=int(cfg.n_jobs), overwrite=True, progress=True)
    stages["generate"] = time.perf_counter() - t0
    state = (f"{len(gen['computed'])} shard(s) simulated" if gen["computed"]
             else "already there and valid, skipped")
    print(f"[1/2] data set: {gen['windows']} windows in {data_dir} ({state}), "
          f"{stages['generate']:.1f} s", flush=True)

    from learn.study import run_paper_study

    t1 = time.perf_counter()
    s = cfg.study
    study = run_paper_study(
        data_dir, report_dir, tracking_uri=cfg.tracking_uri, n_jobs=int(cfg.n_jobs),
        random_state=int(cfg.seed),
        tables=None if s.tables is None else [str(t) for t in s.tables],
        models=None if s.models is None else [str(m) for m in s.models],
        scale=bool(s.scale), figures=bool(s.figures))
    stages["study"] = time.perf_counter() - t1
    stages["total"] = time.perf_counter() - t0
    res = study.pop("results")
    print(f"[2/2] study: {study['n_jobs_run']} jobs, {len(res)} fits, "
          f"{stages['study']:.1f} s", flush=True)
    for k, v in study.get("timings_s", {}).items():
        print(f"      {k:<12s} {v:7.1f} s")
    print(f"report: {report_dir}")
    for kind, path in study.get("files", {}).items():
        print(f"      {kind:<12s} {path}")
    from learn.tracking import default_tracking_uri

    print(f"MLflow runs: {cfg.tracking_uri or default_tracking_uri()}  "
          "(browse: mlflow ui --backend-store-uri sqlite:///mlflow.db)")
    print(f"total wall time {stages['total']:.1f} s "
          f"(generate {stages['generate']:.1f} s, study {stages['study']:.1f} s)")
    return {"stages_s": stages, "data_dir": data_dir, "report_dir": report_dir,
            "generate": gen, "study": study}


@hydra.main(version_base="1.3", config_path=CONF_DIR, config_name="paper")
def _main(cfg: DictConfig) -> None:
    try:
        run_paper(cfg)
    except ValueError as e:
        log.error("%s", e)
        print(f"swgsim-paper: error: {e}", file=sys.stderr)
        sys.exit(2)


def main() -> None:
    """Console entry point."""
    _main()


if __name__ == "__main__":
    main()
