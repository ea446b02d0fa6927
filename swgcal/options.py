"""Option ranges written once: typed option dataclasses declare each range on the field,
the library checks it on construction and apps read it from there.

A field made with :func:`ranged` carries a :class:`Range` in its metadata;
:func:`check_ranges` (called from the dataclass's ``__post_init__``) refuses a value
outside it with one line naming the key, the allowed range and the value
(docs/STYLE.md, "Errors and files"). :func:`build` makes such a dataclass from a plain
mapping (an app's config group) and prefixes the key's full name to the message, e.g.
``selection.max_rel_se must lie in (0, inf), got -1``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, is_dataclass
from typing import Any

__all__ = ["Range", "ranged", "check_ranges", "build", "plain"]


@dataclass(frozen=True)
class Range:
    """Allowed values of a numeric option.

    Attributes
    ----------
    lo, hi : float
        Bounds (``-inf``/``inf`` for an open side).
    lo_open, hi_open : bool
        Whether a bound itself is excluded.
    odd : bool
        Only odd integers.
    nullable : bool
        ``None`` (null) is allowed too.
    """

    lo: float = -math.inf
    hi: float = math.inf
    lo_open: bool = False
    hi_open: bool = False
    odd: bool = False
    nullable: bool = False

    def contains(self, value: Any) -> bool:
        """Whether ``value`` is allowed."""
        if value is None:
            return self.nullable
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return False
        v = float(value)
        if self.odd and not (v == int(v) and int(v) % 2 == 1):
            return False
        above = v > self.lo if self.lo_open or math.isinf(self.lo) else v >= self.lo
        below = v < self.hi if self.hi_open or math.isinf(self.hi) else v <= self.hi
        return above and below

    def text(self) -> str:
        """The allowed values in words, e.g. ``"lie in (0, 1]"``."""
        lo = "(" if self.lo_open or math.isinf(self.lo) else "["
        hi = ")" if self.hi_open or math.isinf(self.hi) else "]"
        what = "be an odd integer in" if self.odd else "lie in"
        out = f"{what} {lo}{self.lo:g}, {self.hi:g}{hi}"
        return out + " or be null" if self.nullable else out


def ranged(default: Any, lo: float = -math.inf, hi: float = math.inf, *,
           lo_open: bool = False, hi_open: bool = False, odd: bool = False) -> Any:
    """A dataclass field with a default and its allowed range (``None`` default: nullable).

    Parameters
    ----------
    default : int or float or None
    lo, hi : float
        Bounds, inclusive unless ``lo_open``/``hi_open``.
    odd : bool
        Only odd integers.

    Returns
    -------
    dataclasses.Field
    """
    rng = Range(float(lo), float(hi), lo_open, hi_open, odd, nullable=default is None)
    return field(default=default, metadata={"range": rng})


def check_ranges(obj: Any) -> None:
    """Refuse a field of a dataclass instance outside its declared :class:`Range`.

    Raises
    ------
    ValueError
        ``<field> must lie in [lo, hi], got <value>`` for the first field outside.
    """
    for f in fields(obj):
        rng = f.metadata.get("range")
        value = getattr(obj, f.name)
        if rng is not None and not rng.contains(value):
            raise ValueError(f"{f.name} must {rng.text()}, got {value}")


def build(cls: type, values: Mapping[str, Any] | None, prefix: str = "") -> Any:
    """An option dataclass from a plain mapping, nested dataclasses included.

    Lists become tuples; keys left out take the dataclass defaults.

    Parameters
    ----------
    cls : dataclass type
    values : mapping, optional
    prefix : str
        Full name of the mapping with a trailing dot (``"selection."``), put in front of
        the key of a refused value.

    Returns
    -------
    instance of ``cls``

    Raises
    ------
    ValueError
        A value outside its range or an unknown key, naming the key by its full name.
    """
    values = dict(values or {})
    known = {f.name: f for f in fields(cls)}
    unknown = sorted(set(values) - set(known))
    if unknown:
        raise ValueError(f"{prefix}{unknown[0]}: unknown key; allowed: {sorted(known)}")
    kwargs = {}
    for name, v in values.items():
        sub = _nested_type(cls, known[name])
        if sub is not None and isinstance(v, Mapping):
            v = build(sub, v, f"{prefix}{name}.")
        elif isinstance(v, list):
            v = tuple(v)
        kwargs[name] = v
    try:
        return cls(**kwargs)
    except ValueError as e:
        raise ValueError(f"{prefix}{e}") from None


def _nested_type(cls: type, f: dataclasses.Field) -> type | None:
    """The dataclass type of a field whose default is a dataclass instance, else None."""
    if f.default_factory is not dataclasses.MISSING:
        default = f.default_factory()
        return type(default) if is_dataclass(default) else None
    return None


def plain(obj: Any) -> Any:
    """A dataclass instance as plain data (dicts, lists), as an app's config holds it."""
    if is_dataclass(obj):
        return {f.name: plain(getattr(obj, f.name)) for f in fields(obj)}
    if isinstance(obj, (list, tuple)):
        return [plain(x) for x in obj]
    return obj
