"""A MUTR3D-style projection tracker: the non-learned core of MUTR3D's 3D-to-2D queries.

After Zhang, Chen, Wang, Zhao, "MUTR3D: A Multi-camera Tracking Framework via 3D-to-2D Queries" (CVPR
Workshops 2022). MUTR3D keeps one query per object in 3D, projects its reference point into every camera
(Eq. 4) and gathers that camera's image features there; the query is updated from all the cameras it was seen
in, and lives and dies by its score (§3.4). Without the learned decoder, the same structure is:

1. predict every 3D track (constant-velocity Kalman filter in the world frame, so the ego-motion update of
   Eq. 7 is the identity here);
2. project each track's predicted box into every camera (:func:`simrig.geometry.project_boxes`: the clipped
   silhouette's bounding box, as the detector's 2D boxes are drawn);
3. in each camera, associate the tracks whose predicted box projects into it with that camera's detections —
   by default with the 3D Mahalanobis distance under the filter's uncertainty (``cost2d="mahalanobis"``, gate
   5σ), or *in the image* with 1 − IoU (``cost2d="iou"``, gate 0.9: IoU ≥ 0.1) or the centre distance over the
   projected box's diagonal (``cost2d="centre"``, gate 0.5) — one Hungarian per camera, so a track takes at most
   one detection per camera. MUTR3D has no gate (a learned decoder reads the image features where the query
   projects); a fixed image gate stood in for it until measurement showed it was what made this tracker switch
   identities most: a far car's monocular 3D box projects onto its own 2D box with a median IoU of 0.24 at
   ≤ 20 px, so IoU ≥ 0.1 rejected 24 % of the true pairs, the track died and was reborn under a new id
   (``reports/trackers/mutr3d.md``). The image costs stay as options;
4. update each track in 3D with the 3D boxes of the detections every camera matched to it (sequential
   updates, as the other Kalman trackers); its velocity is then the velocity its best-scored matched detection
   carries, when it carries one: MUTR3D moves a query's reference point with the velocity the network predicts
   from the image (Eq. 7, "velocity predicted from queries", not a Kalman filter's estimate from positions), and
   the detector's velocity stands in for that prediction here. A filter fed positions alone lags a braking car
   by several m/s (``reports/velocity_lag/``);
5. life: MUTR3D's query life management (:class:`~simrig.trackers.life.QueryLife`): start at score ≥ τ_new = 0.4,
   die after T = 5 successive frames below τ_old = 0.35 (``life="mutr3d"``, §3.4) or by the public code's
   count (``life="mutr3d_code"``), reported while the frame's score ≥ τ_old. Unmatched detections of one
   new object seen by two cameras start one track (``birth_merge_m``).

A track whose predicted box is in no camera's view cannot be matched (as a MUTR3D query whose reference point
projects outside every image gathers no features) and ages by its life rule.
"""

from __future__ import annotations

import numpy as np

from simrig.geometry import project_boxes
from simrig.types import SensorFrame, Track

from .assignment import UNMATCHED, hungarian
from .boxes2d import iou
from .cost_models import MahalanobisCost
from .detections import DetectionArrays
from .kalman_tracker import KalmanTracker
from .settings import build_kalman, build_life

COSTS_2D = {"mahalanobis": 5.0, "iou": 0.9, "centre": 0.5}
"""The per-camera costs and their default gates (Mahalanobis in standard deviations, the image costs in their
units)."""


def _centre_distance(projected: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(N, M) distance between box centres over the projected box's diagonal [-].

    >>> _centre_distance(np.array([[0.0, 0.0, 30.0, 40.0]]), np.array([[10.0, 0.0, 40.0, 40.0]])).tolist()
    [[0.2]]
    """
    pc = (projected[:, None, :2] + projected[:, None, 2:]) / 2
    dc = (boxes[None, :, :2] + boxes[None, :, 2:]) / 2
    diagonal = np.hypot(projected[:, 2] - projected[:, 0], projected[:, 3] - projected[:, 1])[:, None]
    return np.hypot(*(pc - dc).transpose(2, 0, 1)) / np.maximum(diagonal, 1e-9)


class Mutr3dTracker(KalmanTracker):
    """See the module docstring. cost2d: ``mahalanobis``, ``iou`` or ``centre``; gate2d: its gate (default per
    :data:`COSTS_2D`)."""

    def __init__(self, *, cost2d: str, gate2d: float | None, **kw):
        super().__init__(cost=None, assign=hungarian, **kw)
        if cost2d not in COSTS_2D:
            raise ValueError(f"unknown cost2d {cost2d!r}; known: {', '.join(COSTS_2D)}")
        self.cost2d = cost2d
        self.gate2d = COSTS_2D[cost2d] if gate2d is None else float(gate2d)
        if cost2d == "mahalanobis":
            self.cost = MahalanobisCost(gate=self.gate2d)
        if not self.gate2d > 0:
            raise ValueError(f"gate2d must be positive, got {gate2d}")
        self._frame: SensorFrame | None = None

    def step(self, frame: SensorFrame) -> list[Track]:
        self._frame = frame
        return super().step(frame)

    def image_costs(self, detections: DetectionArrays) -> list[tuple[np.ndarray, np.ndarray]]:
        """Per camera of the rig: (detection rows of that camera, (N, m) cost of every track against them),
        +inf where the track is out of that camera's view or of another class."""
        frame = self._frame
        predicted = np.stack([track.kf.x[:7, 0] for track in self.tracks])
        projected = project_boxes(predicted, frame.rig, frame.ego).boxes  # (C, N, 4), NaN out of view
        labels = np.array([track.label for track in self.tracks])
        mahalanobis = self.cost_matrix(detections) if self.cost2d == "mahalanobis" else None  # (N, M)
        out = []
        for camera in range(len(frame.rig.cameras)):
            rows = np.nonzero(detections.cameras == camera)[0]
            if len(rows) == 0:
                continue
            boxes = projected[camera]
            seen = np.isfinite(boxes).all(axis=1)
            cost = np.full((len(self.tracks), len(rows)), np.inf)
            if seen.any():
                mine = detections.boxes2d[rows]
                if mahalanobis is not None:
                    cost[seen] = mahalanobis[np.ix_(seen, rows)]
                elif self.cost2d == "iou":
                    cost[seen] = 1.0 - iou(boxes[seen], mine)
                else:
                    cost[seen] = _centre_distance(boxes[seen], mine)
            cost[labels[:, None] != detections.labels[rows][None, :]] = np.inf
            out.append((rows, cost))
        return out

    def update(self, detections: DetectionArrays, owner: np.ndarray) -> dict[int, float]:
        """The Kalman update of every matched track, then its velocity [m/s, world frame] set to its best-scored
        matched detection's, where that detection has one (module docstring, step 4)."""
        scores = super().update(detections, owner)
        velocities = detections.boxes3d[:, 7:9] if detections.boxes3d.shape[1] >= 9 else None
        if velocities is None:
            return scores
        taken: set[int] = set()
        for j in np.lexsort((np.arange(len(owner)), -detections.scores)):  # highest score first
            i = int(owner[j])
            if i != UNMATCHED and i not in taken and np.isfinite(velocities[j]).all():
                taken.add(i)
                self.tracks[i].kf.x[7:9, 0] = velocities[j]
        return scores

    def associate(self, detections: DetectionArrays) -> np.ndarray:
        """owner (M,): per camera, a Hungarian between the projected tracks and that camera's detections."""
        owner = np.full(len(detections), UNMATCHED, dtype=np.int64)
        if not self.tracks or len(detections) == 0:
            return owner
        for rows, cost in self.image_costs(detections):
            owner[rows] = hungarian(cost, self.gate2d)
        return owner


def mutr3d(
    *,
    cost2d: str = "mahalanobis",
    gate2d: float | None = None,
    life: str = "mutr3d",
    min_hits: int = 1,
    max_age_s: float = 1.0,
    score_threshold: float = 0.0,
    birth_merge_m: float = 3.0,
    measurement_variance: float = 1.0,
    motion_compensation: bool = True,
) -> Mutr3dTracker:
    """MUTR3D-style projection tracker (module docstring). cost2d, gate2d: the per-camera cost (``mahalanobis``,
    ``iou``, ``centre``) and its gate; life: ``mutr3d`` (§3.4, default), ``mutr3d_code`` (public code) or ``hits``
    (then min_hits, max_age_s apply); birth_merge_m [m]: detections of one new object from two cameras start one track;
    measurement_variance: the filter's R [m², rad²]; motion_compensation: tracks predicted to each detection's capture
    time (:class:`~simrig.trackers.kalman_tracker.KalmanTracker`)."""
    return Mutr3dTracker(
        cost2d=cost2d,
        gate2d=gate2d,
        life=build_life(life, min_hits=min_hits, max_age_s=max_age_s),
        kalman=build_kalman(measurement_variance),
        score_threshold=float(score_threshold),
        birth_merge_m=float(birth_merge_m),
        motion_compensation=bool(motion_compensation),
    )
