"""Names read from data that become parts of paths: one rule, checked in one place.

A scenario, a camera of a custom rig, a search space or a suite is named in a data file, and the name becomes a
folder or file name (``runs/NAME-seed0``, ``images/CAMERA/000012.png``, ``runs/search/NAME``). A name is
safe as one path part when it is 1–:data:`MAX_LENGTH` characters, has no folder separator (``/``, ``\\``), does
not start with a dot (so neither ``.`` nor ``..`` nor a hidden file), and holds no control, format (the Unicode
bidi overrides among them), surrogate, private-use or unassigned character, and no line or paragraph separator.
Letters of any script, digits, spaces and punctuation otherwise stay as they are.
"""

from __future__ import annotations

import unicodedata

from .errors import SimrigError

MAX_LENGTH = 100
"""[characters] the longest name used as a path part (file systems allow 255 bytes; UTF-8 takes up to 4 each
and simrig adds suffixes such as ``-seed12``)."""
_REFUSED_CATEGORIES = {"Cc": "control", "Cf": "format (e.g. a bidi override)", "Cs": "surrogate",
                       "Co": "private-use", "Cn": "unassigned", "Zl": "line separator", "Zp": "paragraph separator"}


class UnsafeNameError(SimrigError):
    """A name from data cannot be used as a part of a path; the message names what it names and why."""


def name_problem(name: object) -> str | None:
    """Why ``name`` cannot be one path part, or None when it can (see the module docstring)."""
    if not isinstance(name, str):
        return f"is a {type(name).__name__}, not a string"
    if not name:
        return "is empty"
    if len(name) > MAX_LENGTH:
        return f"has {len(name)} characters, more than {MAX_LENGTH}"
    if "/" in name or "\\" in name:
        return "holds a folder separator (/ or \\)"
    if name.startswith("."):
        return "starts with a dot (., .. and hidden names are refused)"
    if name != name.strip():
        return "starts or ends with white space"
    for position, character in enumerate(name):
        kind = _REFUSED_CATEGORIES.get(unicodedata.category(character))
        if kind is not None:
            return f"holds the {kind} character U+{ord(character):04X} at position {position}"
    return None


def path_part(name: object, what: str) -> str:
    """``name`` unchanged when it is safe as one path part, else an :class:`UnsafeNameError` naming ``what``
    (e.g. ``"scenario name"``) and the reason."""
    problem = name_problem(name)
    if problem is not None:
        shown = repr(name)[:60] + ("…" if len(repr(name)) > 60 else "")
        raise UnsafeNameError(f"{what} {shown} {problem}; it becomes a file or folder name")
    return name
