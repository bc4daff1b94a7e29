"""Association costs by name, each with the gate that decides whether a pair may match at all.

A cost model maps predicted tracks (their boxes ẑ (N, 7) and innovation covariances S (N, 7, 7)) and
detections (M, ≥7) to a cost matrix (N, M), lower is better; a pair matches only if its cost ≤ ``gate``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .costs import bev_distance, enlarged, mahalanobis, overlaps


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
        iou, _ = overlaps(enlarged(predicted, self.enlarge), detections, floor=None if self.gate >= 1 else 0.0)
        return 1.0 - iou


@dataclass(frozen=True)
class DistanceCost:
    """Bird's-eye-view centre distance [m]; gate in metres."""

    gate: float = 2.0

    def __call__(self, predicted: np.ndarray, innovation: np.ndarray, detections: np.ndarray) -> np.ndarray:
        return bev_distance(predicted, detections)


COST_MODELS = {
    "mahalanobis": MahalanobisCost,
    "giou3d": GiouCost,
    "giou_bev": lambda **kw: GiouCost(bev=True, **kw),
    "iou3d": IouCost,
    "distance": DistanceCost,
}
"""Cost models by the name a tracker's ``cost`` parameter takes; keyword arguments go to the model."""


def cost_model(name: str, **params):
    """The cost model ``name`` built with ``params``; a ``ValueError`` naming the known ones otherwise."""
    try:
        factory = COST_MODELS[name]
    except KeyError:
        raise ValueError(f"unknown cost {name!r}; known: {', '.join(COST_MODELS)}") from None
    return factory(**params)
