"""The dataset's tables: Parquet schemas with units, and how one frame of ground truth becomes rows.

``ego_poses``   one row per frame: the ego pose in the world frame.
``ground_truth`` one row per (frame, actor): id, class, exact world-frame 3D box and velocity.
``projections`` one row per (frame, actor, camera), in rig order: the pixel box of the actor's silhouette
                clipped to the near plane and the image (NaN when not in view), truncation, depth and in_view.
``visibility``  one row per (frame, actor, camera), same order as ``projections``: visible and unoccluded
                silhouette pixels at the visibility resolution (−1 when not rendered), occlusion ratio.
``detections``  what trackers see: one row per detection, by frame, then camera (rig order), then its
                index in that camera's list: pixel box, score, class, world-frame 3D estimate, embedding.
``sensor_truth`` why: one row per (frame, camera, actor) and per false positive (actor_id −1), by frame,
                camera (rig order), actors then clutter: the detection it produced (index, −1 if missed),
                its detection probability and the causes that affected it. Never given to a tracker.
``frames``      one row per frame: whether the sensor frame was dropped, and the events active then.

Rows are sorted by frame; within a frame as described per table, exactly as written.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from ..causes import CAUSE_BITS, CAUSE_NAMES, Cause
from ..geometry import Projection
from ..render.visibility import Visibility
from ..sensor.model import SensorOutput
from ..types import BOX2D_FIELDS, BOX3D_FIELDS, GroundTruthFrame

_F64 = pa.float64()

EGO_POSES = pa.schema(
    [pa.field("frame", pa.int32()), pa.field("timestamp", _F64, metadata={"unit": "s"})]
    + [pa.field(name, _F64, metadata={"unit": unit}) for name, unit in zip(
        ("x", "y", "z", "yaw", "vx", "vy"), ("m", "m", "m", "rad", "m/s", "m/s"), strict=True
    )]
)
GROUND_TRUTH = pa.schema(
    [pa.field("frame", pa.int32()), pa.field("actor_id", pa.int64()), pa.field("class", pa.string())]
    + [pa.field(name, _F64) for name in BOX3D_FIELDS],
    metadata={"frame": "world: x along the road, y left, z up [m]; yaw [rad] CCW from +x; v [m/s]"},
)
PROJECTIONS = pa.schema(
    [pa.field("frame", pa.int32()), pa.field("actor_id", pa.int64()), pa.field("camera", pa.string())]
    + [pa.field(name, _F64) for name in BOX2D_FIELDS]
    + [pa.field("truncation", _F64), pa.field("depth", _F64), pa.field("in_view", pa.bool_())],
    metadata={"units": "boxes [px] from the top-left corner; truncation [0, 1]; depth [m] camera-frame z"},
)
VISIBILITY = pa.schema(
    [pa.field("frame", pa.int32()), pa.field("actor_id", pa.int64()), pa.field("camera", pa.string()),
     pa.field("visible_px", pa.int32()), pa.field("silhouette_px", pa.int32()), pa.field("occlusion", _F64)],
    metadata={"units": "pixels at the visibility resolution (-1: not rendered); occlusion = 1 - visible/silhouette"},
)
DETECTIONS = pa.schema(
    [pa.field("frame", pa.int32()), pa.field("camera", pa.string()), pa.field("index", pa.int32())]
    + [pa.field(name, _F64) for name in BOX2D_FIELDS]
    + [pa.field("score", _F64), pa.field("label", pa.string())]
    + [pa.field(name, _F64) for name in BOX3D_FIELDS]
    + [pa.field("embedding", pa.list_(pa.float32()))],
    metadata={"units": "2D box [px]; 3D box world frame [m, rad, m/s]; embedding: unit vector"},
)
SENSOR_TRUTH = pa.schema(
    [pa.field("frame", pa.int32()), pa.field("camera", pa.string()), pa.field("actor_id", pa.int64()),
     pa.field("detection", pa.int32()), pa.field("probability", _F64), pa.field("causes", pa.list_(pa.string()))],
    metadata={"actor_id": "-1 for a false positive (clutter)", "detection": "index in detections, -1 if missed"},
)
FRAMES = pa.schema(
    [pa.field("frame", pa.int32()), pa.field("timestamp", _F64, metadata={"unit": "s"}),
     pa.field("dropped", pa.bool_()), pa.field("events", pa.list_(pa.string()))]
)
SCHEMAS: dict[str, pa.Schema] = {
    "ego_poses": EGO_POSES,
    "ground_truth": GROUND_TRUTH,
    "projections": PROJECTIONS,
    "visibility": VISIBILITY,
    "detections": DETECTIONS,
    "sensor_truth": SENSOR_TRUTH,
    "frames": FRAMES,
}


def _actor_major(array: np.ndarray) -> np.ndarray:
    """``(C, N, ...)`` per-camera arrays → actor-major rows: actor 0 in every camera, actor 1, ..."""
    return np.swapaxes(array, 0, 1).reshape(-1, *array.shape[2:])


def frame_columns(
    state: GroundTruthFrame,
    projection: Projection,
    visibility: Visibility,
    sensor: SensorOutput,
    camera_names: tuple[str, ...],
) -> dict[str, dict]:
    """Column arrays of one frame for each table (vectorised; camera order is the rig's)."""
    n, c = len(state.actor_ids), len(camera_names)
    ego = state.ego
    ego_columns = {
        "frame": np.array([state.frame], dtype=np.int32),
        "timestamp": np.array([state.timestamp]),
        **{name: np.array([getattr(ego, name)], dtype=float) for name in ("x", "y", "z", "yaw", "vx", "vy")},
    }
    truth = {
        "frame": np.full(n, state.frame, dtype=np.int32),
        "actor_id": state.actor_ids,
        "class": state.classes.astype(str),
        **{name: state.boxes[:, i] for i, name in enumerate(BOX3D_FIELDS)},
    }
    boxes = _actor_major(projection.boxes)
    pair_columns = {
        "frame": np.full(n * c, state.frame, dtype=np.int32),
        "actor_id": np.repeat(state.actor_ids, c),
        "camera": np.tile(np.array(camera_names, dtype=str), n),
    }
    visibility_columns = {
        **pair_columns,
        "visible_px": _actor_major(visibility.visible_px).astype(np.int32),
        "silhouette_px": _actor_major(visibility.silhouette_px).astype(np.int32),
        "occlusion": _actor_major(visibility.occlusion),
    }
    projections = {
        "frame": np.full(n * c, state.frame, dtype=np.int32),
        "actor_id": np.repeat(state.actor_ids, c),
        "camera": np.tile(np.array(camera_names, dtype=str), n),
        **{name: boxes[:, i] for i, name in enumerate(BOX2D_FIELDS)},
        "truncation": projection.truncation.T.reshape(-1),
        "depth": projection.depth.T.reshape(-1),
        "in_view": projection.in_view.T.reshape(-1),
    }
    return {
        "ego_poses": ego_columns,
        "ground_truth": truth,
        "projections": projections,
        "visibility": visibility_columns,
        **sensor_columns(state.frame, state.timestamp, sensor),
    }


def sensor_columns(frame: int, timestamp: float, sensor: SensorOutput) -> dict[str, dict]:
    """The ``detections``, ``sensor_truth`` and ``frames`` columns of one frame of sensor output."""
    detections = {name: [] for name in ("camera", "index", "box2d", "score", "label", "box3d", "embedding")}
    truth = {name: [] for name in ("camera", "actor_id", "detection", "probability", "causes")}
    for batch in sensor.batches:
        name = batch.camera.name
        hit = np.nonzero(batch.detection_index >= 0)[0]
        clutter = batch.clutter
        k = len(batch.clutter_index)
        index = np.concatenate([batch.detection_index[hit], batch.clutter_index])
        order = np.argsort(index, kind="stable")
        detections["camera"].append(np.full(len(index), name, dtype=object))
        detections["index"].append(index[order])
        detections["box2d"].append(np.concatenate([batch.det_boxes2d[hit], clutter["boxes2d"]])[order])
        detections["score"].append(np.concatenate([batch.scores[hit], clutter["scores"]])[order])
        detections["label"].append(np.concatenate([batch.labels[hit], clutter["labels"]]).astype(object)[order])
        detections["box3d"].append(np.concatenate([batch.det_boxes3d[hit], clutter["boxes3d"]])[order])
        detections["embedding"].append(np.concatenate([batch.embeddings[hit], clutter["embeddings"]])[order])
        n = len(batch)
        truth["camera"].append(np.full(n + k, name, dtype=object))
        truth["actor_id"].append(np.concatenate([batch.actor_ids, np.full(k, -1, dtype=np.int64)]))
        truth["detection"].append(np.concatenate([batch.detection_index, batch.clutter_index]))
        truth["probability"].append(np.concatenate([batch.probability, np.zeros(k)]))
        truth["causes"].append(np.concatenate([batch.causes, clutter.get("causes", np.full(k, int(Cause.CLUTTER)))]))
    joined = {key: np.concatenate(value) for key, value in detections.items()}
    d = len(joined["index"])
    embeddings = joined["embedding"].astype(np.float32)
    dimension = embeddings.shape[1] if embeddings.ndim == 2 else 0
    detection_columns = {
        "frame": np.full(d, frame, dtype=np.int32),
        "camera": joined["camera"],
        "index": joined["index"].astype(np.int32),
        **{field: joined["box2d"].reshape(d, 4)[:, i] for i, field in enumerate(BOX2D_FIELDS)},
        "score": joined["score"],
        "label": joined["label"],
        **{field: joined["box3d"].reshape(d, 9)[:, i] for i, field in enumerate(BOX3D_FIELDS)},
        "embedding": pa.ListArray.from_arrays(
            pa.array(np.arange(d + 1, dtype=np.int32) * dimension), pa.array(embeddings.reshape(-1))
        ),
    }
    rows = {key: np.concatenate(value) for key, value in truth.items()}
    truth_columns = {
        "frame": np.full(len(rows["actor_id"]), frame, dtype=np.int32),
        "camera": rows["camera"],
        "actor_id": rows["actor_id"],
        "detection": rows["detection"].astype(np.int32),
        "probability": rows["probability"],
        "causes": cause_lists(rows["causes"]),
    }
    frame_row = {
        "frame": np.array([frame], dtype=np.int32),
        "timestamp": np.array([timestamp]),
        "dropped": np.array([sensor.dropped]),
        "events": pa.array([list(sensor.events)], type=pa.list_(pa.string())),
    }
    return {"detections": detection_columns, "sensor_truth": truth_columns, "frames": frame_row}


def cause_lists(masks: np.ndarray) -> pa.ListArray:
    """A list<string> column from ``(R,)`` int64 bit masks, names in :data:`CAUSE_NAMES` order.

    >>> cause_lists(np.array([0, int(Cause.FAR | Cause.OCCLUDED)])).to_pylist()
    [[], ['occluded', 'far']]
    """
    bits = (np.asarray(masks, dtype=np.int64)[:, None] & CAUSE_BITS[None, :]) != 0
    rows, which = np.nonzero(bits)
    offsets = np.concatenate([[0], np.cumsum(bits.sum(axis=1))]).astype(np.int32)
    names = pa.array(np.array(CAUSE_NAMES, dtype=object)[which].tolist(), type=pa.string())
    return pa.ListArray.from_arrays(pa.array(offsets), names)
