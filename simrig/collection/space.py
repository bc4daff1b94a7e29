"""A space file read for ``simrig generate --space``: its base scenario (or a choice of bases), the settings
changed once, and the dimensions sampled. Any search space file is also a generation space: the keys only a search
uses (tracker, objective, budget, ...) are ignored, and :attr:`GenerationSpace.ignored` lists them.

Beyond a search, a generation space may weight its choices (``weights``), make a choice of any TOML value (a
table, a list: a whole perturbation list, say) and choose the base scenario (a dimension with ``path = "base"``).
Every dimension is checked against every base: a setting a base lacks, or an extreme value it refuses, is one
clear line naming the file, the dimension and the base.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from simrig.scenarios import Scenario, describe_errors, dimension_labels
from simrig.scenarios.overrides import with_setting
from simrig.scenarios.search_schema import BASE_PATH, SEARCH_ONLY_KEYS, Dimension, SpaceConfig
from simrig.scenarios.space_file import (
    Candidate,
    SpaceError,
    base_scenario,
    check_dimensions,
    read_space_file,
    setting_value,
    space_path,
)


@dataclass(frozen=True)
class GenerationSpace:
    """A checked generation space: its settings, its file, its base scenarios by name (frames and
    ``base_settings`` applied; one unless a dimension chooses the base) and the search-only keys it ignores."""

    config: SpaceConfig
    path: Path
    bases: dict[str, Scenario]
    ignored: tuple[str, ...] = ()

    @property
    def dimensions(self) -> tuple[Dimension, ...]:
        return self.config.dimensions

    @property
    def names(self) -> tuple[str, ...]:
        """Every sampled parameter's name, in the file's order (a window gives two)."""
        return tuple(name for dimension in self.dimensions for name in dimension.names)

    def scenario_for(self, candidate: Candidate) -> Scenario:
        """The base scenario (``candidate["base"]`` when the base is chosen) with every other dimension set to its
        value in ``candidate``, in the file's order."""
        scenario = self.bases[candidate.get(BASE_PATH, self.config.base)]
        for dimension in self.dimensions:
            if dimension.path != BASE_PATH:
                scenario = with_setting(scenario, dimension.path, setting_value(dimension, candidate))
        return scenario


def load_generation_space(name_or_path: str | Path) -> GenerationSpace:
    """The checked generation space of a catalog name or a file; a :class:`SpaceError` naming the file and the
    key otherwise, before any work."""
    path = space_path(name_or_path, "space")
    where = f"space file {str(path)!r}"
    raw = read_space_file(path)
    ignored = tuple(key for key in SEARCH_ONLY_KEYS if key in raw)
    for key in ignored:
        del raw[key]
    try:
        config = SpaceConfig.model_validate(raw)
    except ValidationError as error:
        raise SpaceError(f"{where}: {describe_errors(error, dimension_labels(raw))}") from None
    bases: dict[str, Scenario] = {}
    for name in _base_names(config):  # the file's base too: a candidate without a chosen base falls back to it
        named = where if name == config.base else f"{where}: base {name!r}"
        bases[name] = base_scenario(config, name, path, named)
        check_dimensions(config.dimensions, bases[name], named)
    return GenerationSpace(config, path, bases, ignored)


def _base_names(config: SpaceConfig) -> list[Any]:
    """The file's ``base`` and every choice of a ``base`` dimension, each once, in order."""
    names = [config.base]
    for dimension in config.dimensions:
        if dimension.path == BASE_PATH:
            names.extend(choice for choice in dimension.choices if choice not in names)
    return names
