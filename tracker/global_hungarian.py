"""AB3DMOT-style global baseline: every camera's detections pooled, one-to-one assignment (Hungarian by
default, greedy optional), every unmatched detection starts a track. MUTR3D's basic baseline is
``cost='iou3d'`` (predicted boxes enlarged by ``enlarge`` = 1.2 before 3D IoU)."""

from __future__ import annotations

from .assignment import greedy, hungarian
from .kalman_tracker import KalmanTracker
from .settings import kalman_tracker_parts

ASSIGNERS = {"hungarian": hungarian, "greedy": greedy}


def global_hungarian(
    *,
    cost: str = "mahalanobis",
    gate: float | None = None,
    enlarge: float | None = None,
    assignment: str = "hungarian",
    life: str = "hits",
    min_hits: int = 1,
    max_age_s: float = 1.0,
    score_threshold: float = 0.0,
    duplicate_iou: float = 0.0,
    measurement_variance: float = 1.0,
    motion_compensation: bool = True,
) -> KalmanTracker:
    """cost, gate: as for ``saga`` (the same defaults, so the two differ only in the assignment);
    enlarge: box scale before IoU/GIoU (``iou3d``/``giou*`` costs only); assignment: ``hungarian`` or
    ``greedy``; duplicate_iou: off by default (AB3DMOT has no such rule), on for an ablation; the rest as
    for ``saga``.
    motion_compensation: tracks predicted to each detection's capture time (off: every detection taken at the
    frame's time)."""
    if assignment not in ASSIGNERS:
        raise ValueError(f"unknown assignment {assignment!r}; known: {', '.join(ASSIGNERS)}")
    extra = {} if enlarge is None else {"enlarge": float(enlarge)}
    return KalmanTracker(
        **kalman_tracker_parts(cost=cost, gate=gate, life=life, min_hits=min_hits, max_age_s=max_age_s,
                               measurement_variance=measurement_variance, score_threshold=score_threshold,
                               motion_compensation=motion_compensation, **extra),
        assign=ASSIGNERS[assignment],
        duplicate_iou=float(duplicate_iou),
    )
