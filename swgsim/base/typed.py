"""Typed configs: plain mappings checked against dataclass schemas, before any work.

A config travels as a dataclass; plain data (YAML, JSON, a notebook's dict) enters through
:func:`complete` (every unknown, missing or mistyped key refused with its full name, e.g.
``dataset.chain.windows_s: unknown key; allowed: sample_rate_hz, window_s, ...``) and
:func:`build` (the typed object); :func:`plain` is the way back to plain data,
:func:`schema_of` the way to an app's Hydra structured config. A field may declare its
allowed range in its metadata (:func:`allowed`), refused in one line naming the full key,
the range and the value, e.g. ``selection.max_rel_se must lie in (0, inf), got -1``
(:func:`check_range`'s words). :func:`check_tree` checks a typed config in one pass: NaN
and infinity first (:func:`check_finite`: every comparison with NaN is false, so NaN
passes a range check written ``if v < lo or v > hi: raise``), then every part's ranges and
its own ``check(self, where)`` (scikit-learn's ``_parameter_constraints`` idea), each part
after its children's, so that a part's rule may rely on its parts being valid.

Used by every schema of the project: the data set's (:mod:`swgsim.datasets.config`), the
calibration's options (:mod:`swgcal.loop`, ``swgcal.friction.options``, ...) and the apps'
(``swgcli.schema``).
"""

from __future__ import annotations

import collections.abc
import dataclasses
import functools
import math
import numbers
import types
import typing
from collections.abc import Iterator, Mapping
from typing import Any, Union

import numpy as np

__all__ = ["LATER", "MISSING", "NONFINITE", "RANGE", "Range", "allowed", "build",
           "check_finite", "check_keys", "check_range", "check_ranges", "check_tree",
           "complete", "plain", "schema_of", "without_later_defaults"]

MISSING = "???"  # Hydra's and OmegaConf's marker of a mandatory value

_SCALARS = {int: "an integer", float: "a number", str: "a string", bool: "true or false"}
_LISTS = (list, tuple, collections.abc.Sequence)  # origins of the types held as lists


def _describe(tp) -> str:
    origin = typing.get_origin(tp)
    if tp in _SCALARS:
        return _SCALARS[tp]
    if origin in _LISTS:
        return "a list"
    if origin in (dict, Mapping) or dataclasses.is_dataclass(tp):
        return "a mapping"
    return str(tp)


def _fields(schema: type) -> dict[str, Any]:
    hints = typing.get_type_hints(schema)
    return {f.name: hints[f.name] for f in dataclasses.fields(schema)}


def _default(schema: type, name: str) -> Any:
    f = {f.name: f for f in dataclasses.fields(schema)}[name]
    if f.default_factory is not dataclasses.MISSING:
        value = f.default_factory()
    elif f.default is not dataclasses.MISSING:
        value = f.default
    else:
        value = MISSING
    return plain(value)


def plain(value: Any) -> Any:
    """A typed config as plain data, as YAML, an app's config or a run's log holds it.

    Parameters
    ----------
    value : Any
        A dataclass instance (e.g. :class:`swgcal.SelectionConfig`), a mapping, a list,
        a tuple or a scalar.

    Returns
    -------
    Any
        Dataclasses and mappings as dicts (field order), lists and tuples as lists,
        recursively; anything else as it is.
    """
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, Mapping):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    return value


#: Key of a field's metadata marking an option added after data were made with its schema,
#: the reason as its value: ``field(default=0.0, metadata={LATER: "issue 83"})``. While it
#: holds its default, :func:`without_later_defaults` leaves it out of the plain data, so that
#: a config digest (a data set's config hash) stays what it was before the option.
LATER = "later"


def _dataclass_of(tp: Any) -> type | None:
    """The dataclass a field's type holds (``X``, ``X | None``, ``list[X]``), else None."""
    if typing.get_origin(tp) in (Union, types.UnionType):
        inner = [a for a in typing.get_args(tp) if a is not type(None)]
        tp = inner[0] if len(inner) == 1 else None
    if typing.get_origin(tp) in _LISTS:
        tp = (typing.get_args(tp) or (None,))[0]
    return tp if dataclasses.is_dataclass(tp) else None


def without_later_defaults(data: Mapping[str, Any], schema: type) -> dict[str, Any]:
    """Plain data of ``schema`` without the fields marked :data:`LATER` that hold their
    defaults, at every depth (nested dataclasses, optional ones and lists of them).

    Parameters
    ----------
    data : mapping
        Plain data (:func:`plain`) of an instance of ``schema``; keys it lacks stay absent.
    schema : type
        The dataclass ``data`` is of.

    Returns
    -------
    dict
        A copy; ``data`` is not changed.
    """
    hints, out = _hints(schema), dict(data)
    for f in dataclasses.fields(schema):
        if f.name not in out:
            continue
        value = out[f.name]
        if LATER in f.metadata and value == _default(schema, f.name):
            del out[f.name]
            continue
        sub = _dataclass_of(hints.get(f.name, Any))
        if sub is not None and isinstance(value, Mapping):
            out[f.name] = without_later_defaults(value, sub)
        elif sub is not None and isinstance(value, list):
            out[f.name] = [without_later_defaults(v, sub) if isinstance(v, Mapping) else v
                           for v in value]
    return out


def _value(value: Any, tp, where: str, fill: bool) -> Any:
    if isinstance(value, str) and value == MISSING:
        raise ValueError(f"{where}: missing value (give {where}=...)")
    if tp is Any:
        return value
    origin = typing.get_origin(tp)
    if origin in (Union, types.UnionType):
        args = typing.get_args(tp)
        if value is None and type(None) in args:
            return None
        inner = [a for a in args if a is not type(None)]
        return _value(value, inner[0], where, fill)
    if value is None:
        raise ValueError(f"{where}: must be {_describe(tp)}, got null")
    if dataclasses.is_dataclass(tp):
        if not isinstance(value, Mapping):
            raise ValueError(f"{where}: must be a mapping of {', '.join(_fields(tp))}, "
                             f"got {value!r}")
        return _mapping(value, tp, where, fill)
    if origin in _LISTS:
        if not isinstance(value, (list, tuple)):
            raise ValueError(f"{where}: must be a list, got {value!r}")
        (item,) = typing.get_args(tp)[:1] or (Any,)
        return [_value(v, item, f"{where}[{i}]", fill) for i, v in enumerate(value)]
    if origin is dict:
        if not isinstance(value, Mapping):
            raise ValueError(f"{where}: must be a mapping, got {value!r}")
        _, item = typing.get_args(tp)
        return {k: _value(v, item, f"{where}.{k}", fill) for k, v in value.items()}
    if tp is bool:
        ok = isinstance(value, bool)
    elif tp is int:  # numpy's integers and floats too, from a program
        ok = isinstance(value, numbers.Integral) and not isinstance(value, bool)
    elif tp is float:
        ok = isinstance(value, numbers.Real) and not isinstance(value, bool)
    elif tp is str:
        ok = isinstance(value, str)
    else:
        ok = True
    if not ok:
        raise ValueError(f"{where}: must be {_describe(tp)}, got {value!r}")
    return value


#: Key of a field's metadata holding its allowed range, a :class:`Range`, checked with the
#: keys (:func:`check_keys`, :func:`complete`), so before any work, and on a typed config
#: (:func:`check_ranges` in ``__post_init__``, :func:`check_tree`):
#: ``n_jobs: int = field(default=2, metadata=allowed(1, None, "worker processes"))``.
RANGE = "range"


@dataclasses.dataclass(frozen=True)
class Range:
    """Allowed values of a number field (:func:`allowed`): finite, within the bounds.

    Attributes
    ----------
    lo, hi : float or None
        Bounds; None leaves that end open (any finite number beyond).
    what : str
        What the value is or its unit, for the message (e.g. ``"worker processes"``).
    lo_open, hi_open : bool
        Whether the bound itself is excluded.
    odd : bool
        Only odd integers (e.g. a filter's window length).
    unit : str
        Unit for the message, after the range (e.g. ``"h"``), as :func:`check_range`
        writes it.

    Notes
    -----
    None is allowed where the field's type admits it (``float | None``), nowhere else.
    """

    lo: float | None = None
    hi: float | None = None
    what: str = ""
    lo_open: bool = False
    hi_open: bool = False
    odd: bool = False
    unit: str = ""

    def contains(self, value: Any) -> bool:
        """Whether ``value`` is an allowed number (booleans, None, NaN and infinities
        are not)."""
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            return False
        v = float(value)
        if not math.isfinite(v) or (self.odd and not (v.is_integer() and int(v) % 2 == 1)):
            return False
        above = self.lo is None or (v > self.lo if self.lo_open else v >= self.lo)
        below = self.hi is None or (v < self.hi if self.hi_open else v <= self.hi)
        return above and below

    def text(self, nullable: bool = False) -> str:
        """The allowed values in the words of :func:`check_range`, e.g. ``"must lie in
        (0, 1]"``, ``"must lie in (0, inf) or be null"``, ``"must be an odd integer in
        [5, 1001] (samples)"``, ``"must lie in [1, inf) (worker processes)"``,
        ``"must lie in (0, 100000] h"``."""
        rng = _interval(-math.inf if self.lo is None else self.lo,
                        math.inf if self.hi is None else self.hi, self.lo_open, self.hi_open)
        return (f"must {'be an odd integer in' if self.odd else 'lie in'} {rng}"
                f"{' ' + self.unit if self.unit else ''}{' or be null' if nullable else ''}"
                f"{' (' + self.what + ')' if self.what else ''}")


def _interval(lo: float, hi: float, lo_open: bool, hi_open: bool) -> str:
    """``[lo, hi]`` with round brackets at open or infinite ends, e.g. ``(0, inf)``."""
    return (f"{'(' if lo_open or math.isinf(lo) else '['}{lo:g}, "
            f"{hi:g}{')' if hi_open or math.isinf(hi) else ']'}")


def allowed(lo: float | None, hi: float | None, what: str = "", *, lo_open: bool = False,
            hi_open: bool = False, odd: bool = False, unit: str = "") -> dict[str, Range]:
    """Field metadata declaring the allowed range of a number (:data:`RANGE`).

    Parameters
    ----------
    lo, hi : float or None
        Bounds, inclusive unless ``lo_open``/``hi_open``; None leaves that end open.
    what : str
        What the value is or its unit, for the message (e.g. ``"worker processes"``).
    lo_open, hi_open : bool
        Exclude the bound itself.
    odd : bool
        Only odd integers.
    unit : str
        Unit for the message, after the range, e.g. ``"h"``: ``must lie in (0, 100000] h``.

    Returns
    -------
    dict
        ``{RANGE: Range(...)}``, for ``dataclasses.field(metadata=...)``; None is allowed
        where the field's type admits it.
    """
    return {RANGE: Range(lo, hi, what, lo_open, hi_open, odd, unit)}


def _nullable(tp: Any) -> bool:
    """Whether a field type admits None (``X | None``, ``Optional[X]``, ``Any``)."""
    if tp is Any:
        return True
    if isinstance(tp, str):  # an annotation left unresolved
        return "None" in tp or "Optional" in tp
    return (typing.get_origin(tp) in (Union, types.UnionType)
            and type(None) in typing.get_args(tp))


@functools.cache
def _hints(schema: type) -> dict[str, Any]:
    """Field types of a dataclass, resolved where they can be (else the annotations)."""
    try:
        return _fields(schema)
    except (NameError, TypeError):
        return {f.name: f.type for f in dataclasses.fields(schema)}


def _check_range(value: Any, rng: Range, where: str, nullable: bool) -> None:
    """Refuse a value outside its field's :data:`RANGE` in one line naming the full key,
    the range and the value, in :func:`check_range`'s words:
    ``selection.max_rel_se must lie in (0, inf), got -1``; NaN and infinity as
    :func:`check_finite` does."""
    if (value is None and nullable) or rng.contains(value):
        return
    if (isinstance(value, numbers.Real) and not isinstance(value, bool)
            and not math.isfinite(value)):
        raise ValueError(f"{where} must be a finite number, got {value}")
    shown = repr(value) if isinstance(value, str) else value
    raise ValueError(f"{where} {rng.text(nullable)}, got {shown}")


def check_ranges(obj: Any, where: str = "") -> None:
    """Refuse a field of a dataclass instance outside its declared range (:func:`allowed`).

    Called from a dataclass's ``__post_init__``, it refuses a bad value on construction,
    before any work; its parts (nested dataclasses) check their own fields.

    Parameters
    ----------
    obj : dataclass instance
    where : str
        Full name of ``obj`` for the message (``""``: the field's name alone).

    Raises
    ------
    ValueError
        For the first field outside its range, in field order, e.g.
        ``max_rel_se must lie in (0, inf), got -1``: not a number, outside the bounds,
        not odd where odd integers are asked for, or None where its type does not admit
        it; NaN and infinity as :func:`check_finite` words them
        (``max_rel_se must be a finite number, got nan``).
    """
    hints = _hints(type(obj))
    for f in dataclasses.fields(obj):
        if RANGE in f.metadata:
            _check_range(getattr(obj, f.name), f.metadata[RANGE],
                         f"{where}.{f.name}" if where else f.name,
                         _nullable(hints.get(f.name, Any)))


def _mapping(cfg: Mapping[str, Any], schema: type, where: str, fill: bool) -> dict:
    fields = _fields(schema)
    ranges = {f.name: f.metadata[RANGE] for f in dataclasses.fields(schema)
              if RANGE in f.metadata}
    pre = f"{where}." if where else ""
    unknown = [k for k in cfg if k not in fields]
    if unknown:
        raise ValueError(f"{pre}{unknown[0]}: unknown key; allowed: {', '.join(fields)}")
    out = {}
    for name, tp in fields.items():
        if name in cfg:
            out[name] = _value(cfg[name], tp, f"{pre}{name}", fill)
            if name in ranges:
                _check_range(out[name], ranges[name], f"{pre}{name}", _nullable(tp))
        elif fill:
            default = _default(schema, name)
            if isinstance(default, str) and default == MISSING:
                raise ValueError(f"{pre}{name}: missing key")
            out[name] = _value(default, tp, f"{pre}{name}", fill)
        else:
            raise ValueError(f"{pre}{name}: missing key")
    return out


def check_keys(cfg: Mapping[str, Any], schema: type, where: str) -> None:
    """Check a complete mapping against a dataclass schema, recursively.

    Parameters
    ----------
    cfg : mapping
        Config to check, every key of the schema present (e.g. a composed app config).
    schema : dataclass type
        E.g. :class:`DatasetConfig`. Fields typed ``Any`` are not looked into.
    where : str
        Full name of ``cfg`` for messages, e.g. ``"dataset"`` ("" for a root config).

    Raises
    ------
    ValueError
        One line naming the first unknown key (with the allowed ones), missing key,
        value of the wrong type or number outside its field's range (:func:`allowed`), by
        its full name.
    """
    _mapping(cfg, schema, where, fill=False)


def complete(cfg: Mapping[str, Any], schema: type, where: str) -> dict:
    """A checked copy of a mapping with the keys it leaves out taken from the schema.

    Parameters
    ----------
    cfg, schema, where
        As in :func:`check_keys`; keys absent from ``cfg`` (at any depth) take the
        schema's defaults, except mandatory ones.

    Returns
    -------
    dict
        Plain, complete config.

    Raises
    ------
    ValueError
        As :func:`check_keys` (unknown key, mandatory key missing, wrong type).
    """
    return _mapping(cfg, schema, where, fill=True)


def build(value: Any, tp: Any, where: str | None = None) -> Any:
    """A typed object of schema ``tp`` from a checked plain value (:func:`complete`).

    Dataclasses are built from their mappings, recursively through lists, tuples, dicts and
    optional fields; fields typed ``Any`` keep their plain value; ``tuple`` and
    ``Sequence`` fields become tuples, ``float`` fields floats.

    Parameters
    ----------
    value : Any
        Plain, complete config (:func:`complete`).
    tp : type
        Its schema, e.g. :class:`swgcal.SelectionConfig`.
    where : str, optional
        Full name of ``value`` (``""`` for a root config): given, the message of a
        ``ValueError`` that a dataclass raises on construction (its ``__post_init__``
        checks) starts with the full name of that dataclass, e.g.
        ``split.validation_blocks must list blocks in [-10, 9], got [12]``.

    Returns
    -------
    Any
        The typed object.

    Raises
    ------
    ValueError
        What a dataclass refuses on construction, prefixed as above.
    """
    origin = typing.get_origin(tp)
    if tp is Any or value is None:
        return value
    if origin in (Union, types.UnionType):
        inner = [a for a in typing.get_args(tp) if a is not type(None)]
        return build(value, inner[0], where)
    if dataclasses.is_dataclass(tp):
        hints = _fields(tp)
        sub = (lambda k: None) if where is None else (lambda k: f"{where}.{k}" if where else k)
        kwargs = {k: build(v, hints[k], sub(k)) for k, v in value.items()}
        if not where:
            return tp(**kwargs)
        try:
            return tp(**kwargs)
        except ValueError as e:
            raise ValueError(f"{where}.{e}") from None
    if origin in _LISTS:
        (item,) = typing.get_args(tp)[:1] or (Any,)
        items = [build(v, item, None if where is None else f"{where}[{i}]")
                 for i, v in enumerate(value)]
        return items if origin is list else tuple(items)
    if origin is dict:
        _, item = typing.get_args(tp)
        return {k: build(v, item, None if where is None else f"{where}.{k}")
                for k, v in value.items()}
    if tp is float:
        return float(value)
    return value


# ------------------------------------------------------------------- finiteness
#: Key of a field's metadata that lets it hold NaN or infinity, with the reason as its value:
#: ``field(default=..., metadata={NONFINITE: "inf: no cut-off"})``. No field of
#: :class:`DatasetConfig` or :class:`~swgsim.datasets.schedule.LifeConfig` sets it.
NONFINITE = "nonfinite"


def _key(where: str, name: Any) -> str:
    """The full key of a part ``name`` of ``where`` (``name`` alone at a root named "")."""
    return f"{where}.{name}" if where else str(name)


def _nonfinite(value: Any, where: str) -> Iterator[tuple[str, Any]]:
    """(full key, value) of every NaN or infinity in ``value``, depth first, in field order.

    Dataclasses are walked field by field (a field whose metadata holds :data:`NONFINITE`
    is skipped), mappings by key, lists and tuples by index, arrays element by element;
    integers, booleans, strings and None are finite by nature.
    """
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        for f in dataclasses.fields(value):
            if NONFINITE not in f.metadata:
                yield from _nonfinite(getattr(value, f.name), _key(where, f.name))
    elif isinstance(value, Mapping):
        for k, v in value.items():
            yield from _nonfinite(v, _key(where, k))
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            yield from _nonfinite(v, f"{where}[{i}]")
    elif isinstance(value, np.ndarray):
        if value.dtype.kind in "fc":
            for idx in np.argwhere(~np.isfinite(value)):
                yield f"{where}[{', '.join(str(int(i)) for i in idx)}]", value[tuple(idx)]
        elif value.dtype.kind == "O":
            for idx in np.ndindex(value.shape):
                yield from _nonfinite(value[idx], f"{where}[{', '.join(map(str, idx))}]")
    elif (isinstance(value, numbers.Real) and not isinstance(value, numbers.Integral)
          and not math.isfinite(value)):
        yield where, value


def check_finite(obj: Any, where: str) -> None:
    """Refuse NaN and infinity in any float of a config tree, naming its full key.

    Every float is checked, whatever its key: in nested dataclasses, lists, tuples, dicts
    and arrays, and in fields typed ``Any`` (e.g. ``sensor_effects[i].params``), unless
    the dataclass field declares otherwise in its metadata (:data:`NONFINITE`). A NaN
    can arrive as ``.nan`` in YAML, ``nan`` on the command line or from a program; it is
    refused here, before any range check compares with it.

    Parameters
    ----------
    obj : Any
        The config: a dataclass (e.g. :class:`DatasetConfig`), a mapping, a list, ...
    where : str
        Full name of ``obj`` for the message, e.g. ``"dataset"`` (``""`` for a root
        config: its keys by their names alone, ``bridges.unit``).

    Raises
    ------
    ValueError
        One line naming the first non-finite value by its full key, e.g.
        ``dataset.sensors.grid_length_mm must be a finite number, got nan``.
    """
    for key, value in _nonfinite(obj, where):
        raise ValueError(f"{key} must be a finite number, got {value}")


def check_range(value: Any, lo: float, hi: float, key: str, unit: str = "", *,
                lo_open: bool = False, hi_open: bool = False, why: str = "") -> None:
    """Refuse a number outside [lo, hi] (or the open ends), NaN and infinity included,
    in one line naming the key, the value and the range.

    Parameters
    ----------
    value : number
    lo, hi : float
        Bounds (``-inf`` or ``inf`` for an open end).
    key : str
        Full name, e.g. ``dataset.chain.window_s``.
    unit : str
        Unit for the message, e.g. ``"s"``.
    lo_open, hi_open : bool
        Exclude the bound.
    why : str
        What the range means, for the message.

    Raises
    ------
    ValueError
        ``<key> must lie in [lo, hi] unit (why), got <value>``.
    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = float("nan")
    ok = math.isfinite(v) and (v > lo if lo_open else v >= lo) and (v < hi if hi_open else v <= hi)
    if not ok:
        rng = _interval(lo, hi, lo_open, hi_open)
        raise ValueError(f"{key} must lie in {rng}{' ' + unit if unit else ''}"
                         f"{' (' + why + ')' if why else ''}, got {value}")


def _check_parts(obj: Any, where: str) -> None:
    """Range metadata and ``check(where)`` of every dataclass in ``obj``, children first."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        hints = _hints(type(obj))
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            _check_parts(value, _key(where, f.name))
            if RANGE in f.metadata:
                _check_range(value, f.metadata[RANGE], _key(where, f.name),
                             _nullable(hints.get(f.name, Any)))
        hook = getattr(obj, "check", None)
        if callable(hook):
            hook(where)
    elif isinstance(obj, Mapping):
        for k, v in obj.items():
            _check_parts(v, _key(where, k))
    elif isinstance(obj, (list, tuple)):
        for i, v in enumerate(obj):
            _check_parts(v, f"{where}[{i}]")


def check_tree(obj: Any, where: str) -> None:
    """Check a typed config in one pass: finiteness, field ranges, then each part's rules.

    Parameters
    ----------
    obj : dataclass
        The config, e.g. a :class:`~swgsim.datasets.config.DatasetConfig`.
    where : str
        Full name of ``obj`` for messages, e.g. ``"dataset"`` (``""`` for a root config:
        its keys by their names alone, e.g. ``bridges.unit``).

    Raises
    ------
    ValueError
        One line naming the first bad key: a NaN or infinity anywhere
        (:func:`check_finite`, first, so that no range check compares with a NaN), a number
        outside its field's :data:`RANGE`, or what a part's ``check(where)`` refuses (parts
        are checked depth first, in field order, each after its own parts).
    """
    check_finite(obj, where)
    _check_parts(obj, where)


def _structured_type(tp: Any) -> Any:
    """The structured-config type of a library field type (tuples and sequences become
    lists, ``X | None`` becomes ``Optional[X]``)."""
    args = typing.get_args(tp)
    origin = typing.get_origin(tp)
    if origin in (types.UnionType, typing.Union) and type(None) in args:
        (inner,) = [a for a in args if a is not type(None)]
        return typing.Optional[_structured_type(inner)]  # noqa: UP045 (OmegaConf needs it)
    if origin in (tuple, list, collections.abc.Sequence):
        return list[args[0]] if args else list
    return tp


def schema_of(cls: type, name: str | None = None) -> type:
    """The app schema of a library option dataclass: the same keys, types and defaults
    (the library's, written once), nested dataclasses included; the way from a typed
    config to a Hydra structured config, as :func:`plain` is the way to plain data.

    Parameters
    ----------
    cls : dataclass type
        E.g. :class:`swgcal.SelectionConfig`.
    name : str, optional
        Name of the schema class (default: the library class's).

    Returns
    -------
    dataclass type
        Usable as a Hydra structured config.
    """
    hints = typing.get_type_hints(cls)
    out = []
    for f in dataclasses.fields(cls):
        if f.default_factory is not dataclasses.MISSING:
            sub = schema_of(type(f.default_factory()))
            out.append((f.name, sub, dataclasses.field(default_factory=sub)))
        elif isinstance(f.default, tuple):
            out.append((f.name, _structured_type(hints[f.name]),
                        dataclasses.field(default_factory=lambda d=f.default: list(d))))
        else:
            out.append((f.name, _structured_type(hints[f.name]),
                        dataclasses.field(default=f.default)))
    schema = dataclasses.make_dataclass(name or cls.__name__, out)
    schema.__doc__ = f"App keys of :class:`{cls.__module__}.{cls.__qualname__}`."
    return schema
