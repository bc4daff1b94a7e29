"""Recovering the gap of a reconnected tracklet by linear interpolation (Ninh and Kim, IEEE Access 2024, §III-E, Eq. 7).

Lost tracklet T_k (last frame ``last``) and current tracklet T_i (first frame ``first``) of one camera share a
global id. Boxes are interpolated between b(t₁) of T_k and b(t₂) of T_i with t₁ = last − ω and
t₂ = first + ω (ω = ω_interpolated, clipped to the tracklets' extents). The gap is filled only if every
interpolated box at a frame where one of the two tracklets has its own box — (last − ω, last] of T_k and
[first, first + ω) of T_i — overlaps that box with IoU > λ_int_iou; gap boxes whose occlusion ratio (Eq. 4,
against the camera's other boxes at that frame) exceeds λ_int_occlusion are dropped.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..boxes2d import iou, occlusion_ratios
from .tracklets import Tracklet


def _linear_boxes(box1: np.ndarray, frame1: int, box2: np.ndarray, frame2: int, frames: np.ndarray) -> np.ndarray:
    """Eq. 7: b(t) = b₁ + (b₂ − b₁)/(t₂ − t₁)·(t − t₁) for each of ``frames`` → (len(frames), 4) [px].

    >>> _linear_boxes(np.array([0, 0, 10, 10]), 0, np.array([10, 0, 20, 10]), 4, np.array([1, 2])).tolist()
    [[2.5, 0.0, 12.5, 10.0], [5.0, 0.0, 15.0, 10.0]]
    """
    step = (np.asarray(box2, dtype=float) - np.asarray(box1, dtype=float)) / (frame2 - frame1)
    return np.asarray(box1, dtype=float)[None, :] + step[None, :] * (np.asarray(frames)[:, None] - frame1)


def ready_at(lost: Tracklet, current: Tracklet, depth: int) -> int:
    """The frame from which the gap can be filled: ω frames after ``current`` started."""
    return current.first + depth


def fill_gap(lost: Tracklet, current: Tracklet, *, depth: int, iou_limit: float, occlusion_limit: float,
             others_at: Callable[[int], np.ndarray]) -> dict[int, np.ndarray]:
    """The interpolated boxes of the frames strictly between ``lost.last`` and ``current.first`` (frame →
    box), or ``{}`` when the IoU check fails or there is no gap. ``others_at(frame)`` gives the camera's
    other boxes (M, 4) at a frame, for the occlusion ratio."""
    last, first = lost.last, current.first
    if first - last < 2:
        return {}
    before = sorted(f for f in lost.boxes if f >= last - depth)
    after = sorted(f for f in current.boxes if f <= first + depth)
    t1, t2 = before[0], after[-1]
    check = [f for f in before if f > t1] + [f for f in after if f < t2]
    if check:
        boxes = _linear_boxes(lost.boxes[t1], t1, current.boxes[t2], t2, np.array(check))
        own = np.stack([lost.boxes[f] if f in lost.boxes else current.boxes[f] for f in check])
        if not np.all(np.diag(iou(boxes, own)) > iou_limit):
            return {}
    gap = np.arange(last + 1, first)
    boxes = _linear_boxes(lost.boxes[t1], t1, current.boxes[t2], t2, gap)
    out = {}
    for frame, box in zip(gap.tolist(), boxes, strict=True):
        others = others_at(frame)
        occlusion = occlusion_ratios(np.vstack([box[None, :], others]))[0] if len(others) else 0.0
        if occlusion <= occlusion_limit:
            out[frame] = box
    return out
