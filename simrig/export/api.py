"""The export entry point: load what the scorer loads once, hand it to a format, publish atomically."""

from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path

from simrig.dataset.tracks_file import TrackRows, TrackSet, read_tracks

from ..dataset import Dataset
from ..errors import SimrigError
from ..scoring.ground_truth import GroundTruth, load_ground_truth
from ..scoring.inputs import project_tracks


class ExportError(SimrigError):
    """An export could not be written (unknown format, output folder in the way)."""


@dataclass(frozen=True, eq=False)
class ExportInput:
    """What every format gets: the dataset, its ground truth, and the tracker's rows (``None`` without
    ``--tracks``): ``rows2d`` as the scorer compares them, ``rows3d`` when the tracker gave 3D boxes."""

    dataset: Dataset
    truth: GroundTruth
    rows2d: TrackRows | None
    rows3d: TrackRows | None
    tracker_name: str


def _formats():
    from . import kitti, motchallenge, nuscenes

    return {"motchallenge": motchallenge.write, "kitti": kitti.write, "nuscenes": nuscenes.write}


FORMATS = ("motchallenge", "kitti", "nuscenes")


def export(dataset: Dataset | Path | str, fmt: str, out: Path | str, *, tracks: Path | str | None = None,
           overwrite: bool = False) -> Path:
    """Write ``dataset`` (and ``tracks``, a tracks folder or file) in format ``fmt`` to the folder ``out``."""
    if fmt not in FORMATS:
        raise ExportError(f"--format {fmt!r}: known formats are {', '.join(FORMATS)}")
    if not isinstance(dataset, Dataset):
        dataset = Dataset.open(dataset)
    out = Path(out)
    if out.exists() and not overwrite:
        raise ExportError(f"--out {str(out)!r} already exists; pass --overwrite to replace it")
    truth = load_ground_truth(dataset)
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
    data = ExportInput(dataset, truth, rows2d, rows3d, name)
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
