"""Before a run's work: every library it will import resolved (:func:`check_imports`), so
that a broken install is one line naming the package, not a traceback after hours of
work. The tracking store is opened by :func:`learn.tracking.store.check_tracking`.

Each app declares the libraries it needs (``NEEDS`` in its module of :mod:`swgcli`);
:func:`swgcli.app.hydra_app` checks them after the config and before the task.
"""

from __future__ import annotations

import importlib
from collections.abc import Sequence

import numpy as np

#: How a broken install is mended, said in every :class:`BrokenInstall` line.
REINSTALL = "reinstall with bash scripts/quickstart.sh (or pip install -e .)"


class BrokenInstall(ValueError):
    """A library a run needs cannot be imported (a ValueError: the apps print it as one
    line and exit 2, :func:`swgcli.app.run`)."""


def import_failure(module: str, exc: BaseException) -> BrokenInstall:
    """The one-line error of ``module`` failing to import with ``exc``.

    Parameters
    ----------
    module : str
        The module the run imports (e.g. ``mlflow``).
    exc : BaseException
        What importing it raised; a missing module inside it is named
        (``ModuleNotFoundError.name``, e.g. ``cryptography``).

    Returns
    -------
    BrokenInstall
    """
    inner = getattr(exc, "name", None)
    where = f", which needs {inner}" if inner and inner.split(".")[0] != module else ""
    reason = (str(exc).splitlines() or [""])[0] or type(exc).__name__
    return BrokenInstall(f"broken install: {module} cannot be imported{where} "
                         f"({type(exc).__name__}: {reason}); {REINSTALL}")


def check_imports(modules: Sequence[str]) -> None:
    """Import each of ``modules``, in order, before any work.

    Parameters
    ----------
    modules : sequence of str
        Importable names (``torch``, ``sklearn``, ``mlflow``, ``skops.io``, ...).

    Raises
    ------
    BrokenInstall
        One line naming the first module that cannot be imported, what it raised (any
        exception, not only ImportError: a library failing at import is as broken) and
        how to reinstall.
    """
    for name in modules:
        try:
            with np.errstate():  # kept: emlearn sets numpy.seterr(all='raise') when imported
                importlib.import_module(name)
        except Exception as e:  # noqa: BLE001 - any failure at import is a broken install
            raise import_failure(name, e) from None


__all__ = ["REINSTALL", "BrokenInstall", "check_imports", "import_failure"]
