"""The one reader of YAML files a user writes (a recording's mapping, an own joint's
files): PyYAML's safe loader, stricter in two ways that a plain ``yaml.safe_load`` is not.

* **A key given twice is refused**, naming the key, the file and both lines; with
  ``safe_load`` the last one silently wins (issue 43, cause 9).
* **What the file expands to is bounded before it is built**: YAML aliases (``*name``)
  repeat an anchored node (``&name``) without repeating its text, so a file of a few
  hundred bytes can stand for billions of values (a "billion laughs" alias bomb: 714 bytes
  gave a 656 MB error line and 3 GB of memory, issue 43, cause 7). The document is first
  composed into its node graph (aliases shared, nothing copied), the values it expands to
  are counted over that graph, and only a document of at most :data:`MAX_YAML_VALUES`
  values (and no alias that contains itself) is constructed.

Every refusal is one ``ValueError`` line, clipped to :data:`MAX_MESSAGE_CHARS` by
:func:`clip`, which callers also use for the messages they build from the values read.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import yaml

__all__ = ["MAX_MESSAGE_CHARS", "MAX_YAML_VALUES", "clip", "load_user_yaml",
           "user_yaml"]

#: Most values (scalars, lists and mappings, aliases expanded) a user YAML may stand for;
#: a 1 MiB file written out holds at most about half a million.
MAX_YAML_VALUES = 1_000_000
#: Longest message line built from a user's file (the rest is elided).
MAX_MESSAGE_CHARS = 500

_MERGE = "tag:yaml.org,2002:merge"


def clip(text: str, limit: int = MAX_MESSAGE_CHARS) -> str:
    """``text`` on one line of at most ``limit`` characters (the middle elided).

    Parameters
    ----------
    text : str
        A message, possibly quoting a user's values.
    limit : int, default MAX_MESSAGE_CHARS
        Most characters kept.

    Returns
    -------
    str
    """
    text = " ".join(text.splitlines())
    if len(text) <= limit:
        return text
    mark = f" ... [{len(text)} characters in all] ... "
    half = max(0, (limit - len(mark)) // 2)
    return f"{text[:half]}{mark}{text[len(text) - half:]}"


class _Loader(yaml.SafeLoader):
    """:class:`yaml.SafeLoader` refusing a key given twice in one mapping."""

    source = "<string>"

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        if isinstance(node, yaml.MappingNode):
            seen: dict[Any, int] = {}
            for key_node, _ in node.value:
                if key_node.tag == _MERGE:
                    continue  # '<<: *base': its keys may be overridden, as YAML says
                key = self.construct_object(key_node, deep=True)
                line = key_node.start_mark.line + 1
                try:
                    first = seen.get(key)
                except TypeError:
                    continue  # an unhashable key: the safe loader refuses it below
                if first is not None:
                    raise ValueError(clip(
                        f"{self.source}: line {line}: key {key!r} given twice in one "
                        f"mapping (first at line {first}); give each key once"))
                seen[key] = line
        return super().construct_mapping(node, deep=deep)


def _count(root: yaml.Node, source: str, limit: int) -> int:
    """Values ``root`` expands to (aliases counted each time they occur), refusing more
    than ``limit`` or an alias inside the node it names; linear in the nodes written."""
    memo: dict[int, int] = {}
    busy: set[int] = set()

    def size(node: yaml.Node) -> int:
        k = id(node)
        if k in memo:
            return memo[k]
        if k in busy:
            raise ValueError(f"{source}: line {node.start_mark.line + 1}: an alias inside "
                             "the node it names (a recursive YAML anchor); write the values "
                             "out")
        busy.add(k)
        n = 1
        if isinstance(node, yaml.SequenceNode):
            n += sum(size(c) for c in node.value)
        elif isinstance(node, yaml.MappingNode):
            n += sum(size(a) + size(b) for a, b in node.value)
        busy.discard(k)
        if n > limit:
            raise ValueError(f"{source}: line {node.start_mark.line + 1}: expands to more "
                             f"than {limit} values (YAML aliases '*name' repeating anchored "
                             "nodes); write the values out")
        memo[k] = n
        return n

    return size(root)


def load_user_yaml(text: str, source: str = "<string>",
                   max_values: int = MAX_YAML_VALUES) -> Any:
    """Parse a user's YAML text: safe tags only, no key twice, at most ``max_values``
    values once aliases are expanded (module docstring).

    Parameters
    ----------
    text : str
        The YAML document.
    source : str
        What the text is (``mapping joint.yaml``), the start of every message.
    max_values : int, default MAX_YAML_VALUES
        Most values the document may expand to [count].

    Returns
    -------
    object
        The document (None for an empty one).

    Raises
    ------
    ValueError
        One line beginning with ``source``: not YAML, a key given twice (naming it and
        both lines), an alias containing itself, or more than ``max_values`` values.
    """
    loader = _Loader(text)
    loader.source = source
    try:
        try:
            node = loader.get_single_node()
        except yaml.YAMLError as e:
            raise ValueError(clip(f"{source}: not YAML ({str(e).splitlines()[0]})")) from None
        if node is None:
            return None
        _count(node, source, max_values)
        try:
            return loader.construct_document(node)
        except yaml.YAMLError as e:
            raise ValueError(clip(f"{source}: not YAML ({str(e).splitlines()[0]})")) from None
    finally:
        loader.dispose()


def user_yaml(path: str | os.PathLike, what: str,
              max_values: int = MAX_YAML_VALUES) -> Any:
    """Read a user's YAML file (UTF-8) with :func:`load_user_yaml`; the caller has
    checked that it is a regular file of a bounded size.

    Parameters
    ----------
    path : path-like
        The file.
    what : str
        What it is, for messages (``mapping``): they begin ``<what> <path>:``.
    max_values : int, default MAX_YAML_VALUES
        See :func:`load_user_yaml`.

    Returns
    -------
    object

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    ValueError
        As :func:`load_user_yaml`, or the file is not UTF-8 text.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as e:
        raise ValueError(f"{what} {p}: not YAML (not UTF-8 text: {e.reason} at byte "
                         f"{e.start})") from None
    return load_user_yaml(text, f"{what} {p}", max_values)
