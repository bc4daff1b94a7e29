"""The "global baseline" of SAGA-Track's comparison: a tracker per camera, then heuristic merging.

Each camera runs its own Kalman tracker (one-to-one Hungarian on that camera's detections). Each frame the
cameras' reported tracks are merged: tracks of one class from different cameras whose bird's-eye-view IoU
is at least ``merge_iou`` are joined (transitively) into one global object; its box is the score-weighted
mean of the members' boxes (yaw from the best-scored member) and its score the best member's. Global ids
follow per-camera tracks: a (camera, local id) keeps the global id it was last merged under; a group takes
the oldest (smallest) global id among its members that no other group has taken this frame, else a new id.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from simrig.types import ActorClass, Box3D, Rig, SensorFrame, Track

from .assignment import hungarian
from .clock import FrameClock
from .costs import iou
from .detections import LABELS, detection_arrays
from .kalman_tracker import KalmanTracker
from .settings import kalman_tracker_parts


class PerCameraMerge:
    """See the module docstring. ``make_camera_tracker()`` builds one camera's tracker."""

    def __init__(self, make_camera_tracker, merge_iou: float):
        if not 0 < merge_iou <= 1:
            raise ValueError(f"merge_iou must be in (0, 1], got {merge_iou}")
        self.make_camera_tracker = make_camera_tracker
        self.merge_iou = merge_iou
        self.cameras: list[KalmanTracker] = []
        self.global_ids: dict[tuple[int, int], int] = {}
        self._next_id = 1
        self.clock = FrameClock()

    def reset(self, *, rig: Rig, seed: int | None = None) -> None:
        self.cameras = [self.make_camera_tracker() for _ in rig.cameras]
        self.global_ids = {}
        self._next_id = 1
        self.clock.reset()

    def step(self, frame: SensorFrame) -> list[Track]:
        if len(self.cameras) != len(frame.rig.cameras):
            raise ValueError(f"frame {frame.frame}: rig has {len(frame.rig.cameras)} cameras but the tracker was "
                             f"reset for {len(self.cameras)}; call reset(rig=...) first")
        detections = detection_arrays(frame)
        dt = self.clock.advance(frame)
        members = []  # (camera, KalmanTrack)
        for camera, tracker in enumerate(self.cameras):
            tracker.step_arrays(tracker.select(detections.take(detections.cameras == camera)), dt)
            members.extend((camera, t) for t in tracker.tracks if tracker.life.is_reported(t.life))
        return self._merge(members)

    def _merge(self, members) -> list[Track]:
        if not members:
            return []
        boxes = np.stack([t.kf.x[:9, 0] for _, t in members])
        cameras = np.array([c for c, _ in members])
        labels = np.array([t.label for _, t in members])
        scores = np.array([t.life.score for _, t in members])
        linked = ((iou(boxes, boxes, bev=True) >= self.merge_iou) & (cameras[:, None] != cameras[None, :])
                  & (labels[:, None] == labels[None, :]))
        count, group = connected_components(csr_matrix(linked), directed=False)
        keys = [(c, t.track_id) for c, t in members]
        taken: set[int] = set()
        tracks = []
        order = sorted(range(count), key=lambda g: min(
            (self.global_ids.get(keys[k], np.inf) for k in np.nonzero(group == g)[0]), default=np.inf))
        for g in order:
            rows = np.nonzero(group == g)[0]
            known = sorted({self.global_ids[keys[k]] for k in rows if keys[k] in self.global_ids} - taken)
            if known:
                gid = known[0]
            else:
                gid = self._next_id
                self._next_id += 1
            taken.add(gid)
            for k in rows:
                self.global_ids[keys[k]] = gid
            weights = scores[rows] / max(scores[rows].sum(), 1e-12) if scores[rows].sum() > 0 else None
            mean = np.average(boxes[rows], axis=0, weights=weights)
            best = rows[np.argmax(scores[rows])]
            mean[6] = boxes[best, 6]
            tracks.append(Track(track_id=gid, label=ActorClass(LABELS[labels[best]]), score=float(scores[best]),
                                box3d=Box3D(*(float(v) for v in mean))))
        return tracks


def percam_merge(
    *,
    cost: str = "mahalanobis",
    gate: float | None = None,
    merge_iou: float = 0.1,
    life: str = "hits",
    min_hits: int = 1,
    max_age_s: float = 1.0,
    score_threshold: float = 0.0,
    measurement_variance: float = 1.0,
) -> PerCameraMerge:
    """merge_iou: BEV IoU at which two cameras' tracks are one object [-]; the rest as for
    ``global_hungarian`` (each camera's tracker is one)."""
    def camera_tracker() -> KalmanTracker:
        return KalmanTracker(
            **kalman_tracker_parts(cost=cost, gate=gate, life=life, min_hits=min_hits, max_age_s=max_age_s,
                                   measurement_variance=measurement_variance, score_threshold=score_threshold),
            assign=hungarian,
        )

    camera_tracker()  # check the settings now, not at reset
    return PerCameraMerge(camera_tracker, float(merge_iou))
