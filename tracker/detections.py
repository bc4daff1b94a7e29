"""One frame's detections from every camera as flat arrays (:class:`~simrig.types.DetectionArrays`), checked
once on the way in.

Trackers work on arrays, not on :class:`~simrig.types.Detection` objects: a frame read from a dataset
already carries them (``frame.arrays``); a frame a user built from ``Detection`` objects is flattened here.
"""

from __future__ import annotations

import numpy as np

from simrig.types import BOX3D_FIELDS, LABELS, ActorClass, DetectionArrays, SensorFrame

from .errors import TrackerInputError

__all__ = ["LABELS", "DetectionArrays", "detection_arrays"]

_LABEL_CODE = {label: code for code, label in enumerate(LABELS)}


def detection_arrays(frame: SensorFrame, *, require_3d: bool = True) -> DetectionArrays:
    """Flatten ``frame.detections`` (cameras in rig order) and check every number.

    Raises :class:`TrackerInputError` naming the frame, camera, detection index and field for a non-finite
    value, a score outside [0, 1], an unknown camera, or (``require_3d``) a detection without a 3D box.
    A frame that already carries arrays is only checked (vectorised), not rebuilt.
    """
    if frame.arrays is not None:
        _check_arrays(frame, frame.arrays, require_3d)
        return frame.arrays
    names = frame.rig.camera_names
    unknown = sorted(set(frame.detections) - set(names))
    if unknown:
        raise TrackerInputError(f"frame {frame.frame}: detections from camera {unknown[0]!r}, not in rig {names}")
    boxes3d, boxes2d, scores, labels, cameras, embeddings, times, late = [], [], [], [], [], [], [], []
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
            time = detection.capture_time
            if time is not None and not np.isfinite(time):
                raise TrackerInputError(f"{where}: capture_time is {time} (a time in seconds, or None)")
            times.append(np.nan if time is None else float(time))
            late.append(bool(detection.late))
    if not scores:
        return DetectionArrays.empty()
    out = DetectionArrays(
        np.asarray(boxes3d, dtype=float),
        np.asarray(boxes2d, dtype=float),
        np.asarray(scores, dtype=float),
        np.asarray(labels, dtype=np.int64),
        np.asarray(cameras, dtype=np.int64),
        _embedding_rows(frame, embeddings, cameras),
        np.asarray(times, dtype=float),
        np.asarray(late, dtype=bool),
    )
    _check_finite(frame, out, require_3d)
    return out


def _check_arrays(frame: SensorFrame, arrays: DetectionArrays, require_3d: bool) -> None:
    """The checks of :func:`detection_arrays` on a frame that came as arrays: camera and label codes in range,
    a 3D box where one is required, then every number."""
    cameras = len(frame.rig.cameras)
    if len(arrays) and (arrays.cameras.min() < 0 or arrays.cameras.max() >= cameras):
        raise TrackerInputError(f"frame {frame.frame}: a detection's camera index is outside the rig's {cameras}")
    if len(arrays) and (arrays.labels.min() < 0 or arrays.labels.max() >= len(LABELS)):
        row = int(np.argmax((arrays.labels < 0) | (arrays.labels >= len(LABELS))))
        raise TrackerInputError(f"{_where(frame, arrays, row)}: unknown label code {int(arrays.labels[row])}")
    if require_3d:
        missing = np.isnan(arrays.boxes3d).all(axis=1)
        if missing.any():
            row = int(np.argmax(missing))
            raise TrackerInputError(f"{_where(frame, arrays, row)}: no box3d (this tracker needs a world-frame 3D box)")
    _check_finite(frame, arrays, require_3d)


def _where(frame: SensorFrame, arrays: DetectionArrays, row: int) -> str:
    """'frame F, camera 'NAME', detection K' of flat row ``row`` (K counts within the camera)."""
    camera = int(arrays.cameras[row])
    index = int(row - np.searchsorted(arrays.cameras, camera))
    return f"frame {frame.frame}, camera {frame.rig.camera_names[camera]!r}, detection {index}"


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
            field = f"{name}.{columns[column]}" if columns[column] else name
            raise TrackerInputError(
                f"{_where(frame, arrays, row)}: {field} is {float(values[row, column])}"
                + (" (scores must be in [0, 1])" if name == "score" and np.isfinite(values[row, column]) else "")
            )
    if np.any(arrays.boxes3d[:, 3:6] <= 0) and require_3d:
        row, column = np.argwhere(arrays.boxes3d[:, 3:6] <= 0)[0]
        raise TrackerInputError(
            f"{_where(frame, arrays, row)}: "
            f"box3d.{BOX3D_FIELDS[3 + column]} must be positive, got {arrays.boxes3d[row, 3 + column]!r}"
        )
