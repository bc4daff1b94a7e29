"""What a bench worker does with one cell: find or generate its dataset, run each pending tracker, score it.

Runs in a pool process or a Ray task, so it takes and returns plain picklable values. Tracks go to a
the scorer in memory and are not kept; a cell's tracks can be made again exactly (same dataset, same seed).
"""

from __future__ import annotations

import math
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from simrig.dataset import Dataset
from simrig.pipeline.cache import cached_dataset
from simrig.pipeline.guard import TrackerFault, TrackerTimeout
from simrig.pipeline.track import run_tracker
from simrig.scoring.drive_outcome import DRIVE_COLUMNS, traffic_crashes
from simrig.scoring.planner import PLANNER_METRICS
from simrig.scoring.results import METRICS_2D, METRICS_3D
from simrig.trackers.registry import register_again

from ..errors import SimrigError, TrafficCrashError
from ..scoring import ScoreReport, score
from ..scoring.attribution import errors_by_cause
from .plan import Job

METRIC_COLUMNS = (*(f"3d_{name}" for name in (*METRICS_3D, *PLANNER_METRICS)), *(f"2d_{name}" for name in METRICS_2D),
                  *DRIVE_COLUMNS, "traffic_crashes")
"""Metric columns of the results table: ``3d_`` overall 3D metrics (nuScenes style, null for a tracker scored on
one camera, with the planner-aware scores), ``2d_`` overall 2D metrics (TrackEval style; of that one camera when the
tracker names one), and ``drive_`` the closed-loop outcomes (:data:`~simrig.scoring.drive_outcome.DRIVE_COLUMNS`; null
unless the suite drives closed loop); ``traffic_crashes``: collisions between road users other than the ego in the
world the tracker was scored on (:func:`~simrig.scoring.drive_outcome.traffic_crashes`)."""


class BenchError(SimrigError):
    """A cell could not be evaluated; the message names the cell and the tracker."""


@dataclass(frozen=True)
class Outcome:
    """One tracker on one cell: its metric values (NaN where not scored), its errors by cause as
    (dimension, cause, kind, count), the seconds it took (tracking ``step()``s, scoring), how it was scored
    (``3d``; ``2d``: a 2D tracker over every camera; or the one camera named) and its 2D metrics per camera
    (:data:`CAMERA_METRICS` and the ignored ground truth)."""

    cell: str
    tracker_key: str
    metrics: dict[str, float]
    causes: tuple[tuple[str, str, str, int], ...]
    tracking_s: float
    scoring_s: float
    scored: str = "3d"
    per_camera: dict[str, dict[str, float]] = field(default_factory=dict)
    failure: str = ""
    """Why the tracker has no metrics on this cell (a timeout); empty when it ran to the end."""


def evaluate(job: Job) -> tuple[list[Outcome], float]:
    """Every pending tracker of ``job`` on its cell, and the seconds spent finding or generating the dataset."""
    for name, reference in job.registered:  # simrig.register() calls made in the driver's process
        try:
            register_again(name, reference)
        except Exception as error:  # noqa: BLE001  (whatever importing the user's module raised)
            raise BenchError(f"tracker {name!r}, registered with simrig.register() as {reference}, cannot be "
                             f"imported in a bench worker ({type(error).__name__}: {error}): define it at the "
                             "top level of a module of its own, register it by entry point, or name it "
                             "module:attribute") from None
    with tempfile.TemporaryDirectory(prefix="simrig-reference-drive-") as work:
        return _evaluate(job, Path(work))


def _evaluate(job: Job, work: Path) -> tuple[list[Outcome], float]:
    started = time.perf_counter()
    where = f"cell {job.cell} ({job.scenario.name}, seed {job.seed}, {job.frames} frames)"
    reference = dataset = None
    try:
        if job.closed_loop:  # each tracker drives its own world; the ground-truth drive is the reference
            from simrig.pipeline.drive import closed_loop_score, reference_drive

            reference = reference_drive(job.scenario, job.seed, job.frames, work)
            if job.scores_on == "reference":
                dataset = Dataset.open(reference.dataset)
        else:
            dataset = cached_dataset(job.scenario, job.seed, job.frames, job.cache)
    except TrafficCrashError as error:  # the scenario refuses crashes and this seed's traffic crashed
        return [_failed(job.cell, key, f"traffic crash: {error}") for key, _ in job.trackers], 0.0
    except SimrigError as error:
        raise BenchError(f"{where}: {error}") from None
    dataset_s = time.perf_counter() - started
    outcomes = []
    for key, entry in job.trackers:
        try:
            drive_values: dict[str, float] = {}
            step_s = 0.0
            if reference is not None:
                driven = closed_loop_score(job.scenario, job.seed, entry.tracker, dict(entry.params), job.frames,
                                           reference.outcome, job.frame_time_limit_s, scored=dataset is None)
                report, drive_values, step_s = driven.report, driven.outcomes, driven.step_seconds
            scoring_started = time.perf_counter()
            if dataset is not None:
                run = run_tracker(dataset, entry.tracker, None, dict(entry.params), seed=job.seed,  # in memory
                                  frame_time_limit_s=job.frame_time_limit_s)
                step_s += run.step_seconds
                scoring_started = time.perf_counter()
                report = score(dataset, run.tracks, camera=entry.camera)
        except TrackerTimeout as error:  # the tracker's recorded failure on this cell; the bench goes on
            outcomes.append(_failed(job.cell, key, f"timeout: {error}"))
            continue
        except TrafficCrashError as error:  # other vehicles crashed in its drive's world, which the scenario refuses
            outcomes.append(_failed(job.cell, key, f"traffic crash: {error}"))
            continue
        except TrackerFault as error:  # a user's tracker failing: the message names it and the frame
            raise BenchError(f"{where}, tracker {entry.name}: {error}") from error
        except SimrigError as error:
            raise BenchError(f"{where}, tracker {entry.name}: {error}") from None
        except Exception as error:  # a user's tracker failing: keep its traceback as the cause
            raise BenchError(f"{where}, tracker {entry.name}: {type(error).__name__}: {error}") from error
        if dataset is not None:  # else the drive's own world, counted by closed_loop_score
            drive_values["traffic_crashes"] = float(traffic_crashes(dataset.ground_truth))
        outcomes.append(Outcome(job.cell, key, metric_values(report, drive_values), _cause_counts(report),
                                step_s, time.perf_counter() - scoring_started,
                                _scored_as(report, entry.camera), _camera_values(report)))
    return outcomes, dataset_s


def _failed(cell: str, key: str, failure: str) -> Outcome:
    """A tracker's row on a cell without metrics, saying why (``failure``)."""
    return Outcome(cell, key, dict.fromkeys(METRIC_COLUMNS, math.nan), (), math.nan, 0.0, failure=failure)


def metric_values(report: ScoreReport, drive: dict[str, float] | None = None) -> dict[str, float]:
    """The overall metrics of ``report`` (and the closed-loop outcomes ``drive``) under :data:`METRIC_COLUMNS`
    names; NaN where absent."""
    overall3d = report.metrics3d["overall"] if report.metrics3d is not None else {}
    overall2d = report.metrics2d["overall"]
    values = {f"3d_{name}": overall3d.get(name) for name in (*METRICS_3D, *PLANNER_METRICS)}
    values |= {f"2d_{name}": overall2d.get(name) for name in METRICS_2D}
    values |= {name: (drive or {}).get(name) for name in (*DRIVE_COLUMNS, "traffic_crashes")}
    return {name: math.nan if value is None else float(value) for name, value in values.items()}


def _scored_as(report: ScoreReport, camera: str | None) -> str:
    """``3d`` for a tracker scored in 3D, ``2d`` for a 2D-only tracker scored over every camera, or the one
    camera it was scored on."""
    if camera is not None:
        return camera
    return "3d" if report.metrics3d is not None else "2d"


CAMERA_METRICS = ("HOTA", "AssA", "IDF1", "MOTA", "IDSW", "Frag", "CLR_TP", "CLR_FN", "CLR_FP")
"""The 2D metrics kept per camera in the bench's ``cameras.parquet``."""


def _camera_values(report: ScoreReport) -> dict[str, dict[str, float]]:
    """Per scored camera: :data:`CAMERA_METRICS` and how many ground-truth boxes were in view and ignored."""
    ignored = report.metrics2d.get("ground_truth", {}).get("per_camera", {})
    return {camera: {**{name: float(values[name]) for name in CAMERA_METRICS},
                     "boxes": float(ignored.get(camera, {}).get("boxes", math.nan)),
                     "ignored": float(ignored.get(camera, {}).get("ignored", math.nan))}
            for camera, values in report.metrics2d["per_camera"].items()}


def _cause_counts(report: ScoreReport) -> tuple[tuple[str, str, str, int], ...]:
    """(dimension, cause, kind, count) for every non-zero count of the report's errors by cause."""
    return tuple(
        (dimension, cause, kind, int(count))
        for dimension, table in errors_by_cause(report.errors).items()
        for cause, counts in table.items()
        for kind, count in counts.items()
        if count
    )
