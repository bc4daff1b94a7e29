"""``polymot``: a strong modern filter baseline — simrig's reading of the CPU filter-based trackers at the top
of the nuScenes tracking leaderboard:

* Poly-MOT — Li, Xie, Liu, Gao, Dai, Jiang, Zhao, Wang: "Poly-MOT: A Polyhedral Framework For 3D Multi-Object
  Tracking", IROS 2023;
* Fast-Poly — Li, Liu, Wu, Wu, Zhao, Gao: "Fast-Poly: A Fast Polyhedral Framework For 3D Multi-Object
  Tracking", IEEE RA-L 2024;
* MCTrack — Wang, Qi, Zhao, Zhou, Zhang, Wang, Tu, Guo, Zhao, Li, Yang: "MCTrack: A Unified 3D Multi-Object
  Tracking Framework for Autonomous Driving", arXiv 2409.16149, 2024 (test AMOTA 0.761, 292 IDS).

What it takes from them, and every choice where simrig had to pick (none of it is tuned on simrig's seeds):

1. **Pre-processing** (Poly-MOT): detections below ``score_threshold`` are dropped, then non-maximum
   suppression on the pooled detections of every camera (3D IoU > ``nms_threshold`` = 0.1, SimpleTrack's
   value), which also folds the two views of an object seen by overlapping cameras into one.
2. **Category-specific motion** (Poly-MOT, Fast-Poly): extended Kalman filters — CTRA for cars, trucks and
   buses, the bicycle-like constant-curvature model for motorcycles (:mod:`.turning_motion`).
3. **Multi-cue cost** (Poly-MOT's multi-cue association, MCTrack's rotated GIoU with a distance term):
   (1 − GIoU_bev) + d²/ρ² + ½ (1 − |cos Δθ|), pre-filtered at 6 m (:class:`~simrig.trackers.cost_models.MultiCueCost`),
   +inf across classes; gate 1.5.
4. **Two-stage association with a score split** (ByteTrack's idea, as Fast-Poly and MCTrack use two stages):
   detections with score ≥ ``score_high`` (0.5) against every track (Hungarian, gate ``gate``); then the
   remaining detections with score ≥ ``score_low`` (0.1) against the tracks still unmatched (gate
   ``second_gate``). A match in either stage *updates* the track (unlike SimpleTrack's keep-alive); only
   stage-1 detections start tracks.
5. **Life** (Poly-MOT's count-based life): a track is reported from its first detection (min_hits 1, as
   AMOTA rewards early output), dies after ``max_age_s`` = 1.0 s without an update (as the other reference
   trackers); while it coasts (no update) it is reported for up to ``coast_s`` = 0.2 s on its prediction
   with its score × ``score_decay`` (0.5) per missed frame (Poly-MOT/Fast-Poly's score decay of predicted
   tracks), so a single missed detection is not a gap.
"""

from __future__ import annotations

import numpy as np

from simrig.types import ActorClass, SensorFrame, Track

from .assignment import UNMATCHED, hungarian
from .detections import LABELS, DetectionArrays, detection_arrays
from .kalman_tracker import KalmanTracker
from .settings import kalman_tracker_parts
from .simpletrack import nms
from .turning_motion import BICYCLE, CTRA

MOTION_BY_CLASS = {ActorClass.CAR: CTRA, ActorClass.TRUCK: CTRA, ActorClass.BUS: CTRA,
                   ActorClass.MOTORCYCLE: BICYCLE, ActorClass.BICYCLE: BICYCLE, ActorClass.PEDESTRIAN: CTRA}
"""The motion model of each class (module docstring, 2; Poly-MOT gives bicycles the bicycle model; pedestrians,
which simrig's traffic never makes, get CTRA here)."""
NO_BIRTH = -2


class PolyMot(KalmanTracker):
    """See the module docstring. nms_threshold [-]; score_high, score_low: the score split [-];
    second_gate: stage 2's gate on the multi-cue cost; coast_s [s] and score_decay [-]: reporting of coasting
    tracks."""

    def __init__(self, *, nms_threshold: float, score_high: float, score_low: float, second_gate: float,
                 coast_s: float, score_decay: float, **kw):
        super().__init__(assign=hungarian, **kw)
        if not 0 <= score_low <= score_high <= 1 or not 0 <= nms_threshold <= 1 or not 0 <= score_decay <= 1:
            raise ValueError("polymot: need 0 ≤ score_low ≤ score_high ≤ 1 and nms_threshold, score_decay in "
                             f"[0, 1]; got {score_low}, {score_high}, {nms_threshold}, {score_decay}")
        if second_gate <= 0 or coast_s < 0:
            raise ValueError(f"polymot: need second_gate > 0 and coast_s ≥ 0; got {second_gate}, {coast_s}")
        self.nms_threshold, self.score_high, self.score_low = nms_threshold, score_high, score_low
        self.second_gate, self.coast_s, self.score_decay = second_gate, coast_s, score_decay
        self._dt = 0.1

    def motion_model(self, label: int):
        return MOTION_BY_CLASS[LABELS[label]]

    def select(self, detections: DetectionArrays) -> DetectionArrays:
        detections = super().select(detections)
        return detections.take(nms(detections, self.nms_threshold))

    def associate(self, detections: DetectionArrays) -> np.ndarray:
        owner = np.full(len(detections), UNMATCHED, dtype=np.int64)
        if not self.tracks or len(detections) == 0:
            return owner
        cost = self.cost_matrix(detections)
        high = np.nonzero(detections.scores >= self.score_high)[0]
        if len(high):
            owner[high] = hungarian(cost[:, high], self.cost.gate)
        waiting = np.setdiff1d(np.arange(len(self.tracks)), owner[owner != UNMATCHED])
        low = np.nonzero((owner == UNMATCHED) & (detections.scores >= self.score_low))[0]
        if len(waiting) and len(low):
            second = hungarian(cost[np.ix_(waiting, low)], self.second_gate)
            matched = second != UNMATCHED
            owner[low[matched]] = waiting[second[matched]]
        return owner

    def births(self, detections: DetectionArrays, owner: np.ndarray) -> None:
        low = detections.scores < self.score_high
        super().births(detections, np.where(low & (owner == UNMATCHED), NO_BIRTH, owner))

    def step(self, frame: SensorFrame) -> list[Track]:
        detections = self.select(detection_arrays(frame))
        dt = self.clock.advance(frame)
        self._now = frame.timestamp
        if dt > 0:
            self._dt = dt
        self.step_arrays(detections, dt)
        out = []
        for track in self.tracks:
            if self.life.is_reported(track.life):
                out.append(track.output())
            elif 0 < track.life.since_update <= self.coast_s + 1e-9 and track.life.hits >= self.life.min_hits:
                missed = round(track.life.since_update / self._dt)
                report = track.output()
                out.append(Track(report.track_id, report.label, report.score * self.score_decay ** missed,
                                 report.box3d))
        return out


def polymot(
    *,
    gate: float = 1.5,
    second_gate: float = 1.5,
    max_distance: float = 6.0,
    heading_weight: float = 0.5,
    nms_threshold: float = 0.1,
    score_high: float = 0.5,
    score_low: float = 0.1,
    min_hits: int = 1,
    max_age_s: float = 1.0,
    coast_s: float = 0.2,
    score_decay: float = 0.5,
    score_threshold: float = 0.01,
    measurement_variance: float = 1.0,
    motion_compensation: bool = True,
) -> PolyMot:
    """The modern filter baseline (module docstring). gate, second_gate: the two stages' gates on the
    multi-cue cost; max_distance [m], heading_weight: the cost's pre-filter and heading cue; the rest as in the
    module docstring and for ``saga``.
    motion_compensation: tracks predicted to each detection's capture time (off: every detection taken at the
    frame's time)."""
    return PolyMot(
        **kalman_tracker_parts(cost="multicue", gate=gate, life="hits", min_hits=min_hits, max_age_s=max_age_s,
                               measurement_variance=measurement_variance, score_threshold=score_threshold,
                               motion_compensation=motion_compensation,
                               max_distance=float(max_distance), heading_weight=float(heading_weight)),
        nms_threshold=float(nms_threshold),
        score_high=float(score_high),
        score_low=float(score_low),
        second_gate=float(second_gate),
        coast_s=float(coast_s),
        score_decay=float(score_decay),
    )
