"""What a tracker is given, frame by frame, from a dataset's tables: the detections as arrays (a row group at a
time), the ego pose it is given, and — under capture timing — each detection at the step its capture arrives by,
with its camera's reported time (:meth:`simrig.dataset.Dataset.sensor_frames` is the front door)."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from ..errors import DatasetError
from ..types import BOX2D_FIELDS, BOX3D_FIELDS, LABELS, DetectionArrays, EgoPose, Rig, SensorFrame
from .arrow_columns import string_codes

if TYPE_CHECKING:
    from .reader import Dataset


def frame_detections(table: pa.Table, frame: int, rig: Rig, dimension: int) -> DetectionArrays:
    """What a tracker is given for ``frame`` from a ``detections`` table holding that frame's rows (as written,
    before the dataset exists: the closed-loop drive), exactly as
    :meth:`simrig.dataset.Dataset.sensor_frames` gives it."""
    return _DetectionChunk.of_table(table, rig, dimension, f"frame {frame}: detections").frame_arrays(frame)


def _stack(table: pa.Table, names: tuple[str, ...]) -> np.ndarray:
    """``(rows, len(names))`` float array of the named columns (``(0, len(names))`` for an empty table)."""
    return np.column_stack([table.column(name).to_numpy() for name in names])


def embedding_matrix(column: pa.ChunkedArray, dimension: int) -> np.ndarray:
    """``(R, D)`` float32 embeddings from a list<float> column whose lists hold ``dimension`` (D) values or
    none; a row of NaN where a detection has none."""
    column = column.combine_chunks()
    lengths = np.diff(column.offsets.to_numpy())
    out = np.full((len(lengths), dimension), np.nan, dtype=np.float32)
    present = lengths == dimension
    if not np.all(present | (lengths == 0)):
        raise DatasetError(f"detections: embeddings of {sorted(set(lengths.tolist()))} values; one length expected")
    if dimension:
        out[present] = column.flatten().to_numpy(zero_copy_only=False).reshape(-1, dimension)
    return out


def _image_paths(folder: Path | None, rig: Rig, frame: int) -> dict[str, str]:
    """Per camera, the path of its PNG of ``frame`` in the dataset's ``images/`` ``folder`` (none without one)."""
    return {} if folder is None else {name: str(folder / name / f"{frame:06d}.png") for name in rig.camera_names}


@dataclass(frozen=True, eq=False)
class _DetectionChunk:
    """Detections of consecutive frames as the arrays of :class:`~simrig.types.DetectionArrays` (rows sorted by
    frame): frame ``(R,)``, boxes3d ``(R, 9)`` world frame, boxes2d ``(R, 4)`` [px], scores, labels and cameras
    (codes) ``(R,)``, embeddings ``(R, D)``."""

    frame: np.ndarray
    boxes3d: np.ndarray
    boxes2d: np.ndarray
    scores: np.ndarray
    labels: np.ndarray
    cameras: np.ndarray
    embeddings: np.ndarray

    @classmethod
    def of_table(cls, table: pa.Table, rig: Rig, dimension: int, where: str) -> _DetectionChunk:
        """The rows of a ``detections`` table (:data:`~simrig.dataset.tables.DETECTIONS` columns) with embeddings of
        ``dimension`` values; ``where`` names the table in an error."""
        camera_codes = {name: code for code, name in enumerate(rig.camera_names)}
        label_codes = {label.value: code for code, label in enumerate(LABELS)}
        return cls(
            frame=table.column("frame").to_numpy(),
            boxes3d=_stack(table, BOX3D_FIELDS),
            boxes2d=_stack(table, BOX2D_FIELDS),
            scores=table.column("score").to_numpy(),
            labels=string_codes(table.column("label"), label_codes, f"{where} label"),
            cameras=string_codes(table.column("camera"), camera_codes, f"{where} camera"),
            embeddings=embedding_matrix(table.column("embedding"), dimension),
        )

    @classmethod
    def empty(cls, dimension: int) -> _DetectionChunk:
        return cls(np.zeros(0, np.int32), np.zeros((0, 9)), np.zeros((0, 4)), np.zeros(0), np.zeros(0, np.int64),
                   np.zeros(0, np.int64), np.zeros((0, dimension), np.float32))

    def _fields(self) -> tuple[np.ndarray, ...]:
        return (self.frame, self.boxes3d, self.boxes2d, self.scores, self.labels, self.cameras, self.embeddings)

    def joined(self, other: _DetectionChunk) -> _DetectionChunk:
        """This chunk's rows followed by ``other``'s."""
        return _DetectionChunk(*(np.concatenate([a, b]) for a, b in zip(self._fields(), other._fields(), strict=True)))

    @classmethod
    def concatenated(cls, chunks: list[_DetectionChunk], dimension: int) -> _DetectionChunk:
        """The rows of ``chunks`` in order, as one chunk (each array copied once)."""
        if not chunks:
            return cls.empty(dimension)
        return cls(*(np.concatenate(arrays) for arrays in zip(*(chunk._fields() for chunk in chunks), strict=True)))

    def from_frame(self, frame: int) -> _DetectionChunk:
        """The rows of ``frame`` and later (views)."""
        lo = int(np.searchsorted(self.frame, frame))
        return _DetectionChunk(*(array[lo:] for array in self._fields())) if lo else self

    def frame_arrays(self, frame: int) -> DetectionArrays:
        """The detections of ``frame`` (views on this chunk)."""
        lo, hi = np.searchsorted(self.frame, [frame, frame + 1])
        return DetectionArrays(self.boxes3d[lo:hi], self.boxes2d[lo:hi], self.scores[lo:hi], self.labels[lo:hi],
                               self.cameras[lo:hi], self.embeddings[lo:hi])


def sensor_frames(dataset: Dataset) -> Iterator[SensorFrame]:
    """What a tracker sees, frame by frame: a :class:`SensorFrame` per frame that was not dropped (a
    dropped frame is skipped, so the tracker sees the time jump). No ground truth is in it.

    The frames carry their detections as arrays (rows sorted by camera in rig order, as written);
    ``frame.detections`` builds :class:`~simrig.types.Detection` objects only if asked. When the dataset
    has images (generated with ``--images``), ``frame.images`` maps each camera to the path of its PNG for
    that frame (``images/CAMERA/FFFFFF.png``, RGB, the camera's width × height); empty otherwise."""
    if dataset.has_table("captures"):
        yield from _delivered_sensor_frames(dataset)
        return
    dropped = dataset.columns("frames", ["dropped"]).column("dropped").to_numpy(zero_copy_only=False)
    rig = dataset.rig
    images = dataset.image_folder
    dimension = _embedding_dimension(dataset)
    chunks = _detection_chunks(dataset, rig, dimension)
    window = next(chunks, None)
    for row, (frame, timestamp, pose) in enumerate(_ego_rows(dataset)):
        # Load row groups until the window holds every row of this frame (rows are sorted by frame).
        while window is not None and (len(window.frame) == 0 or window.frame[-1] <= frame):
            following = next(chunks, None)
            if following is None:
                break
            window = window.joined(following)
        if window is not None:
            window = window.from_frame(frame)
        if dropped[row]:
            continue
        arrays = (window.frame_arrays(frame) if window is not None
                  else _DetectionChunk.empty(dimension).frame_arrays(frame))
        yield SensorFrame(frame, timestamp, pose, rig, arrays=arrays, images=_image_paths(images, rig, frame))


def _delivered_sensor_frames(dataset: Dataset) -> Iterator[SensorFrame]:
    """:func:`sensor_frames` of a dataset with capture timing: each detection is given at the step of the
    frame its capture arrives by (``captures.arrival_frame``), with its camera's reported capture time, and
    marked late when that is after its own frame. A capture taken in a dropped frame is lost; one arriving
    at a dropped frame is given at the next frame that is stepped. Reads the detections whole."""
    dropped = dataset.columns("frames", ["dropped"]).column("dropped").to_numpy(zero_copy_only=False)
    rig = dataset.rig
    frames = len(dropped)
    dimension = _embedding_dimension(dataset)
    detections = _DetectionChunk.concatenated(list(_detection_chunks(dataset, rig, dimension)), dimension)
    captures = capture_arrays(dataset)
    stepped = np.flatnonzero(~dropped)
    # the first stepped frame at or after each frame (frames: never)
    next_step = np.append(stepped, frames)[np.searchsorted(stepped, np.arange(frames + 1))]
    rows = detections.frame.astype(np.int64) * len(rig.cameras) + detections.cameras
    arrival = next_step[np.minimum(captures["arrival_frame"][rows], frames)]
    arrival[dropped[detections.frame]] = frames
    reported = captures["reported_time"][rows]
    order = np.lexsort((np.arange(len(rows)), detections.cameras, arrival))
    arrival = arrival[order]
    images = dataset.image_folder
    for frame, timestamp, pose in _ego_rows(dataset):
        if dropped[frame]:
            continue
        lo, hi = np.searchsorted(arrival, [frame, frame + 1])
        take = order[lo:hi]
        arrays = DetectionArrays(detections.boxes3d[take], detections.boxes2d[take], detections.scores[take],
                                 detections.labels[take], detections.cameras[take], detections.embeddings[take],
                                 reported[take], detections.frame[take] < frame)
        yield SensorFrame(frame, timestamp, pose, rig, arrays=arrays, images=_image_paths(images, rig, frame))


def _embedding_dimension(dataset: Dataset) -> int:
    """The length of the detections' embeddings (0: none), over the whole table (one column read)."""
    dimension = 0
    for group in dataset.batches("detections", ["embedding"]):
        lengths = pc.list_value_length(group.column("embedding")).to_numpy(zero_copy_only=False)
        dimension = max(dimension, int(lengths.max(initial=0)))
    return dimension


def _detection_chunks(dataset: Dataset, rig: Rig, dimension: int) -> Iterator[_DetectionChunk]:
    """The detections table a row group at a time, as the arrays a tracker is given."""
    for table in dataset.batches("detections"):
        yield _DetectionChunk.of_table(table, rig, dimension, f"{dataset.path}: detections")


def capture_arrays(dataset: Dataset) -> dict[str, np.ndarray]:
    """The ``captures`` table as arrays indexed by ``frame × C + camera`` (rig order), checked to hold one row
    per frame and camera in that order."""
    table = dataset.columns("captures")
    c = len(dataset.rig.cameras)
    codes = {name: code for code, name in enumerate(dataset.rig.camera_names)}
    key = (table.column("frame").to_numpy().astype(np.int64) * c
           + string_codes(table.column("camera"), codes, f"{dataset.path}: captures camera"))
    if not np.array_equal(key, np.arange(dataset.frame_count * c)):
        raise DatasetError(f"dataset {str(dataset.path)!r}: captures does not hold one row per frame and camera")
    return {"capture_time": table.column("capture_time").to_numpy(),
            "reported_time": table.column("reported_time").to_numpy(),
            "arrival_frame": table.column("arrival_frame").to_numpy().astype(np.int64),
            "fired": table.column("fired").to_numpy(zero_copy_only=False)}


def _ego_rows(dataset: Dataset) -> list[tuple[int, float, EgoPose]]:
    """(frame, timestamp [s], ego pose a tracker is given) of every frame, in order: the true pose, or the
    estimate of ``ego_estimates`` when the scenario sets an ego-pose error."""
    rows = _pose_rows(dataset, "ego_poses")
    if not dataset.has_table("ego_estimates"):
        return rows
    estimates = _pose_rows(dataset, "ego_estimates")
    if [row[0] for row in estimates] != [row[0] for row in rows]:
        raise DatasetError(f"dataset {str(dataset.path)!r}: ego_estimates does not hold one row per frame")
    return [(frame, timestamp, estimate[2]) for (frame, timestamp, _), estimate in zip(rows, estimates,
                                                                                       strict=True)]


def _pose_rows(dataset: Dataset, name: str) -> list[tuple[int, float, EgoPose]]:
    """(frame, timestamp [s] or NaN, pose) of every row of the pose table ``name``."""
    ego = dataset.columns(name)
    columns = {name: ego.column(name).to_numpy() for name in ego.column_names}
    fields = ("x", "y", "z", "yaw", "vx", "vy")
    return [
        (int(frame), float(columns["timestamp"][row]) if "timestamp" in columns else np.nan,
         EgoPose(*(float(columns[name][row]) for name in fields)))
        for row, frame in enumerate(columns["frame"])
    ]
