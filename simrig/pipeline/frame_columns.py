"""How one frame of ground truth, visibility and sensor output becomes the rows of the dataset's tables
(:mod:`simrig.dataset.tables` holds their schemas): the generation's step between making data and storing it."""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from simrig.causes import CAUSE_BITS, CAUSE_NAMES
from simrig.render.visibility import Visibility
from simrig.sensor.model import SensorOutput
from simrig.types import BOX2D_FIELDS, BOX3D_FIELDS, Collision, GroundTruthFrame


def _actor_major(array: np.ndarray) -> np.ndarray:
    """``(C, N, ...)`` per-camera arrays → actor-major rows: actor 0 in every camera, actor 1, ..."""
    return np.swapaxes(array, 0, 1).reshape(-1, *array.shape[2:])


def frame_columns(
    state: GroundTruthFrame,
    visibility: Visibility,
    sensor: SensorOutput,
    camera_names: tuple[str, ...],
) -> dict[str, dict]:
    """Column arrays of one frame for each table (vectorised; camera order is the rig's). The projections are
    the sensor's (each camera's ground truth at its capture time)."""
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
    projection = sensor.projection  # each camera's ground truth at its capture time
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
        **_sensor_columns(state.frame, state.timestamp, sensor),
        **_timing_columns(state.frame, sensor, camera_names),
        "collisions": collision_columns(state.frame, state.collisions),
    }


def collision_columns(frame: int, collisions: tuple[Collision, ...]) -> dict[str, np.ndarray]:
    """The ``collisions`` rows of one frame (usually none)."""
    return {
        "frame": np.full(len(collisions), frame, dtype=np.int32),
        "first": np.array([c.first for c in collisions], dtype=np.int64),
        "second": np.array([c.second for c in collisions], dtype=np.int64),
        "closing_speed": np.array([c.closing_speed for c in collisions], dtype=float),
        "geometry": np.array([c.geometry for c in collisions], dtype=bool),
        "highway_env": np.array([c.highway_env for c in collisions], dtype=bool),
    }


def _timing_columns(frame: int, sensor: SensorOutput, camera_names: tuple[str, ...]) -> dict[str, dict]:
    """The ``captures`` and ``ego_estimates`` rows of one frame, for the timing the scenario sets (none: {})."""
    out = {}
    captures = sensor.captures
    if captures is not None:
        c = len(camera_names)
        out["captures"] = {
            "frame": np.full(c, frame, dtype=np.int32),
            "camera": np.array(camera_names, dtype=str),
            "capture_time": captures.tick + captures.offsets,
            "reported_time": captures.reported,
            "arrival_frame": captures.arrival_frame.astype(np.int32),
            "fired": captures.fired,
        }
    if sensor.ego_estimate is not None:
        ego = sensor.ego_estimate
        out["ego_estimates"] = {"frame": np.array([frame], dtype=np.int32),
                                **{name: np.array([getattr(ego, name)], dtype=float)
                                   for name in ("x", "y", "z", "yaw", "vx", "vy")}}
    return out


def _sensor_columns(frame: int, timestamp: float, sensor: SensorOutput) -> dict[str, dict]:
    """The ``detections``, ``sensor_truth`` and ``frames`` columns of one frame of sensor output, for every
    camera at once (rows by camera in rig order; detections by their index in the camera's list, truth rows
    actors then false positives)."""
    batch = sensor.batch
    c, n = batch.detected.shape
    names = np.array([camera.name for camera in batch.cameras], dtype=object)
    false_positives = [batch.false_positives(index) for index in range(c)]
    k = np.array([len(fp["scores"]) for fp in false_positives], dtype=np.int64)
    fp = {key: np.concatenate([row[key] for row in false_positives]) for key in false_positives[0]}
    clutter_camera = np.repeat(np.arange(c), k)
    clutter_index = np.concatenate(batch.clutter_index).astype(np.int64)

    # detections: detected actors and false positives, each at its camera's start + its index in the list
    hits = batch.detection_index >= 0
    counts = hits.sum(axis=1) + k
    starts = np.cumsum(counts) - counts
    d = int(counts.sum())
    cams, actors = np.nonzero(hits)
    at_actor = starts[cams] + batch.detection_index[cams, actors]
    at_clutter = starts[clutter_camera] + clutter_index
    dimension = batch.embeddings.shape[2] if batch.embeddings is not None else fp["embeddings"].shape[1]

    def scatter(actor_values: np.ndarray, clutter_values: np.ndarray, dtype, width: tuple[int, ...] = ()):
        out = np.empty((d, *width), dtype=dtype)
        out[at_actor] = actor_values
        out[at_clutter] = clutter_values
        return out

    box2d = scatter(batch.det_boxes2d[cams, actors], fp["boxes2d"], float, (4,))
    box3d = scatter(batch.det_boxes3d[cams, actors], fp["boxes3d"], float, (9,))
    embeddings = scatter(np.empty((0, dimension)) if batch.embeddings is None else batch.embeddings[cams, actors],
                         fp["embeddings"], np.float32, (dimension,))
    detection_columns = {
        "frame": np.full(d, frame, dtype=np.int32),
        "camera": names[np.repeat(np.arange(c), counts)],
        "index": (np.arange(d) - np.repeat(starts, counts)).astype(np.int32),
        **{field: box2d[:, i] for i, field in enumerate(BOX2D_FIELDS)},
        "score": scatter(batch.scores[cams, actors], fp["scores"], float),
        "label": scatter(batch.labels[cams, actors], fp["labels"], object),
        **{field: box3d[:, i] for i, field in enumerate(BOX3D_FIELDS)},
        "embedding": pa.ListArray.from_arrays(
            pa.array(np.arange(d + 1, dtype=np.int32) * dimension), pa.array(embeddings.reshape(-1))
        ),
    }

    # sensor truth: per camera its n actors, then its false positives
    per_camera = n + k
    truth_starts = np.cumsum(per_camera) - per_camera
    rows = int(per_camera.sum())
    at_actor = (truth_starts[:, None] + np.arange(n)[None, :]).reshape(-1)
    at_clutter = truth_starts[clutter_camera] + n + (np.arange(len(clutter_camera)) - np.repeat(np.cumsum(k) - k, k))

    def truth(actor_values: np.ndarray, clutter_values, dtype):
        out = np.empty(rows, dtype=dtype)
        out[at_actor] = actor_values.reshape(-1)
        out[at_clutter] = clutter_values
        return out

    truth_columns = {
        "frame": np.full(rows, frame, dtype=np.int32),
        "camera": names[np.repeat(np.arange(c), per_camera)],
        "actor_id": truth(np.broadcast_to(batch.actor_ids, (c, n)), -1,
                          np.result_type(batch.actor_ids.dtype, np.int64)),
        "detection": truth(batch.detection_index, clutter_index, np.int64).astype(np.int32),
        "probability": truth(batch.probability, 0.0, float),
        "causes": cause_lists(truth(batch.causes, fp["causes"], np.int64)),
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

    >>> from simrig.causes import Cause
    >>> cause_lists(np.array([0, int(Cause.FAR | Cause.OCCLUDED)])).to_pylist()
    [[], ['occluded', 'far']]
    """
    bits = (np.asarray(masks, dtype=np.int64)[:, None] & CAUSE_BITS[None, :]) != 0
    rows, which = np.nonzero(bits)
    offsets = np.concatenate([[0], np.cumsum(bits.sum(axis=1))]).astype(np.int32)
    names = pa.array(np.array(CAUSE_NAMES, dtype=object)[which].tolist(), type=pa.string())
    return pa.ListArray.from_arrays(pa.array(offsets), names)
