"""Shared fixtures: a small synthetic schema-v1 data set and a throw-away MLflow store.

The synthetic data set is not a simulation: each class gets a planted signature in the
signals or the efficiency, so that learners can be checked to beat chance quickly.
"""

from __future__ import annotations

import os

# One thread per library in each test process: pytest-xdist already runs a process per
# core, and OpenMP's default of one thread per core in each made the gradient-boosted
# trees' predictions 16 times slower on a shared 2-core machine (a 480-window life
# monitored in 37 s, 2.3 s with one thread). Set before numpy and scikit-learn load.
os.environ.setdefault("OMP_NUM_THREADS", "1")

import shutil  # noqa: E402
from pathlib import Path

import numpy as np
import pytest

from swgsim.datasets.schema import MANIFEST, SCHEMA_VERSION, write_shard
from swgsim.files.ownership import atomic_write_json
from swgsim.gear.faults import PAPER_CLASSES as FAULT_CLASSES


def make_synthetic(
    seed: int = 0,
    gears=(1, 2, 3),
    n_variants: int = 4,
    ops=((2000.0, 7.0), (4000.0, 70.0)),
    n_time: int = 1200,  # 0.12 s: four revolutions at 2000 rpm (DFT order 0.25)
    sample_rate_hz: float = 10_000.0,
    noise: float = 0.005,
):
    """Synthetic schema-v1 data set: gears x classes x variants x ops x {clean, disturbed}
    windows plus one reference window per gear x op x disturbed flag.

    Signatures (severity 0.5..1): reduced_damping +5 % efficiency; reduced_stiffness +10 %
    s0 offset, -2 % efficiency; eccentric_wg offsets on s1/s3 and an order-1 harmonic on
    s1; root_tooth_crack -15 % amplitude on all sensors; tip_tooth_crack order-1 harmonic
    on s2. Healthy s1 = s3 and s2 = s4 up to noise (order-2 signals 180 deg apart).
    """
    from swgsim.datasets.schema import make_dataset

    rng = np.random.default_rng(seed)
    t = np.arange(n_time) / sample_rate_hz
    rows, sigs = [], []
    for disturbed in (False, True):
        for gear in gears:
            for n_in, t_out in ops:
                cases = [("healthy", -1, True)] + [
                    (f, v, False) for f in FAULT_CLASSES for v in range(n_variants)
                ]
                for fault, variant, ref in cases:
                    sev = 0.0 if fault == "healthy" else rng.uniform(0.5, 1.0)
                    pos = rng.uniform(0, 2 * np.pi)
                    n_mean = n_in * (1 + 1e-3 * rng.standard_normal())
                    theta = 2 * np.pi * n_mean / 60 * t + rng.uniform(0, 2 * np.pi)
                    amp = 0.5 * (1 + 0.1 * (gear - 2)) * (1 + t_out / 100)
                    off = 0.1 + 0.05 * gear + 0.002 * t_out
                    eta = 0.7 + 0.02 * gear + 0.001 * t_out + 0.002 * rng.standard_normal()
                    s = np.empty((5, n_time))
                    s[0] = 0.02 * t_out * (1 + 0.05 * gear) + 0.05 * amp * np.cos(2 * theta)
                    for i in range(1, 5):
                        s[i] = off + amp * np.cos(2 * (theta - (i - 1) * np.pi / 2))
                    if fault == "reduced_damping":
                        eta *= 1 + 0.05 * sev
                    elif fault == "reduced_stiffness":
                        s[0] += 0.1 * sev * 0.02 * t_out * (1 + 0.05 * gear)
                        eta *= 1 - 0.02 * sev
                    elif fault == "eccentric_wg":
                        s[1] += 0.05 * sev + 0.05 * sev * np.cos(theta + pos)
                        s[3] -= 0.05 * sev
                    elif fault == "root_tooth_crack":
                        s[1:] = off + (s[1:] - off) * (1 - 0.15 * sev)
                    elif fault == "tip_tooth_crack":
                        s[2] += 0.05 * sev * np.cos(theta + pos)
                    s += noise * rng.standard_normal(s.shape)
                    if disturbed:  # paper eq. (10), small
                        for i in range(5):
                            s[i] += rng.uniform(-0.02, 0.02)
                            for j in range(1, 5):
                                s[i] += rng.uniform(0, 0.02) * np.sin(
                                    2 * np.pi / j * n_mean / 60 * t + rng.uniform(0, 2 * np.pi))
                    sigs.append(s)
                    rows.append({
                        "gear": gear, "fault": fault, "variant": variant, "severity": sev,
                        "position_deg": np.degrees(pos) if fault != "healthy" else np.nan,
                        "n_in_rpm": n_in, "t_out_nm": t_out, "disturbed": disturbed,
                        "reference": ref, "efficiency": eta, "n_in_mean_rpm": n_mean,
                        "t_out_mean_nm": t_out,
                    })
    meta = {k: np.array([r[k] for r in rows]) for k in rows[0]}
    return make_dataset(np.stack(sigs), t, meta, attrs={"seed": seed, "generator": "tests"})


def write_dataset(ds, path) -> None:
    """Write ``ds`` as a one-shard schema-v1 data-set directory at ``path``."""
    path.mkdir(parents=True, exist_ok=True)
    digest = write_shard(ds, path / "shard-00000.nc")
    atomic_write_json(path / MANIFEST, {
        "schema_version": SCHEMA_VERSION, "complete": True,
        "shards": {"shard-00000.nc": {"sha256": digest, "n_samples": int(ds.sizes["sample"])}},
    })


#: Where the UR3 CobotOps day is read from (M. Tyrovolas, K. Aliev, D. Antonelli and
#: C. Stylios, "UR3 CobotOps", UCI Machine Learning Repository, 2024, doi:10.24432/C5J891,
#: CC BY 4.0): the environment variable's path if set, else the workplace's copy beside the
#: checkout (a fresh clone with ``shared/`` next to it, as CI has).
UR3_DAY_ENV = "SWG_UR3_DAY"
UR3_DAY_BESIDE = (Path(__file__).resolve().parents[1].parent / "shared" / "data"
                  / "ur3_cobotops" / "ur3_cobotops_2022-10-26.csv")


@pytest.fixture(scope="session")
def ur3_day() -> Path:
    """Path of the real UR3 CobotOps day (see :data:`UR3_DAY_ENV`); the test is skipped
    where the file is absent."""
    path = Path(os.environ.get(UR3_DAY_ENV) or UR3_DAY_BESIDE)
    if not path.is_file():
        pytest.skip(f"the UR3 CobotOps day is not at {path} (set {UR3_DAY_ENV})")
    return path


@pytest.fixture(scope="session")
def synthetic_ds():
    """In-memory synthetic data set (see :func:`make_synthetic`); do not modify."""
    return make_synthetic()


@pytest.fixture(scope="session")
def tiny_dataset(tmp_path_factory, synthetic_ds):
    """Path of the synthetic data set written to disk (schema v1)."""
    path = tmp_path_factory.mktemp("data") / "tiny"
    write_dataset(synthetic_ds, path)
    return path


@pytest.fixture(scope="session")
def tracking_uri(tmp_path_factory) -> str:
    """A throw-away MLflow sqlite store, shared by the session (creating one is slow)."""
    return f"sqlite:///{tmp_path_factory.mktemp('mlflow') / 'mlflow.db'}"


@pytest.fixture
def torch_one_thread():
    """torch on one thread during a test (small nets; results independent of the cores)."""
    import torch

    n = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(n)


@pytest.fixture(scope="module")
def small(tmp_path_factory) -> Path:
    """A finished two-gear data set of ``bad_input.small_cfg`` (about a second)."""
    from bad_input import small_cfg

    from swgsim.datasets import generate as gen

    out = tmp_path_factory.mktemp("small") / "small"
    gen.generate(small_cfg(), out, n_jobs=1, progress=False)
    return out


@pytest.fixture
def copy_of(small, tmp_path):
    """A copy of :func:`small` under ``tmp_path / name`` to edit."""
    def make(name: str = "ds") -> Path:
        dst = tmp_path / name
        shutil.copytree(small, dst)
        return dst
    return make
