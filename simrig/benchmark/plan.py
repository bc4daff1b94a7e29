"""A suite expanded into points (rows of the results table) and cells (what is generated and tracked).

A **point** is (scenario, sweep, value, seed): the base settings or one swept value. A **cell** is the
dataset a point needs, keyed by content (:func:`~simrig.pipeline.content_keys.dataset_key`): two points with the same
resolved scenario — a sweep value equal to the scenario's own setting, say — share one cell, which is
generated and tracked once and reported under both.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

from simrig.pipeline.content_keys import dataset_key, world_key
from simrig.scenarios import Scenario
from simrig.trackers.registry import registered_here

from .parameters import apply_parameter, parameter_value
from .suite import Suite, SuiteError, TrackerEntry, tracker_runs_on

BASE = ""
MAX_CELLS = 100_000
"""The most datasets (cells) one bench may plan: more is refused before anything runs."""
FRAME_SECONDS = 0.05
"""[s] rough cost of one frame of one cell on one worker, generation and every tracker of a 12-tracker suite
included (the standard suite on a 2-core machine); only for the warning a long plan gets before it starts."""
"""The ``sweep`` of a point that runs a scenario with its own settings."""


@dataclass(frozen=True)
class Point:
    """One row group of the results: ``sweep`` is the swept parameter (:data:`BASE` for none), ``value`` its
    value (None for the base), ``settings`` the cell's value of every parameter the suite sweeps (None where
    the parameter does not apply to the scenario)."""

    scenario: str
    rig: str
    sweep: str
    value: float | None
    seed: int
    frames: int
    cell: str
    settings: tuple[tuple[str, float | None], ...]


@dataclass(frozen=True)
class Job:
    """One cell to generate (or find in ``cache``) and the trackers still to run on it (key, entry)."""

    cell: str
    scenario: Scenario
    seed: int
    frames: int
    cache: Path
    trackers: tuple[tuple[str, TrackerEntry], ...]
    frame_time_limit_s: float = 60.0
    """[s] limit on one tracker call (the suite's ``frame_time_limit_s``; 0: none)."""
    registered: tuple[tuple[str, str], ...] = ()
    """(name, ``module:qualname``) of trackers registered with ``simrig.register`` in the driver's process, which
    a worker registers again before it runs them (:func:`simrig.trackers.registry.register_again`)."""
    closed_loop: bool = False
    """Each tracker drives the cell closed loop (the suite's ``closed_loop``)."""
    scores_on: str = "drive"
    """Closed loop: score the tracks on the tracker's own drive or on the ground-truth drive (the suite's
    ``scores_on``)."""


def tracker_key(entry: TrackerEntry, suite: Suite | None = None) -> str:
    """Content key of a tracker entry: its spec, parameters and scored camera (not its label), and for a
    closed-loop ``suite`` what its rows are (a drive, scored on which world), so that a bench resumed with those
    settings changed runs its cells again."""
    identity = {"tracker": entry.tracker, "params": entry.params, "camera": entry.camera}
    if suite is not None and suite.closed_loop:
        identity["closed_loop"] = suite.scores_on
    return hashlib.sha256(json.dumps(identity, sort_keys=True, default=str).encode()).hexdigest()[:16]


@dataclass(frozen=True)
class Plan:
    """Every point of a suite, and the cells behind them with the trackers each runs."""

    suite: Suite
    points: tuple[Point, ...]
    cells: dict[str, tuple[Scenario, int, int]]
    """cell key → (resolved scenario, seed, frames)."""
    parameters: tuple[str, ...]

    def trackers_of(self, scenario: Scenario) -> tuple[TrackerEntry, ...]:
        return tuple(entry for entry in self.suite.trackers if tracker_runs_on(entry, scenario))

    def work(self) -> dict[str, tuple[tuple[str, TrackerEntry], ...]]:
        """cell key → the (tracker key, entry) pairs to run on it, in suite order."""
        return {key: tuple((tracker_key(entry, self.suite), entry) for entry in self.trackers_of(scenario))
                for key, (scenario, _, _) in self.cells.items()}

    def jobs(self, finished: set[tuple[str, str]], cache: Path) -> list[Job]:
        """The cells with trackers not yet in ``finished`` (a set of (cell, tracker key)): the first cell of
        each world (:func:`~simrig.pipeline.content_keys.world_key`) in plan order, then the cells that share a world
        with an earlier one (detector sweeps), so that by the time those start their world is likely in the
        cache and only the sensor model runs. Results are written in plan order whatever the run order."""
        first, later, worlds = [], [], set()
        registered = tuple((entry.tracker, reference) for entry in self.suite.trackers
                           if (reference := registered_here(entry.tracker)) is not None)
        for key, pairs in self.work().items():
            pending = tuple(pair for pair in pairs if (key, pair[0]) not in finished)
            scenario, seed, frames = self.cells[key]
            world = world_key(scenario, seed, frames)
            if pending:
                (later if world in worlds else first).append(Job(key, scenario, seed, frames, cache, pending,
                                                                    self.suite.frame_time_limit_s, registered,
                                                                    self.suite.closed_loop, self.suite.scores_on))
            worlds.add(world)
        return first + later


def make_plan(suite: Suite, scenarios: dict[str, Scenario]) -> Plan:
    """Points in suite order: per scenario, per seed, the base and then each sweep's values."""
    parameters = tuple(sweep.parameter for sweep in suite.sweeps)
    points, cells = [], {}
    for reference, scenario in scenarios.items():
        variants: list[tuple[str, float | None, Scenario]] = [(BASE, None, scenario)] if suite.base else []
        for sweep in suite.sweeps:
            if reference in suite.sweep_scenarios(sweep):
                variants += [(sweep.parameter, float(value), apply_parameter(scenario, sweep.parameter, value))
                             for value in sweep.values]
        for seed in suite.seeds:
            for sweep_name, value, variant in variants:
                frames = suite.frames or variant.frames
                key = dataset_key(variant, seed, frames)
                cells.setdefault(key, (variant, seed, frames))
                if len(cells) > MAX_CELLS:
                    raise SuiteError(f"suite {suite.name!r}: more than {MAX_CELLS:,} cells (scenarios × sweep values × "
                                     "seeds); split it into several suites")
                settings = tuple((sweep.parameter, parameter_value(variant, sweep.parameter)
                                  if reference in suite.sweep_scenarios(sweep) else None) for sweep in suite.sweeps)
                points.append(Point(scenario.name, scenario.rig.preset, sweep_name, value, seed, frames, key,
                                    settings))
    return Plan(suite, tuple(points), cells, parameters)
