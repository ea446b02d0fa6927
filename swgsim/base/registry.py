"""One registry type for every kind of plug-in, and the registries travelling with the work.

The project's extension points are registries: gear faults
(:data:`swgsim.gear.faults.FAULTS`), sensor faults
(:data:`swgsim.sensing.sensor_faults.SENSOR_FAULTS` with their evaluation severities),
friction effects (:data:`swgsim.gear.friction.FRICTION_LIBRARY`), the thermal calibration's
effects (``swgcal.thermal.library.THERMAL_LIBRARY``), the strain calibration's
(``swgcal.strain.effects.STRAIN_LIBRARY``), learners
(:data:`learn.learners.models.MODELS`) and the monitor's detectors
(:data:`swgmon.evaluation.detectors.DETECTORS`). Each is a :class:`Registry`: a dict of name to
entry that knows its kind and where it lives, and refuses a name taken, except by an
extension of its entry (:func:`extends`: a subclass of the class registered under it,
which takes its place; the calibration adds its fit to a friction effect's form so).

A user registers an entry from their own script. Worker processes (joblib's loky) import
the project afresh, so they would not know it: every call that runs in a worker is made
through :func:`travelling`, which takes the registries of this process with it (their
entries pickled by value where they are not importable, as loky pickles) and adds what a
worker lacks, or extends, before the call. Only registries whose module this process
imported travel.
"""

from __future__ import annotations

import functools
import importlib
from collections.abc import Callable, Iterable
from typing import Any, TypeVar

T = TypeVar("T")

#: Every registry made, by ``"module:NAME"`` (:attr:`Registry.where`).
REGISTRIES: dict[str, Registry] = {}


class Registry(dict[str, T]):
    """Entries of one kind by name, e.g. ``Registry("gear fault", __name__, "FAULTS",
    ...)``; a dict in every other respect.

    Parameters
    ----------
    kind : str
        What an entry is, in errors (``gear fault``, ``learner``, ...).
    module, name : str
        Where it lives (``swgsim.gear.faults``, ``FAULTS``): a worker imports the module
        to find it (:func:`install`).
    entries : iterable of (str, entry)
        The built-in ones.
    """

    def __init__(self, kind: str, module: str, name: str,
                 entries: Iterable[tuple[str, T]] = ()) -> None:
        super().__init__(entries)
        self.kind = kind
        self.where = f"{module}:{name}"
        REGISTRIES[self.where] = self

    def add(self, name: str, entry: T) -> T:
        """Register ``entry`` under ``name``, or in place of an entry it
        :func:`extends`; returns it.

        Raises
        ------
        ValueError
            ``name`` is taken (by another entry, or by this one).
        """
        if name in self and not extends(entry, self[name]):
            raise ValueError(f"{self.kind} {name!r} is registered already")
        self[name] = entry
        return entry


def extends(entry: Any, held: Any) -> bool:
    """Whether ``entry`` may take the place of ``held`` under its name.

    Parameters
    ----------
    entry, held : object
        The entry offered and the one registered.

    Returns
    -------
    bool
        True when both are classes and ``entry`` subclasses ``held`` and is not it (a
        friction effect's form with its fit, :mod:`swgcal.friction.library`).
    """
    return (isinstance(entry, type) and isinstance(held, type) and entry is not held
            and issubclass(entry, held))


def carried() -> dict[str, dict[str, Any]]:
    """The entries of every registry this process made, by :attr:`Registry.where`."""
    return {w: dict(r) for w, r in REGISTRIES.items()}


def install(entries: dict[str, dict[str, Any]]) -> None:
    """Add to this process's registries the entries of :func:`carried` they lack or that
    :func:`extends` theirs (a registry's module is imported first, so that its built-ins
    come from it)."""
    for where, items in entries.items():
        if where not in REGISTRIES:
            importlib.import_module(where.split(":")[0])
        reg = REGISTRIES[where]
        for name, entry in items.items():
            if name not in reg or extends(entry, reg[name]):
                reg[name] = entry


def travelling(fn: Callable[..., T]) -> Callable[..., T]:
    """``fn``, to be run in another process with this one's registries (module docstring):
    ``joblib.delayed(travelling(fn))(*args)``. Take it once per batch of calls: the
    registries are read when it is made."""
    return functools.partial(_with_registries, carried(), fn)


def _with_registries(entries: dict[str, dict[str, Any]], fn: Callable[..., T], *args: Any,
                     **kwargs: Any) -> T:
    install(entries)
    return fn(*args, **kwargs)


__all__ = ["REGISTRIES", "Registry", "carried", "extends", "install", "travelling"]
