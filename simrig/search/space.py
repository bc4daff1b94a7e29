"""A search space loaded and checked against everything it names: the base scenario, every dimension's
setting path and extreme values, the tracker and its parameters, the scorer's metrics.

A data file never makes simrig import code: a ``module:attribute`` tracker in a space file is refused unless the
caller trusts the file (``trust_file=True``, ``--trust-file``; as bench suites and replay files); a tracker the
user types (``--tracker``, the ``tracker`` argument) is the user's own choice.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from pydantic import ValidationError

from simrig.benchmark.evaluate import METRIC_COLUMNS
from simrig.pipeline.track import TrackingError, build_tracker
from simrig.pipeline.trust import TrackerReferenceError, check_file_reference
from simrig.scenarios import Scenario, describe_errors, dimension_labels
from simrig.scenarios.overrides import with_setting
from simrig.scenarios.search_schema import BASE_PATH, SearchSpaceConfig
from simrig.scenarios.space_file import (
    Candidate,
    SpaceError,
    base_scenario,
    check_dimensions,
    read_space_file,
    setting_value,
    space_path,
)
from simrig.scoring.drive_outcome import DRIVE_COLUMNS

SearchError = SpaceError
"""A search space cannot be found or is invalid, or a search cannot run (the space file's error: a collection reads
the same files); the message names file and key."""


@dataclass(frozen=True)
class SearchSpace:
    """A checked search space: its settings, its file, and its base scenario (frames and ``base_settings``
    applied)."""

    config: SearchSpaceConfig
    path: Path
    base: Scenario

    @property
    def tracker(self) -> str:
        return self.config.tracker

    @property
    def params(self) -> dict:
        return dict(self.config.params)

    def scenario_for(self, candidate: Candidate) -> Scenario:
        """The base scenario with every dimension set to its value in ``candidate``."""
        scenario = self.base
        for dimension in self.config.dimensions:
            scenario = with_setting(scenario, dimension.path, setting_value(dimension, candidate))
        return scenario


def load_space(name_or_path: str | Path, *, tracker: str | None = None, params: dict | None = None,
               budget: int | None = None, trust_file: bool = False) -> SearchSpace:
    """The checked search space of a catalog name or a file; ``tracker``/``params``/``budget`` replace the
    file's. A :class:`SearchError` naming the file and the key otherwise."""
    path = space_path(name_or_path)
    where = f"search space file {str(path)!r}"
    raw = read_space_file(path)
    if "objective" not in raw:
        raise SearchError(f"{where}: no [objective]: a space for simrig generate --space, which samples it; a search "
                          "needs [objective] metric = ..., direction = ...")
    file_tracker = raw.get("tracker")
    if tracker is not None:
        raw["tracker"] = tracker
        raw["params"] = {}
    if params is not None:
        raw["params"] = dict(params)
    if budget is not None:
        raw["budget"] = budget
    try:
        config = SearchSpaceConfig.model_validate(raw)
    except ValidationError as error:
        raise SearchError(f"{where}: {describe_errors(error, dimension_labels(raw))}") from None
    if tracker is None:  # the space file's own tracker: data, so no module:attribute unless trusted
        try:
            check_file_reference(file_tracker, trusted=trust_file, where=where)
        except TrackerReferenceError as error:
            raise SearchError(str(error)) from None
    _check_searchable(config, where)
    base = base_scenario(config, config.base, path, where)
    check_dimensions(config.dimensions, base, where)
    _check_objective(config, where)
    try:
        build_tracker(config.tracker, dict(config.params))
    except TrackingError as error:
        raise SearchError(f"{where}: tracker: {error}") from None
    return SearchSpace(config, path, base)


def _check_searchable(config: SearchSpaceConfig, where: str) -> None:
    """What only ``simrig generate --space`` samples: a weighted choice, a choice of base, non-scalar choices."""
    for index, dimension in enumerate(config.dimensions):
        if dimension.path == BASE_PATH:
            raise SearchError(f"{where}: dimensions.{index}.path: a search varies one base scenario; choosing the "
                              "base ('base') is for simrig generate --space")
        if dimension.weights is not None:
            raise SearchError(f"{where}: dimensions.{index}.weights: a search explores choices evenly; weights are "
                              "for simrig generate --space")
        if dimension.kind == "choice":
            bad = [c for c in dimension.choices if not isinstance(c, (bool, int, float, str))]
            if bad:
                raise SearchError(f"{where}: dimensions.{index}.choices: {bad[0]!r} is not a number, string "
                                  "or boolean")


def _check_objective(config: SearchSpaceConfig, where: str) -> None:
    named = [("objective.metric", config.objective.metric)]
    if config.objective.failure is not None and config.objective.failure.metric is not None:
        named.append(("objective.failure.metric", config.objective.failure.metric))
    for key, metric in named:
        if metric in DRIVE_COLUMNS:
            raise SearchError(f"{where}: {key}: {metric!r} is a closed-loop outcome, and a search scores open loop; "
                              "use an open-loop planner-aware score (3d_PKL, 3d_HZ_MISS, ...) or a bench with "
                              "closed_loop = true")
        if metric not in METRIC_COLUMNS:
            raise SearchError(f"{where}: {key}: {metric!r} is not a metric the scorer reports; known: "
                              f"{', '.join(m for m in METRIC_COLUMNS if m not in DRIVE_COLUMNS)}")
