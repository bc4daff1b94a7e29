"""Bench suites: which scenarios, trackers, seeds and sweeps to run — a TOML file validated like a scenario.

Named suites live in ``scenarios/suites/<name>.toml``. A suite's scenarios are catalog names or ``.toml``
paths relative to the suite file. Example::

    name = "mine"
    scenarios = ["highway_surround6", "my_scenario.toml"]
    seeds = [0, 1, 2]
    frames = 100                      # optional: every scenario's own frame count when omitted
    frame_time_limit_s = 60           # optional: a step() running longer is stopped, recorded as a failure

    [[trackers]]
    tracker = "saga"                  # registered name ("module:attribute" only with --trust-file)
    [[trackers]]
    label = "hungarian+dedup"         # shown in tables and plots; the tracker spec by default
    tracker = "global_hungarian"
    params = { duplicate_iou = 0.3 }
    [[trackers]]
    tracker = "sort"
    camera = "left"                   # scored on that camera only, in 2D
    rigs = ["stereo"]                 # runs only on scenarios with these rig presets

    [[sweeps]]
    parameter = "miss_probability"    # an alias (simrig.benchmark.parameters) or a dotted scenario path
    values = [0.05, 0.2, 0.35, 0.5]
    [[sweeps]]
    parameter = "rig.overlap_deg"
    values = [0, 10, 20, 30]
    scenarios = ["highway_surround6"] # default: every scenario of the suite

Each sweep varies one parameter from each scenario's own settings (one at a time, not a grid); ``base = true``
(the default) also runs every scenario as it is. Everything is checked when the suite loads: every scenario,
every tracker with its parameters, every camera, every sweep value on every scenario it applies to. An error
names the suite file and the entry.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import Field, ValidationError, model_validator

from simrig.pipeline.track import TrackingError, build_tracker
from simrig.pipeline.trust import TrackerReferenceError, check_file_reference
from simrig.scenarios import (
    Scenario,
    ScenarioError,
    describe_errors,
    load_scenario,
    suite_catalog,
)
from simrig.scenarios.base import Strict
from simrig.scenarios.files import catalog_entry_or_file, read_toml, validate_strict
from simrig.scenarios.schema import RIG_PRESETS

from ..errors import SimrigError
from ..rig import build_rig
from .parameters import ALIASES, apply_parameter, parameter_value


class SuiteError(SimrigError):
    """A suite cannot be found or is invalid; the message names the file and the entry."""


class TrackerEntry(Strict):
    """One tracker of a suite: ``tracker`` with ``params``, shown as ``label``."""

    tracker: Annotated[str, Field(min_length=1)]
    label: Annotated[str, Field(min_length=1)] | None = None
    params: dict[str, Any] = Field(default_factory=dict)
    camera: Annotated[str, Field(min_length=1)] | None = None
    """Score only this camera, in 2D (for per-camera trackers); every camera and 3D when omitted."""
    rigs: tuple[str, ...] = ()
    """Rig presets it runs on; every scenario when empty."""

    @property
    def name(self) -> str:
        """The label, or the tracker spec with its parameters."""
        if self.label:
            return self.label
        return self.tracker + "".join(f":{key}={value}" for key, value in sorted(self.params.items()))

    @model_validator(mode="after")
    def _check(self) -> TrackerEntry:
        unknown = sorted(set(self.rigs) - set(RIG_PRESETS))
        if unknown:
            raise ValueError(f"rigs: unknown preset {unknown[0]!r}; known: {', '.join(RIG_PRESETS)}")
        return self


MAX_SEEDS = 10_000
"""The most seeds a suite may list."""


class Sweep(Strict):
    """One parameter varied over ``values``, from each scenario's own settings."""

    parameter: Annotated[str, Field(min_length=1)]
    values: Annotated[tuple[Annotated[float, Field(allow_inf_nan=False)], ...], Field(min_length=1, max_length=1000)]
    scenarios: tuple[str, ...] = ()
    """The suite's scenarios it applies to; all when empty."""

    @model_validator(mode="after")
    def _check(self) -> Sweep:
        if len(set(self.values)) != len(self.values):
            raise ValueError(f"values: listed twice in {list(self.values)}")
        return self


class Suite(Strict):
    """A validated suite."""

    name: Annotated[str, Field(pattern=r"^[A-Za-z0-9_][A-Za-z0-9_.-]*$", max_length=100)]
    """Names the default bench folder ``runs/bench/NAME``: letters, digits, ``_.-``, no folder part."""
    description: str = ""
    scenarios: Annotated[tuple[str, ...], Field(min_length=1)]
    seeds: Annotated[tuple[Annotated[int, Field(ge=0, lt=2**63)], ...], Field(min_length=1, max_length=MAX_SEEDS)]
    """At most :data:`MAX_SEEDS`; the plan's cells are bounded too (:data:`simrig.benchmark.plan.MAX_CELLS`)."""
    frames: Annotated[int, Field(ge=1, le=1_000_000)] | None = None
    """[-] frames of every cell; each scenario's own when omitted."""
    frame_time_limit_s: Annotated[float, Field(ge=0, le=86_400, allow_inf_nan=False)] = 60.0
    """[s] a tracker call (one ``step()``) that runs longer is stopped and that tracker's rows of the cell record
    the timeout (``failure``) instead of metrics; 0: no limit."""
    closed_loop: bool = False
    """Each tracker drives every cell closed loop (``simrig drive``): its scores are those of its tracks on the world
    it drove, and the results gain the drive outcome columns (``drive_*``) against the cell's ground-truth drive."""
    scores_on: Literal["drive", "reference"] = "drive"
    """A closed-loop suite's metric columns score the tracker's tracks on ``drive``, the world it drove itself, or
    on ``reference``, the world of the cell's ground-truth drive (the log an open-loop benchmark would score on),
    where the tracker also runs open loop: the open-loop score and the closed-loop outcome of one tracker side by
    side (the ``metric_validity`` suite)."""
    base: bool = True
    """Also run each scenario with its own settings (besides the sweeps)."""
    trackers: Annotated[tuple[TrackerEntry, ...], Field(min_length=1)]
    sweeps: tuple[Sweep, ...] = ()

    @model_validator(mode="after")
    def _check(self) -> Suite:
        for key, items in (("seeds", self.seeds), ("scenarios", self.scenarios),
                           ("trackers", [entry.name for entry in self.trackers]),
                           ("sweeps", [sweep.parameter for sweep in self.sweeps])):
            repeated = sorted({item for item in items if list(items).count(item) > 1}, key=str)
            if repeated:
                raise ValueError(f"{key}: {repeated[0]!r} is listed twice (tracker labels must be unique)")
        for index, sweep in enumerate(self.sweeps):
            foreign = sorted(set(sweep.scenarios) - set(self.scenarios))
            if foreign:
                raise ValueError(f"sweeps.{index}.scenarios: {foreign[0]!r} is not one of the suite's scenarios")
        if self.closed_loop:
            for index, entry in enumerate(self.trackers):
                if entry.camera is not None:
                    raise ValueError(f"trackers.{index}.camera: a closed-loop suite drives on 3D tracks over every "
                                     "camera; a tracker scored on one camera cannot drive")
        if self.scores_on != "drive" and not self.closed_loop:
            raise ValueError("scores_on: only a closed-loop suite (closed_loop = true) has a drive to score on")
        if not self.base and not self.sweeps:
            raise ValueError("base: with base = false the suite needs at least one sweep")
        return self

    def sweep_scenarios(self, sweep: Sweep) -> tuple[str, ...]:
        """The scenario references a sweep applies to."""
        return sweep.scenarios or self.scenarios


def _path(name_or_path: str | Path) -> Path:
    return catalog_entry_or_file(name_or_path, suite_catalog(), "suite", SuiteError)


def load_suite(name_or_path: str | Path, *, trust_file: bool = False) -> tuple[Suite, dict[str, Scenario]]:
    """The validated suite and its scenarios by reference (as written in the suite), every check done.

    A tracker given as ``module:attribute`` is refused unless ``trust_file`` (``--trust-file``): a suite file
    is data and imports nothing on its own (:mod:`simrig.pipeline.trust`)."""
    path = _path(name_or_path)
    raw = read_toml(path, "suite file", SuiteError)
    raw.setdefault("name", path.stem)
    try:
        suite = validate_strict(Suite, raw)
    except ValidationError as error:
        raise SuiteError(f"suite file {str(path)!r}: {describe_errors(error)}") from None
    except ValueError as error:
        raise SuiteError(f"suite file {str(path)!r}: {error}") from None
    where = f"suite file {str(path)!r}"
    scenarios = {}
    for index, reference in enumerate(suite.scenarios):
        target = reference if Path(reference).suffix != ".toml" else path.parent / reference
        try:
            scenarios[reference] = load_scenario(target)
        except ScenarioError as error:
            raise SuiteError(f"{where}: scenarios.{index}: {error}") from None
    _check_trackers(suite, scenarios, where, trust_file)
    _check_sweeps(suite, scenarios, where)
    return suite, scenarios


def tracker_runs_on(entry: TrackerEntry, scenario: Scenario) -> bool:
    """Whether the suite runs ``entry`` on ``scenario`` (its ``rigs`` filter)."""
    return not entry.rigs or scenario.rig.preset in entry.rigs


def _check_trackers(suite: Suite, scenarios: dict[str, Scenario], where: str, trust_file: bool) -> None:
    for index, entry in enumerate(suite.trackers):
        try:
            check_file_reference(entry.tracker, trusted=trust_file, where=f"{where}: trackers.{index}",
                                 override=None)
        except TrackerReferenceError as error:
            raise SuiteError(str(error)) from None
        try:
            build_tracker(entry.tracker, dict(entry.params))
        except TrackingError as error:
            raise SuiteError(f"{where}: trackers.{index} ({entry.name}): {error}") from None
        targets = [s for s in scenarios.values() if tracker_runs_on(entry, s)]
        if not targets:
            raise SuiteError(f"{where}: trackers.{index} ({entry.name}): rigs {list(entry.rigs)} match none of "
                             "the suite's scenarios")
        if entry.camera is not None:
            for scenario in targets:
                names = build_rig(scenario.rig).camera_names
                if entry.camera not in names:
                    raise SuiteError(f"{where}: trackers.{index} ({entry.name}): camera {entry.camera!r} is not "
                                     f"in the rig of {scenario.name} ({', '.join(names)}); limit it with rigs")


def _check_sweeps(suite: Suite, scenarios: dict[str, Scenario], where: str) -> None:
    for index, sweep in enumerate(suite.sweeps):
        if "." not in sweep.parameter and sweep.parameter not in ALIASES:
            raise SuiteError(f"{where}: sweeps.{index}.parameter: {sweep.parameter!r} is neither a dotted scenario "
                             f"path (e.g. 'rig.overlap_deg') nor an alias ({', '.join(ALIASES)})")
        for reference in suite.sweep_scenarios(sweep):
            try:
                parameter_value(scenarios[reference], sweep.parameter)
                for value in sweep.values:
                    apply_parameter(scenarios[reference], sweep.parameter, value)
            except (ScenarioError, ValueError) as error:
                raise SuiteError(f"{where}: sweeps.{index} ({sweep.parameter}) on {reference}: {error}; "
                                 "limit the sweep with scenarios = [...]") from None
