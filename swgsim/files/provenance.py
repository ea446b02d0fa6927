"""What a result was made with: this package's version, the git commit of its source
tree, the versions of the numerical libraries whose releases can change a number, and the
BLAS kernel they run on this processor (which can change the last bits of a number: see
``docs/DATASET.md``, "Reproducibility")."""

from __future__ import annotations

import functools
import subprocess
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy  # noqa: F401  (its BLAS is loaded, so that threadpoolctl lists it)
import scipy
import threadpoolctl

__all__ = ["LIBRARIES", "blas_kernels", "git_revision", "library_versions",
           "package_version"]

#: Distributions whose versions a data set's manifest and every MLflow run record: the
#: libraries whose releases have changed this project's numbers (random streams, solvers,
#: estimators).
LIBRARIES = ("numpy", "scipy", "scikit-learn", "torch")


def package_version() -> str:
    """Installed version of this package, ``"unknown"`` when not installed."""
    try:
        return version("swg-monitor")
    except PackageNotFoundError:
        return "unknown"


def git_revision() -> str:
    """Short git commit (12 hex digits) of the source tree, ``"unknown"`` without git."""
    try:
        out = subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], capture_output=True,
                             text=True, cwd=Path(__file__).parent, timeout=10)
        return out.stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):  # no git
        return "unknown"


def blas_kernels() -> str:
    """The BLAS libraries numpy and scipy run, with the kernel each selected at run time.

    An OpenBLAS built for many processors (the wheels') picks its kernels when it loads,
    from the processor or ``OPENBLAS_CORETYPE``; two kernels can differ in a product's
    last bits, so that two machines with the same library versions make arrays that agree
    only to round-off (``docs/DATASET.md``, "Reproducibility").

    Returns
    -------
    str
        One ``"<library> <version> <kernel> (<file name>)"`` per loaded BLAS, sorted and
        joined by ``"; "``, e.g. ``"openblas 0.3.30 Haswell (libscipy_openblas64_...so)"``;
        ``"unknown"`` where threadpoolctl finds none.

    Notes
    -----
    ``scipy.linalg`` is loaded first (scipy loads its own BLAS with it), so that both
    numpy's and scipy's appear.
    """
    scipy.linalg  # noqa: B018  (scipy loads its submodules on first use)
    rows = {f"{i['internal_api']} {i['version']} {i.get('architecture') or '?'} "
            f"({Path(i['filepath']).name})"
            for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas"}
    return "; ".join(sorted(rows)) or "unknown"


def library_versions() -> dict[str, str]:
    """Installed versions of :data:`LIBRARIES` (``"not installed"`` for a missing one) and
    the BLAS kernels in use (key ``"blas"``, :func:`blas_kernels`).

    Returns
    -------
    dict of str to str
        Distribution name -> version, e.g. ``{"numpy": "2.1.3", ..., "blas": "openblas
        0.3.30 Haswell (...)"}``.
    """
    return {**_versions(), "blas": blas_kernels()}


@functools.cache
def _versions() -> dict[str, str]:
    """:data:`LIBRARIES`' versions, read once per process (reading a distribution's
    metadata costs milliseconds, and a study logs hundreds of runs); copied by the caller."""
    out = {}
    for name in LIBRARIES:
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = "not installed"
    return out
