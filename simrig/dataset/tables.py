"""The dataset's tables: Parquet schemas with units (how one frame becomes their rows:
:mod:`simrig.pipeline.frame_columns`).

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

import pyarrow as pa

from ..types import BOX2D_FIELDS, BOX3D_FIELDS

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
