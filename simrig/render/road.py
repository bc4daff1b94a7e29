"""The road as colour renders show it: a grey ground plane and the lane markings of highway-env's network.

Markings arrive as world-frame polylines (:class:`RoadMarkings`, produced by :mod:`simrig.world`, stored in
the dataset as ``road.json``); :func:`painted_quads` turns them into flat quads (the scene makes one
static mesh of them).
Markings and ground are absent from segmentation renders: they never occlude a vehicle.
"""

from __future__ import annotations

import numpy as np

from ..road import RoadMarkings, dash_segments

MARKING_WIDTH_M = 0.15
"""[m] painted line width."""
GROUND_HALF_SIZE_M = 2000.0
"""[m] half side of the square ground plane under the whole map."""
MARKING_HEIGHT_M = 0.02
"""[m] markings float this far above the ground to avoid z-fighting."""


def painted_quads(markings: RoadMarkings) -> np.ndarray:
    """``(Q, 4, 3)`` world-frame corners of every painted segment, a flat quad just above the road."""
    segments = [dash_segments(line, dashed) for line, dashed in zip(markings.lines, markings.dashed, strict=True)]
    segments = np.concatenate(segments) if segments else np.zeros((0, 2, 2))
    direction = segments[:, 1] - segments[:, 0]
    norm = np.linalg.norm(direction, axis=1, keepdims=True)
    keep = norm[:, 0] > 0
    segments, direction, norm = segments[keep], direction[keep], norm[keep]
    side = np.stack([-direction[:, 1], direction[:, 0]], axis=1) / norm * (MARKING_WIDTH_M / 2.0)
    quads = np.stack([segments[:, 0] - side, segments[:, 1] - side, segments[:, 1] + side, segments[:, 0] + side], 1)
    return np.concatenate([quads, np.full((*quads.shape[:2], 1), MARKING_HEIGHT_M)], axis=2)
