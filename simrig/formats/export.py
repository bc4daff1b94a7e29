"""The export entry point: load what the scorer loads once, hand it to a format, publish atomically.

Every export folder holds ``simrig-export.json`` (the format, the dataset's scenario and seed, and every file the
export wrote); ``--overwrite`` replaces only a folder whose marker is a complete, valid one, and deletes only the
files it lists: a file a user added to the export is moved into the new one. The
output is checked before any work (:func:`simrig.dataset.outputs.check_output_path`): not inside or around the
dataset or the tracks, not in a system folder, not under a file. The partial folder is named per process.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from simrig.dataset import Dataset
from simrig.dataset.ground_truth import relative_to_true_ego
from simrig.dataset.manifest import write_json_atomic
from simrig.dataset.outputs import (
    PARTIAL_MARKER,
    check_output_path,
    make_partial,
    partial_sibling,
    publish,
    remove_stale_partials,
)
from simrig.dataset.tracks_file import TrackSet, read_tracks
from simrig.formats import OUTSIDE_FORMATS
from simrig.formats.evaluation import evaluation_of, ignore_rules, projected_in_range
from simrig.formats.export_input import ExportError, ExportInput
from simrig.formats.kitti import writer as kitti_writer
from simrig.formats.motchallenge import writer as motchallenge_writer
from simrig.formats.nuscenes import writer as nuscenes_writer
from simrig.reading import read_capped


def _formats():
    return {"motchallenge": motchallenge_writer.write, "kitti": kitti_writer.write, "nuscenes": nuscenes_writer.write}


FORMATS = OUTSIDE_FORMATS
WRITTEN_BY = "simrig export"
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
        written = _written_files(out)
    truth = dataset.ground_truth
    config = evaluation_of(dataset.scenario, evaluation)
    ignored = ignore_rules(truth, config)
    rows2d = rows3d = None
    name = "tracker"
    if tracks is not None:
        track_set: TrackSet = read_tracks(tracks, frame_count=len(truth.frames), cameras=truth.rig.camera_names)
        rows3d = track_set.tracks3d
        if rows3d is not None:  # with an ego-pose error: from the pose the tracker was given to the true one, as
            rows3d = relative_to_true_ego(truth, rows3d)  # simrig score does, so a peer scores what it scores
        if track_set.tracks2d is not None and len(track_set.tracks2d):
            rows2d = track_set.tracks2d
        elif rows3d is not None:
            rows2d = projected_in_range(truth, rows3d, config)
        name = Path(tracks).stem if Path(tracks).is_file() else Path(tracks).name
    data = ExportInput(dataset, truth, config, ignored, rows2d, rows3d, name)
    out.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_partials(out)
    partial = partial_sibling(out)
    make_partial(partial)
    try:
        _formats()[fmt](data, partial)
        files = sorted(path.relative_to(partial).as_posix() for path in partial.rglob("*")
                       if path.is_file() and path.name != PARTIAL_MARKER)
        scenario = dataset.scenario
        write_json_atomic(partial / MARKER, {"written_by": WRITTEN_BY, "format": fmt,
                                             "scenario": scenario["name"], "seed": dataset.seed,
                                             "tracker": name if tracks is not None else None, "files": files})
    except BaseException:
        shutil.rmtree(partial, ignore_errors=True)
        raise
    if out.exists():
        written = _written_files(out)  # it may have changed since we started
    publish(partial, out, lambda relative: relative.as_posix() in written)
    return out


def _written_files(out: Path) -> set[str]:
    """The files an earlier export in ``out`` wrote (its marker among them), from its marker; an
    :class:`ExportError` when ``out`` holds no complete, valid marker (then it is not ours to replace)."""
    refuse = (f"--out {str(out)!r} was not written by simrig export (it has no complete {MARKER}); --overwrite "
              "replaces only an earlier export: choose another folder")
    try:
        marker = json.loads(read_capped(out / MARKER, MARKER, ExportError))
    except (OSError, ValueError):
        raise ExportError(refuse) from None
    files = marker.get("files") if isinstance(marker, dict) else None
    if (not isinstance(marker, dict) or marker.get("written_by") != WRITTEN_BY or marker.get("format") not in FORMATS
            or not isinstance(files, list) or not all(isinstance(f, str) and f and ".." not in f.split("/")
                                                      for f in files)):
        raise ExportError(refuse)
    return {*files, MARKER}
