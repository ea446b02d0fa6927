"""Old module paths kept working for one release, with a deprecation warning.

When a package is reorganised, code outside it (a notebook, a script, a pickled object)
still names the old modules. A package lists them in a table, old dotted name -> the new
modules that hold its names, and installs :class:`MovedModules` once (in its
``__init__``): importing an old name then gives a small module whose attributes are read
from the new ones, and warns once with a :class:`DeprecationWarning` naming where the
module went. Nothing of the project itself imports an old path (a test checks it).
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import types
import warnings
from collections.abc import Mapping, Sequence

__all__ = ["MovedModules", "install"]


class _MovedModule(types.ModuleType):
    """A module standing for an old path: attributes from the new modules, in order."""

    def __init__(self, name: str, targets: Sequence[str]) -> None:
        super().__init__(name, f"Moved to {', '.join(targets)} (deprecated path).")
        self.__targets = tuple(targets)

    def __getattr__(self, attr: str):
        if attr.startswith("__") and attr.endswith("__"):
            raise AttributeError(attr)
        for t in self.__targets:
            mod = importlib.import_module(t)
            if hasattr(mod, attr):
                return getattr(mod, attr)
        # a submodule of a moved package (swgsim.friction.effects)
        try:
            return importlib.import_module(f"{self.__targets[0]}.{attr}")
        except ImportError:
            raise AttributeError(f"module {self.__name__!r} (moved to "
                                 f"{', '.join(self.__targets)}) has no attribute "
                                 f"{attr!r}") from None

    def __dir__(self) -> list[str]:
        return sorted({n for t in self.__targets for n in dir(importlib.import_module(t))})


class MovedModules(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds old module names of a table and loads them as stand-ins for the new ones.

    Parameters
    ----------
    table : mapping of str to sequence of str
        Old dotted module name -> new dotted module names holding its public names (the
        first also its submodules and private names).
    release : str
        When the old paths go (named in the warning).
    """

    def __init__(self, table: Mapping[str, Sequence[str]], release: str) -> None:
        self.table, self.release = dict(table), release

    def find_spec(self, fullname, path=None, target=None):  # noqa: D102 - importlib's protocol
        if fullname not in self.table:
            return None
        return importlib.machinery.ModuleSpec(fullname, self, is_package=True)

    def create_module(self, spec):  # noqa: D102
        targets = self.table[spec.name]
        warnings.warn(f"{spec.name} moved to {', '.join(targets)}; the old path is removed in "
                      f"{self.release}", DeprecationWarning, stacklevel=3)
        return _MovedModule(spec.name, targets)

    def exec_module(self, module) -> None:  # noqa: D102
        module.__path__ = []  # a package: its old submodules are found by the table too


def install(table: Mapping[str, Sequence[str]], release: str) -> None:
    """Install a :class:`MovedModules` for ``table`` (once per table)."""
    if not any(isinstance(f, MovedModules) and f.table == dict(table) for f in sys.meta_path):
        sys.meta_path.append(MovedModules(table, release))
