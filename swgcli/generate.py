"""swgsim-generate: simulate a schema-v1 data set (Hydra app, config ``conf/generate.yaml``).

Examples
--------
    swgsim-generate dataset=paper out_dir=data/paper
    swgsim-generate dataset=tiny out_dir=/tmp/tiny n_jobs=1
    swgsim-generate dataset=paper dataset.seed=7 dataset.mesh.n_theta=240 out_dir=/tmp/fine
"""

from __future__ import annotations

from omegaconf import DictConfig, OmegaConf

from swgcli.app import hydra_app
from swgcli.schema import GenerateApp
from swgsim.files.inputs import absolute_path


def run_generate(cfg: DictConfig) -> dict:
    """Generate the data set described by ``cfg`` (task function, no Hydra needed).

    Parameters
    ----------
    cfg : DictConfig
        Composed ``generate`` config: ``dataset``, ``out_dir``, ``n_jobs``, ``overwrite``,
        ``shard``, ``progress``.

    Returns
    -------
    dict
        The summary of :func:`swgsim.datasets.generate.generate`.
    """
    from swgsim.datasets.generate import generate

    ds_cfg = OmegaConf.to_object(cfg.dataset)  # the typed DatasetConfig
    out_dir = absolute_path(str(cfg.out_dir))
    return generate(ds_cfg, out_dir, n_jobs=int(cfg.n_jobs), overwrite=bool(cfg.overwrite),
                    shard_index=None if cfg.shard is None else int(cfg.shard),
                    progress=bool(cfg.progress))


#: The libraries its runs import, resolved before any work
#: (:func:`learn.tracking.preflight.check_imports`).
NEEDS = ("numpy", "scipy", "xarray", "h5netcdf", "joblib", "tqdm")


@hydra_app("generate", GenerateApp, "swgsim-generate", NEEDS)
def main(cfg: DictConfig) -> dict:
    """Generate the data set and print a one-line summary."""
    s = run_generate(cfg)
    state = "complete" if s["complete"] else "incomplete (other shards pending)"
    if s.get("replaced"):
        print(f"swgsim-generate: {s['replaced']}")
    print(f"swgsim-generate: {s['windows']} windows, {len(s['computed'])} shard(s) computed, "
          f"{len(s['skipped'])} skipped, {s['wall_s']:.1f} s -> {s['out_dir']} [{state}]")
    return s


if __name__ == "__main__":
    main()
