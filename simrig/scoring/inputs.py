"""From a dataset's ground truth and a tracker's rows to the sequences the metrics read.

2D: one :class:`~simrig.scoring.sequence.Sequence` per (camera, class). Ground truth: every actor in the
camera's view (its clipped silhouette box). Tracker boxes: the tracker's own 2D rows, or — for a 3D-only
tracker — its 3D boxes projected through the rig with the ground truth's geometry (boxes clipped to the near
plane and the image, kept where in view), so that 3D and 2D trackers are compared on the same camera.

3D: one :class:`~simrig.scoring.bev.BevSequence` per class. Ground truth and tracker boxes count only closer to
the ego than the class range (strict, BEV): :data:`CLASS_RANGE_M`. A track's score is the mean of its
per-frame scores over its boxes in range (nuScenes).
"""

from __future__ import annotations

import numpy as np

from simrig.dataset.tracks_file import TrackRows

from ..geometry import project_boxes
from ..types import ActorClass
from .bev import BevSequence, bev_sequence
from .ground_truth import GroundTruth
from .sequence import Sequence, sequence_from_rows

CLASS_RANGE_M = {ActorClass.CAR: 50.0, ActorClass.TRUCK: 50.0, ActorClass.BUS: 50.0, ActorClass.MOTORCYCLE: 40.0}
"""[m] nuScenes' evaluation range per class (car, truck, bus 50 m; motorcycle 40 m), BEV distance from the ego."""


def project_tracks(truth: GroundTruth, tracks3d: TrackRows) -> TrackRows:
    """2D rows of 3D tracks: each box projected into every camera at its frame's ego pose, kept where in view."""
    frame, camera, index, boxes = [], [], [], []
    names = np.array(truth.rig.camera_names, dtype=object)
    starts = np.searchsorted(tracks3d.frame, truth.frames)
    stops = np.searchsorted(tracks3d.frame, truth.frames, side="right")
    for position, (lo, hi) in enumerate(zip(starts, stops, strict=True)):
        if hi == lo:
            continue
        projection = project_boxes(tracks3d.boxes[lo:hi], truth.rig, truth.egos[position])
        cam, box = np.nonzero(projection.in_view)
        order = np.lexsort((cam, box))  # by track row, then camera: stays sorted by frame
        cam, box = cam[order], box[order]
        frame.append(np.full(len(box), truth.frames[position]))
        camera.append(names[cam])
        index.append(lo + box)
        boxes.append(projection.boxes[cam, box])
    if not index:
        return TrackRows(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, object), np.zeros(0),
                         np.zeros((0, 4)), np.zeros(0, object))
    index = np.concatenate(index)
    return TrackRows(
        frame=np.concatenate(frame),
        track_id=tracks3d.track_id[index],
        label=tracks3d.label[index],
        score=tracks3d.score[index],
        boxes=np.concatenate(boxes),
        camera=np.concatenate(camera),
    )


def camera_sequences(truth: GroundTruth, tracks2d: TrackRows, cameras: tuple[str, ...] | None = None
                     ) -> list[Sequence]:
    """One sequence per (camera, class) for every camera of the rig (or of ``cameras``) and every class present
    on either side."""
    sequences = []
    for c, camera in enumerate(truth.rig.camera_names):
        if cameras is not None and camera not in cameras:
            continue
        gt_rows = np.nonzero(truth.in_view[:, c])[0]
        track_rows = np.nonzero(tracks2d.camera == camera)[0]
        labels = sorted(set(truth.label[gt_rows].tolist()) | set(tracks2d.label[track_rows].tolist()))
        for label in labels:
            g = gt_rows[truth.label[gt_rows] == label]
            t = track_rows[tracks2d.label[track_rows] == label]
            sequences.append(sequence_from_rows(
                camera, label, truth.frames,
                truth.frame[g], truth.actor_id[g], truth.boxes2d[g, c],
                tracks2d.frame[t], tracks2d.track_id[t], tracks2d.boxes[t],
            ))
    return sequences


def _ego_distance(truth: GroundTruth, frame: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """BEV distance [m] of world points ``(n, 2)`` at frame numbers ``(n,)`` from the ego at that frame."""
    position = np.searchsorted(truth.frames, frame)
    ego_xy = np.array([(ego.x, ego.y) for ego in truth.egos]).reshape(-1, 2)[position]
    return np.hypot(xy[:, 0] - ego_xy[:, 0], xy[:, 1] - ego_xy[:, 1])


def _in_range(truth: GroundTruth, frame: np.ndarray, label: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    limit = np.array([CLASS_RANGE_M[ActorClass(name)] for name in label]) if len(label) else np.zeros(0)
    return _ego_distance(truth, frame, boxes[:, :2]) < limit


def class_sequences(truth: GroundTruth, tracks3d: TrackRows) -> list[BevSequence]:
    """One BEV sequence per class present on either side (within the class range)."""
    gt_keep = np.nonzero(_in_range(truth, truth.frame, truth.label, truth.boxes))[0]
    track_keep = np.nonzero(_in_range(truth, tracks3d.frame, tracks3d.label, tracks3d.boxes))[0]
    track_ids, inverse = np.unique(tracks3d.track_id[track_keep], return_inverse=True)
    mean_score = (np.bincount(inverse, weights=tracks3d.score[track_keep], minlength=len(track_ids))
                  / np.maximum(np.bincount(inverse, minlength=len(track_ids)), 1))
    track_score = mean_score[inverse]
    labels = sorted(set(truth.label[gt_keep].tolist()) | set(tracks3d.label[track_keep].tolist()))
    sequences = []
    for label in labels:
        g = gt_keep[truth.label[gt_keep] == label]
        in_class = tracks3d.label[track_keep] == label
        t = track_keep[in_class]
        sequences.append(bev_sequence(
            label, truth.frames,
            truth.frame[g], truth.actor_id[g], truth.boxes[g, :2], truth.boxes[g, 7:9],
            tracks3d.frame[t], tracks3d.track_id[t], tracks3d.boxes[t, :2], tracks3d.boxes[t, 7:9],
            track_score[in_class],
        ))
    return sequences
