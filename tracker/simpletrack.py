"""SimpleTrack-style tracker (tusen-ai/SimpleTrack, nuScenes settings; MUTR3D's GIoU Kalman baseline).

3D GIoU cost with Hungarian assignment (match if GIoU ≥ −0.5), NMS on the pooled detections (3D IoU 0.1,
which also removes most duplicates from overlapping cameras), and two-stage association: detections with
score ≥ ``score_high`` update and start tracks; a track left unmatched that still finds an unused
detection with score > ``score_low`` within the gate is kept alive on its own prediction (not updated) and
reported with its score × ``score_decay``.
"""

from __future__ import annotations

import numpy as np

from .assignment import UNMATCHED, hungarian
from .costs import iou
from .detections import DetectionArrays
from .kalman_tracker import KalmanTracker
from .settings import kalman_tracker_parts


def nms(detections: DetectionArrays, threshold: float) -> np.ndarray:
    """Indices of the detections kept by greedy non-maximum suppression, best score first: a detection is
    dropped when its 3D IoU with a kept detection of the same class exceeds ``threshold``."""
    order = np.lexsort((np.arange(len(detections)), -detections.scores))
    if len(order) == 0:
        return order
    same = detections.labels[:, None] == detections.labels[None, :]
    suppress = (iou(detections.boxes3d, detections.boxes3d) > threshold) & same
    kept: list[int] = []
    removed = np.zeros(len(detections), dtype=bool)
    for j in order.tolist():
        if removed[j]:
            continue
        kept.append(j)
        removed |= suppress[j]
    return np.array(kept, dtype=np.int64)


class SimpleTrack(KalmanTracker):
    """See the module docstring. nms_threshold: 3D IoU above which the weaker of two detections is
    dropped [-]; score_high, score_low: the two stages' score thresholds [-]; score_decay: factor on a
    kept-alive track's score per frame [-]."""

    def __init__(self, *, nms_threshold: float, score_high: float, score_low: float, score_decay: float, **kw):
        super().__init__(**kw)
        if not 0 <= score_low <= score_high <= 1 or not 0 <= score_decay <= 1 or not 0 <= nms_threshold <= 1:
            raise ValueError("simpletrack: need 0 ≤ score_low ≤ score_high ≤ 1 and score_decay, nms_threshold "
                             f"in [0, 1]; got {score_low}, {score_high}, {score_decay}, {nms_threshold}")
        self.nms_threshold, self.score_high, self.score_low, self.score_decay = (
            nms_threshold, score_high, score_low, score_decay)

    def select(self, detections: DetectionArrays) -> DetectionArrays:
        detections = super().select(detections)
        return detections.take(nms(detections, self.nms_threshold))

    def associate(self, detections: DetectionArrays) -> np.ndarray:
        owner = np.full(len(detections), UNMATCHED, dtype=np.int64)
        high = np.nonzero(detections.scores >= self.score_high)[0]
        if self.tracks and len(high):
            owner[high] = self.assign(self.cost_matrix(detections.take(high)), self.cost.gate)
        return owner

    def births(self, detections: DetectionArrays, owner: np.ndarray) -> None:
        low = detections.scores < self.score_high
        super().births(detections, np.where(low, -2, owner))  # −2: never starts a track

    def keep_alive(self, detections: DetectionArrays, owner: np.ndarray, updated: dict[int, float]) -> None:
        waiting = [i for i in range(len(self.tracks)) if i not in updated]
        spare = np.nonzero((owner == UNMATCHED) & (detections.scores > self.score_low))[0]
        if not waiting or len(spare) == 0:
            return
        cost = self.cost_matrix(detections.take(spare), [self.tracks[i] for i in waiting])
        second = self.assign(cost, self.cost.gate)
        for row in second[second != UNMATCHED].tolist():
            life = self.tracks[waiting[row]].life
            life.since_update = 0.0
            life.score *= self.score_decay


def simpletrack(
    *,
    gate: float = 1.5,
    nms_threshold: float = 0.1,
    score_high: float = 0.5,
    score_low: float = 0.1,
    score_decay: float = 0.01,
    life: str = "hits",
    min_hits: int = 0,
    max_age_s: float = 1.0,
    score_threshold: float = 0.01,
    measurement_variance: float = 1.0,
    motion_compensation: bool = True,
) -> SimpleTrack:
    """gate: on 1 − GIoU (1.5: GIoU ≥ −0.5); the rest as in the module docstring and for ``saga``.
    motion_compensation: tracks predicted to each detection's capture time (off: every detection taken at the
    frame's time)."""
    return SimpleTrack(
        **kalman_tracker_parts(cost="giou3d", gate=gate, life=life, min_hits=min_hits, max_age_s=max_age_s,
                               measurement_variance=measurement_variance, score_threshold=score_threshold,
                               motion_compensation=motion_compensation),
        assign=hungarian,
        nms_threshold=float(nms_threshold),
        score_high=float(score_high),
        score_low=float(score_low),
        score_decay=float(score_decay),
    )
