"""nuScenes ground truth and a tracker's results written as another tool would (not by simrig): the database
tables the devkit's ``NuScenes`` class loads (two scenes of key frames with LIDAR_TOP ego poses, instances,
categories, annotations with point counts) plus a ``splits.json`` naming a custom split, and a tracking-results
JSON. Objects of several classes (car, truck, pedestrian, bicycle), one annotation with no lidar or radar point,
objects beyond the class range; a tracker with noise, misses, identity switches and false positives. Neither side
has a gap inside a track (the devkit interpolates across gaps; simrig does not)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

VERSION, SPLIT = "v1.0-casetest", "casetest"
CATEGORIES = {"car": "vehicle.car", "truck": "vehicle.truck", "pedestrian": "human.pedestrian.adult",
              "bicycle": "vehicle.bicycle"}
SIZES = {"car": (1.9, 4.6, 1.7), "truck": (2.5, 9.0, 3.5), "pedestrian": (0.7, 0.7, 1.8), "bicycle": (0.6, 1.7, 1.3)}


def _quaternion(yaw: float) -> list[float]:
    return [float(np.cos(yaw / 2)), 0.0, 0.0, float(np.sin(yaw / 2))]


def write_case(root: Path, seed: int = 0, scenes=(("scene-a", 24, 24), ("scene-b", 18, 16))) -> Path:
    """Write ``root/VERSION/*.json`` and ``root/results.json``; returns the results file."""
    rng = np.random.default_rng(seed)
    tables = {name: [] for name in ("category", "attribute", "visibility", "instance", "sensor", "calibrated_sensor",
                                    "ego_pose", "log", "scene", "sample", "sample_data", "sample_annotation", "map")}
    tables["category"] = [{"token": f"cat-{k}", "name": v, "description": ""} for k, v in CATEGORIES.items()]
    tables["visibility"] = [{"token": "4", "level": "v80-100", "description": ""}]
    tables["sensor"] = [{"token": "sensor-lidar", "channel": "LIDAR_TOP", "modality": "lidar"}]
    tables["calibrated_sensor"] = [{"token": "cs-lidar", "sensor_token": "sensor-lidar", "translation": [0.9, 0, 1.8],
                                    "rotation": [1, 0, 0, 0], "camera_intrinsic": []}]
    tables["log"] = [{"token": "log-0", "logfile": "case", "vehicle": "case", "date_captured": "2026-01-01",
                      "location": "case"}]
    tables["map"] = [{"token": "map-0", "log_tokens": ["log-0"], "category": "semantic_prior", "filename": ""}]
    results: dict[str, list] = {}
    for s, (scene_name, frames, objects) in enumerate(scenes):
        t0 = 1_600_000_000_000_000 + s * 10**9
        samples = [f"{scene_name}-sample-{k:03d}" for k in range(frames)]
        ego_speed = rng.uniform(5, 12)
        ego_yaw = rng.uniform(-np.pi, np.pi)
        heading = np.array([np.cos(ego_yaw), np.sin(ego_yaw)])
        for k, token in enumerate(samples):
            time = t0 + k * 500_000
            ego_xy = np.array([300.0 + 100 * s, 600.0]) + heading * ego_speed * 0.5 * k
            tables["sample"].append({"token": token, "timestamp": time, "scene_token": scene_name,
                                     "prev": samples[k - 1] if k else "",
                                     "next": samples[k + 1] if k + 1 < frames else ""})
            tables["ego_pose"].append({"token": f"ego-{token}", "timestamp": time,
                                       "translation": [float(ego_xy[0]), float(ego_xy[1]), 0.0],
                                       "rotation": _quaternion(ego_yaw)})
            tables["sample_data"].append({"token": f"sd-{token}", "sample_token": token,
                                          "ego_pose_token": f"ego-{token}", "calibrated_sensor_token": "cs-lidar",
                                          "timestamp": time,
                                          "fileformat": "pcd", "is_key_frame": True, "height": 0, "width": 0,
                                          "filename": "", "prev": "", "next": ""})
            results[token] = []
        tables["scene"].append({"token": scene_name, "name": scene_name, "description": "", "log_token": "log-0",
                                "nbr_samples": frames, "first_sample_token": samples[0],
                                "last_sample_token": samples[-1]})
        next_track = 1
        for o in range(objects):
            label = ("car", "car", "truck", "pedestrian", "bicycle")[o % 5]
            first, last = np.sort(rng.integers(0, frames, size=2))
            # around the ego, some beyond the class range; never crossing it (a track that leaves the range and
            # comes back has a gap there, which the devkit would interpolate)
            bearing, radius = rng.uniform(-np.pi, np.pi), rng.uniform(*((5, 25) if o % 4 else (62, 80)))
            offset = radius * np.array([np.cos(bearing), np.sin(bearing)])
            speed = heading * ego_speed + rng.normal(0, 0.5, size=2)
            yaw = float(np.arctan2(speed[1], speed[0]))
            instance = f"{scene_name}-instance-{o}"
            anns = [f"{instance}-ann-{k}" for k in range(first, last + 1)]
            tables["instance"].append({"token": instance, "category_token": f"cat-{label}",
                                       "nbr_annotations": len(anns), "first_annotation_token": anns[0],
                                       "last_annotation_token": anns[-1]})
            track, switched = f"{s}-{next_track}", False
            next_track += 1
            for j, k in enumerate(range(first, last + 1)):
                ego_xy = np.array([300.0 + 100 * s, 600.0]) + heading * ego_speed * 0.5 * k
                xy = ego_xy + offset + speed * 0.5 * (k - first)
                points = 0 if (o == 1 and j == 0) else int(rng.integers(1, 50))
                tables["sample_annotation"].append({
                    "token": anns[j], "sample_token": samples[k], "instance_token": instance,
                    "visibility_token": "4", "attribute_tokens": [],
                    "translation": [float(xy[0]), float(xy[1]), 1.0], "size": list(SIZES[label]),
                    "rotation": _quaternion(yaw), "num_lidar_pts": points, "num_radar_pts": 0,
                    "prev": anns[j - 1] if j else "", "next": anns[j + 1] if j + 1 < len(anns) else ""})
                if k == last and rng.random() < 0.3:
                    continue  # the tracker drops the object one frame early (no gap)
                if not switched and j == len(anns) // 2 and o % 3 == 0:
                    track, switched = f"{s}-{next_track}", True  # identity switch
                    next_track += 1
                noise = rng.normal(0, 0.8, size=2)
                results[samples[k]].append({
                    "sample_token": samples[k], "translation": [float(xy[0] + noise[0]), float(xy[1] + noise[1]), 1.0],
                    "size": list(SIZES[label]), "rotation": _quaternion(yaw),
                    "velocity": [float(speed[0]), float(speed[1])], "tracking_id": track, "tracking_name": label,
                    "tracking_score": float(rng.uniform(0.2, 1.0))})
        for f in range(0, frames, 4):  # a false-positive track near the ego
            ego_xy = np.array([300.0 + 100 * s, 600.0]) + heading * ego_speed * 0.5 * f
            for k in (f, min(f + 1, frames - 1)):
                results[samples[k]].append({
                    "sample_token": samples[k], "translation": [float(ego_xy[0] + 15), float(ego_xy[1] - 12), 1.0],
                    "size": list(SIZES["car"]), "rotation": _quaternion(0.0), "velocity": [0.0, 0.0],
                    "tracking_id": f"{s}-fp{f}", "tracking_name": "car", "tracking_score": 0.3})
    folder = root / VERSION
    folder.mkdir(parents=True)
    for name, rows in tables.items():
        (folder / f"{name}.json").write_text(json.dumps(rows, indent=1))
    (folder / "splits.json").write_text(json.dumps({SPLIT: [name for name, _, _ in scenes]}))
    meta = {"use_camera": True, "use_lidar": False, "use_radar": False, "use_map": False, "use_external": False}
    path = root / "results.json"
    path.write_text(json.dumps({"meta": meta, "results": results}, indent=1))
    return path
