"""``run_tracker(tracker, scenario)``: one call from a scenario to scores, for property tests.

Datasets are generated once per (scenario, seed, frames) and process into a temporary folder, so a property
that runs several trackers on one drawn scenario pays for the generation once. Every run is recorded
(:func:`recorded_runs`) so that the pytest plugin can write the last one of a failing test as a replay file.
"""

from __future__ import annotations

import atexit
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from simrig.pipeline.cache import cached_dataset
from simrig.pipeline.content_keys import dataset_key
from simrig.pipeline.track import run_tracker as run_on_dataset
from simrig.pipeline.track import tracker_reference
from simrig.scenarios.schema import Scenario

from ..dataset import Dataset
from ..scoring import ScoreReport, score

Scores = ScoreReport
"""What :func:`run_tracker` returns: the full score report (``.metrics3d``, ``.metrics2d``, ``.errors``)."""


@dataclass
class Run:
    """One recorded run: the scenario, seed, tracker spec (a registered name or ``module:attribute``, ``None``
    for an object that has no importable name), its parameters and its scores."""

    scenario: Scenario
    seed: int
    tracker: str | None
    params: dict = field(default_factory=dict)
    scores: ScoreReport | None = None


_RUNS: list[Run] = []
_CACHE: dict[str, Dataset] = {}
_ROOT: Path | None = None


def recorded_runs() -> list[Run]:
    """Every run since the last :func:`clear_runs` (the plugin clears them before each test)."""
    return _RUNS


def clear_runs() -> None:
    _RUNS.clear()


def _root() -> Path:
    global _ROOT
    if _ROOT is None:
        _ROOT = Path(tempfile.mkdtemp(prefix="simrig-testing-"))
        atexit.register(shutil.rmtree, _ROOT, True)
    return _ROOT


def dataset_for(scenario: Scenario, seed: int = 0, frames: int | None = None) -> Dataset:
    """The dataset of ``scenario`` and ``seed``, generated on first use in this process."""
    key = dataset_key(scenario, seed, frames)
    if key not in _CACHE:
        _CACHE[key] = cached_dataset(scenario, seed, frames, _root())
    return _CACHE[key]


def run_tracker(tracker, scenario: Scenario, *, seed: int = 0, params: dict | None = None,
                frames: int | None = None, camera: str | None = None) -> ScoreReport:
    """Generate ``scenario`` with ``seed`` (cached), run ``tracker`` — a registered name, ``module:attribute``,
    a factory or class (called with ``params``), or a tracker object — over it and return the scores
    (``camera``: one camera only, as ``simrig score --camera``)."""
    dataset = dataset_for(scenario, seed, frames)
    spec = tracker_reference(tracker)
    run = Run(scenario, seed, spec, dict(params or {}))
    _RUNS.append(run)
    outcome = run_on_dataset(dataset, tracker, None, params)
    run.scores = score(dataset, outcome.tracks, camera=camera)
    return run.scores
