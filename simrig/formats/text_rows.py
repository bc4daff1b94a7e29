"""Rows of an outside format's text files (MOTChallenge, KITTI): lines split into fields, fields read as
numbers, every error naming the file, line and column."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from simrig.errors import TracksError
from simrig.reading import open_regular


def parse_lines(file: Path, separator: str | None, minimum: int, names: tuple[str, ...]) -> list[tuple[int, list[str]]]:
    """The non-empty lines of ``file`` as (line number, fields), each with the first line's field count."""
    try:
        with open_regular(file, "tracks file", TracksError) as handle:
            text = handle.read().decode("utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise TracksError(f"{file}: cannot be read as text ({error})") from None
    lines, expected = [], None
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        if not separator:
            fields = line.split()
        elif " " in line or "\t" in line or "\r" in line:
            fields = [f.strip() for f in line.split(separator)]
        else:  # nothing to strip (most files): skip a call per field
            fields = line.split(separator)
        if expected is None:
            expected = len(fields)
            if expected < minimum:
                raise TracksError(f"{file}:{number}: {expected} columns where at least {minimum} are expected "
                                  f"({', '.join(names)}, …)")
        elif len(fields) != expected:
            raise TracksError(f"{file}:{number}: {len(fields)} columns where {expected} are expected (as on the "
                              "file's first line)")
        lines.append((number, fields))
    return lines


def number(file: Path, line: int, fields: list[str], column: int, names: tuple[str, ...]) -> float:
    """Field ``column`` as a finite float; an error naming file, line and column otherwise."""
    try:
        value = float(fields[column])
    except ValueError:
        value = float("nan")
    if not np.isfinite(value):
        raise TracksError(f"{file}:{line}: column {column + 1} ({names[column]}) is {fields[column]!r}, "
                          "not a finite number")
    return value


def integer(file: Path, line: int, fields: list[str], column: int, names: tuple[str, ...]) -> int:
    value = number(file, line, fields, column, names)
    if value != int(value):
        raise TracksError(f"{file}:{line}: column {column + 1} ({names[column]}) is {fields[column]!r}, "
                          "not an integer")
    return int(value)


def numbers(file: Path, lines: list[tuple[int, list[str]]], columns: tuple[int, ...], names: tuple[str, ...],
            integers: tuple[int, ...] = ()) -> np.ndarray:
    """Fields ``columns`` of every line as an ``(N, len(columns))`` float array, all finite, those in ``integers``
    integral: converted at once, and only when some field is not a finite number field by field again
    (:func:`number`, :func:`integer`) to name the first bad one's file, line and column."""
    if not lines:
        return np.zeros((0, len(columns)))
    try:
        values = np.array([[fields[c] for c in columns] for _, fields in lines], dtype=float)
    except ValueError:  # a field numpy does not read (text, or a form only Python's float takes)
        values = None
    whole = [columns.index(c) for c in integers]
    if values is not None and np.isfinite(values).all() and (values[:, whole] == np.round(values[:, whole])).all():
        return values
    return np.array([[integer(file, line, fields, c, names) if c in integers else number(file, line, fields, c, names)
                      for c in columns] for line, fields in lines], dtype=float)
