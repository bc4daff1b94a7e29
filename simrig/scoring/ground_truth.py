"""The dataset's ground truth as the scorer needs it, loaded once: boxes per (frame, actor), their pixel boxes
and visibility per camera, and the causes the sensor recorded for each (frame, actor, camera).

Row ``r`` is one (frame, actor) of the ``ground_truth`` table, in its order (sorted by frame). Per-camera
arrays are ``(R, C)`` in rig order. Cause masks are :class:`~simrig.causes.Cause` bit flags.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..causes import Cause, cause_masks
from ..dataset import Dataset
from ..errors import DatasetError
from ..types import BOX2D_FIELDS, BOX3D_FIELDS, EgoPose, Rig


@dataclass(frozen=True, eq=False)
class GroundTruth:
    """Exact ground truth of a dataset, flat.

    frames: ``(F,)`` frame numbers; timestamps ``(F,)`` [s]; egos: the ego pose per frame. frame, actor_id,
    label: ``(R,)``; boxes: ``(R, 9)`` world boxes. boxes2d: ``(R, C, 4)`` pixel boxes (NaN: not in view);
    in_view: ``(R, C)``. causes: ``(R, C)`` every cause recorded for the actor in that camera; detected:
    ``(R, C)`` whether that camera's detector reported it.
    """

    rig: Rig
    frames: np.ndarray
    timestamps: np.ndarray
    egos: tuple[EgoPose, ...]
    frame: np.ndarray
    actor_id: np.ndarray
    label: np.ndarray
    boxes: np.ndarray
    boxes2d: np.ndarray
    in_view: np.ndarray
    causes: np.ndarray
    detected: np.ndarray

    @property
    def miss_causes(self) -> np.ndarray:
        """``(R, C)`` why each camera did not deliver the actor: its causes where it was missed, 0 where it
        was detected (an error there is the tracker's own)."""
        return np.where(self.detected, 0, self.causes)

    @property
    def miss_causes_3d(self) -> np.ndarray:
        """``(R,)`` why no camera delivered the actor: 0 if some camera detected it; else the union of the
        causes of the cameras that had it in view, or ``out_of_view`` when none had."""
        seen = self.in_view.any(axis=1)
        in_view_causes = np.bitwise_or.reduce(np.where(self.in_view, self.causes, 0), axis=1)
        union = np.where(seen, in_view_causes & ~int(Cause.OUT_OF_VIEW), int(Cause.OUT_OF_VIEW))
        return np.where(self.detected.any(axis=1), 0, union)

    @cached_property
    def camera_sets(self) -> np.ndarray:
        """``(R,)`` bit mask of the cameras that have the actor in view (bit c: camera c in rig order)."""
        return np.sum(self.in_view.astype(np.int64) << np.arange(self.in_view.shape[1]), axis=1)

    def rows_of(self, frame: np.ndarray, actor_id: np.ndarray) -> np.ndarray:
        """Row index of each (frame, actor id) pair; a ``KeyError`` for a pair not in the ground truth."""
        key = self._keys(np.asarray(frame), np.asarray(actor_id))
        position = np.searchsorted(self._sorted_keys, key)
        position = np.minimum(position, len(self._sorted_keys) - 1)
        if len(key) and not np.all(self._sorted_keys[position] == key):
            raise KeyError("some (frame, actor) pairs are not in the ground truth")
        return self._key_order[position]

    def _keys(self, frame: np.ndarray, actor_id: np.ndarray) -> np.ndarray:
        return frame.astype(np.int64) * (int(self.actor_id.max(initial=0)) + 1) + actor_id.astype(np.int64)

    @cached_property
    def _key_order(self) -> np.ndarray:
        return np.argsort(self._keys(self.frame, self.actor_id), kind="stable")

    @cached_property
    def _sorted_keys(self) -> np.ndarray:
        return self._keys(self.frame, self.actor_id)[self._key_order]


def load_ground_truth(dataset: Dataset) -> GroundTruth:
    """Read the ground truth, projections and sensor truth of ``dataset`` into a :class:`GroundTruth`."""
    rig = dataset.rig
    cameras = rig.camera_names
    c = len(cameras)
    ego = dataset.table("ego_poses")
    frames = ego.column("frame").to_numpy().astype(np.int64)
    ego_columns = {name: ego.column(name).to_numpy() for name in ("x", "y", "z", "yaw", "vx", "vy")}
    egos = tuple(EgoPose(*(float(ego_columns[name][i]) for name in ego_columns)) for i in range(len(frames)))
    truth = dataset.table("ground_truth")
    frame = truth.column("frame").to_numpy().astype(np.int64)
    actor_id = truth.column("actor_id").to_numpy()
    n = len(frame)
    projections = dataset.table("projections")
    if projections.num_rows != n * c:
        raise DatasetError(f"{dataset.path}: {projections.num_rows} projection rows for {n} actors × {c} cameras")
    boxes2d = np.column_stack([projections.column(name).to_numpy() for name in BOX2D_FIELDS]).reshape(n, c, 4)
    in_view = projections.column("in_view").to_numpy(zero_copy_only=False).reshape(n, c)
    ground_truth = GroundTruth(
        rig=rig,
        frames=frames,
        timestamps=ego.column("timestamp").to_numpy(),
        egos=egos,
        frame=frame,
        actor_id=actor_id,
        label=np.asarray(truth.column("class").to_pylist(), dtype=object),
        boxes=np.column_stack([truth.column(name).to_numpy() for name in BOX3D_FIELDS]).reshape(n, 9),
        boxes2d=boxes2d,
        in_view=in_view,
        causes=np.zeros((n, c), dtype=np.int64),
        detected=np.zeros((n, c), dtype=bool),
    )
    sensor = dataset.table("sensor_truth")
    actor = sensor.column("actor_id").to_numpy()
    real = actor >= 0
    if real.any():
        rows = ground_truth.rows_of(sensor.column("frame").to_numpy()[real], actor[real])
        camera_of = {name: i for i, name in enumerate(cameras)}
        camera = np.array([camera_of[name] for name in np.asarray(sensor.column("camera").to_pylist())[real]])
        ground_truth.causes[rows, camera] = cause_masks(sensor.column("causes").filter(real).to_pylist())
        ground_truth.detected[rows, camera] = sensor.column("detection").to_numpy()[real] >= 0
    return ground_truth
