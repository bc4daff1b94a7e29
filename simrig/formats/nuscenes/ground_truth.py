"""nuScenes ground truth (the database tables the devkit loads) → a 3D-only dataset.

``SRC`` is the folder of one version's tables (``v1.0-mini/`` holding ``scene.json``, ``sample.json``, …) or
the data root above it with exactly one such folder (as ``simrig export --format nuscenes`` writes it). Read:
``scene``, ``sample``, ``sample_data``, ``ego_pose``, ``calibrated_sensor``, ``sensor``, ``sample_annotation``,
``instance`` and ``category``.

What the import does, following the devkit's tracking evaluation (nuscenes-devkit 1.2,
``eval/common/loaders.py`` and ``eval/tracking``), so that ``simrig score`` on the dataset gives the devkit's
AMOTA family:

- every scene, in the order of ``scene.json``, its key frames (samples) from ``first_sample_token`` along
  ``next``; the scenes' frames follow each other (timestamps are the samples' own, each scene shifted to start
  0.5 s after the previous one ends; the frame rate is the median step, 2 Hz for nuScenes' key frames);
- the ego pose of a frame is that of the sample's ``LIDAR_TOP`` key-frame sample data (as the devkit's range
  filter reads it); the ego velocity a finite difference of the poses;
- boxes: ``sample_annotation`` rows whose category maps to a tracking class (``category_to_tracking_name``:
  car, truck, bus, trailer, motorcycle, bicycle, pedestrian); ``trailer``, which simrig has no class for, and
  boxes with no lidar and no radar point (the devkit drops them) are left out and counted in
  ``source.left_out_boxes``; the class range (50 m vehicles, 40 m motorcycle, bicycle, pedestrian) is applied
  by the scorer as the devkit applies it. The bike-rack rule (bicycles inside a ``static_object.bicycle_rack``
  box) is not applied;
- an object is its ``instance_token``: actor ids number the instances in order of first appearance; the
  velocity is the annotation's ``velocity`` when it has one (``simrig export`` writes the exact velocity), else
  the devkit's ``box_velocity`` (centred difference of the neighbouring annotations, NaN when it cannot be
  estimated);
- a tracker's results JSON is read with this dataset's sample tokens (``sample_tokens.json``), and its
  ``tracking_id`` names one track per scene, as in the devkit.

The devkit fills gaps in a track (an object missing from some samples between two appearances) by linear
interpolation before it scores; simrig scores the samples as given (see the notes on devkit issue 1141): the two
agree exactly on ground truth and tracks without gaps. There are no cameras (``rig`` with none), so only 3D is
scored; no detections; every error's cause is ``unknown``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from simrig.formats.imported_truth import ImportedTruth, SourceError
from simrig.reading import open_regular
from simrig.types import Rig

TABLES = ("scene", "sample", "sample_data", "ego_pose", "calibrated_sensor", "sensor", "sample_annotation",
          "instance", "category")
TRACKING_NAME = {
    "vehicle.bicycle": "bicycle", "vehicle.bus.bendy": "bus", "vehicle.bus.rigid": "bus", "vehicle.car": "car",
    "vehicle.motorcycle": "motorcycle", "human.pedestrian.adult": "pedestrian",
    "human.pedestrian.child": "pedestrian", "human.pedestrian.construction_worker": "pedestrian",
    "human.pedestrian.police_officer": "pedestrian", "vehicle.trailer": "trailer", "vehicle.truck": "truck",
}
"""The devkit's ``category_to_tracking_name``."""
FRAME_RATE_HZ = 2.0
"""nuScenes key frames (samples) come at 2 Hz."""
SCENE_GAP_S = 0.5
MAX_TIME_DIFF_S = 1.5
"""The devkit's ``box_velocity`` limit on the time between the two annotations it differences (doubled for a
centred difference)."""


def table_folder(src: Path) -> Path:
    """The folder holding the tables: ``src`` itself, or its one sub-folder with a ``scene.json``."""
    if (src / "scene.json").is_file():
        return src
    found = sorted(p for p in src.iterdir() if (p / "scene.json").is_file()) if src.is_dir() else []
    if len(found) != 1:
        raise SourceError(f"{src}: expected the folder of one nuScenes version's tables (scene.json, sample.json, "
                          f"…) or a data root with exactly one; found {len(found)}")
    return found[0]


class Tables:
    """The nuScenes tables of one version, by token, with error messages that name the file and line."""

    def __init__(self, folder: Path):
        self.folder = folder
        self.rows: dict[str, dict[str, dict]] = {}
        self.texts: dict[str, str] = {}
        for name in TABLES:
            path = folder / f"{name}.json"
            try:
                with open_regular(path, f"nuScenes table {name}.json", SourceError) as handle:
                    text = handle.read().decode("utf-8")
                records = json.loads(text)
            except FileNotFoundError:
                raise SourceError(f"{path}: missing (a nuScenes version holds {', '.join(TABLES)} …)") from None
            except (OSError, UnicodeDecodeError) as error:
                raise SourceError(f"{path}: cannot be read ({error})") from None
            except json.JSONDecodeError as error:
                raise SourceError(f"{path}:{error.lineno}: not JSON ({error.msg})") from None
            except RecursionError:
                raise SourceError(f"{path}: nested too deeply to be a nuScenes table") from None
            if not isinstance(records, list) or not all(isinstance(r, dict) and "token" in r for r in records):
                raise SourceError(f"{path}:1: not a nuScenes table (a list of records with a token)")
            self.texts[name] = text
            self.rows[name] = {r["token"]: r for r in records}

    def line(self, table: str, token: str) -> int:
        """The line of ``token``'s record in ``table``'s file (1 when not found)."""
        text = self.texts[table]
        at = text.find(f'"{token}"')
        return text.count("\n", 0, at) + 1 if at >= 0 else 1

    def get(self, table: str, token: str, *, referrer: tuple[str, str, str]) -> dict:
        """The ``table`` record ``token``, referred to by (table, record token, field); an error naming the
        referring file and line when there is none."""
        record = self.rows[table].get(token)
        if record is None:
            where, record_token, field = referrer
            raise SourceError(f"{self.folder / (where + '.json')}:{self.line(where, record_token)}: {field} "
                              f"{token!r} is not in {table}.json")
        return record

    def field(self, table: str, record: dict, key: str):
        if key not in record:
            raise SourceError(f"{self.folder / (table + '.json')}:{self.line(table, record['token'])}: record "
                              f"{record['token']!r} has no {key!r}")
        return record[key]


def _yaw(quaternion) -> float:
    """Yaw [rad] about +z of a unit quaternion (w, x, y, z)."""
    w, x, y, z = (float(v) for v in quaternion)
    return float(np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)))


def _velocity(tables: Tables, annotation: dict) -> tuple[float, float]:
    """The devkit's ``box_velocity`` (x, y) [m/s]: NaN when it cannot be estimated."""
    rows, samples = tables.rows["sample_annotation"], tables.rows["sample"]
    previous, following = rows.get(annotation.get("prev", "")), rows.get(annotation.get("next", ""))
    if previous is None and following is None:
        return float("nan"), float("nan")
    first, last = previous or annotation, following or annotation
    time = 1e-6 * (samples[last["sample_token"]]["timestamp"] - samples[first["sample_token"]]["timestamp"])
    limit = MAX_TIME_DIFF_S * (2 if previous is not None and following is not None else 1)
    if time > limit or time <= 0:
        return float("nan"), float("nan")
    diff = np.asarray(last["translation"], dtype=float) - np.asarray(first["translation"], dtype=float)
    return float(diff[0] / time), float(diff[1] / time)


def _scene_samples(tables: Tables, scene: dict) -> list[dict]:
    samples, token = [], tables.field("scene", scene, "first_sample_token")
    while token:
        sample = tables.get("sample", token, referrer=("scene", scene["token"], "sample"))
        samples.append(sample)
        if token == scene.get("last_sample_token") or len(samples) > len(tables.rows["sample"]):
            break
        token = sample.get("next", "")
    return samples


def _lidar_key_frames(tables: Tables) -> dict[str, dict]:
    """Each sample's ``LIDAR_TOP`` key-frame ``sample_data`` record (where its ego pose is), by sample token."""
    lidar = {}
    for record in tables.rows["sample_data"].values():
        if not record.get("is_key_frame"):
            continue
        sensor_calibration = tables.get("calibrated_sensor", record["calibrated_sensor_token"],
                                        referrer=("sample_data", record["token"], "calibrated_sensor_token"))
        sensor = tables.get("sensor", sensor_calibration["sensor_token"],
                            referrer=("calibrated_sensor", sensor_calibration["token"], "sensor_token"))
        if sensor.get("channel") == "LIDAR_TOP":
            lidar[record["sample_token"]] = record
    return lidar


def _annotations_by_sample(tables: Tables) -> dict[str, list[dict]]:
    """The ``sample_annotation`` records by sample token; one naming an unknown sample is refused."""
    annotations: dict[str, list[dict]] = {}
    for record in tables.rows["sample_annotation"].values():
        if record.get("sample_token") not in tables.rows["sample"]:
            raise SourceError(f"{tables.folder / 'sample_annotation.json'}:"
                              f"{tables.line('sample_annotation', record['token'])}: unknown sample token "
                              f"{record.get('sample_token')!r} (not in sample.json)")
        annotations.setdefault(record["sample_token"], []).append(record)
    return annotations


def _scene_times(tables: Tables, samples: list[dict], start: float) -> list[float]:
    """[s] each sample's time on simrig's clock, the scene starting at ``start``; a timestamp that is no integer
    number of microseconds is refused."""
    bad = next((s for s in samples if isinstance(s.get("timestamp"), bool)
                or not isinstance(s.get("timestamp"), int)), None)
    if bad is not None:
        raise SourceError(f"{tables.folder / 'sample.json'}: sample {bad['token']!r}: timestamp "
                          f"{bad.get('timestamp')!r} is not an integer number of microseconds")
    first_time = samples[0]["timestamp"]
    return [start + 1e-6 * (s["timestamp"] - first_time) for s in samples]


def _scene_egos(tables: Tables, samples: list[dict], lidar: dict[str, dict], times: list[float]) -> np.ndarray:
    """``(S, 6)`` the ego pose of each sample [x, y, z, yaw] from its ``LIDAR_TOP`` key frame, with the world-frame
    velocity [m/s] differentiated over the scene's times."""
    poses = []
    for sample in samples:
        if sample["token"] not in lidar:
            raise SourceError(f"{tables.folder / 'sample.json'}:{tables.line('sample', sample['token'])}: sample "
                              f"{sample['token']!r} has no LIDAR_TOP key-frame sample_data (its ego pose)")
        pose = tables.get("ego_pose", lidar[sample["token"]]["ego_pose_token"],
                          referrer=("sample_data", lidar[sample["token"]]["token"], "ego_pose_token"))
        poses.append([*pose["translation"][:3], _yaw(pose["rotation"])])
    poses = np.array(poses, dtype=float).reshape(-1, 4)
    velocity = (np.gradient(poses[:, :2], np.array(times), axis=0) if len(samples) > 1
                else np.zeros((len(samples), 2)))
    return np.hstack([poses, velocity])


def _annotation_row(tables: Tables, annotation: dict, frame: int, instances: dict[str, int],
                    left_out: dict[str, int]) -> tuple | None:
    """(frame, actor, class, x, y, z, length, width, height, yaw, vx, vy) of one annotation, or ``None`` (counted
    in ``left_out``) for a box of another category, a trailer or one with no lidar or radar point."""
    instance = tables.get("instance", annotation["instance_token"],
                          referrer=("sample_annotation", annotation["token"], "instance_token"))
    category = tables.get("category", instance["category_token"],
                          referrer=("instance", instance["token"], "category_token"))
    name = TRACKING_NAME.get(category.get("name"))
    if name is None:
        left_out["other_categories"] += 1
        return None
    if name == "trailer":
        left_out["trailer"] += 1
        return None
    if annotation.get("num_lidar_pts", 0) + annotation.get("num_radar_pts", 0) == 0:
        left_out["no_points"] += 1
        return None
    actor = instances.setdefault(annotation["instance_token"], len(instances))
    try:
        x, y, z = (float(v) for v in annotation["translation"])
        width, length, height = (float(v) for v in annotation["size"])
        yaw = _yaw(annotation["rotation"])
    except (KeyError, TypeError, ValueError) as error:
        raise SourceError(f"{tables.folder / 'sample_annotation.json'}:"
                          f"{tables.line('sample_annotation', annotation['token'])}: annotation "
                          f"{annotation['token']!r}: {error} (translation 3, size 3, rotation 4 numbers)") from None
    exact = annotation.get("velocity")  # simrig's export writes the exact one
    return (frame, actor, name, x, y, z, length, width, height, yaw,
            *(_velocity(tables, annotation) if exact is None else map(float, exact[:2])))


def read_nuscenes_truth(src: Path) -> ImportedTruth:
    """The ground truth of the nuScenes tables at ``src`` (see the module docstring)."""
    tables = Tables(table_folder(src))
    lidar, annotations = _lidar_key_frames(tables), _annotations_by_sample(tables)
    tokens, scenes, timestamps, poses = [], [], [], []
    rows: list[tuple] = []
    instances: dict[str, int] = {}
    left_out = {"trailer": 0, "no_points": 0, "other_categories": 0}
    start = 0.0
    for scene in tables.rows["scene"].values():
        samples = _scene_samples(tables, scene)
        scenes.append({"name": scene.get("name", scene["token"]), "token": scene["token"],
                       "first_frame": len(tokens), "frames": len(samples)})
        scene_times = _scene_times(tables, samples, start)
        start = scene_times[-1] + SCENE_GAP_S
        egos = _scene_egos(tables, samples, lidar, scene_times)
        for k, sample in enumerate(samples):
            frame = len(tokens)
            tokens.append(sample["token"])
            timestamps.append(scene_times[k])
            poses.append(list(egos[k]))
            for annotation in annotations.get(sample["token"], []):
                row = _annotation_row(tables, annotation, frame, instances, left_out)
                if row is not None:
                    rows.append(row)
    if not tokens:
        raise SourceError(f"{tables.folder / 'scene.json'}: holds no scene")
    rows.sort(key=lambda r: (r[0], r[1]))
    n = len(rows)
    frame = np.array([r[0] for r in rows], dtype=np.int64)
    steps = np.diff(np.array(timestamps))
    steps = steps[steps > 0]
    rate = 1.0 / float(np.median(steps)) if len(steps) else FRAME_RATE_HZ
    return ImportedTruth(
        name=f"nuscenes-{tables.folder.name}", frame_rate_hz=rate, rig=Rig("none", ()),
        timestamps=np.array(timestamps), egos=np.array(poses, dtype=float).reshape(-1, 6),
        frame=frame, actor_id=np.array([r[1] for r in rows], dtype=np.int64),
        label=np.array([r[2] for r in rows], dtype=object), boxes=np.array([r[3:] for r in rows]).reshape(n, 9),
        boxes2d=np.zeros((n, 0, 4)), in_view=np.zeros((n, 0), dtype=bool), occlusion=np.zeros((n, 0)),
        ignored=np.zeros((n, 0), dtype=np.int8), reasons=np.full(n, "", dtype=object),
        evaluation={}, tokens=tokens, scenes=scenes,
        source={"format": "nuscenes", "path": str(src), "ground_truth_3d": True, "calibrated_rig": False,
                "causes": "unknown", "scenes": len(scenes), "instances": len(instances),
                "left_out_boxes": left_out},
    )
