"""Markdown tables and number formatting for reports."""

from __future__ import annotations

import math


def number(value, digits: int = 3) -> str:
    """``value`` for a table: ``-`` for a missing one, integers without decimals."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if float(value).is_integer():
        return str(int(value))
    return f"{value:.{digits}f}"


def table(header: list[str], rows: list[list], *, first_left: bool = True,
          align: list[str] | None = None) -> list[str]:
    """A Markdown table: the first column left-aligned (unless ``first_left`` is false), the others
    right-aligned; ``align`` gives each column's own marker (``---``, ``---:``) instead.

    >>> table(["tracker", "HOTA"], [["saga", 0.5]])
    ['| tracker | HOTA |', '|---|---:|', '| saga | 0.500 |']
    """
    align = align or ["---" if first_left and i == 0 else "---:" for i in range(len(header))]
    out = ["| " + " | ".join(header) + " |", "|" + "|".join(align) + "|"]
    for row in rows:
        out.append("| " + " | ".join(cell if isinstance(cell, str) else number(cell) for cell in row) + " |")
    return out
