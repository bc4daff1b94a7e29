"""nuScenes-style tracking JSON: ``OUT/ground_truth.json`` and, with 3D tracks, ``OUT/NAME.json``.

``{"meta": {...}, "results": {sample_token: [box, …]}}`` with a key for every frame (``SCENARIO-seedN-FFFFFF``)
and per box: ``sample_token``, ``translation`` (world-frame centre [m]), ``size`` (width, length, height [m]),
``rotation`` (unit quaternion w, x, y, z of the yaw about +z), ``velocity`` (vx, vy [m/s]), ``tracking_id``
(string), ``tracking_name`` (one class per track: its most frequent), ``tracking_score``. Ground truth has
score 1. The world frame is simrig's (x along the road, y left, z up), not a nuScenes map's.
"""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import numpy as np

from simrig.dataset.tracks_nuscenes import sample_token

from .api import ExportError, ExportInput

META = {"use_camera": True, "use_lidar": False, "use_radar": False, "use_map": False, "use_external": False}


def token(data: ExportInput, frame: int) -> str:
    return sample_token(data.dataset.scenario["name"], data.dataset.seed, frame)


def results(data: ExportInput, frame, ids, labels, boxes, scores) -> dict:
    """The ``results`` mapping of rows (frame, id, label, (R, 9) world box, score)."""
    names: dict[int, str] = {}
    for ident in np.unique(ids):
        names[int(ident)] = Counter(labels[ids == ident].tolist()).most_common(1)[0][0]
    out: dict[str, list] = {token(data, f): [] for f in data.truth.frames}
    for f, ident, box, score in zip(frame, ids, boxes, scores, strict=True):
        half = float(box[6]) / 2
        out[token(data, f)].append({
            "sample_token": token(data, f),
            "translation": [float(box[0]), float(box[1]), float(box[2])],
            "size": [float(box[4]), float(box[3]), float(box[5])],
            "rotation": [float(np.cos(half)), 0.0, 0.0, float(np.sin(half))],
            "velocity": [float(box[7]), float(box[8])],
            "tracking_id": str(int(ident)),
            "tracking_name": names[int(ident)],
            "tracking_score": float(score),
        })
    return out


def write(data: ExportInput, out: Path) -> None:
    truth = data.truth
    gt = results(data, truth.frame, truth.actor_id, truth.label, truth.boxes, np.ones(len(truth.frame)))
    (out / "ground_truth.json").write_text(json.dumps({"meta": META, "results": gt}, indent=1))
    if data.rows2d is not None and data.rows3d is None:
        raise ExportError("--format nuscenes needs 3D tracks (tracks3d.parquet); these tracks are 2D only")
    if data.rows3d is not None:
        r = data.rows3d
        tracks = results(data, r.frame, r.track_id, r.label, r.boxes, r.score)
        (out / f"{data.tracker_name}.json").write_text(json.dumps({"meta": META, "results": tracks}, indent=1))
