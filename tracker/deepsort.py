"""DeepSORT (Wojke et al., ICIP 2017) on one camera: appearance matching cascade, then IoU for the rest.

Filter: constant velocity on (x, y, a, h) — box centre [px], aspect w/h, height [px] — and their velocities
[per frame], noise proportional to the box height (σ_position = h/20, σ_velocity = h/160), as the reference
implementation. Association each frame:

1. Confirmed tracks, most recently updated first (the matching cascade, one level per frames-since-update),
   against detections by appearance: the smallest cosine distance between the detection's embedding and the
   track's gallery (its last ``budget`` embeddings); a pair is allowed if that distance is ≤
   ``max_cosine_distance`` and the squared Mahalanobis distance of the box is ≤ 9.4877 (χ²₄, 95 %).
2. Tentative tracks and confirmed tracks missed for one frame, against the remaining detections by
   1 − IoU ≤ ``max_iou_distance``.

A track is confirmed after ``n_init`` hits (deleted if missed while tentative), deleted after ``max_age``
frames without an update, and reported while confirmed and missed for at most one frame (its filter's box).
A detection without an embedding takes part in step 2 only. Pairs of different classes never match.
Defaults follow CollabMOT's use of it (§IV-C: min_hits 1, max_iou_distance 0.9).
"""

from __future__ import annotations

from collections import deque

import numpy as np
from filterpy.kalman import KalmanFilter

from .assignment import UNMATCHED, hungarian
from .boxes2d import iou
from .camera_tracking import LocalTrack, PerCameraTracking
from .detections import DetectionArrays

CHI2_4_95 = 9.4877
"""χ² quantile, 4 degrees of freedom, 95 %: the Mahalanobis gate."""
POSITION_WEIGHT = 1.0 / 20.0
VELOCITY_WEIGHT = 1.0 / 160.0


def _box_to_xyah(box: np.ndarray) -> np.ndarray:
    """(x1, y1, x2, y2) → (centre x, centre y, aspect w/h, height) [px, px, -, px]."""
    w, h = box[2] - box[0], box[3] - box[1]
    return np.array([box[0] + w / 2, box[1] + h / 2, w / h, h])


def xyah_to_box(x: np.ndarray) -> np.ndarray:
    cx, cy, a, h = (float(v) for v in np.ravel(x)[:4])
    w = a * h
    return np.array([cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2])


def _noise(height: float, position: tuple[float, ...], velocity: tuple[float, ...] = ()) -> np.ndarray:
    """Diagonal covariance from per-axis standard deviations given as multiples of ``height`` (the aspect
    entries are absolute)."""
    std = [v * height if k != 2 else v for k, v in enumerate(position)]
    std += [v * height if k != 2 else v for k, v in enumerate(velocity)]
    return np.diag(np.square(std))


def _new_xyah_filter(box: np.ndarray) -> KalmanFilter:
    kf = KalmanFilter(dim_x=8, dim_z=4)
    kf.F = np.eye(8)
    kf.F[:4, 4:] = np.eye(4)
    kf.H = np.eye(4, 8)
    z = _box_to_xyah(box)
    kf.x[:4, 0] = z
    p, v = 2 * POSITION_WEIGHT, 10 * VELOCITY_WEIGHT
    kf.P = _noise(z[3], (p, p, 1e-2, p), (v, v, 1e-5, v))
    return kf


class DeepSortTrack:
    """One DeepSORT track: filter, class, last score, appearance gallery, state and counters (frames)."""

    def __init__(self, track_id: int, box: np.ndarray, label: int, score: float, embedding: np.ndarray,
                 detection: int, confirmed: bool, budget: int):
        self.track_id, self.kf, self.label, self.score = track_id, _new_xyah_filter(box), label, score
        self.gallery: deque[np.ndarray] = deque(maxlen=budget)
        if np.isfinite(embedding).all() and len(embedding):
            self.gallery.append(embedding)
        self.hits, self.time_since_update, self.confirmed, self.detection = 1, 0, confirmed, detection

    def predict(self) -> None:
        for size, rate in ((2, 6), (3, 7)):  # aspect and height must not go negative (SORT's rule for its area)
            if self.kf.x[size, 0] + self.kf.x[rate, 0] <= 0:
                self.kf.x[rate, 0] = 0.0
        h = float(self.kf.x[3, 0])
        p, v = POSITION_WEIGHT, VELOCITY_WEIGHT
        self.kf.predict(Q=_noise(h, (p, p, 1e-2, p), (v, v, 1e-5, v)))
        self.time_since_update += 1
        self.detection = -1

    def measurement_space(self) -> tuple[np.ndarray, np.ndarray]:
        """Projected mean (4,) and covariance (4, 4) including the measurement noise."""
        h = float(self.kf.x[3, 0])
        p = POSITION_WEIGHT
        return self.kf.x[:4, 0], self.kf.P[:4, :4] + _noise(h, (p, p, 1e-1, p))

    def update(self, box: np.ndarray, score: float, embedding: np.ndarray, detection: int, n_init: int) -> None:
        h = float(self.kf.x[3, 0])
        p = POSITION_WEIGHT
        self.kf.update(_box_to_xyah(box), R=_noise(h, (p, p, 1e-1, p)))
        if np.isfinite(embedding).all() and len(embedding):
            self.gallery.append(embedding)
        self.score, self.detection = score, detection
        self.hits += 1
        self.time_since_update = 0
        self.confirmed = self.confirmed or self.hits >= n_init


class DeepSort:
    """DeepSORT on one camera; see the module docstring."""

    def __init__(self, *, max_age: int = 30, n_init: int = 1, max_cosine_distance: float = 0.2,
                 max_iou_distance: float = 0.9, budget: int = 100, score_threshold: float = 0.5):
        if max_age < 1 or n_init < 1 or budget < 1:
            raise ValueError(f"max_age, n_init and budget must be ≥ 1, got {max_age}, {n_init}, {budget}")
        for name, value in (("max_cosine_distance", max_cosine_distance), ("max_iou_distance", max_iou_distance),
                            ("score_threshold", score_threshold)):
            if not 0 <= value <= 2:
                raise ValueError(f"{name} must be in [0, 1] (cosine distance: [0, 2]), got {value}")
        self.max_age, self.n_init, self.budget = max_age, n_init, budget
        self.max_cosine_distance, self.max_iou_distance = max_cosine_distance, max_iou_distance
        self.score_threshold = score_threshold
        self.tracks: list[DeepSortTrack] = []
        self._next_id = 1

    def step(self, detections: DetectionArrays, frames: int = 1) -> list[LocalTrack]:
        rows = np.nonzero(detections.scores >= self.score_threshold)[0]
        chosen = detections.take(rows)
        for _ in range(frames):
            for track in self.tracks:
                track.predict()
        owner = self.associate(chosen)
        for j in range(len(rows)):
            embedding = chosen.embeddings[j]
            if owner[j] != UNMATCHED:
                self.tracks[owner[j]].update(chosen.boxes2d[j], float(chosen.scores[j]), embedding, int(rows[j]),
                                             self.n_init)
            else:
                self.tracks.append(DeepSortTrack(
                    self._next_id, chosen.boxes2d[j], int(chosen.labels[j]), float(chosen.scores[j]), embedding,
                    int(rows[j]), self.n_init <= 1, self.budget))
                self._next_id += 1
        self.tracks = [
            track for track in self.tracks
            if track.time_since_update <= self.max_age and (track.confirmed or track.time_since_update == 0)
        ]
        return [
            LocalTrack(track.track_id, xyah_to_box(track.kf.x), track.score, track.label, track.detection)
            for track in self.tracks if track.confirmed and track.time_since_update <= 1
        ]

    def associate(self, detections: DetectionArrays) -> np.ndarray:
        """owner (M,): the track index each detection goes to, or −1 (cascade, then IoU)."""
        owner = np.full(len(detections), UNMATCHED, dtype=np.int64)
        if not self.tracks or len(detections) == 0:
            return owner
        labels = np.array([track.label for track in self.tracks])
        same_class = labels[:, None] == detections.labels[None, :]
        appearance = self.appearance_cost(detections)
        confirmed = [i for i, track in enumerate(self.tracks) if track.confirmed]
        for level in range(1, self.max_age + 1):
            free = np.nonzero(owner == UNMATCHED)[0]
            level_tracks = [i for i in confirmed if self.tracks[i].time_since_update == level]
            if len(free) == 0:
                break
            if not level_tracks:
                continue
            cost = appearance[np.ix_(level_tracks, free)]
            cost = np.where(same_class[np.ix_(level_tracks, free)], cost, np.inf)
            matched = hungarian(cost, self.max_cosine_distance)
            hit = matched != UNMATCHED
            owner[free[hit]] = np.asarray(level_tracks)[matched[hit]]
        taken = set(owner[owner != UNMATCHED].tolist())
        rest = [i for i, track in enumerate(self.tracks)
                if i not in taken and (not track.confirmed or track.time_since_update == 1)]
        free = np.nonzero(owner == UNMATCHED)[0]
        if rest and len(free):
            predicted = np.stack([xyah_to_box(self.tracks[i].kf.x) for i in rest])
            cost = 1.0 - iou(predicted, detections.boxes2d[free])
            cost = np.where(same_class[np.ix_(rest, free)], cost, np.inf)
            matched = hungarian(cost, self.max_iou_distance)
            hit = matched != UNMATCHED
            owner[free[hit]] = np.asarray(rest)[matched[hit]]
        return owner

    def appearance_cost(self, detections: DetectionArrays) -> np.ndarray:
        """(N, M) smallest cosine distance to each track's gallery, +inf where a side has no embedding or the
        box fails the Mahalanobis gate."""
        n, m = len(self.tracks), len(detections)
        cost = np.full((n, m), np.inf)
        has = np.isfinite(detections.embeddings).all(axis=1) & (detections.embeddings.shape[1] > 0)
        measurements = np.stack([_box_to_xyah(b) for b in detections.boxes2d])
        for i, track in enumerate(self.tracks):
            if not track.gallery:
                continue
            gallery = np.stack(track.gallery)
            distance = 1.0 - (detections.embeddings[has] @ gallery.T).max(axis=1)
            mean, covariance = track.measurement_space()
            delta = measurements - mean
            gate = np.einsum("mi,ij,mj->m", delta, np.linalg.inv(covariance), delta) <= CHI2_4_95
            row = np.full(m, np.inf)
            row[has] = distance
            cost[i] = np.where(gate, row, np.inf)
        return cost


def deepsort(*, max_age: int = 30, n_init: int = 1, max_cosine_distance: float = 0.2,
             max_iou_distance: float = 0.9, budget: int = 100, score_threshold: float = 0.5,
             cameras: str = "") -> PerCameraTracking:
    """DeepSORT on every camera of the rig (or on the comma-separated ``cameras``), each camera on its own."""
    return PerCameraTracking(
        lambda: DeepSort(max_age=max_age, n_init=n_init, max_cosine_distance=max_cosine_distance,
                         max_iou_distance=max_iou_distance, budget=budget, score_threshold=score_threshold),
        tuple(name for name in cameras.split(",") if name) or None,
    )
