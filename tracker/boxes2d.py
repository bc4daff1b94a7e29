"""Pixel-box geometry for the 2D trackers: IoU between box sets and the occlusion ratio of CollabMOT's Eq. 4.

Boxes are ``(N, 4)`` arrays (x1, y1, x2, y2) [px], image top-left origin.
"""

from __future__ import annotations

import numpy as np


def areas(boxes: np.ndarray) -> np.ndarray:
    """``(N,)`` areas [px²]; 0 for an empty box."""
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    return np.clip(boxes[:, 2] - boxes[:, 0], 0, None) * np.clip(boxes[:, 3] - boxes[:, 1], 0, None)


def intersections(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``(N, M, 4)`` intersection boxes of every pair (empty ones have x2 ≤ x1 or y2 ≤ y1)."""
    a = np.asarray(a, dtype=float).reshape(-1, 4)[:, None, :]
    b = np.asarray(b, dtype=float).reshape(-1, 4)[None, :, :]
    return np.concatenate([np.maximum(a[..., :2], b[..., :2]), np.minimum(a[..., 2:], b[..., 2:])], axis=-1)


def iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``(N, M)`` intersection over union of every box of ``a`` with every box of ``b`` (0 for two empty boxes).

    >>> iou(np.array([[0, 0, 2, 2]]), np.array([[1, 0, 3, 2], [5, 5, 6, 6]])).round(3).tolist()
    [[0.333, 0.0]]
    """
    a = np.asarray(a, dtype=float).reshape(-1, 4)
    b = np.asarray(b, dtype=float).reshape(-1, 4)
    inter = areas(intersections(a, b).reshape(-1, 4)).reshape(len(a), len(b))
    union = areas(a)[:, None] + areas(b)[None, :] - inter
    return np.divide(inter, union, out=np.zeros_like(inter), where=union > 0)


def occlusion_ratios(boxes: np.ndarray) -> np.ndarray:
    """CollabMOT's Eq. 4 for each box: the area of the union of its overlaps with every other box of the set,
    over its own area (0 for a lone box, 1 for a box covered entirely; 0 for an empty box).

    The union is measured exactly on the grid of the overlaps' edges.

    >>> occlusion_ratios(np.array([[0, 0, 4, 4], [2, 0, 6, 4], [0, 2, 4, 6]])).tolist()
    [0.75, 0.5, 0.5]
    """
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    n = len(boxes)
    out = np.zeros(n)
    if n < 2:
        return out
    overlap = intersections(boxes, boxes)
    own = areas(boxes)
    for i in range(n):
        parts = np.delete(overlap[i], i, axis=0)
        parts = parts[(parts[:, 2] > parts[:, 0]) & (parts[:, 3] > parts[:, 1])]
        if len(parts) == 0 or own[i] <= 0:
            continue
        xs, ys = np.unique(parts[:, [0, 2]]), np.unique(parts[:, [1, 3]])
        cx, cy = (xs[:-1] + xs[1:]) / 2, (ys[:-1] + ys[1:]) / 2
        inside_x = (parts[:, None, 0] <= cx[None, :]) & (cx[None, :] <= parts[:, None, 2])  # (P, X)
        inside_y = (parts[:, None, 1] <= cy[None, :]) & (cy[None, :] <= parts[:, None, 3])  # (P, Y)
        covered = np.einsum("px,py->xy", inside_x.astype(np.int32), inside_y.astype(np.int32)) > 0
        out[i] = float(np.diff(xs) @ covered @ np.diff(ys)) / own[i]
    return out
