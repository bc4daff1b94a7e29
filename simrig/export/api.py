"""The export entry point: load what the scorer loads once, hand it to a format, publish atomically.

Every export folder holds ``simrig-export.json`` (the format and the dataset's scenario and seed); ``--overwrite``
replaces only a folder that holds it, so it can never delete a dataset or a folder of the user's files. The
output is checked before any work (:func:`simrig.dataset.outputs.check_output_path`): not inside or around the
dataset or the tracks, not in a system folder, not under a file. The partial folder is named per process.
"""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from simrig.dataset.tracks_file import TrackRows, TrackSet, read_tracks
from simrig.scenarios.evaluation_schema import EvaluationConfig

from ..dataset import Dataset
from ..dataset.evaluation import evaluation_of, ignore_rules
from ..dataset.ground_truth import GroundTruth, project_tracks
from ..dataset.manifest import write_json_atomic
from ..dataset.outputs import check_output_path, partial_sibling, remove_stale_partials
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
MARKER = "simrig-export.json"
"""The file that marks a folder as written by ``simrig export`` (the only kind ``--overwrite`` replaces)."""


def export(dataset: Dataset | Path | str, fmt: str, out: Path | str, *, tracks: Path | str | None = None,
           overwrite: bool = False, evaluation: dict | None = None) -> Path:
    """Write ``dataset`` (and ``tracks``, a tracks folder or file) in format ``fmt`` to the folder ``out``;
    ``evaluation``: keys on top of the dataset scenario's ``[evaluation]`` table, as ``simrig score`` takes
    them (the ground truth it ignores is written as each format's distractors)."""
    if fmt not in FORMATS:
        raise ExportError(f"--format {fmt!r}: known formats are {', '.join(FORMATS)}")
    if not isinstance(dataset, Dataset):
        dataset = Dataset.open(dataset)
    if fmt == "nuscenes" and not dataset.has_3d:
        raise ExportError(f"--format nuscenes: dataset {str(dataset.path)!r} holds 2D ground truth only (imported "
                          "without a rig); export it as motchallenge or kitti")
    if fmt != "nuscenes" and not dataset.has_2d:
        raise ExportError(f"--format {fmt}: dataset {str(dataset.path)!r} has no cameras (imported 3D ground truth "
                          "only); export it as nuscenes")
    out = check_output_path(out, what="--out", inputs=(dataset.path, tracks))
    if out.exists():
        if not overwrite:
            raise ExportError(f"--out {str(out)!r} already exists; pass --overwrite to replace it")
        if not (out / MARKER).is_file():
            raise ExportError(f"--out {str(out)!r} was not written by simrig export (it has no {MARKER}); "
                              "--overwrite replaces only an earlier export: choose another folder")
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
    out.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_partials(out)
    partial = partial_sibling(out)
    partial.mkdir()
    try:
        _formats()[fmt](data, partial)
        scenario = dataset.scenario
        write_json_atomic(partial / MARKER, {"written_by": "simrig export", "format": fmt,
                                             "scenario": scenario["name"], "seed": dataset.seed,
                                             "tracker": name if tracks is not None else None})
    except BaseException:
        shutil.rmtree(partial, ignore_errors=True)
        raise
    old = None
    if out.exists():
        old = out.parent / f".{out.name}.old-{os.getpid()}"
        os.replace(out, old)
    os.replace(partial, out)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
    return out
