"""SAGA-Track (Nguyen et al., arXiv 2022, §3.2): one global association of world-frame tracks with every
camera's detections.

The four steps, one frame: (1) predict every track with a constant-velocity Kalman filter; (2) cost of every
track against every detection of every camera in the world frame (Mahalanobis, Eq. 4, by default);
(3) one-to-many FOTA assignment (Eq. 6–15); (4) update each track with all detections assigned to it.
"""

from __future__ import annotations

import numpy as np

from .assignment import UNMATCHED
from .detections import DetectionArrays
from .fota import GAMMA, ITERATIONS, fota
from .kalman_tracker import KalmanTracker
from .settings import kalman_tracker_parts


class SagaTrack(KalmanTracker):
    """The Kalman coordinator with FOTA as its assignment. gamma, iterations, track_mass: FOTA's γ, T and
    track mass; one_per_camera: a track takes at most one detection of each camera per frame (enforced in
    FOTA's decoding, :func:`~simrig.trackers.fota.fota`)."""

    def __init__(self, *, gamma: float, iterations: int, track_mass: float, one_per_camera: bool, **kw):
        super().__init__(assign=self._unused, **kw)
        self.fota_params = {"gamma": float(gamma), "iterations": int(iterations), "track_mass": float(track_mass)}
        self.one_per_camera = bool(one_per_camera)

    @staticmethod
    def _unused(cost, gate):  # pragma: no cover - associate() below calls fota directly
        raise AssertionError("SagaTrack assigns with fota(), not with an assigner")

    def associate(self, detections: DetectionArrays) -> np.ndarray:
        if not self.tracks or len(detections) == 0:
            return np.full(len(detections), UNMATCHED, dtype=np.int64)
        cameras = detections.cameras if self.one_per_camera else None
        return fota(self.cost_matrix(detections), self.cost.gate, cameras=cameras, **self.fota_params).owner


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
    motion_compensation: bool = True,
    one_per_camera: bool = True,
) -> SagaTrack:
    """SAGA-Track with FOTA. cost: a name from :data:`~simrig.trackers.cost_models.COST_MODELS`; gate: its gate
    (model default when None); gamma, iterations, track_mass: FOTA's γ, T and track mass; life: ``hits``
    or ``mutr3d``; min_hits, max_age_s: the ``hits`` rule; birth_merge_m [m]: detections of one new object
    from two cameras start one track; duplicate_iou: tracks overlapping by this BEV IoU are one object, the
    younger is dropped; measurement_variance: the filter's R [m², rad²]; one_per_camera: a track takes at most
    one detection per camera per frame (physics: on by default; off reproduces unconstrained FOTA decoding).
    ``birth_merge_m=0, duplicate_iou=0`` is pure FOTA (no birth merge, no duplicate rule).
    motion_compensation: tracks predicted to each detection's capture time (off: every detection taken at the
    frame's time)."""
    return SagaTrack(
        **kalman_tracker_parts(cost=cost, gate=gate, life=life, min_hits=min_hits, max_age_s=max_age_s,
                               measurement_variance=measurement_variance, score_threshold=score_threshold,
                               motion_compensation=motion_compensation),
        gamma=gamma, iterations=iterations, track_mass=track_mass, one_per_camera=one_per_camera,
        birth_merge_m=float(birth_merge_m),
        duplicate_iou=float(duplicate_iou),
    )
