"""Per camera and frame, how much of each actor is visible: segmentation render vs analytic silhouette.

``visible_px`` is the actor's pixel count in a segmentation render at the visibility resolution (the
image resolution × the scenario's ``render.visibility_scale``); ``silhouette_px`` the count of its own,
unoccluded silhouette inside the image at the same resolution (:mod:`.silhouette`); the occlusion ratio is
``1 − visible / silhouette`` (NaN where the silhouette covers no pixel). Only cameras that see at least
one actor are rendered (:class:`simrig.render.meter.VisibilityMeter`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry import Projection


@dataclass(frozen=True, eq=False)
class Visibility:
    """``(C, N)`` arrays in rig order: visible and unoccluded silhouette pixels at the visibility
    resolution, and the occlusion ratio in [0, 1] (NaN where the actor covers no pixel of the camera)."""

    visible_px: np.ndarray
    silhouette_px: np.ndarray
    occlusion: np.ndarray

    @classmethod
    def from_counts(cls, visible_px: np.ndarray, silhouette_px: np.ndarray) -> Visibility:
        with np.errstate(divide="ignore", invalid="ignore"):
            occlusion = np.where(silhouette_px > 0, 1.0 - visible_px / silhouette_px, np.nan)
        return cls(visible_px, silhouette_px, np.clip(occlusion, 0.0, 1.0))

    @classmethod
    def unmeasured(cls, projection: Projection) -> Visibility:
        """Without rendering: no pixel counts (−1), occlusion 0 wherever the box is in view."""
        counts = np.full(projection.in_view.shape, -1, dtype=np.int64)
        return cls(counts, counts.copy(), np.where(projection.in_view, 0.0, np.nan))
