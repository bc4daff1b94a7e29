"""The dataset's tables: Parquet schemas with units, and how one frame of ground truth becomes rows.

``ego_poses``   one row per frame: the ego pose in the world frame.
``ground_truth`` one row per (frame, actor): id, class, exact world-frame 3D box and velocity.
``projections`` one row per (frame, actor, camera), in rig order: the pixel box of the actor's silhouette
                clipped to the near plane and the image (NaN when not in view), truncation, depth and in_view.

Rows are sorted by frame, then actor order, then camera (rig order), exactly as written.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from ..geometry import Projection
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
SCHEMAS: dict[str, pa.Schema] = {"ego_poses": EGO_POSES, "ground_truth": GROUND_TRUTH, "projections": PROJECTIONS}


def frame_columns(state: GroundTruthFrame, projection: Projection, camera_names: tuple[str, ...]) -> dict[str, dict]:
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
    # (C, N) arrays → actor-major rows: actor 0 in every camera, actor 1 in every camera, ...
    boxes = projection.boxes.transpose(1, 0, 2).reshape(n * c, 4)
    projections = {
        "frame": np.full(n * c, state.frame, dtype=np.int32),
        "actor_id": np.repeat(state.actor_ids, c),
        "camera": np.tile(np.array(camera_names, dtype=str), n),
        **{name: boxes[:, i] for i, name in enumerate(BOX2D_FIELDS)},
        "truncation": projection.truncation.T.reshape(-1),
        "depth": projection.depth.T.reshape(-1),
        "in_view": projection.in_view.T.reshape(-1),
    }
    return {"ego_poses": ego_columns, "ground_truth": truth, "projections": projections}
