"""Measuring :class:`.visibility.Visibility` frame by frame: pyrender segmentation + analytic silhouettes."""

from __future__ import annotations

import numpy as np

from ..geometry import Projection
from ..rig import scaled_rig
from ..types import GroundTruthFrame, Rig
from .scene import RigScene
from .shapes import part_boxes
from .silhouette import silhouette_pixel_counts
from .visibility import Visibility


class VisibilityMeter:
    """Measures :class:`Visibility` frame by frame with one reused scene (see :class:`.scene.RigScene`)."""

    def __init__(self, rig: Rig, scale: float, scene: RigScene):
        self.rig = scaled_rig(rig, scale)
        self.scene = scene

    def measure(self, state: GroundTruthFrame, projection: Projection) -> Visibility:
        """Visibility of ``state``'s actors; ``projection`` (at image resolution) says which pairs to count."""
        c, n = projection.in_view.shape
        visible = np.zeros((c, n), dtype=np.int64)
        silhouette = np.zeros((c, n), dtype=np.int64)
        camera_index, actor_index = np.nonzero(projection.in_view)
        if len(camera_index):
            silhouette[camera_index, actor_index] = silhouette_pixel_counts(
                part_boxes(state.boxes, state.classes), self.rig, state.ego, camera_index, actor_index
            )
            self.scene.set_frame(state.ego, state.classes, state.boxes)
            for index in np.unique(camera_index):
                visible[index] = self.scene.visible_pixel_counts(self.rig.cameras[index], self.rig, state.ego)
        return Visibility.from_counts(visible, silhouette)
