"""KITTI tracking label files, one folder per camera: ``OUT/CAMERA/label_02/0000.txt`` (ground truth) and, with
tracks, ``OUT/CAMERA/NAME/0000.txt`` — one sequence, every frame, space-separated:

``frame track_id type truncated occluded alpha left top right bottom height width length x y z rotation_y
[score]``

Pixel boxes are written at full precision (17 significant digits), so a file read back (``simrig score``,
``simrig import``) holds exactly the boxes it was written from; the 3D fields at 4 decimals.

Frames from 0; pixel boxes; 3D in the camera frame (x right, y down, z forward; location = bottom centre of the
box [m]; rotation_y [rad] about the camera's y axis, 0 facing +x; alpha = rotation_y − atan2(x, z)). Types:
car → ``Car``, truck → ``Truck``, bus → ``Misc``, motorcycle and bicycle → ``Cyclist`` (KITTI has no bus or
motorcycle class; read back, ``Cyclist`` is a motorcycle), pedestrian → ``Pedestrian``. ``truncated`` is the
KITTI tracking level from the projected box's fraction outside the image
(0: inside the image, 1: up to 0.5 outside, 2: more); ``occluded`` the KITTI level from the rendered occlusion
ratio (0: < 0.1, 1: < 0.5, 2: ≥ 0.5, 3: not rendered). Ground truth the evaluation region ignores (as
``simrig score`` with the same settings) is written as KITTI's ``DontCare`` (id −1, its pixel box, the other
fields unknown). A tracker's rows carry its pixel box and score; their 3D fields are KITTI's "unknown" values
(−1, −1000, −10). TrackEval's KITTI reader applies KITTI's own rules to these files (only ``Car`` is evaluated
there, a ``DontCare`` region removes unmatched tracker boxes mostly inside it, truncated or heavily occluded
cars are distractors, unmatched tracker boxes ≤ 25 px are dropped), so its numbers differ from ``simrig
score``'s; the MOTChallenge export is the one that reproduces them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from simrig.formats.export_input import ExportInput

KITTI_TYPE = {"car": "Car", "truck": "Truck", "bus": "Misc", "motorcycle": "Cyclist", "pedestrian": "Pedestrian",
              "bicycle": "Cyclist"}
TRUNCATION_LEVELS = (1e-9, 0.5)
"""Upper bounds of KITTI tracking's truncation levels 0 (inside the image) and 1 (partly); above: 2 (heavily)."""


def _keyed(table, camera: str, frame: np.ndarray, actor: np.ndarray, column: str, missing: float) -> np.ndarray:
    """``column`` of ``table`` at each (frame, actor) in ``camera``; ``missing`` where the table has no row."""
    mask = table.column("camera").to_numpy(zero_copy_only=False) == camera
    frames, actors = table.column("frame").to_numpy()[mask], table.column("actor_id").to_numpy()[mask]
    keys = frames.astype(np.int64) * (1 << 32) + actors
    order = np.argsort(keys)
    keys, values = keys[order], table.column(column).to_numpy()[mask][order]
    wanted = frame.astype(np.int64) * (1 << 32) + actor
    if len(keys) == 0:
        return np.full(len(wanted), missing)
    position = np.clip(np.searchsorted(keys, wanted), 0, len(keys) - 1)
    return np.where(keys[position] == wanted, values[position], missing)


def _camera_boxes(truth, rows: np.ndarray, c: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(dimensions h, w, l; bottom-centre location in camera ``c``'s frame; rotation_y) of ground-truth rows."""
    camera = truth.rig.cameras[c]
    boxes = truth.boxes[rows]
    position = np.searchsorted(truth.frames, truth.frame[rows])
    location = np.zeros((len(rows), 3))
    rotation = np.zeros(len(rows))
    camera_from_ego = np.linalg.inv(camera.ego_from_camera())
    for k, (box, p) in enumerate(zip(boxes, position, strict=True)):
        ego_from_world = np.linalg.inv(truth.egos[p].world_from_ego())
        transform = camera_from_ego @ ego_from_world
        bottom = transform @ np.array([box[0], box[1], box[2] - box[5] / 2, 1.0])
        heading = transform[:3, :3] @ np.array([np.cos(box[6]), np.sin(box[6]), 0.0])
        location[k] = bottom[:3]
        rotation[k] = np.arctan2(-heading[2], heading[0])
    dimensions = np.column_stack([boxes[:, 5], boxes[:, 4], boxes[:, 3]])
    return dimensions, location, rotation


def _wrap(angle: np.ndarray) -> np.ndarray:
    return (angle + np.pi) % (2 * np.pi) - np.pi


def write(data: ExportInput, out: Path) -> None:
    truth = data.truth
    projections, visibility = data.dataset.table("projections"), data.dataset.table("visibility")
    for c, camera in enumerate(truth.rig.camera_names):
        rows = np.nonzero(truth.in_view[:, c])[0]
        truncated = _keyed(projections, camera, truth.frame[rows], truth.actor_id[rows], "truncation", 0.0)
        occlusion = _keyed(visibility, camera, truth.frame[rows], truth.actor_id[rows], "occlusion", np.nan)
        occluded = np.where(np.isnan(occlusion), 3, np.digitize(np.nan_to_num(occlusion), [0.1, 0.5]))
        truncation_level = np.digitize(truncated, TRUNCATION_LEVELS, right=True)
        if data.dataset.has_3d:
            dimensions, location, rotation = _camera_boxes(truth, rows, c)
            alpha = _wrap(rotation - np.arctan2(location[:, 0], location[:, 2]))
        else:  # imported 2D boxes: KITTI's "unknown" 3D values
            dimensions, location = np.full((len(rows), 3), -1.0), np.full((len(rows), 3), -1000.0)
            rotation, alpha = np.full(len(rows), -10.0), np.full(len(rows), -10.0)
        lines = []
        boxes = truth.boxes2d_in(rows, c)
        for k, r in enumerate(rows):
            b = boxes[k]
            if data.ignored[r, c]:
                lines.append(f"{truth.frame[r]} -1 DontCare -1 -1 -10 {b[0]:.17g} {b[1]:.17g} {b[2]:.17g} {b[3]:.17g} "
                             "-1 -1 -1 -1000 -1000 -1000 -10\n")
                continue
            lines.append(
                f"{truth.frame[r]} {truth.actor_id[r]} {KITTI_TYPE[truth.label[r]]} {truncation_level[k]} "
                f"{occluded[k]} "
                f"{alpha[k]:.6f} {b[0]:.17g} {b[1]:.17g} {b[2]:.17g} {b[3]:.17g} "
                + " ".join(f"{v:.4f}" for v in (*dimensions[k], *location[k])) + f" {rotation[k]:.6f}\n")
        folder = out / camera / "label_02"
        folder.mkdir(parents=True)
        (folder / "0000.txt").write_text("".join(lines))
        if data.rows2d is not None:
            t = np.nonzero(data.rows2d.camera == camera)[0]
            t = t[np.lexsort((data.rows2d.track_id[t], data.rows2d.frame[t]))]
            rows2d = data.rows2d
            folder = out / camera / data.tracker_name
            folder.mkdir(parents=True)
            (folder / "0000.txt").write_text("".join(
                f"{rows2d.frame[k]} {rows2d.track_id[k]} {KITTI_TYPE[rows2d.label[k]]} -1 -1 -10 "
                + " ".join(f"{v:.17g}" for v in rows2d.boxes[k]) + " "
                f"-1 -1 -1 -1000 -1000 -1000 -10 {rows2d.score[k]:.6f}\n" for k in t))
