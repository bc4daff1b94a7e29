"""Association costs by name, each with the gate that decides whether a pair may match at all.

A cost model maps predicted tracks (their boxes ẑ (N, 7) and innovation covariances S (N, 7, 7)) and
detections (M, ≥7) to a cost matrix (N, M), lower is better; a pair matches only if its cost ≤ ``gate``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .costs import bev_corners, bev_distance, enlarged, iou, mahalanobis, overlaps


@dataclass(frozen=True)
class MahalanobisCost:
    """Eq. 4 with the filter's S; gate in standard deviations [-] (√χ²₇: 99.9 % of true pairs ≤ 4.9)."""

    gate: float = 5.0

    def __call__(self, predicted: np.ndarray, innovation: np.ndarray, detections: np.ndarray) -> np.ndarray:
        return mahalanobis(predicted, innovation, detections)


@dataclass(frozen=True)
class GiouCost:
    """1 − GIoU (Eq. 5) of rotated boxes, in 3D or bird's-eye view; gate 1.5 means GIoU ≥ −0.5
    (SimpleTrack's nuScenes setting). ``enlarge`` scales the predicted boxes' sizes first."""

    gate: float = 1.5
    bev: bool = False
    enlarge: float = 1.0

    def __call__(self, predicted: np.ndarray, innovation: np.ndarray, detections: np.ndarray) -> np.ndarray:
        _, giou = overlaps(enlarged(predicted, self.enlarge), detections, bev=self.bev, floor=1.0 - self.gate)
        return 1.0 - giou


@dataclass(frozen=True)
class IouCost:
    """1 − IoU of rotated 3D boxes; ``enlarge`` 1.2 is MUTR3D's basic baseline (predicted boxes 20 % larger
    before IoU, for low frame rates). Gate 0.9 means IoU ≥ 0.1."""

    gate: float = 0.9
    enlarge: float = 1.2

    def __call__(self, predicted: np.ndarray, innovation: np.ndarray, detections: np.ndarray) -> np.ndarray:
        return 1.0 - iou(enlarged(predicted, self.enlarge), detections)


@dataclass(frozen=True)
class DistanceCost:
    """Bird's-eye-view centre distance [m]; gate in metres."""

    gate: float = 2.0

    def __call__(self, predicted: np.ndarray, innovation: np.ndarray, detections: np.ndarray) -> np.ndarray:
        return bev_distance(predicted, detections)


@dataclass(frozen=True)
class MultiCueCost:
    """Geometry, distance and heading in one cost, for the modern filter baseline (after Poly-MOT's multi-cue
    association and MCTrack's Ro_GDIoU: a rotated GIoU with DIoU's distance term):

        C = (1 − GIoU_bev) + d² / ρ² + heading_weight · (1 − |cos Δθ|)

    with d the footprint centres' distance and ρ the diagonal of the axis-aligned rectangle enclosing both
    footprints (DIoU's normalisation, so the distance term is in [0, 1)); |cos Δθ| makes a box facing backwards
    as good as one facing forwards. Pairs whose centres are more than ``max_distance`` [m] apart are never
    compared (+inf), as Poly-MOT's pre-filter. Gate 1.5 on C."""

    gate: float = 1.5
    max_distance: float = 6.0
    heading_weight: float = 0.5

    def __call__(self, predicted: np.ndarray, innovation: np.ndarray, detections: np.ndarray) -> np.ndarray:
        _, giou = overlaps(predicted, detections, bev=True, floor=1.0 - self.gate)
        corners_t, corners_d = bev_corners(predicted), bev_corners(detections)
        low = np.minimum(corners_t.min(axis=1)[:, None, :], corners_d.min(axis=1)[None, :, :])
        high = np.maximum(corners_t.max(axis=1)[:, None, :], corners_d.max(axis=1)[None, :, :])
        rho2 = np.sum((high - low) ** 2, axis=-1)
        d = bev_distance(predicted, detections)
        heading = 1.0 - np.abs(np.cos(predicted[:, None, 6] - detections[None, :, 6]))
        cost = (1.0 - giou) + d * d / np.maximum(rho2, 1e-12) + self.heading_weight * heading
        return np.where(d <= self.max_distance, cost, np.inf)


COST_MODELS = {
    "mahalanobis": MahalanobisCost,
    "giou3d": GiouCost,
    "giou_bev": lambda **kw: GiouCost(bev=True, **kw),
    "iou3d": IouCost,
    "distance": DistanceCost,
    "multicue": MultiCueCost,
}
"""Cost models by the name a tracker's ``cost`` parameter takes; keyword arguments go to the model."""


def cost_model(name: str, **params):
    """The cost model ``name`` built with ``params``; a ``ValueError`` naming the known ones otherwise."""
    try:
        factory = COST_MODELS[name]
    except KeyError:
        raise ValueError(f"unknown cost {name!r}; known: {', '.join(COST_MODELS)}") from None
    return factory(**params)
