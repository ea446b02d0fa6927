"""The one writer of markdown tables, shared by every report of the project (the
calibration's, the learning studies', the monitor's)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

__all__ = ["md_table"]

_RULE = {"l": "---", "r": "---:"}


def _cell(v: object, nan: str) -> str | None:
    """One cell's text: a float to 3 significant digits (NaN as ``nan``); None stays."""
    if isinstance(v, (float, np.floating)):
        return nan if np.isnan(v) else f"{v:.3g}"
    return v if v is None else str(v)


def _line(cells: Iterable[str | None]) -> str:
    """``| a | b |``; a blank cell (None) as ``| |``."""
    return "|" + "".join(" |" if c is None else f" {c} |" for c in cells)


def md_table(header: Sequence[object], rows: Iterable[Iterable[object]], align: str = "",
             nan: str = "nan") -> str:
    """A markdown table: the header line, the separator line, then one line per row.

    A cell is written as ``str`` gives it, but for a float of a row (Python's or NumPy's),
    written to 3 significant digits, and None, a blank cell (``| |``; the empty string
    gives ``|  |``). A cell is not escaped: a ``|`` in it splits it.

    Parameters
    ----------
    header : sequence
        The columns' names.
    rows : iterable of iterable
        The cells of each row (a DataFrame's ``itertuples(index=False)``, lists of text).
    align : str, default ""
        One letter per column: ``l`` (separator ``---``) or ``r`` (``---:``, right
        aligned); empty: every column ``---``.
    nan : str, default "nan"
        How a NaN float is written.

    Returns
    -------
    str
        The table's lines joined by newlines, without a newline at the end.

    Raises
    ------
    ValueError
        If ``align`` is neither empty nor one letter ``l`` or ``r`` per column.
    """
    heads = [h if h is None else str(h) for h in header]
    if align and (len(align) != len(heads) or set(align) - set(_RULE)):
        raise ValueError(f"align {align!r}: one letter l or r per column "
                         f"({len(heads)} columns)")
    rule = "|" + "".join(_RULE[a] + "|" for a in align or "l" * len(heads))
    return "\n".join([_line(heads), rule,
                      *(_line(_cell(v, nan) for v in r) for r in rows)])
