"""Reading a data file (scenario, suite, replay) and validating it strictly.

A data file is read as UTF-8 TOML; a file that is missing, a folder, unreadable, not UTF-8, not TOML or
nested too deeply is one error naming the file. Validation is strict, as the values came from a file: ``true``
is not an integer, ``"no"`` is not a boolean and ``1.7`` is not an integer (an integer is a number, though).
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path
from typing import TYPE_CHECKING, Any

from simrig.reading import read_capped

if TYPE_CHECKING:
    from pydantic import BaseModel


def catalog_entry_or_file(name_or_path: str | Path, entries: dict[str, Path], what: str,
                          error: type[Exception]) -> Path:
    """The catalog entry called ``name_or_path`` (a bare name), else that path if something is there; else
    ``error`` naming ``what`` (``suite``, ``search space``) and the catalog's entries.

    >>> catalog_entry_or_file("smoke", {"smoke": Path("suites/smoke.toml")}, "suite", ValueError)
    PosixPath('suites/smoke.toml')
    >>> catalog_entry_or_file("no/such/file.toml", {"smoke": Path("smoke.toml")}, "suite", ValueError)
    Traceback (most recent call last):
    ...
    ValueError: unknown suite 'no/such/file.toml': not a named suite (smoke) nor a .toml file
    """
    text = str(name_or_path)
    if text in entries and not Path(text).suffix:
        return entries[text]
    path = Path(text)
    if not path.exists():
        raise error(f"unknown {what} {text!r}: not a named {what} ({', '.join(entries)}) nor a .toml file")
    return path


def read_toml(path: Path, what: str, error: type[Exception]) -> dict[str, Any]:
    """The table of the TOML file ``path`` (``what`` names it in messages, e.g. ``scenario file``)."""
    where = f"{what} {str(path)!r}"
    try:
        data = read_capped(path, what, error)
    except FileNotFoundError:
        raise error(f"{where} does not exist") from None
    except IsADirectoryError:
        raise error(f"{where} is a folder, not a file") from None
    except OSError as problem:
        raise error(f"{where} cannot be read: {problem.strerror or problem}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as problem:
        raise error(f"{where}: not UTF-8 text (byte {problem.start}); TOML files are UTF-8") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as problem:
        raise error(f"{where}: not valid TOML: {problem}") from None
    except RecursionError:
        raise error(f"{where}: nested too deeply to be a {what}") from None


def _json_value(value: Any) -> str:
    """TOML dates and times have no JSON form: passed as text, so a field that is not text refuses them."""
    return str(value)


def validate_strict(model: type[BaseModel], raw: dict[str, Any]) -> BaseModel:
    """``model`` validated from a file's table in pydantic's strict mode (JSON rules: arrays are tuples,
    integers are numbers, nothing else is converted). Raises :class:`pydantic.ValidationError`."""
    try:
        text = json.dumps(raw, default=_json_value, allow_nan=True)
    except (RecursionError, ValueError) as problem:
        raise ValueError(f"cannot be validated: {problem}") from None
    return model.model_validate_json(text, strict=True)
