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

Written only when the scenario sets capture timing (:mod:`simrig.scenarios.timing_schema`), so that a dataset of an
ideal rig has the tables it always had:

``captures``      one row per (frame, camera), rig order: the camera's true capture time, the timestamp it
                  reported, the frame at whose step its detections reach the tracker, and whether it fired.
                  ``projections`` then holds each camera's ground truth at its true capture time.
``ego_estimates`` one row per frame: the ego pose the tracker is given (``ego_poses`` keeps the true one).

Written by every generation since the planner-aware scores (datasets made before, and imported ones, lack it):

``truth_plans``   one row per frame: what the ego's planner commands on the ground truth within the class ranges
                  (:mod:`simrig.scoring.truth_plans`), and the consequence of missing each vehicle it reads.

Written by every generation since collisions are found from geometry (datasets made before, and imported ones,
lack it; their ego crashes are the manifest's ``ego_crashed`` events):

``collisions``    one row per collision (:class:`~simrig.types.Collision`): the frame whose step it happened in,
                  the two actor ids (−1: the ego, −2: a fixed obstacle), the closing speed, and the two verdicts
                  (footprints touching; highway-env's crash flag).

Rows are sorted by frame; within a frame as described per table, exactly as written.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from ..causes import CAUSE_BITS, CAUSE_NAMES
from ..render.visibility import Visibility
from ..sensor.model import SensorOutput
from ..types import BOX2D_FIELDS, BOX3D_FIELDS, Collision, GroundTruthFrame

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
CAPTURES = pa.schema(
    [pa.field("frame", pa.int32()), pa.field("camera", pa.string()),
     pa.field("capture_time", _F64, metadata={"unit": "s"}), pa.field("reported_time", _F64, metadata={"unit": "s"}),
     pa.field("arrival_frame", pa.int32()), pa.field("fired", pa.bool_())],
    metadata={"arrival_frame": "the frame whose tracker step receives this capture's detections",
              "fired": "false: the camera (slower than the frame rate) took no image at this frame"},
)
EGO_ESTIMATES = pa.schema(
    [pa.field("frame", pa.int32())]
    + [pa.field(name, _F64, metadata={"unit": unit}) for name, unit in zip(
        ("x", "y", "z", "yaw", "vx", "vy"), ("m", "m", "m", "rad", "m/s", "m/s"), strict=True
    )]
)
TRUTH_PLANS = pa.schema(
    [pa.field("frame", pa.int32()), pa.field("acceleration", _F64, metadata={"unit": "m/s2"}),
     pa.field("lane_change", pa.int8()), pa.field("leader", pa.int64()),
     pa.field("read", pa.list_(pa.int64())), pa.field("consequence", pa.list_(_F64), metadata={"unit": "nats"})],
    metadata={"lane_change": "-1 left, 0 keep, +1 right", "leader": "actor id followed (-1: free road)",
              "read": "actor ids the plan read, ascending", "consequence": "KL(plan || plan without that actor)"},
)
COLLISIONS = pa.schema(
    [pa.field("frame", pa.int32()), pa.field("first", pa.int64()), pa.field("second", pa.int64()),
     pa.field("closing_speed", _F64, metadata={"unit": "m/s"}), pa.field("geometry", pa.bool_()),
     pa.field("highway_env", pa.bool_())],
    metadata={"first": "actor id, -1 the ego, -2 a fixed obstacle; first <= second",
              "geometry": "footprints touch or overlap (the verdict)", "highway_env": "highway-env's crash flag"},
)
OPTIONAL_SCHEMAS: dict[str, pa.Schema] = {"captures": CAPTURES, "ego_estimates": EGO_ESTIMATES,
                                          "truth_plans": TRUTH_PLANS, "collisions": COLLISIONS}
"""Tables a dataset may lack: ``captures`` and ``ego_estimates`` (capture timing only), ``truth_plans`` and
``collisions`` (imported datasets, and those generated before they were recorded)."""
SCHEMAS: dict[str, pa.Schema] = {
    "ego_poses": EGO_POSES,
    "ground_truth": GROUND_TRUTH,
    "projections": PROJECTIONS,
    "visibility": VISIBILITY,
    "detections": DETECTIONS,
    "sensor_truth": SENSOR_TRUTH,
    "frames": FRAMES,
}
"""The tables every dataset holds."""
ALL_SCHEMAS: dict[str, pa.Schema] = {**SCHEMAS, **OPTIONAL_SCHEMAS}


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
