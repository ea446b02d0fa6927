"""Shared fixtures: a small synthetic schema-v1 data set (:mod:`data_sets`), the real UR3
day and a throw-away MLflow store."""

from __future__ import annotations

import os

# One thread per library in each test process: pytest-xdist already runs a process per
# core, and OpenMP's default of one thread per core in each made the gradient-boosted
# trees' predictions 16 times slower on a shared 2-core machine (a 480-window life
# monitored in 37 s, 2.3 s with one thread). Set before numpy and scikit-learn load.
os.environ.setdefault("OMP_NUM_THREADS", "1")

import atexit  # noqa: E402
import shutil  # noqa: E402
import tempfile  # noqa: E402
from pathlib import Path

import pytest
from data_sets import built_once, make_synthetic, write_dataset  # noqa: E402

# The user's MLflow store is the user's (issue 87): every run a test makes without naming
# its own store (an app's default, a leaky switch) goes to a throw-away store of this
# process, and so do the apps the tests start as subprocesses (they inherit it).
_STORE = tempfile.mkdtemp(prefix="swg-tests-mlflow-")
atexit.register(shutil.rmtree, _STORE, ignore_errors=True)
os.environ["MLFLOW_TRACKING_URI"] = f"sqlite:///{_STORE}/mlflow.db"

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


@pytest.fixture(scope="session")
def tiny_bench():
    """The tiny bench's plan (preset ``tiny_bench``) and a record bank per gear, shared by
    every test of the worker that takes the bench's lives as its input (a trained model, a
    monitored stream): a record is simulated once per worker, with the others its first
    window asks for, instead of once per test file (a batch costs 2-4 s whatever it holds).
    A record is the same whichever batch simulates it
    (tests/swgsim/test_life.py::test_a_record_is_the_same_whichever_batch_simulates_it);
    a test of the simulation of records makes its own banks. Do not modify."""
    from swgcli import dataset_preset
    from swgsim.datasets.plan import plan
    from swgsim.datasets.records import record_bank

    p = plan(dataset_preset("tiny_bench"))
    return p, {int(g.id): record_bank(p, int(g.id)) for g in p.config.gears}


@pytest.fixture
def torch_one_thread():
    """torch on one thread during a test (small nets; results independent of the cores)."""
    import torch

    n = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(n)


@pytest.fixture(scope="session")
def small(tmp_path_factory) -> Path:
    """A finished two-gear data set of ``bad_input.small_cfg`` (about a second), made once
    per test run (:func:`data_sets.built_once`); read it, or edit a copy (:func:`copy_of`)."""
    from bad_input import small_cfg

    from swgsim.datasets import generate as gen

    return built_once(tmp_path_factory, "small", lambda out: gen.generate(
        small_cfg(), out, n_jobs=1, progress=False))


@pytest.fixture
def copy_of(small, tmp_path):
    """A copy of :func:`small` under ``tmp_path / name`` to edit."""
    def make(name: str = "ds") -> Path:
        dst = tmp_path / name
        shutil.copytree(small, dst)
        return dst
    return make
