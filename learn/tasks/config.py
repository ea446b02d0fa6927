"""Typed objects from the apps' composed configs: the one place where a task turns a
config node into the dataclass that travels on."""

from __future__ import annotations

import dataclasses
from typing import TypeVar

T = TypeVar("T")


def typed(node, cls: type[T]) -> T:
    """The dataclass ``cls`` of a config node.

    Parameters
    ----------
    node : omegaconf.DictConfig, mapping or None
        A node of a structured config (:mod:`swgcli.schema`; converted with
        ``OmegaConf.to_object``), a plain mapping with some of the fields, or None.
    cls : type
        A dataclass.

    Returns
    -------
    cls
        ``cls()`` for None; the defaults fill the fields a plain mapping lacks.

    Raises
    ------
    ValueError
        A plain mapping with a key that is not a field of ``cls``.
    """
    from omegaconf import DictConfig, OmegaConf

    if node is None:
        return cls()
    if isinstance(node, cls):
        return node
    obj = OmegaConf.to_object(node) if isinstance(node, DictConfig) else dict(node)
    if isinstance(obj, cls):
        return obj
    fields = {f.name for f in dataclasses.fields(cls)}
    bad = sorted(set(obj) - fields)
    if bad:
        raise ValueError(f"{bad[0]}: not a field of {cls.__name__}; allowed: {sorted(fields)}")
    return cls(**obj)
