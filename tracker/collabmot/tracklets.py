"""CollabMOT's tracklet record (Ninh and Kim, IEEE Access 2024, §III) and its appearance EMA (Eq. 3-4).

A tracklet is one single-camera tracker's track, seen from CollabMOT: its pixel boxes by frame, the
appearance feature f̃, its global id 𝒢 (−1 while it has none) and minS, the cost of its current inter-camera
link (∞ while it has none).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

NO_ID = -1
"""𝒢 of a tracklet that has no global id."""


@dataclass(eq=False)
class Tracklet:
    """camera: ``"ego"`` or ``"remote"``; local_id: the single-camera tracker's id; label: class code;
    boxes: frame → ``(4,)`` pixel box [px]; scores: frame → confidence; feature: the EMA appearance vector
    (``None`` until a box qualified); global_id: 𝒢 (−1: none); min_cost: minS; partner: the tracklet of the
    other camera it was last linked with; ids: frame → the global id it carried when reported (−1: none)."""

    camera: str
    local_id: int
    label: int
    boxes: dict[int, np.ndarray] = field(default_factory=dict)
    scores: dict[int, float] = field(default_factory=dict)
    feature: np.ndarray | None = None
    global_id: int = NO_ID
    min_cost: float = np.inf
    partner: Tracklet | None = None
    ids: dict[int, int] = field(default_factory=dict)

    @property
    def first(self) -> int:
        return min(self.boxes)

    @property
    def last(self) -> int:
        return max(self.boxes)

    def overlaps_in_time(self, other: Tracklet) -> bool:
        """Whether the two were reported at a common frame (coexisting tracklets are different objects)."""
        if not self.boxes or not other.boxes or self.first > other.last or other.first > self.last:
            return False
        small, large = (self.boxes, other.boxes) if len(self.boxes) <= len(other.boxes) else (other.boxes, self.boxes)
        return any(frame in large for frame in small)

    def __repr__(self) -> str:
        return f"Tracklet({self.camera} {self.local_id}, 𝒢={self.global_id})"


def update_feature(tracklet: Tracklet, embedding: np.ndarray | None, score: float, occlusion: float, *,
                   alpha: float, occlusion_limit: float, min_score: float = 0.3) -> bool:
    """Eq. 3: f̃ ← α f̃ + (1 − α) f, only if the box's ``score`` ≥ ``min_score`` and its ``occlusion`` ratio
    (Eq. 4) ≤ ``occlusion_limit``; the first qualifying feature starts f̃. Returns whether it updated.

    >>> t = Tracklet("ego", 1, 0)
    >>> update_feature(t, np.array([1.0, 0.0]), 0.9, 0.0, alpha=0.9, occlusion_limit=0.5)
    True
    >>> update_feature(t, np.array([0.0, 1.0]), 0.9, 0.2, alpha=0.9, occlusion_limit=0.5), t.feature.round(6).tolist()
    (True, [0.9, 0.1])
    >>> update_feature(t, np.array([0.0, 1.0]), 0.2, 0.0, alpha=0.9, occlusion_limit=0.5)
    False
    """
    if embedding is None or len(embedding) == 0 or not np.isfinite(embedding).all():
        return False
    if score < min_score or occlusion > occlusion_limit:
        return False
    embedding = np.asarray(embedding, dtype=float)
    if tracklet.feature is None:
        tracklet.feature = embedding.copy()
    else:
        tracklet.feature = alpha * tracklet.feature + (1 - alpha) * embedding
    return True
