"""The export entry point: load what the scorer loads once, hand it to a format, publish atomically."""

from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from simrig.dataset.tracks_file import TrackRows, TrackSet, read_tracks
from simrig.scenarios.evaluation_schema import EvaluationConfig

from ..dataset import Dataset
from ..dataset.evaluation import evaluation_of, ignore_rules
from ..dataset.ground_truth import GroundTruth, project_tracks
from ..errors import SimrigError


class ExportError(SimrigError):
    """An export could not be written (unknown format, output folder in the way)."""


@dataclass(frozen=True, eq=False)
class ExportInput:
    """What every format gets: the dataset, its ground truth, the :class:`~simrig.dataset.evaluation.IgnoreRule`
    bits of every box ``(R, C)`` (what ``simrig score`` ignores with the same settings), and the tracker's rows
    (``None`` without ``--tracks``): ``rows2d`` as the scorer compares them, ``rows3d`` when the tracker gave 3D
    boxes."""

    dataset: Dataset
    truth: GroundTruth
    evaluation: EvaluationConfig
    ignored: np.ndarray
    rows2d: TrackRows | None
    rows3d: TrackRows | None
    tracker_name: str


def _formats():
    from . import kitti, motchallenge, nuscenes

    return {"motchallenge": motchallenge.write, "kitti": kitti.write, "nuscenes": nuscenes.write}


FORMATS = ("motchallenge", "kitti", "nuscenes")


def export(dataset: Dataset | Path | str, fmt: str, out: Path | str, *, tracks: Path | str | None = None,
           overwrite: bool = False, evaluation: dict | None = None) -> Path:
    """Write ``dataset`` (and ``tracks``, a tracks folder or file) in format ``fmt`` to the folder ``out``;
    ``evaluation``: keys on top of the dataset scenario's ``[evaluation]`` table, as ``simrig score`` takes
    them (the ground truth it ignores is written as each format's distractors)."""
    if fmt not in FORMATS:
        raise ExportError(f"--format {fmt!r}: known formats are {', '.join(FORMATS)}")
    if not isinstance(dataset, Dataset):
        dataset = Dataset.open(dataset)
    out = Path(out)
    if out.exists() and not overwrite:
        raise ExportError(f"--out {str(out)!r} already exists; pass --overwrite to replace it")
    truth = dataset.ground_truth
    config = evaluation_of(dataset.scenario, evaluation)
    ignored = ignore_rules(truth, config)
    rows2d = rows3d = None
    name = "tracker"
    if tracks is not None:
        track_set: TrackSet = read_tracks(tracks, frame_count=len(truth.frames), cameras=truth.rig.camera_names)
        rows3d = track_set.tracks3d
        if track_set.tracks2d is not None and len(track_set.tracks2d):
            rows2d = track_set.tracks2d
        elif rows3d is not None:
            rows2d = project_tracks(truth, rows3d)
        name = Path(tracks).stem if Path(tracks).is_file() else Path(tracks).name
    data = ExportInput(dataset, truth, config, ignored, rows2d, rows3d, name)
    partial = out.with_name(f".{out.name}.partial")
    shutil.rmtree(partial, ignore_errors=True)
    partial.mkdir(parents=True)
    try:
        _formats()[fmt](data, partial)
    except BaseException:
        shutil.rmtree(partial, ignore_errors=True)
        raise
    if out.exists():
        shutil.rmtree(out)
    partial.rename(out)
    return out
