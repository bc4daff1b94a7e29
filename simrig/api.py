"""The front door's functions: one call per step of the chain scenario → dataset → tracks → scores.

Each wraps the module that does the work (:mod:`simrig.pipeline`, :mod:`simrig.scoring`,
:mod:`simrig.benchmark`) with keyword arguments and the records a script wants back (an open
:class:`~simrig.dataset.Dataset`, a :class:`~simrig.pipeline.track.TrackingRun`, a
:class:`~simrig.scoring.ScoreReport`). ``import simrig`` exposes them lazily, so importing simrig loads none of
the simulator, the scorer or the trackers until one is called.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from simrig.benchmark.api import BenchRun
    from simrig.dataset import Dataset
    from simrig.dataset.tracks_file import TrackSet
    from simrig.pipeline.run import PipelineResult
    from simrig.pipeline.track import TrackingRun
    from simrig.scenarios import Scenario
    from simrig.scoring import ScoreReport

__all__ = ["bench", "generate", "load_scenario", "open_dataset", "run", "score", "track"]


def load_scenario(name_or_path: str | Path) -> Scenario:
    """A validated scenario from a catalog name (``simrig scenarios`` lists them) or a TOML file; a
    :class:`~simrig.scenarios.ScenarioError` naming the file and key otherwise."""
    from simrig.scenarios import load_scenario as _load

    return _load(name_or_path)


def _scenario(scenario: str | Path | Scenario) -> Scenario:
    from simrig.scenarios import Scenario

    return scenario if isinstance(scenario, Scenario) else load_scenario(scenario)


def generate(scenario: str | Path | Scenario, *, out: Path | str, seed: int = 0, frames: int | None = None,
             overwrite: bool = False, images: bool = False, progress: bool = False) -> Dataset:
    """Run ``scenario`` (a :class:`~simrig.scenarios.Scenario`, a catalog name or a TOML file) with ``seed``
    and write its dataset into the folder ``out``; the opened dataset. ``frames`` defaults to the scenario's;
    ``images`` adds a PNG per camera and frame. Same scenario and seed give the same bytes. Refuses to replace a
    complete dataset unless ``overwrite``."""
    from simrig.dataset import Dataset
    from simrig.pipeline.generate import generate as _generate

    result = _generate(_scenario(scenario), seed=seed, out=out, frames=frames, overwrite=overwrite,
                       images=images, progress=progress)
    return Dataset.open(result.path)


def open_dataset(path: Path | str, *, verify: bool = False) -> Dataset:
    """The complete dataset in the folder ``path`` (``verify``: also check every file's SHA-256)."""
    from simrig.dataset import Dataset

    return Dataset.open(path, verify=verify)


def track(dataset: Dataset | Path | str, tracker, *, params: dict | None = None, out: Path | str | None = None,
          seed: int | None = None, frame_time_limit_s: float | None = 60.0) -> TrackingRun:
    """Run ``tracker`` over the dataset's sensor frames: a registered name (``simrig trackers``), a
    ``"module:attribute"``, a factory or class (called with ``params``) or a tracker object. The tracks stay in
    memory (``.tracks``, ready for :func:`score`); ``out`` also writes them as a tracks folder. A ``step()``
    running longer than ``frame_time_limit_s`` [s] is stopped (None: no limit)."""
    from simrig.pipeline.track import run_tracker

    return run_tracker(dataset, tracker, out, params, seed=seed, frame_time_limit_s=frame_time_limit_s)


def score(dataset: Dataset | Path | str, tracks: TrackingRun | TrackSet | Path | str, *,
          camera: str | None = None, lookback_s: float | None = None, truth=None, evaluation=None,
          fmt: str | None = None, interpolation: str = "devkit") -> ScoreReport:
    """Score ``tracks`` (what :func:`track` returned, a tracks folder or file) against ``dataset``: 3D and
    per-camera 2D metrics and every error with its causes (``camera``: that camera alone, in 2D). ``truth``,
    ``evaluation``, ``fmt`` and ``interpolation`` as in :func:`simrig.scoring.score` (ground truth already read,
    ``[evaluation]`` keys on top of the dataset's, the tracks' format, how 3D track gaps are filled).

    Loads no tracker: scoring needs only the dataset and the tracks."""
    from simrig.scoring import score as _score
    from simrig.scoring.api import LOOKBACK_S

    if not isinstance(tracks, (str, Path)) and hasattr(tracks, "tracks"):  # a TrackingRun (not imported: no tracker)
        tracks = tracks.tracks
    return _score(dataset, tracks, camera=camera, lookback_s=LOOKBACK_S if lookback_s is None else lookback_s,
                  truth=truth, evaluation=evaluation, fmt=fmt, interpolation=interpolation)


def run(scenario: str | Path | Scenario = "highway_surround6", *, seed: int = 0, tracker="saga",
        params: dict | None = None, out: Path | str | None = None, frames: int | None = None,
        overwrite: bool = False, camera: str | None = None, frame_time_limit_s: float | None = 60.0) -> PipelineResult:
    """Generate, track, score and report into ``out`` (default ``runs/SCENARIO-seedN``), as ``simrig run``: a
    matching complete dataset already in ``out/dataset`` is reused. ``tracker``: anything :func:`track` takes
    (a registered name, ``"module:attribute"``, a factory or class, a tracker object)."""
    from simrig.pipeline.run import run_pipeline

    return run_pipeline(scenario, seed=seed, tracker=tracker, params=params, out=out, frames=frames,
                        overwrite=overwrite, camera=camera, frame_time_limit_s=frame_time_limit_s)


def bench(suite: str | Path, *, engine: str = "local", workers: int | None = None, out: Path | str | None = None,
          cache: Path | str | None = None, address: str | None = None, progress: bool = False,
          trust_file: bool = False) -> BenchRun:
    """Run a suite (a named one such as ``"smoke"``, or a suite file) as ``simrig bench``: every scenario ×
    sweep value × seed, every tracker on the same detections, resumable, into ``out``. ``trust_file`` lets the
    suite file import its ``module:attribute`` trackers."""
    from simrig.benchmark import run_bench

    return run_bench(suite, engine=engine, workers=workers, out=out, cache=cache, address=address,
                     progress=progress, trust_file=trust_file)
