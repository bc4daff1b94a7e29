"""Similarities between ground truth and tracker outputs, computed once per frame and shared by every metric.

2D: intersection over union of pixel boxes (x1, y1, x2, y2) [px], with TrackEval's conventions (a box of zero
area overlaps nothing). 3D: bird's-eye-view distance between world-frame box centres [m], as nuScenes.
Both are elementwise and broadcast: ``(…, 4)`` against ``(…, 4)`` gives ``(…)``.
"""

from __future__ import annotations

import numpy as np

_EPS = np.finfo(float).eps


def iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Elementwise IoU of broadcastable ``(…, 4)`` pixel boxes (x1, y1, x2, y2) [px], in [0, 1].

    >>> float(iou(np.array([0.0, 0.0, 2.0, 2.0]), np.array([1.0, 0.0, 3.0, 2.0])))
    0.3333333333333333
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    extent = np.maximum(np.minimum(a[..., 2:], b[..., 2:]) - np.maximum(a[..., :2], b[..., :2]), 0.0)
    intersection = extent[..., 0] * extent[..., 1]
    area_a = (a[..., 2] - a[..., 0]) * (a[..., 3] - a[..., 1])
    area_b = (b[..., 2] - b[..., 0]) * (b[..., 3] - b[..., 1])
    union = area_a + area_b - intersection
    empty = (area_a <= _EPS) | (area_b <= _EPS) | (union <= _EPS)
    return np.where(empty, 0.0, intersection / np.where(union <= _EPS, 1.0, union))


def intersects(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Elementwise: do broadcastable ``(…, 4)`` pixel boxes overlap with a positive area? (A cheap pre-filter.)

    >>> intersects(np.array([[0.0, 0.0, 2.0, 2.0]]), np.array([[2.0, 0.0, 3.0, 2.0]])).tolist()
    [False]
    """
    return ((np.minimum(a[..., 2], b[..., 2]) > np.maximum(a[..., 0], b[..., 0]))
            & (np.minimum(a[..., 3], b[..., 3]) > np.maximum(a[..., 1], b[..., 1])))


def bev_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Elementwise bird's-eye-view distance [m] between broadcastable ``(…, ≥2)`` world-frame centres (x, y only).

    >>> float(bev_distance(np.array([0.0, 0.0, 5.0]), np.array([3.0, 4.0, 0.0])))
    5.0
    """
    delta = np.asarray(a, dtype=float)[..., :2] - np.asarray(b, dtype=float)[..., :2]
    return np.sqrt(np.sum(delta * delta, axis=-1))
