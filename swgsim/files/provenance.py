"""What a result was made with: this package's version, the git commit of its source
tree, and the versions of the numerical libraries whose releases can change a number."""

from __future__ import annotations

import subprocess
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

__all__ = ["LIBRARIES", "git_revision", "library_versions", "package_version"]

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


def library_versions() -> dict[str, str]:
    """Installed versions of :data:`LIBRARIES` (``"not installed"`` for a missing one).

    Returns
    -------
    dict of str to str
        Distribution name -> version, e.g. ``{"numpy": "2.1.3", ...}``.
    """
    out = {}
    for name in LIBRARIES:
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = "not installed"
    return out
