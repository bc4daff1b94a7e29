"""One frame's detections from every camera as flat arrays, checked once on the way in.

Trackers work on arrays, not on :class:`~simrig.types.Detection` objects: row ``j`` of every array is one
detection, cameras in rig order and detections in camera order.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from simrig.types import BOX3D_FIELDS, ActorClass, SensorFrame

from .errors import TrackerInputError

LABELS: tuple[ActorClass, ...] = tuple(ActorClass)
"""Class codes: ``labels[j]`` indexes this tuple."""
_LABEL_CODE = {label: code for code, label in enumerate(LABELS)}


@dataclass(frozen=True, eq=False)
class DetectionArrays:
    """Detections of one frame, ``M`` rows.

    boxes3d: ``(M, 9)`` world-frame boxes in :data:`~simrig.types.BOX3D_FIELDS` order [m, rad, m/s];
    boxes2d: ``(M, 4)`` pixel boxes [px]; scores: ``(M,)`` in [0, 1]; labels: ``(M,)`` int codes into
    :data:`LABELS`; cameras: ``(M,)`` int index of the camera in the rig; embeddings: ``(M, D)`` appearance
    unit vectors, a row of NaN where a detection has none (``D`` = 0 when none has one).
    """

    boxes3d: np.ndarray
    boxes2d: np.ndarray
    scores: np.ndarray
    labels: np.ndarray
    cameras: np.ndarray
    embeddings: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), dtype=np.float32))

    def __post_init__(self) -> None:
        if len(self.embeddings) != len(self.scores):
            object.__setattr__(self, "embeddings", np.full((len(self.scores), 0), np.nan, dtype=np.float32))

    def __len__(self) -> int:
        return len(self.scores)

    def take(self, rows: np.ndarray) -> DetectionArrays:
        """The detections at ``rows`` (an index or boolean array), in that order."""
        return DetectionArrays(
            self.boxes3d[rows], self.boxes2d[rows], self.scores[rows], self.labels[rows], self.cameras[rows],
            self.embeddings[rows],
        )

    @staticmethod
    def empty() -> DetectionArrays:
        return DetectionArrays(
            np.zeros((0, 9)), np.zeros((0, 4)), np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        )


def detection_arrays(frame: SensorFrame, *, require_3d: bool = True) -> DetectionArrays:
    """Flatten ``frame.detections`` (cameras in rig order) and check every number.

    Raises :class:`TrackerInputError` naming the frame, camera, detection index and field for a non-finite
    value, a score outside [0, 1], an unknown camera, or (``require_3d``) a detection without a 3D box.
    """
    names = frame.rig.camera_names
    unknown = sorted(set(frame.detections) - set(names))
    if unknown:
        raise TrackerInputError(f"frame {frame.frame}: detections from camera {unknown[0]!r}, not in rig {names}")
    boxes3d, boxes2d, scores, labels, cameras, embeddings = [], [], [], [], [], []
    for camera_index, name in enumerate(names):
        for index, detection in enumerate(frame.detections.get(name, ())):
            where = f"frame {frame.frame}, camera {name!r}, detection {index}"
            box = detection.box3d
            if box is None:
                if require_3d:
                    raise TrackerInputError(f"{where}: no box3d (this tracker needs a world-frame 3D box)")
                boxes3d.append((np.nan,) * 9)
            else:
                boxes3d.append((box.x, box.y, box.z, box.length, box.width, box.height, box.yaw, box.vx, box.vy))
            b = detection.box
            boxes2d.append((b.x1, b.y1, b.x2, b.y2))
            scores.append(detection.score)
            try:
                labels.append(_LABEL_CODE[ActorClass(detection.label)])
            except ValueError:
                raise TrackerInputError(f"{where}: unknown label {detection.label!r}") from None
            cameras.append(camera_index)
            embeddings.append(detection.embedding)
    if not scores:
        return DetectionArrays.empty()
    out = DetectionArrays(
        np.asarray(boxes3d, dtype=float),
        np.asarray(boxes2d, dtype=float),
        np.asarray(scores, dtype=float),
        np.asarray(labels, dtype=np.int64),
        np.asarray(cameras, dtype=np.int64),
        _embedding_rows(frame, embeddings, cameras),
    )
    _check_finite(frame, out, require_3d)
    return out


def _embedding_rows(frame: SensorFrame, embeddings: list, cameras: list[int]) -> np.ndarray:
    """Stack the detections' embeddings (NaN rows where missing); one length for all, else an error naming
    the detection."""
    lengths = {len(e) for e in embeddings if e is not None}
    if len(lengths) > 1:
        first = next(len(e) for e in embeddings if e is not None)
        row = next(k for k, e in enumerate(embeddings) if e is not None and len(e) != first)
        camera = frame.rig.camera_names[cameras[row]]
        index = row - cameras.index(cameras[row])
        raise TrackerInputError(f"frame {frame.frame}, camera {camera!r}, detection {index}: embedding has "
                                f"{len(embeddings[row])} values, other detections have {first}")
    dimension = lengths.pop() if lengths else 0
    present = [row for row, embedding in enumerate(embeddings) if embedding is not None]
    out = np.full((len(embeddings), dimension), np.nan, dtype=np.float32)
    if present:
        out[present] = np.asarray([embeddings[row] for row in present], dtype=np.float32)
        bad = ~np.isfinite(out[present]).all(axis=1)
        if bad.any():
            row = present[int(np.argmax(bad))]
            camera = frame.rig.camera_names[cameras[row]]
            raise TrackerInputError(f"frame {frame.frame}, camera {camera!r}, detection "
                                    f"{row - cameras.index(cameras[row])}: embedding has a non-finite value")
    return out


def _check_finite(frame: SensorFrame, arrays: DetectionArrays, require_3d: bool) -> None:
    """Name the first bad value, if any (cheap when all is well: three vectorised checks)."""
    fields = [("box", arrays.boxes2d, ("x1", "y1", "x2", "y2")), ("score", arrays.scores[:, None], ("",))]
    if require_3d:
        fields.insert(0, ("box3d", arrays.boxes3d, BOX3D_FIELDS))
    for name, values, columns in fields:
        bad = ~np.isfinite(values)
        if name == "score":
            bad |= (values < 0) | (values > 1)
        if bad.any():
            row, column = np.argwhere(bad)[0]
            camera = frame.rig.camera_names[arrays.cameras[row]]
            index = int(row - np.searchsorted(arrays.cameras, arrays.cameras[row]))
            field = f"{name}.{columns[column]}" if columns[column] else name
            raise TrackerInputError(
                f"frame {frame.frame}, camera {camera!r}, detection {index}: {field} is {float(values[row, column])}"
                + (" (scores must be in [0, 1])" if name == "score" and np.isfinite(values[row, column]) else "")
            )
    if np.any(arrays.boxes3d[:, 3:6] <= 0) and require_3d:
        row, column = np.argwhere(arrays.boxes3d[:, 3:6] <= 0)[0]
        camera = frame.rig.camera_names[arrays.cameras[row]]
        index = int(row - np.searchsorted(arrays.cameras, arrays.cameras[row]))
        raise TrackerInputError(
            f"frame {frame.frame}, camera {camera!r}, detection {index}: "
            f"box3d.{BOX3D_FIELDS[3 + column]} must be positive, got {arrays.boxes3d[row, 3 + column]!r}"
        )
