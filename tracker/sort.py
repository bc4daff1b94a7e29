"""SORT (Bewley et al., ICIP 2016) on one camera: a constant-velocity Kalman filter on the image box and a
thresholded IoU Hungarian.

State (7,): box centre u, v [px], area s [px²], aspect ratio r = w/h [-], and the velocities of u, v, s
[per frame]; the ratio is constant. Noise as the SORT paper's reference settings: R = diag(1, 1, 10, 10),
P₀ = diag(10, 10, 10, 10, 10⁴, 10⁴, 10⁴), Q = diag(1, 1, 1, 1, 10⁻², 10⁻², 10⁻⁴). One predict per frame
(so dropped frames are predicted over). A track is reported at a frame only if a detection updated it there
and it has ``min_hits`` consecutive hits (or the sequence is younger than ``min_hits`` frames); it is deleted
after ``max_age`` frames without an update. Pairs of different classes never match.
"""

from __future__ import annotations

import numpy as np
from filterpy.kalman import KalmanFilter

from .assignment import UNMATCHED, hungarian
from .boxes2d import iou
from .camera_tracking import LocalTrack, PerCameraTracking
from .detections import DetectionArrays


def _box_to_measurement(box: np.ndarray) -> np.ndarray:
    """(x1, y1, x2, y2) [px] → (u, v, s, r): centre [px], area [px²], aspect w/h."""
    w, h = box[2] - box[0], box[3] - box[1]
    return np.array([box[0] + w / 2, box[1] + h / 2, w * h, w / h])


def _state_to_box(x: np.ndarray) -> np.ndarray:
    """(u, v, s, r, …) → (x1, y1, x2, y2) [px]; an empty box at the centre if the area is not positive."""
    u, v, s, r = (float(value) for value in np.ravel(x)[:4])
    w = np.sqrt(max(s * r, 0.0))
    h = s / w if w > 0 else 0.0
    return np.array([u - w / 2, v - h / 2, u + w / 2, v + h / 2])


def _new_box_filter(box: np.ndarray) -> KalmanFilter:
    """A filterpy filter started at ``box`` with zero velocity."""
    kf = KalmanFilter(dim_x=7, dim_z=4)
    kf.F = np.eye(7)
    kf.F[0, 4] = kf.F[1, 5] = kf.F[2, 6] = 1.0
    kf.H = np.eye(4, 7)
    kf.R = np.diag([1.0, 1.0, 10.0, 10.0])
    kf.P = np.diag([10.0, 10.0, 10.0, 10.0, 1e4, 1e4, 1e4])
    kf.Q = np.diag([1.0, 1.0, 1.0, 1.0, 1e-2, 1e-2, 1e-4])
    kf.x[:4, 0] = _box_to_measurement(box)
    return kf


class SortTrack:
    """One SORT track: its filter, class, last score and hit/miss counters (in frames)."""

    __slots__ = ("track_id", "kf", "label", "score", "hits", "hit_streak", "age", "time_since_update", "detection")

    def __init__(self, track_id: int, box: np.ndarray, label: int, score: float, detection: int):
        self.track_id, self.kf, self.label, self.score = track_id, _new_box_filter(box), label, score
        self.hits, self.hit_streak, self.age, self.time_since_update = 1, 1, 0, 0
        self.detection = detection

    def predict(self) -> np.ndarray:
        if self.kf.x[2, 0] + self.kf.x[6, 0] <= 0:
            self.kf.x[6, 0] = 0.0  # the area must not go negative
        self.kf.predict()
        self.age += 1
        if self.time_since_update > 0:
            self.hit_streak = 0
        self.time_since_update += 1
        self.detection = -1
        return _state_to_box(self.kf.x)

    def update(self, box: np.ndarray, score: float, detection: int) -> None:
        self.kf.update(_box_to_measurement(box))
        self.detection = detection
        self.time_since_update = 0
        self.hits += 1
        self.hit_streak += 1
        self.score = score


class Sort:
    """SORT on one camera; see the module docstring."""

    def __init__(self, *, max_age: int = 1, min_hits: int = 3, iou_threshold: float = 0.3,
                 score_threshold: float = 0.5):
        if max_age < 1 or min_hits < 0:
            raise ValueError(f"max_age must be ≥ 1 and min_hits ≥ 0, got {max_age} and {min_hits}")
        if not 0 < iou_threshold <= 1 or not 0 <= score_threshold <= 1:
            raise ValueError(f"iou_threshold must be in (0, 1] and score_threshold in [0, 1], got "
                             f"{iou_threshold} and {score_threshold}")
        self.max_age, self.min_hits = max_age, min_hits
        self.iou_threshold, self.score_threshold = iou_threshold, score_threshold
        self.tracks: list[SortTrack] = []
        self.frame_count = 0
        self._next_id = 1

    def step(self, detections: DetectionArrays, frames: int = 1) -> list[LocalTrack]:
        rows = np.nonzero(detections.scores >= self.score_threshold)[0]
        boxes, labels, scores = detections.boxes2d[rows], detections.labels[rows], detections.scores[rows]
        predicted = np.zeros((len(self.tracks), 4))
        for _ in range(frames):
            self.frame_count += 1
            for index, track in enumerate(self.tracks):
                predicted[index] = track.predict()
        finite = np.isfinite(predicted).all(axis=1)
        self.tracks = [track for track, ok in zip(self.tracks, finite, strict=True) if ok]
        predicted = predicted[finite]
        owner = self.associate(predicted, boxes, labels)
        for j in range(len(rows)):
            if owner[j] != UNMATCHED:
                self.tracks[owner[j]].update(boxes[j], float(scores[j]), int(rows[j]))
            else:
                self.tracks.append(SortTrack(self._next_id, boxes[j], int(labels[j]), float(scores[j]), int(rows[j])))
                self._next_id += 1
        young = self.frame_count <= self.min_hits
        out = [
            LocalTrack(track.track_id, _state_to_box(track.kf.x), track.score, track.label, track.detection)
            for track in self.tracks
            if track.time_since_update < 1 and (track.hit_streak >= self.min_hits or young)
        ]
        self.tracks = [track for track in self.tracks if track.time_since_update <= self.max_age]
        return out

    def associate(self, predicted: np.ndarray, boxes: np.ndarray, labels: np.ndarray) -> np.ndarray:
        """owner (M,): the track index each detection goes to, or −1; cost 1 − IoU, gated at 1 − threshold."""
        if len(self.tracks) == 0 or len(boxes) == 0:
            return np.full(len(boxes), UNMATCHED, dtype=np.int64)
        cost = 1.0 - iou(predicted, boxes)
        track_labels = np.array([track.label for track in self.tracks])
        cost = np.where(track_labels[:, None] == labels[None, :], cost, np.inf)
        return hungarian(cost, 1.0 - self.iou_threshold)


def sort(*, max_age: int = 1, min_hits: int = 3, iou_threshold: float = 0.3, score_threshold: float = 0.5,
         cameras: str = "") -> PerCameraTracking:
    """SORT on every camera of the rig (or on the comma-separated ``cameras``), each camera on its own."""
    return PerCameraTracking(
        lambda: Sort(max_age=max_age, min_hits=min_hits, iou_threshold=iou_threshold,
                     score_threshold=score_threshold),
        tuple(name for name in cameras.split(",") if name) or None,
    )
