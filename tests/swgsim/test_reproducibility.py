"""Same answers on any machine (docs/DATASET.md, "Reproducibility").

Within one environment a seed gives the same bytes (tested by comparing two runs:
``test_generate.py``'s workers and kill-and-resume tests, ``test_conditions.py``'s neutral
conditions). Across machines the BLAS kernel that OpenBLAS selects for the processor can
change a product's last bits, so the data sets agree to a tolerance, tested here by
generating the tiny presets under three ``OPENBLAS_CORETYPE`` settings in one test.

The tolerance, derived: the simulation runs in float64, where two kernels' results differ
by round-off. That error is absolute, of the size of the terms summed (a window's full
scale S), not of the value: measured, the stored float32 signals of ``tiny`` differ in 1
sample in 20,000-40,000, by at most half a float32 unit in the last place at S (ulp(S),
3e-8 mV/V at 0.3 mV/V). The last rounding of each stored value - to float32, or to the
converter's step where the acquisition quantises (one LSB of the 24-bit ADS131M04, 3.4e-7
mV/V) - turns that into no difference or one step; more than one step would need a float64
difference of a whole step. So a stored sample may differ by at most one step plus ulp(S)
(both roundings), and only rarely: at most 1 in 1,000 samples (measured: at most 1 in
21,000; one sample of ``tiny_life``'s 1.44 million, by one LSB). float64 variables are not
rounded again: relative 1e-9, far beyond the round-off and far below any physical effect
(measured: equal). Everything else (labels, integers, booleans) is equal.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from swgcli import dataset_preset
from swgsim.datasets.config import dataset_config
from swgsim.datasets.generate import generate
from swgsim.files.provenance import blas_kernels
from swgsim.sensing.acquisition import Amplifier

#: Kernels to try, each with the processor flags it needs (Linux /proc/cpuinfo names):
#: a kernel the processor lacks dies with SIGILL (SkylakeX without AVX-512).
KERNELS = {"Haswell": {"avx2", "fma"},
           "SkylakeX": {"avx512f", "avx512bw", "avx512dq", "avx512vl"},
           "Sandybridge": {"avx"}, "Nehalem": {"sse4_2"}, "Prescott": {"pni"}}
#: Most samples of one stored array that may differ by their one step.
MAX_SHARE = 1e-3
#: Relative tolerance of float64 variables.
RTOL64 = 1e-9

GENERATE = """
import json, sys
from swgcli import dataset_preset
from swgsim.datasets.config import dataset_config
from swgsim.datasets.generate import generate
from swgsim.files.provenance import blas_kernels
out = sys.argv[1]
for p in sys.argv[2:]:
    generate(dataset_config(dataset_preset(p)), f"{out}/{p}", n_jobs=1, progress=False)
print(json.dumps(blas_kernels()))
"""


def cpu_kernels(n: int = 3) -> list[str]:
    """The first ``n`` kernels of :data:`KERNELS` this processor can run."""
    if sys.platform != "linux" or os.uname().machine != "x86_64":
        pytest.skip("OPENBLAS_CORETYPE names x86-64 kernels; the flags come from Linux")
    flags = set()
    for line in Path("/proc/cpuinfo").read_text().splitlines():
        if line.startswith("flags"):
            flags = set(line.split(":", 1)[1].split())
            break
    return [k for k, need in KERNELS.items() if need <= flags][:n]


def generate_under_kernels(presets: list[str], out: Path) -> dict[str, str]:
    """Generate ``presets`` once per kernel, in parallel processes; return kernel ->
    the BLAS the process ran (:func:`swgsim.files.provenance.blas_kernels`)."""
    kernels = cpu_kernels()
    assert len(kernels) == 3, f"this processor runs only {kernels}"
    procs = {}
    for k in kernels:
        env = {**os.environ, "OPENBLAS_CORETYPE": k, "OPENBLAS_NUM_THREADS": "1"}
        procs[k] = subprocess.Popen([sys.executable, "-c", GENERATE, str(out / k), *presets],
                                    env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                    text=True)
    ran = {}
    for k, p in procs.items():
        stdout, stderr = p.communicate(timeout=900)
        assert p.returncode == 0, f"{k}: {stderr[-2000:]}"
        ran[k] = json.loads(stdout.strip().splitlines()[-1])
    return ran


def step_of(ds: xr.Dataset) -> float:
    """The converter's quantisation step of a data set's signals [mV/V], 0 without one."""
    amp = json.loads(ds.attrs["config"])["acquisition"]["amplifier"]
    return Amplifier(**amp).lsb_mvv if amp else 0.0


def assert_agree(a: np.ndarray, b: np.ndarray, step: float, what: str) -> None:
    """``a`` and ``b`` equal within the tolerance derived in the module's docstring."""
    if a.dtype.kind not in "fc":
        assert np.array_equal(a, b), f"{what}: differs"
        return
    if a.dtype == np.float64:
        np.testing.assert_allclose(a, b, rtol=RTOL64, atol=0, err_msg=what)
        return
    diff = np.abs(a.astype(np.float64) - b)
    full_scale = max(np.abs(a).max(initial=0), np.abs(b).max(initial=0))
    bound = step + float(np.spacing(full_scale))  # one step, and float32's rounding at S
    assert (diff <= bound).all(), f"{what}: {diff.max():.3g} beyond one step"
    assert (diff > 0).mean() <= MAX_SHARE, f"{what}: {(diff > 0).mean():.2g} of samples"


def check_presets(presets: list[str], tmp_path: Path) -> None:
    ran = generate_under_kernels(presets, tmp_path)
    assert len(set(ran.values())) == len(ran), f"the kernels were not distinct: {ran}"
    first, *others = ran
    for preset in presets:
        for shard in sorted((tmp_path / first / preset).glob("*.nc")):
            ref = xr.load_dataset(shard)
            step = step_of(ref)
            for k in others:
                other = xr.load_dataset(tmp_path / k / preset / shard.name)
                assert set(other.variables) == set(ref.variables)
                for v in ref.variables:
                    assert_agree(ref[v].values, other[v].values, step,
                                 f"{preset}/{shard.name}/{v}, {first} vs {k}")


def test_the_tiny_grid_agrees_across_blas_kernels(tmp_path):
    """tiny (float32, no converter) under three kernels this processor runs (the other
    presets: the slow test below; 14 s each on 2 cores)."""
    check_presets(["tiny"], tmp_path)


@pytest.mark.slow
def test_every_tiny_preset_agrees_across_blas_kernels(tmp_path):
    """tiny_motion (a profile, angle channels), tiny_life (a life through the 24-bit
    converter) and the larger tiny presets."""
    check_presets(["tiny_motion", "tiny_life", "tiny_bench", "tiny_motion_life",
                   "tiny_real_day"], tmp_path)


def test_the_tolerance_catches_two_steps_and_too_many_samples():
    a = np.linspace(-1.0, 1.0, 10_000, dtype=np.float32)
    step = 3.4e-7
    one = a.copy()
    one[7] += np.float32(step)
    assert_agree(a, one, step, "one step")
    two = a.copy()
    two[7] += np.float32(2.5 * step)
    with pytest.raises(AssertionError, match="beyond one step"):
        assert_agree(a, two, step, "two steps")
    many = a + np.float32(step) * (np.arange(a.size) % 100 == 0)
    with pytest.raises(AssertionError, match="of samples"):
        assert_agree(a, many, step, "many")
    with pytest.raises(AssertionError):
        assert_agree(a.astype(np.float64), a.astype(np.float64) * (1 + 1e-8), 0.0, "f64")


def test_the_manifest_records_the_blas_kernel(tmp_path):
    generate(dataset_config(dataset_preset("tiny")), tmp_path / "t", n_jobs=1, progress=False)
    blas = json.loads((tmp_path / "t" / "manifest.json").read_text())["library_versions"]
    assert blas["blas"] == blas_kernels() != "unknown"
