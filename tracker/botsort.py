"""A BoT-SORT-style tracker on one camera (Aharon, Orfaig, Bobrovsky: "BoT-SORT: Robust Associations
Multi-Pedestrian Tracking", arXiv 2206.14651, 2022): ByteTrack's two-stage association with IoU and appearance
fused, a Kalman filter on the box's width and height, and camera-motion compensation.

* Filter (BoT-SORT §3.1): state (x_c, y_c, w, h) and their rates, constant velocity; process and measurement
  noise standard deviations proportional to the box's width (x, w) and height (y, h): σ_p = 0.05, σ_v = 0.00625,
  σ_m = 0.05.
* Camera motion (BoT-SORT §3.2 estimates a global affine warp from image features): here the warp comes from
  the known ego motion — the camera's rotation between the two frames gives the image homography H = K·R·K⁻¹
  (exact for distant points, a pure rotation; the translation's image motion depends on depth and is left to
  the filter). Each track's state is warped with H's local affine linearisation at its centre, mean and
  covariance as BoT-SORT warps them (the rotation part applied to every (x, y)-like pair).
* Appearance (§3.3): a track's feature is the exponential moving average e ← α·e + (1 − α)·f, α = 0.9, of its
  detections' unit embeddings (renormalised).
* Association (§3.4, with ByteTrack's stages — :mod:`.bytetrack`): detections with score ≥ ``track_high_thresh``
  (0.6) against every activated track with the fused cost C = min(d_iou, d̂_cos), where d̂_cos = 0.5·d_cos if
  d_cos < θ_emb and d_iou < θ_iou, else 1 — d_cos = 1 − cos, so 0.5·d_cos is the halved scale d = 0.5·(1 − cos)
  on which θ_emb = ``appearance_thresh`` = 0.25 is set, θ_iou = ``proximity_thresh`` = 0.5; matches need
  C ≤ ``match_thresh`` (0.8). Then low detections (> ``track_low_thresh`` 0.1) against the still-tracked
  tracks on IoU alone (1 − IoU ≤ 0.5); then the remaining high detections against unconfirmed tracks with the
  fused cost (≤ 0.7); new tracks from high detections with score ≥ ``new_track_thresh`` (0.7); lost tracks
  dropped after ``track_buffer`` frames (10: 1 s at simrig's 10 Hz, BoT-SORT's 30 frames at 30 Hz).

Pairs of different classes never match. One Hungarian per stage (scipy).
"""

from __future__ import annotations

import numpy as np
from filterpy.kalman import KalmanFilter

from simrig.geometry import camera_from_world
from simrig.types import EgoPose, Rig

from .assignment import UNMATCHED, assign_into
from .boxes2d import iou
from .camera_tracking import LocalTrack, PerCameraTracking
from .detections import DetectionArrays

SIGMA_POSITION, SIGMA_VELOCITY, SIGMA_MEASUREMENT = 0.05, 0.00625, 0.05
"""BoT-SORT's noise factors, multiplied by the box's width or height."""


def _box_to_xywh(box: np.ndarray) -> np.ndarray:
    """(x1, y1, x2, y2) → (centre x, centre y, width, height) [px]."""
    return np.array([(box[0] + box[2]) / 2, (box[1] + box[3]) / 2, box[2] - box[0], box[3] - box[1]])


def _xywh_to_box(state: np.ndarray) -> np.ndarray:
    cx, cy, w, h = (float(v) for v in np.ravel(state)[:4])
    return np.array([cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2])


def _scaled(w: float, h: float, factor: float) -> np.ndarray:
    """Standard deviations (w, h, w, h)·factor of the (x, y, w, h) block."""
    return np.array([w, h, w, h]) * factor


def _rotation_homographies(rig: Rig, before: EgoPose, now: EgoPose) -> np.ndarray:
    """``(C, 3, 3)``: per camera, the image homography K·R·K⁻¹ of the camera's rotation R from the ``before`` pose to
    ``now`` (pixels of the earlier image to pixels of the later one, for points at infinity)."""
    relative = camera_from_world(rig, now) @ np.linalg.inv(camera_from_world(rig, before))
    k = np.stack([camera.intrinsics for camera in rig.cameras])
    return k @ relative[:, :3, :3] @ np.linalg.inv(k)


def _local_affine(homography: np.ndarray, x: float, y: float) -> tuple[np.ndarray, np.ndarray]:
    """(A (2, 2), t (2,)): the affine map that agrees with ``homography`` at (x, y) to first order.

    >>> a, t = _local_affine(np.array([[1.0, 0, 5], [0, 1, -2], [0, 0, 1]]), 10.0, 20.0)
    >>> a.tolist(), t.tolist()
    ([[1.0, 0.0], [0.0, 1.0]], [5.0, -2.0])
    """
    u, v, s = homography @ np.array([x, y, 1.0])
    jacobian = (homography[:2, :2] * s - np.outer([u, v], homography[2, :2])) / s**2
    return jacobian, np.array([u / s, v / s]) - jacobian @ np.array([x, y])


class BotSortTrack:
    """One track: its (x, y, w, h) filter, class, score, appearance feature, state and counters (frames)."""

    def __init__(self, track_id: int, box: np.ndarray, label: int, score: float, embedding: np.ndarray,
                 detection: int, activated: bool):
        z = _box_to_xywh(box)
        self.kf = KalmanFilter(dim_x=8, dim_z=4)
        self.kf.F = np.eye(8)
        self.kf.F[:4, 4:] = np.eye(4)
        self.kf.H = np.eye(4, 8)
        self.kf.x[:4, 0] = z
        self.kf.P = np.diag(np.square(np.concatenate([_scaled(z[2], z[3], 2 * SIGMA_POSITION),
                                                      _scaled(z[2], z[3], 10 * SIGMA_VELOCITY)])))
        self.track_id, self.label, self.score, self.detection = track_id, label, score, detection
        self.feature = embedding / np.linalg.norm(embedding) if _usable(embedding) else None
        self.confirmed, self.lost, self.time_since_update = activated, False, 0

    def size(self) -> tuple[float, float]:
        return max(float(self.kf.x[2, 0]), 1e-3), max(float(self.kf.x[3, 0]), 1e-3)

    def compensate(self, homography: np.ndarray) -> None:
        """Warp the state by the camera's motion (see the module docstring)."""
        a, t = _local_affine(homography, float(self.kf.x[0, 0]), float(self.kf.x[1, 0]))
        warp = np.kron(np.eye(4), a)
        self.kf.x = warp @ self.kf.x
        self.kf.x[:2, 0] += t
        self.kf.P = warp @ self.kf.P @ warp.T

    def predict(self) -> None:
        if self.lost:  # BoT-SORT: a lost track's size rates are zeroed before predicting
            self.kf.x[6:, 0] = 0.0
        for size, rate in ((2, 6), (3, 7)):  # width and height must not go negative (SORT's rule for its area)
            if self.kf.x[size, 0] + self.kf.x[rate, 0] <= 0:
                self.kf.x[rate, 0] = 0.0
        w, h = self.size()
        self.kf.predict(Q=np.diag(np.square(np.concatenate([_scaled(w, h, SIGMA_POSITION),
                                                            _scaled(w, h, SIGMA_VELOCITY)]))))
        self.time_since_update += 1
        self.detection = -1

    def box(self) -> np.ndarray:
        return _xywh_to_box(self.kf.x)

    def update(self, box: np.ndarray, score: float, embedding: np.ndarray, detection: int, alpha: float) -> None:
        w, h = self.size()
        self.kf.update(_box_to_xywh(box), R=np.diag(np.square(_scaled(w, h, SIGMA_MEASUREMENT))))
        if _usable(embedding):
            unit = embedding / np.linalg.norm(embedding)
            feature = unit if self.feature is None else alpha * self.feature + (1 - alpha) * unit
            self.feature = feature / np.linalg.norm(feature)
        self.score, self.detection = score, detection
        self.time_since_update, self.lost, self.confirmed = 0, False, True


def _usable(embedding: np.ndarray) -> bool:
    return len(embedding) > 0 and bool(np.isfinite(embedding).all()) and float(np.linalg.norm(embedding)) > 0


class BotSort:
    """BoT-SORT-style tracking on one camera; see the module docstring."""

    def __init__(self, *, track_high_thresh: float = 0.6, track_low_thresh: float = 0.1,
                 new_track_thresh: float = 0.7, match_thresh: float = 0.8, proximity_thresh: float = 0.5,
                 appearance_thresh: float = 0.25, track_buffer: int = 10, alpha: float = 0.9):
        if not 0 <= track_low_thresh <= track_high_thresh <= 1 or not 0 <= new_track_thresh <= 1:
            raise ValueError("botsort: need 0 ≤ track_low_thresh ≤ track_high_thresh ≤ 1 and new_track_thresh in "
                             f"[0, 1]; got {track_low_thresh}, {track_high_thresh}, {new_track_thresh}")
        for name, value in (("match_thresh", match_thresh), ("proximity_thresh", proximity_thresh),
                            ("appearance_thresh", appearance_thresh), ("alpha", alpha)):
            if not 0 <= value <= 1:
                raise ValueError(f"botsort: {name} must be in [0, 1], got {value}")
        if isinstance(track_buffer, bool) or not float(track_buffer).is_integer() or track_buffer < 1:
            raise ValueError(f"botsort: track_buffer must be a whole number of frames ≥ 1, got {track_buffer}")
        track_buffer = int(track_buffer)
        self.high, self.low, self.new = track_high_thresh, track_low_thresh, new_track_thresh
        self.match_thresh, self.proximity, self.appearance = match_thresh, proximity_thresh, appearance_thresh
        self.track_buffer, self.alpha = track_buffer, alpha
        self.tracks: list[BotSortTrack] = []
        self.frame_count = 0
        self._next_id = 1
        self._motion: np.ndarray | None = None

    def compensate(self, homography: np.ndarray) -> None:
        """The camera moved by ``homography`` since the last frame: the next :meth:`step` warps every track by it
        after predicting (BoT-SORT's order)."""
        self._motion = homography

    def _cost(self, track_indices: list[int], rows: np.ndarray, detections: DetectionArrays, *, fused: bool
              ) -> np.ndarray:
        """(len(track_indices), len(rows)) cost: 1 − IoU, or BoT-SORT's min(d_iou, d̂_cos); ∞ across classes."""
        boxes = np.stack([self.tracks[i].box() for i in track_indices])
        cost = 1.0 - iou(boxes, detections.boxes2d[rows])
        if fused:
            features = [self.tracks[i].feature for i in track_indices]
            embeddings = detections.embeddings[rows]
            has = np.isfinite(embeddings).all(axis=1) & (embeddings.shape[1] > 0)
            appearance = np.ones_like(cost)
            if has.any() and any(f is not None for f in features):
                units = embeddings[has] / np.linalg.norm(embeddings[has], axis=1, keepdims=True)
                for row, feature in enumerate(features):
                    if feature is not None:
                        appearance[row, has] = 0.5 * (1.0 - units @ feature)  # d = 0.5·(1 − cos)
            gated = (appearance < self.appearance) & (cost < self.proximity)
            cost = np.minimum(cost, np.where(gated, appearance, 1.0))
        labels = np.array([self.tracks[i].label for i in track_indices])
        return np.where(labels[:, None] == detections.labels[rows][None, :], cost, np.inf)

    def _match(self, track_indices: list[int], rows: np.ndarray, detections: DetectionArrays, gate: float,
               owner: np.ndarray, *, fused: bool) -> None:
        if not track_indices or len(rows) == 0:
            return
        assign_into(owner, rows, track_indices, self._cost(track_indices, rows, detections, fused=fused), gate)

    def step(self, detections: DetectionArrays, frames: int = 1) -> list[LocalTrack]:
        for _ in range(frames):
            self.frame_count += 1
            for track in self.tracks:
                track.predict()
        if self._motion is not None:
            for track in self.tracks:
                track.compensate(self._motion)
            self._motion = None
        owner = np.full(len(detections), UNMATCHED, dtype=np.int64)
        high = np.nonzero(detections.scores >= self.high)[0]
        low = np.nonzero((detections.scores > self.low) & (detections.scores < self.high))[0]
        activated = [i for i, t in enumerate(self.tracks) if t.confirmed]
        unconfirmed = [i for i, t in enumerate(self.tracks) if not t.confirmed]
        self._match(activated, high, detections, self.match_thresh, owner, fused=True)
        taken = set(owner[owner != UNMATCHED].tolist())
        tracked_left = [i for i in activated if i not in taken and not self.tracks[i].lost]
        self._match(tracked_left, low, detections, 0.5, owner, fused=False)
        self._match(unconfirmed, high[owner[high] == UNMATCHED], detections, 0.7, owner, fused=True)
        updated: set[int] = set()
        for j in np.nonzero(owner != UNMATCHED)[0].tolist():
            self.tracks[owner[j]].update(detections.boxes2d[j], float(detections.scores[j]), detections.embeddings[j],
                                         j, self.alpha)
            updated.add(int(owner[j]))
        kept = []
        for i, track in enumerate(self.tracks):
            if i in updated:
                kept.append(track)
            elif track.confirmed and track.time_since_update <= self.track_buffer:
                track.lost = True
                kept.append(track)  # an unconfirmed track missed once is removed
        self.tracks = kept
        first = self.frame_count == 1
        for j in high[owner[high] == UNMATCHED].tolist():
            if detections.scores[j] >= self.new:
                self.tracks.append(BotSortTrack(self._next_id, detections.boxes2d[j], int(detections.labels[j]),
                                                float(detections.scores[j]), detections.embeddings[j], j,
                                                activated=first))
                self._next_id += 1
        return [LocalTrack(t.track_id, t.box(), t.score, t.label, t.detection)
                for t in self.tracks if t.confirmed and t.time_since_update == 0]


def botsort(*, track_high_thresh: float = 0.6, track_low_thresh: float = 0.1, new_track_thresh: float = 0.7,
            match_thresh: float = 0.8, proximity_thresh: float = 0.5, appearance_thresh: float = 0.25,
            track_buffer: int = 10, alpha: float = 0.9, motion_compensation: bool = True,
            cameras: str = "") -> PerCameraTracking:
    """BoT-SORT-style tracking on every camera of the rig (or on the comma-separated ``cameras``), each camera on
    its own, with camera-motion compensation from the ego motion unless ``motion_compensation`` is off."""
    if motion_compensation not in (True, False):  # 1 and 0 compare equal to them
        raise ValueError(f"botsort: motion_compensation must be true or false (or 1 / 0), got {motion_compensation!r}")
    return PerCameraTracking(
        lambda: BotSort(track_high_thresh=track_high_thresh, track_low_thresh=track_low_thresh,
                        new_track_thresh=new_track_thresh, match_thresh=match_thresh,
                        proximity_thresh=proximity_thresh, appearance_thresh=appearance_thresh,
                        track_buffer=track_buffer, alpha=alpha),
        tuple(name for name in cameras.split(",") if name) or None,
        motion=_rotation_homographies if motion_compensation else None,
    )
