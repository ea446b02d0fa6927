"""Lazy imports shared by ``swgsim`` and ``learn``: package attributes imported on first use
(PEP 562, :func:`lazy_exports`) and heavy libraries imported on first use (:func:`lazy_module`)."""

from __future__ import annotations

import importlib
import importlib.util
import sys
from collections.abc import Callable, Mapping
from types import ModuleType


def lazy_exports(package: str, exports: Mapping[str, str]
                 ) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` of a package whose public names are imported on
    first use.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    exports : mapping of str to str
        Public name -> submodule (relative to the package) that defines it.

    Returns
    -------
    getattr_, dir_ : callable
        To assign to the package's ``__getattr__`` and ``__dir__``; a resolved name is
        cached in the package's namespace.

    Raises
    ------
    AttributeError
        From ``getattr_``, for a name that is not exported.
    """

    def getattr_(name: str) -> object:
        if name in exports:
            value = getattr(importlib.import_module(f".{exports[name]}", package), name)
            setattr(sys.modules[package], name, value)
            return value
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def dir_() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | {"__version__", *exports})

    return getattr_, dir_



class _LazyModule(ModuleType):
    """Stands in for a module not imported yet: the first attribute looked up imports it
    (a plain import: one that fails raises and is tried again next time) and every
    attribute is the real module's (what a test patches on it is seen here)."""

    def __getattr__(self, attr: str) -> object:
        return getattr(importlib.import_module(self.__name__), attr)

    def __dir__(self) -> list[str]:
        return dir(importlib.import_module(self.__name__))


def lazy_module(name: str) -> ModuleType:
    """A module that is imported on its first attribute access, so that a heavy library
    costs nothing to a process that never uses it: an app's ``--help`` or a refused
    override answers before pandas, the scipy submodules or skops are loaded.

    Parameters
    ----------
    name : str
        Absolute module name, e.g. ``"pandas"`` or ``"scipy.signal"``; the parent packages
        of a dotted name are imported at once (keep them light: ``scipy`` is).

    Returns
    -------
    types.ModuleType
        The module itself if it is imported already, else a stand-in that imports it on
        first use and is not registered in ``sys.modules`` (the standard library's
        ``importlib.util.LazyLoader`` is not used: in Python 3.11 a load that fails part
        way, e.g. under a raising ``numpy.seterr``, leaves a half-built module behind).

    Raises
    ------
    ModuleNotFoundError
        The module is not installed (found at once, not at first use).
    """
    if name in sys.modules:
        return sys.modules[name]
    if importlib.util.find_spec(name) is None:
        raise ModuleNotFoundError(f"No module named {name!r}", name=name)
    return _LazyModule(name)
