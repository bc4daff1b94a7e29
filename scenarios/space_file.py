"""A space file's shared parts: where a space name or path leads, its TOML read safely, its base scenario and its
dimensions checked against it, and the values one candidate writes into the scenario.

Both a search (:mod:`simrig.search.space`, a space with an ``[objective]``) and a collection
(:mod:`simrig.collection.space`, any space) read their file through these, and raise :class:`SpaceError`.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

from simrig.errors import SimrigError
from simrig.reading import read_capped

from . import Scenario, ScenarioError, load_scenario
from .files import catalog_entry_or_file
from .overrides import get_setting, with_setting
from .search_schema import BASE_PATH, Dimension, SpaceConfig, space_catalog

Candidate = dict[str, Any]
"""Values of one evaluation or sequence by parameter name (:attr:`Dimension.names`)."""


class SpaceError(SimrigError):
    """A space file cannot be found or is invalid, or what is made from it cannot be; the message names file and
    key."""


def setting_value(dimension: Dimension, candidate: Candidate) -> Any:
    """The value a dimension writes into the scenario: ``[start, start + length − 1]`` for a window."""
    if dimension.kind == "window":
        start = int(candidate[f"{dimension.path}.start"])
        return [start, start + int(candidate[f"{dimension.path}.length"]) - 1]
    return candidate[dimension.path]


def extremes(dimension: Dimension) -> list[Candidate]:
    """Candidates at a dimension's corners (every choice), to check that each is a valid scenario."""
    if dimension.kind == "choice":
        return [{dimension.path: choice} for choice in dimension.choices]
    if dimension.kind == "range":
        return [{dimension.path: dimension.low}, {dimension.path: dimension.high}]
    start, length = dimension.names
    return [{start: s, length: n} for s in dimension.start for n in dimension.length]


def space_path(name_or_path: str | Path, what: str = "search space") -> Path:
    """The file of a catalog space name or a path (``what`` names it in the error)."""
    return catalog_entry_or_file(name_or_path, space_catalog(), what, SpaceError)


def read_space_file(path: Path) -> dict:
    """The TOML table of a space file, its ``name`` defaulting to the file's stem; a :class:`SpaceError`
    naming the file when it cannot be read."""
    where = f"search space file {str(path)!r}"
    try:
        raw = tomllib.loads(read_capped(path, "search space file", SpaceError).decode("utf-8"))
    except UnicodeDecodeError as error:
        raise SpaceError(f"{where}: not UTF-8 text ({error})") from None
    except tomllib.TOMLDecodeError as error:
        raise SpaceError(f"{where}: not valid TOML: {error}") from None
    raw.setdefault("name", path.stem)
    return raw


def base_scenario(config: SpaceConfig, base: str, path: Path, where: str) -> Scenario:
    """The scenario ``base`` (a catalog name, or a ``.toml`` file beside the space file at ``path``) with the
    space's frames and ``base_settings`` applied; a :class:`SpaceError` prefixed with ``where`` otherwise."""
    target = base if Path(base).suffix != ".toml" else path.parent / base
    try:
        base = load_scenario(target)
        if config.frames is not None:
            base = with_setting(base, "frames", config.frames)
        for key, value in config.base_settings.items():
            try:
                base = with_setting(base, key, value)
            except ScenarioError as error:
                raise ScenarioError(f"base_settings.{key}: {error}") from None
    except ScenarioError as error:
        raise SpaceError(f"{where}: base: {error}") from None
    return base


def check_dimensions(dimensions: tuple[Dimension, ...], base: Scenario, where: str) -> None:
    """Every dimension (but a choice of base) names a setting of ``base`` and each of its extreme values makes a
    valid scenario; a :class:`SpaceError` naming the dimension's index and path otherwise."""
    for index, dimension in enumerate(dimensions):
        if dimension.path == BASE_PATH:
            continue
        key = f"dimensions.{index}.path ({dimension.path})"
        try:
            current = get_setting(base, dimension.path)
        except ScenarioError as error:
            raise SpaceError(f"{where}: {key}: {error}") from None
        if dimension.kind == "window":
            if not (isinstance(current, (list, tuple)) and len(current) == 2):
                raise SpaceError(f"{where}: {key}: a start/length window needs a [first, last] setting, "
                                  f"{base.name} has {current!r} there")
            last = dimension.start[1] + dimension.length[1] - 1
            if last >= base.frames:
                raise SpaceError(f"{where}: dimensions.{index}.length: the window can end at frame {last}, past "
                                  f"the last frame {base.frames - 1} of the {base.frames}-frame scenario")
        for candidate in extremes(dimension):
            try:
                with_setting(base, dimension.path, setting_value(dimension, candidate))
            except ScenarioError as error:
                raise SpaceError(f"{where}: {key}: {error}") from None
