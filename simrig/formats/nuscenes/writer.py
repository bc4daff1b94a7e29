"""nuScenes: the ground truth as the devkit's database tables (``OUT/v1.0-simrig/``), the same in the tracking
results format (``OUT/ground_truth.json``) and, with 3D tracks, the tracker's results JSON (``OUT/NAME.json``).

**Tables** (``OUT/v1.0-simrig/*.json``, loaded by ``nuscenes.NuScenes(version="v1.0-simrig", dataroot=OUT)``):
one ``scene`` named ``SCENARIO-seedN``, a ``sample`` per frame (token ``SCENARIO-seedN-FFFFFF``, ``timestamp``
the frame's time [µs]), a ``LIDAR_TOP`` key-frame ``sample_data`` per sample with its ``ego_pose`` (the ego's
position and yaw; the devkit's range filter reads it), a ``CAM_*`` key-frame ``sample_data`` per camera and
frame it took an image at, stamped with its capture time (:mod:`simrig.formats.nuscenes.cameras`), an
``instance`` per actor and a ``sample_annotation`` per (frame, actor) with ``translation``, ``size``, ``rotation``
as below, ``prev``/``next`` links, the category of its class (car ``vehicle.car``, truck ``vehicle.truck``, bus
``vehicle.bus.rigid``, motorcycle ``vehicle.motorcycle``, bicycle ``vehicle.bicycle``, pedestrian
``human.pedestrian.adult``) and ``velocity`` (exact, [m/s]; not a nuScenes field: the devkit ignores it and
``simrig import`` reads it). simrig has no lidar: ``num_lidar_pts`` is 1 for every box (0 would make the devkit
drop it), ``num_radar_pts`` 0, no visibility token.
``OUT/v1.0-simrig/splits.json`` defines the split ``simrig`` (the scene), so the devkit's tracking
evaluation runs on the export as it is::

    TrackingEval(config_factory("tracking_nips_2019"), "OUT/NAME.json", "simrig", "OUT/devkit",
                 "v1.0-simrig", "OUT").main()

and ``simrig import --format nuscenes OUT`` reads it back. The devkit interpolates across gaps in a track, which
simrig's scorer does not (:mod:`simrig.formats.nuscenes.ground_truth`): on tracks without gaps the two agree.

**Results JSON** (``ground_truth.json`` and ``NAME.json``):

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

from simrig.formats.export_input import ExportError, ExportInput
from simrig.formats.nuscenes.cameras import camera_tables, yaw_quaternion
from simrig.formats.nuscenes.samples import sample_token

META = {"use_camera": True, "use_lidar": False, "use_radar": False, "use_map": False, "use_external": False}
VERSION, SPLIT = "v1.0-simrig", "simrig"
CATEGORY = {"car": "vehicle.car", "truck": "vehicle.truck", "bus": "vehicle.bus.rigid",
            "motorcycle": "vehicle.motorcycle", "bicycle": "vehicle.bicycle", "pedestrian": "human.pedestrian.adult"}
"""The nuScenes category written for each class (one the devkit's ``category_to_tracking_name`` maps back)."""
LIDAR = "LIDAR_TOP"


def tables(data: ExportInput) -> dict[str, list[dict]]:
    """The devkit's database tables of the dataset's ground truth (see the module docstring)."""
    truth = data.truth
    scene = f"{data.dataset.scenario['name']}-seed{data.dataset.seed}"
    samples = [token(data, f) for f in truth.frames]
    times = [int(round(float(t) * 1e6)) for t in truth.timestamps]
    out: dict[str, list[dict]] = {
        "category": [{"token": f"category-{label}", "name": name, "description": f"simrig {label}"}
                     for label, name in CATEGORY.items()],
        "attribute": [], "visibility": [],
        "sensor": [{"token": "sensor-lidar", "channel": LIDAR, "modality": "lidar"}],
        "calibrated_sensor": [{"token": "calibrated-lidar", "sensor_token": "sensor-lidar",
                               "translation": [0.0, 0.0, 0.0], "rotation": [1.0, 0.0, 0.0, 0.0],
                               "camera_intrinsic": []}],
        "log": [{"token": f"log-{scene}", "logfile": scene, "vehicle": "simrig", "date_captured": "",
                 "location": data.dataset.scenario["name"]}],
        "map": [{"token": "map-simrig", "log_tokens": [f"log-{scene}"], "category": "", "filename": ""}],
        "scene": [{"token": scene, "name": scene, "description": data.dataset.scenario.get("description", ""),
                   "log_token": f"log-{scene}", "nbr_samples": len(samples), "first_sample_token": samples[0],
                   "last_sample_token": samples[-1]}],
        "sample": [], "sample_data": [], "ego_pose": [], "instance": [], "sample_annotation": [],
    }
    for k, (sample, time, ego) in enumerate(zip(samples, times, truth.egos, strict=True)):
        out["sample"].append({"token": sample, "timestamp": time, "scene_token": scene,
                              "prev": samples[k - 1] if k else "",
                              "next": samples[k + 1] if k + 1 < len(samples) else ""})
        out["ego_pose"].append({"token": f"ego-{sample}", "timestamp": time, "translation": [ego.x, ego.y, ego.z],
                                "rotation": yaw_quaternion(ego.yaw)})
        out["sample_data"].append({"token": f"lidar-{sample}", "sample_token": sample,
                                   "ego_pose_token": f"ego-{sample}", "calibrated_sensor_token": "calibrated-lidar",
                                   "timestamp": time,
                                   "fileformat": "", "is_key_frame": True, "height": 0, "width": 0, "filename": "",
                                   "prev": "", "next": ""})
    for table, records in camera_tables(data, samples, times).items():
        out[table].extend(records)
    order = np.lexsort((truth.frame, truth.actor_id))  # by actor, then frame: each instance's annotations in turn
    annotation = [f"{scene}-actor{truth.actor_id[r]}-{truth.frame[r]:06d}" for r in range(len(truth.frame))]
    starts = np.flatnonzero(np.r_[True, truth.actor_id[order][1:] != truth.actor_id[order][:-1]])
    for first, stop in zip(starts, np.r_[starts[1:], len(order)], strict=True):
        rows = order[first:stop]
        instance = f"{scene}-actor{truth.actor_id[rows[0]]}"
        label = Counter(truth.label[rows].tolist()).most_common(1)[0][0]
        out["instance"].append({"token": instance, "category_token": f"category-{label}",
                                "nbr_annotations": len(rows), "first_annotation_token": annotation[rows[0]],
                                "last_annotation_token": annotation[rows[-1]]})
        for j, r in enumerate(rows):
            box = truth.boxes[r]
            out["sample_annotation"].append({
                "token": annotation[r], "sample_token": token(data, truth.frame[r]), "instance_token": instance,
                "visibility_token": "", "attribute_tokens": [],
                "translation": [float(box[0]), float(box[1]), float(box[2])],
                "size": [float(box[4]), float(box[3]), float(box[5])], "rotation": yaw_quaternion(float(box[6])),
                "velocity": [float(box[7]), float(box[8])], "num_lidar_pts": 1, "num_radar_pts": 0,
                "prev": annotation[rows[j - 1]] if j else "",
                "next": annotation[rows[j + 1]] if j + 1 < len(rows) else ""})
    return out


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
    folder = out / VERSION
    folder.mkdir()
    for name, rows in tables(data).items():
        (folder / f"{name}.json").write_text(json.dumps(rows, indent=1))
    scene = f"{data.dataset.scenario['name']}-seed{data.dataset.seed}"
    (folder / "splits.json").write_text(json.dumps({SPLIT: [scene]}))
    gt = results(data, truth.frame, truth.actor_id, truth.label, truth.boxes, np.ones(len(truth.frame)))
    (out / "ground_truth.json").write_text(json.dumps({"meta": META, "results": gt}, indent=1))
    if data.rows2d is not None and data.rows3d is None:
        raise ExportError("--format nuscenes needs 3D tracks (tracks3d.parquet); these tracks are 2D only")
    if data.rows3d is not None:
        r = data.rows3d
        tracks = results(data, r.frame, r.track_id, r.label, r.boxes, r.score)
        (out / f"{data.tracker_name}.json").write_text(json.dumps({"meta": META, "results": tracks}, indent=1))
