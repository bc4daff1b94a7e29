"""SAGA-Track (seed 000, §3.2): one global association of world-frame tracks with every camera's detections.

The four steps, one frame: (1) predict every track with a constant-velocity Kalman filter; (2) cost of every
track against every detection of every camera in the world frame (Mahalanobis, Eq. 4, by default);
(3) one-to-many FOTA assignment (Eq. 6–15); (4) update each track with all detections assigned to it.
"""

from __future__ import annotations

from functools import partial

from .fota import GAMMA, ITERATIONS, fota
from .kalman_tracker import KalmanTracker
from .settings import kalman_tracker_parts


def _fota_owner(cost, gate, **params):
    return fota(cost, gate, **params).owner


def saga(
    *,
    cost: str = "mahalanobis",
    gate: float | None = None,
    gamma: float = GAMMA,
    iterations: int = ITERATIONS,
    track_mass: float = 2.0,
    life: str = "hits",
    min_hits: int = 1,
    max_age_s: float = 1.0,
    score_threshold: float = 0.0,
    birth_merge_m: float = 3.0,
    duplicate_iou: float = 0.3,
    measurement_variance: float = 1.0,
) -> KalmanTracker:
    """SAGA-Track with FOTA. cost: a name from :data:`~tracker.cost_models.COST_MODELS`; gate: its gate
    (model default when None); gamma, iterations, track_mass: FOTA's γ, T and track mass; life: ``hits``
    or ``mutr3d``; min_hits, max_age_s: the ``hits`` rule; birth_merge_m [m]: detections of one new object
    from two cameras start one track; duplicate_iou: tracks overlapping by this BEV IoU are one object, the
    younger is dropped; measurement_variance: the filter's R [m², rad²]."""
    return KalmanTracker(
        **kalman_tracker_parts(cost=cost, gate=gate, life=life, min_hits=min_hits, max_age_s=max_age_s,
                               measurement_variance=measurement_variance, score_threshold=score_threshold),
        assign=partial(_fota_owner, gamma=float(gamma), iterations=int(iterations), track_mass=float(track_mass)),
        birth_merge_m=float(birth_merge_m),
        duplicate_iou=float(duplicate_iou),
    )
