"""``simrig view RUN_DIR``: a run (or a dataset) logged to rerun, to scrub through frame by frame.

What is logged, on the timelines ``frame`` (the dataset's frame number) and ``time`` [s]:

``world/ground_truth``, ``world/detections``, ``world/tracks``, ``world/ego``
    3D boxes in simrig's world frame (x along the road, y left, z up [m]) — the 3D / bird's-eye view. Ground
    truth is coloured and labelled by actor id, tracks by track id (``T<id>``), each id in one stable colour for
    the whole run (:func:`simrig.figures.mosaic.identity_colour`, :func:`~simrig.figures.mosaic.track_colour`);
    detections by the actor that caused them, red for false positives.
``cameras/NAME/image`` or ``cameras/NAME/frame``
    The camera's image when the dataset has ``images/`` (generated with ``--images``), otherwise the image's
    outline (a static box 0, 0 … width, height [px]).
``cameras/NAME/ground_truth``, ``cameras/NAME/detections``, ``cameras/NAME/tracks``
    Pixel boxes in that camera: ground truth in view, detections, and the tracker's boxes (its own 2D boxes, or
    its 3D boxes projected as the scorer projects them).
``events/FN``, ``events/IDS``, ``events/FRAG``
    One text log entry per error in the run's ``errors.parquet`` (``simrig run``, or ``simrig score --errors``)
    at its frame: dimension, camera, actor, tracks and causes. Misses are logged at debug level, switches as
    warnings, fragmentations at info level.

A run folder is what ``simrig run`` writes: ``dataset/``, ``tracks/LABEL/`` and ``scores/LABEL/errors.parquet``
(one LABEL per tracker run into the folder; ``--tracker LABEL`` chooses when there are several). A plain
dataset folder is logged without tracks or events. rerun-sdk is an optional extra (``pip install
'simrig-mot[view]'``).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pyarrow.compute as pc

from simrig.dataset import Dataset
from simrig.dataset.outputs import check_output_path
from simrig.errors import SimrigError
from simrig.scoring.attribution import KINDS

from .mosaic import CLUTTER_COLOUR, identity_colour, track_colour

INSTALL_HINT = "the viewer needs rerun-sdk: pip install 'simrig-mot[view]' (or pip install rerun-sdk)"


def _has_display() -> bool:
    """Whether a viewer window can open here (on Linux: an X11 or Wayland display is set)."""
    return not sys.platform.startswith("linux") or bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


class ViewerError(SimrigError):
    """The viewer cannot run: rerun-sdk is missing, or the folder is neither a run nor a dataset."""


def _rerun():
    try:
        import rerun
    except ImportError:
        raise ViewerError(INSTALL_HINT) from None
    return rerun


def _run_parts(folder: Path, tracker: str | None = None) -> tuple[Path, Path | None, Path | None]:
    """(dataset folder, tracks folder or None, errors file or None) of a run folder or a dataset folder. A run
    folder (``simrig run``: ``dataset/``, ``tracks/LABEL/``, ``scores/LABEL/errors.parquet``) may hold several
    trackers' runs: ``tracker`` names the LABEL to show (needed only when there are several)."""
    from simrig.dataset.run_folder import DATASET_DIR, SCORES_DIR, TRACKS_DIR

    folder = Path(folder)
    if (folder / "manifest.json").exists():
        return folder, None, None
    if not (folder / DATASET_DIR).is_dir():
        raise ViewerError(f"{folder}: neither a run folder ({DATASET_DIR}/, {TRACKS_DIR}/, {SCORES_DIR}/) "
                          "nor a dataset")
    runs = folder / TRACKS_DIR
    labels = sorted(p.name for p in runs.glob("*") if p.is_dir()) if runs.is_dir() else []
    if tracker is None and len(labels) > 1:
        raise ViewerError(f"{runs}: holds several trackers' output ({', '.join(labels)}); choose one with --tracker")
    if tracker is not None and tracker not in labels:
        raise ViewerError(f"--tracker {tracker!r}: no such run in {runs} (runs: {', '.join(labels) or 'none'})")
    label = tracker if tracker is not None else (labels[0] if labels else None)
    if label is None:
        return folder / DATASET_DIR, None, None
    errors = folder / SCORES_DIR / label / "errors.parquet"
    return folder / DATASET_DIR, runs / label, errors if errors.exists() else None


def _colours(ids: np.ndarray, palette) -> np.ndarray:
    return (np.array([palette(int(i)) for i in ids]).reshape(-1, 3) * 255).astype(np.uint8)


def _boxes3d(rr, boxes: np.ndarray, colours: np.ndarray, labels: list[str]):
    """rerun 3D boxes of world boxes ``(N, ≥7)`` (x, y, z, length, width, height, yaw)."""
    half = boxes[:, 3:6] / 2.0
    yaw = boxes[:, 6]
    quaternions = np.column_stack([np.zeros(len(yaw)), np.zeros(len(yaw)), np.sin(yaw / 2), np.cos(yaw / 2)])
    return rr.Boxes3D(centers=boxes[:, :3], half_sizes=half, quaternions=quaternions, colors=colours, labels=labels)


def _boxes2d(rr, boxes: np.ndarray, colours: np.ndarray, labels: list[str]):
    return rr.Boxes2D(array=boxes.reshape(-1, 4), array_format=rr.Box2DFormat.XYXY, colors=colours, labels=labels)


def log_run(folder: Path | str, *, tracker: str | None = None, save: Path | str | None = None,
            spawn: bool = True, save_option: str = "save") -> Path | None:
    """Log the run (or dataset) at ``folder`` to rerun: to the file ``save`` (an ``.rrd``; refused, as
    ``save_option`` names it, inside the dataset or tracks it reads or in a system folder), else to a viewer
    spawned now (``spawn``). Returns ``save``."""
    rr = _rerun()
    if save is None and spawn and not _has_display():
        raise ViewerError("no display to open the rerun viewer on (DISPLAY and WAYLAND_DISPLAY are unset): pass "
                          "--save FILE.rrd and open it with 'rerun FILE.rrd' where there is one")
    dataset_path, tracks_path, errors_path = _run_parts(Path(folder), tracker)
    if save is not None:  # before any work: not inside the dataset or tracks read, not a system folder
        check_output_path(save, what=save_option, inputs=(dataset_path, tracks_path), folder=False)
        if Path(save).is_symlink():  # rerun streams into the file: it would write through the link
            raise ViewerError(f"{save_option} {str(save)!r} is a symbolic link; simrig does not write through links")
    dataset = Dataset.open(dataset_path)
    truth = dataset.ground_truth
    recording = _recording(rr, dataset, save, spawn, save_option)
    images = dataset.path / "images"
    for camera in truth.rig.cameras:
        if not images.is_dir():
            recording.log(f"cameras/{camera.name}/frame", rr.Boxes2D(array=[[0, 0, camera.width, camera.height]],
                          array_format=rr.Box2DFormat.XYXY, colors=[[128, 128, 128]], labels=[camera.name]),
                          static=True)
    rows3d = rows2d = None
    if tracks_path is not None:
        from simrig.formats.tracks import dataset_tracks

        rows3d, rows2d = dataset_tracks(dataset, tracks_path)
    det, det_owner = _detections_with_owners(dataset)
    for position, frame in enumerate(truth.frames):
        recording.set_time("frame", sequence=int(frame))
        recording.set_time("time", duration=float(truth.timestamps[position]))
        g = np.nonzero(truth.frame == frame)[0]
        d = np.nonzero(det["frame"] == frame)[0]
        _log_world(rr, recording, truth, position, g, det, det_owner[d], d, rows3d)
        _log_cameras(rr, recording, truth, frame, g, det, det_owner, d, rows2d, images)
    if errors_path is not None:
        _log_errors(rr, recording, errors_path, dict(zip(truth.frames.tolist(), truth.timestamps.tolist(),
                                                         strict=True)))
    recording.flush()
    if save is not None:
        recording.disconnect()
    return Path(save) if save is not None else None


def _recording(rr, dataset: Dataset, save: Path | str | None, spawn: bool, save_option: str):
    """A rerun recording of ``dataset``, streaming into the file ``save`` or to a viewer spawned now (``spawn``)."""
    recording = rr.RecordingStream(application_id="simrig", recording_id=f"{dataset.scenario['name']}-"
                                                                         f"seed{dataset.seed}")
    if save is not None:
        try:
            Path(save).parent.mkdir(parents=True, exist_ok=True)
            recording.save(str(save))
        except (OSError, RuntimeError) as error:  # rerun reports a file it cannot create as a RuntimeError
            raise ViewerError(f"{save_option} {str(save)!r}: cannot write the recording there ({error})") from None
    elif spawn:
        recording.spawn()
    return recording


def _detections_with_owners(dataset: Dataset) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The detections' columns the viewer draws, and each detection's actor (−1: clutter)."""
    detections = dataset.table("detections")
    sensor_truth = dataset.table("sensor_truth")
    owner_of = {(r["camera"], r["frame"], r["detection"]): r["actor_id"]
                for r in sensor_truth.filter(pc.greater_equal(pc.field("detection"), 0))
                .select(["camera", "frame", "detection", "actor_id"]).to_pylist()}
    det = {name: detections.column(name).to_numpy(zero_copy_only=False) for name in detections.column_names
           if name in ("frame", "camera", "index", "x1", "y1", "x2", "y2", "x", "y", "z", "length", "width",
                       "height", "yaw")}
    owner = np.array([owner_of.get((c, int(f), int(i)), -1) for c, f, i in
                      zip(det["camera"], det["frame"], det["index"], strict=True)], dtype=np.int64)
    return det, owner


def _detection_colours(owners: np.ndarray) -> np.ndarray:
    """``(N, 3)`` uint8 colours: an actor's identity colour, clutter's own."""
    colours = np.array([CLUTTER_COLOUR if o < 0 else identity_colour(o) for o in owners]).reshape(-1, 3)
    return (colours * 255).astype(np.uint8)


def _log_world(rr, recording, truth, position: int, g: np.ndarray, det: dict, owners: np.ndarray, d: np.ndarray,
               rows3d) -> None:
    """One frame's 3D view: the ego, the ground truth (rows ``g``), the detections (rows ``d``) and the 3D tracks."""
    ego = truth.egos[position]
    recording.log("world/ego", _boxes3d(rr, np.array([[ego.x, ego.y, ego.z + 0.75, 4.6, 1.9, 1.5, ego.yaw]]),
                                        np.array([[0, 0, 0]], dtype=np.uint8), ["ego"]))
    recording.log("world/ground_truth", _boxes3d(rr, truth.boxes[g], _colours(truth.actor_id[g], identity_colour),
                                                 [str(a) for a in truth.actor_id[g]]))
    det_boxes3d = np.column_stack([det[k][d] for k in ("x", "y", "z", "length", "width", "height", "yaw")])
    recording.log("world/detections", _boxes3d(rr, det_boxes3d, _detection_colours(owners), [""] * len(d)))
    if rows3d is not None:
        t = np.nonzero(rows3d.frame == truth.frames[position])[0]
        recording.log("world/tracks", _boxes3d(rr, rows3d.boxes[t], _colours(rows3d.track_id[t], track_colour),
                                               [f"T{i}" for i in rows3d.track_id[t]]))


def _log_cameras(rr, recording, truth, frame: int, g: np.ndarray, det: dict, det_owner: np.ndarray, d: np.ndarray,
                 rows2d, images: Path) -> None:
    """One frame in every camera: its image (when the dataset has them), ground truth, detections and 2D tracks."""
    for c, camera in enumerate(truth.rig.camera_names):
        if images.is_dir():
            recording.log(f"cameras/{camera}/image", rr.EncodedImage(path=images / camera / f"{frame:06d}.png"))
        seen = g[truth.in_view[g, c]]
        recording.log(f"cameras/{camera}/ground_truth", _boxes2d(
            rr, truth.boxes2d_in(seen, c), _colours(truth.actor_id[seen], identity_colour),
            [str(a) for a in truth.actor_id[seen]]))
        k = d[det["camera"][d] == camera]
        recording.log(f"cameras/{camera}/detections", _boxes2d(
            rr, np.column_stack([det[n][k] for n in ("x1", "y1", "x2", "y2")]), _detection_colours(det_owner[k]),
            [""] * len(k)))
        if rows2d is not None:
            t = np.nonzero((rows2d.frame == frame) & (rows2d.camera == camera))[0]
            recording.log(f"cameras/{camera}/tracks", _boxes2d(
                rr, rows2d.boxes[t], _colours(rows2d.track_id[t], track_colour),
                [f"T{i}" for i in rows2d.track_id[t]]))


def event_text(error: dict) -> str:
    """One line for an error row of ``errors.parquet``."""
    where = f"{error['dimension']}" + (f" {error['camera']}" if error["camera"] else "")
    tracks = ""
    if error["kind"] == "IDS":
        tracks = f", track {error['previous_track_id']} → {error['track_id']}"
    elif error["kind"] == "FRAG" and error["track_id"] >= 0:
        tracks = f", resumed by track {error['track_id']}"
    causes = ", ".join(error["causes"]) or "none recorded"
    return f"{error['kind']} {where}: {error['class']} {error['actor_id']}{tracks}; causes: {causes}"


def _log_errors(rr, recording, errors_path: Path, timestamps: dict[int, float]) -> None:
    import pyarrow.parquet as pq

    errors = pq.read_table(errors_path).to_pylist()
    level = {"FN": rr.TextLogLevel.DEBUG, "IDS": rr.TextLogLevel.WARN, "FRAG": rr.TextLogLevel.INFO}
    for error in errors:
        if error["kind"] not in KINDS:
            continue
        recording.set_time("frame", sequence=int(error["frame"]))
        recording.set_time("time", duration=float(timestamps.get(int(error["frame"]), 0.0)))
        recording.log(f"events/{error['kind']}", rr.TextLog(event_text(error), level=level[error["kind"]]))
