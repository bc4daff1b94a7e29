"""One coalition of the explainer's game: the run's sensor rerun with some cause groups removed, the run's
tracker on its detections, the scores — in one call that a worker process (local pool or Ray) can run.

The counterfactual dataset is made from the run's own world (``generate(..., world_from=...)``: traffic and
visibility reused, never simulated or rendered again) into a scratch cache under the run folder, keyed by
the removed groups, so a second ``simrig explain`` of the same run reuses it.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from simrig.dataset import Dataset
from simrig.errors import DatasetError
from simrig.pipeline.generate import generate
from simrig.pipeline.guard import FRAME_TIME_LIMIT_S, TrackerFault
from simrig.pipeline.track import run_tracker
from simrig.scenarios.schema import scenario_from_record
from simrig.scoring import score
from simrig.scoring.attribution import KINDS
from simrig.scoring.planner import PLANNER_METRICS

ErrorKey = tuple[str, str, int, int, str]
"""(dimension, kind, ground-truth actor id, frame, camera — empty in 3D): how an error is matched across runs."""


@dataclass(frozen=True)
class TrackerRun:
    """One tracker to run and score on a coalition's dataset: its record (name, parameters, camera), the
    metrics (``(dimension, name)`` pairs), whether to return the error keys, and the limit [s] on one of its
    calls (the bench suite's ``frame_time_limit_s``; None or 0: none)."""

    tracker: str
    params: tuple[tuple[str, object], ...]
    camera: str | None
    metrics: tuple[tuple[str, str], ...]
    errors: bool
    frame_time_limit_s: float | None = FRAME_TIME_LIMIT_S


@dataclass(frozen=True)
class CoalitionTask:
    """What a worker needs: the run's dataset folder, the removed groups, the scratch folder, and the trackers
    to run on the counterfactual (one for ``simrig explain``; every tracker of a bench cell that needs this
    coalition for ``simrig bench --explain``, so the sensor reruns once for all of them)."""

    dataset: str
    removed: tuple[str, ...]
    scratch: str
    runs: tuple[TrackerRun, ...]


@dataclass(frozen=True)
class CoalitionResult:
    """The metric values ``(M,)`` (NaN where undefined) of one tracker and, when asked, the error keys of
    its run; ``failure``: why the tracker has no values on this coalition (it timed out, raised, or returned
    something that is not tracks — the message names tracker and frame), empty when it ran to the end."""

    removed: tuple[str, ...]
    values: np.ndarray
    errors: frozenset[ErrorKey] | None
    failure: str = ""


def _coalition_key(removed: tuple[str, ...]) -> str:
    """A short folder name for a set of removed groups (``actual`` for none).

    >>> _coalition_key(()), len(_coalition_key(("occlusion", "reid")))
    ('actual', 16)
    """
    if not removed:
        return "actual"
    return hashlib.sha256(json.dumps(sorted(removed)).encode()).hexdigest()[:16]


def _counterfactual_dataset(source: Dataset, removed: tuple[str, ...], scratch: Path) -> Dataset:
    """The dataset of ``source``'s scenario and seed with ``removed`` groups off (``source`` itself for none),
    from the scratch cache or made there now."""
    if not removed:
        return source
    out = scratch / _coalition_key(removed)
    try:
        return Dataset.open(out)
    except DatasetError:
        pass
    scenario = scenario_from_record(source.scenario, f"dataset {source.path}")
    generate(scenario, seed=source.seed, out=out, frames=source.frame_count, overwrite=out.exists(),
             world_from=source, removed=frozenset(removed))
    return Dataset.open(out)


def _metric_value(report, dimension: str, name: str) -> float:
    """One overall metric of a score report (NaN when the report has no such dimension or value)."""
    table = report.metrics3d if dimension == "3d" else report.metrics2d
    value = None if table is None else table["overall"].get(name)
    return float("nan") if value is None else float(value)


def _error_keys(errors) -> frozenset[ErrorKey]:
    """The FN/IDS/FRAG rows of an errors table as matching keys."""
    rows = errors.filter(pc.is_in(errors.column("kind"), value_set=pa.array(KINDS))).select(
        ["dimension", "kind", "actor_id", "frame", "camera"]).to_pydict()
    return frozenset(zip(rows["dimension"], rows["kind"], rows["actor_id"], rows["frame"], rows["camera"],
                         strict=True))


def evaluate_coalition(task: CoalitionTask) -> tuple[CoalitionResult, ...]:
    """Run one coalition: its counterfactual dataset once, then each of ``task.runs`` on it, in order
    (importable by name: the pool and Ray workers call it). A tracker's own fault is its result's ``failure``,
    so that one tracker failing on one counterfactual does not stop the others."""
    source = Dataset.open(task.dataset)
    dataset = _counterfactual_dataset(source, task.removed, Path(task.scratch))
    results = []
    for run in task.runs:
        try:
            tracking = run_tracker(dataset, run.tracker, None, dict(run.params),
                                   frame_time_limit_s=run.frame_time_limit_s)
        except TrackerFault as error:  # the tracker's own failure on this coalition: its caller decides
            results.append(CoalitionResult(task.removed, np.full(len(run.metrics), np.nan), None, str(error)))
            continue
        report = score(dataset, tracking.tracks, camera=run.camera,
                       planner=any(name in PLANNER_METRICS for _, name in run.metrics))
        values = np.array([_metric_value(report, dimension, name) for dimension, name in run.metrics])
        results.append(CoalitionResult(task.removed, values, _error_keys(report.errors) if run.errors else None))
    return tuple(results)
