"""The search-space schema (``simrig search SPACE``): what an optimiser may vary, what it looks for, how long.

A search space is a TOML file, validated strictly like a scenario (an unknown key is an error). Example::

    name = "occlusion_gaps"
    base = "highway_surround6"        # catalog name, or a .toml path relative to this file
    frames = 40                       # optional: the base scenario's own frame count when omitted
    tracker = "saga"                  # a registered name; "module:attribute" only when the user allows it
    params = { max_age_s = 0.3 }      # the tracker's parameters
    budget = 30                       # [-] evaluations of the optimiser (random sampling gets as many)
    seeds = 2                         # [-] scenario seeds 0 … seeds − 1 per evaluation (mean and CI over them)

    [base_settings]                   # optional: settings of the base scenario changed before the search
    "traffic.vehicles" = 3

    [objective]
    metric = "2d_IDF1"                # a results column of the bench (simrig.benchmark.evaluate.METRIC_COLUMNS)
    direction = "minimize"
    failure = { metric = "3d_IDS", at_least = 1 }   # a failing case: the mean over seeds is past this

    [[dimensions]]                    # a range over a setting by its dotted path (ints stay ints)
    path = "perturbations.0.nearest"
    low = 1
    high = 3
    [[dimensions]]                    # a choice
    path = "perturbations.1.probability"
    choices = [0.0, 0.5, 1.0]
    [[dimensions]]                    # a frame window: [start, start + length − 1]
    path = "perturbations.0.frames"
    start = [0, 20]
    length = [1, 15]

``simrig generate --space`` reads the same file (all but the search's keys: tracker, params, objective, budget,
seeds, confirm_top, confirm_seeds) and also takes ``weights`` on a choice, choices that are tables or lists, and a
dimension with ``path = "base"`` choosing the base scenario itself (:mod:`simrig.collection`); a search refuses
those.

Checks that need the layers above (the base scenario's settings, the tracker registry, the scorer's metrics)
are made by :func:`simrig.search.space.load_space`, which every error passes through with the file's name.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field, model_validator

from . import MAX_SEQUENCES, SPACES_DIR, space_catalog  # noqa: F401  (homed in the package: --help reads them)
from .base import FiniteFloat, PathName, Strict

Number = int | FiniteFloat
BASE_PATH = "base"
"""A dimension with this path chooses the base scenario itself (``simrig generate --space`` only): its choices
are catalog names or ``.toml`` files beside the space file; ``base_settings`` apply to each."""


class Failure(Strict):
    """What counts as a failing case: the mean of ``metric`` over an evaluation's seeds is ≥ ``at_least``
    or ≤ ``at_most`` (exactly one of them)."""

    metric: Annotated[str, Field(min_length=1)] | None = None
    """The objective's metric when omitted."""
    at_least: FiniteFloat | None = None
    at_most: FiniteFloat | None = None

    @model_validator(mode="after")
    def _check(self) -> Failure:
        if (self.at_least is None) == (self.at_most is None):
            raise ValueError("at_least: give exactly one of at_least = X or at_most = X")
        return self

    def fails(self, value: float) -> bool:
        """Whether ``value`` (a mean over seeds) is past the threshold; NaN never fails."""
        if self.at_least is not None:
            return bool(value >= self.at_least)
        return bool(value <= self.at_most)


class Objective(Strict):
    """The metric the optimiser drives, its direction, and (optionally) what counts as a failing case."""

    metric: Annotated[str, Field(min_length=1)]
    direction: Literal["maximize", "minimize"]
    failure: Failure | None = None

    @property
    def failure_metric(self) -> str | None:
        if self.failure is None:
            return None
        return self.failure.metric or self.metric


class Dimension(Strict):
    """One setting the search varies: ``low``/``high`` (a range; integers when both are integers; ``log`` for
    a log-uniform float), ``choices``, or a frame window ``start``/``length`` (each an inclusive [min, max])."""

    path: Annotated[str, Field(min_length=1)]
    low: Number | None = None
    high: Number | None = None
    log: bool = False
    choices: tuple[Any, ...] | None = None
    weights: tuple[Annotated[FiniteFloat, Field(gt=0)], ...] | None = None
    """[-] the share of each choice (normalised), for ``simrig generate --space``, which samples a collection;
    a search explores choices evenly and refuses them. Evenly when omitted."""
    start: tuple[Annotated[int, Field(ge=0)], Annotated[int, Field(ge=0)]] | None = None
    length: tuple[Annotated[int, Field(ge=1)], Annotated[int, Field(ge=1)]] | None = None

    @property
    def kind(self) -> Literal["range", "choice", "window"]:
        if self.choices is not None:
            return "choice"
        return "window" if self.start is not None else "range"

    @property
    def integer(self) -> bool:
        """A range of integers (both bounds written as integers)."""
        return isinstance(self.low, int) and isinstance(self.high, int)

    @model_validator(mode="after")
    def _check(self) -> Dimension:
        given = {"range": self.low is not None or self.high is not None, "choice": self.choices is not None,
                 "window": self.start is not None or self.length is not None}
        if sum(given.values()) != 1:
            raise ValueError("low: give one of low/high (a range), choices, or start/length (a frame window)")
        if given["range"]:
            if self.low is None or self.high is None:
                raise ValueError("high: a range needs both low and high")
            if self.low > self.high or (self.low == self.high):
                raise ValueError(f"high: the range [{self.low}, {self.high}] is empty (low must be below high)")
            if self.log and self.low <= 0:
                raise ValueError(f"low: a log range needs low > 0, got {self.low}")
        elif given["choice"]:
            if not self.choices:
                raise ValueError("choices: the list is empty")
            if len({repr(choice) for choice in self.choices}) != len(self.choices):
                raise ValueError(f"choices: a value is listed twice in {list(self.choices)}")
        else:
            if self.start is None or self.length is None:
                raise ValueError("length: a frame window needs both start = [min, max] and length = [min, max]")
            for key, (low, high) in (("start", self.start), ("length", self.length)):
                if low > high:
                    raise ValueError(f"{key}: the range [{low}, {high}] is empty (min is above max)")
        if self.log and not given["range"]:
            raise ValueError("log: only a low/high range can be log-uniform")
        if self.weights is not None:
            if not given["choice"]:
                raise ValueError("weights: only a list of choices can be weighted")
            if len(self.weights) != len(self.choices):
                raise ValueError(f"weights: {len(self.weights)} weights for {len(self.choices)} choices; give one "
                                 "per choice")
        if self.path == BASE_PATH and (not given["choice"] or not all(isinstance(c, str) for c in self.choices)):
            raise ValueError("path: 'base' chooses the base scenario: give choices = [catalog names or .toml files]")
        return self

    @property
    def names(self) -> tuple[str, ...]:
        """The parameter names the optimiser sees: the path, or PATH.start and PATH.length for a window."""
        return (f"{self.path}.start", f"{self.path}.length") if self.kind == "window" else (self.path,)


class SpaceConfig(Strict):
    """What every space file holds (structure only): a base scenario, settings changed once, and the dimensions
    that vary. ``simrig generate --space`` reads these keys of any space file; a search adds its own."""

    name: PathName
    """Names the default output folder (``runs/search/NAME``, ``runs/collections/NAME``); :mod:`simrig.names`'s
    rule."""
    description: str = ""
    base: Annotated[str, Field(min_length=1)]
    frames: Annotated[int, Field(ge=1, le=1_000_000)] | None = None
    """[-] frames of every evaluated scenario; the base scenario's own when omitted."""
    base_settings: dict[str, Any] = Field(default_factory=dict)
    """Settings of the base scenario by dotted path, changed once before the search."""
    dimensions: Annotated[tuple[Dimension, ...], Field(max_length=100)]
    """At least one (checked after the dimensions themselves, so that a file whose only dimension is invalid gets
    that dimension's error alone)."""

    @model_validator(mode="after")
    def _check_names(self) -> SpaceConfig:
        if not self.dimensions:
            raise ValueError("dimensions: give at least one [[dimensions]] table")
        names = [name for dimension in self.dimensions for name in dimension.names]
        repeated = sorted({name for name in names if names.count(name) > 1})
        if repeated:
            raise ValueError(f"dimensions: {repeated[0]!r} is varied twice")
        return self


class SearchSpaceConfig(SpaceConfig):
    """A validated search space (structure only; see :func:`simrig.search.space.load_space`)."""

    tracker: Annotated[str, Field(min_length=1)] = "saga"
    params: dict[str, Any] = Field(default_factory=dict)
    objective: Objective
    budget: Annotated[int, Field(ge=1, le=100_000)] = 30
    """[-] evaluations of the optimiser; random sampling, the baseline, gets the same number."""
    seeds: Annotated[int, Field(ge=1, le=1000)] = 1
    """[-] scenario seeds 0 … seeds − 1 run per evaluation."""
    confirm_top: Annotated[int, Field(ge=0, le=1000)] = 3
    """[-] best candidates of the optimiser re-evaluated on ``confirm_seeds`` fresh seeds."""
    confirm_seeds: Annotated[int, Field(ge=1, le=1000)] = 5


SEARCH_ONLY_KEYS = tuple(key for key in SearchSpaceConfig.model_fields if key not in SpaceConfig.model_fields)
"""Keys of a space file only a search uses (the tracker, the objective, the budget, ...)."""

