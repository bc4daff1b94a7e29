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
        fields = [f.strip() for f in line.split(separator)] if separator else line.split()
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
