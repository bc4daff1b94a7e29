"""Optimal one-to-one matching used by the per-frame metrics (scipy's Hungarian, solved only where needed).

Every metric here keeps the pairs of a maximum-sum assignment whose score is positive. When the candidate
pairs of a frame already form a matching (no ground truth and no tracker box in two candidate pairs — the
usual case in a traffic scene), every optimal assignment contains exactly those pairs, so no solve is needed.
Frames with contested boxes are solved with scipy on the frame's full matrix, as the peer implementations
do, so that ties resolve the same way.
"""

from __future__ import annotations

import numpy as np

from .hungarian import linear_sum_assignment


def positive_matching(score: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of the positive pairs of a maximum-sum assignment of ``score`` ``(n, m)``.

    >>> positive_matching(np.array([[0.9, 0.8], [0.0, 0.7]]))
    (array([0, 1]), array([0, 1]))
    >>> positive_matching(np.array([[0.0, 0.6], [0.0, 0.0]]))
    (array([0]), array([1]))
    """
    positive = score > 0.0
    rows, cols = np.nonzero(positive)
    if len(rows) == len(np.unique(rows)) and len(cols) == len(np.unique(cols)):
        return rows, cols
    rows, cols = linear_sum_assignment(-score)
    keep = score[rows, cols] > 0.0
    return rows[keep], cols[keep]


def contested(pair_gt: np.ndarray, pair_tracker: np.ndarray) -> np.ndarray:
    """``(p,)`` True for candidate pairs sharing a ground-truth row or a tracker row with another candidate
    (rows are frame-specific, so this is a per-frame test).

    >>> contested(np.array([0, 0, 1, 2]), np.array([0, 1, 2, 3])).tolist()
    [True, True, False, False]
    """
    if len(pair_gt) == 0:
        return np.zeros(0, dtype=bool)
    gt_uses = np.bincount(pair_gt)[pair_gt]
    tracker_uses = np.bincount(pair_tracker)[pair_tracker]
    return (gt_uses > 1) | (tracker_uses > 1)


def minimum_cost_matching(costs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of a minimum-cost assignment over the finite entries of ``costs`` (NaN: not allowed),
    as py-motmetrics solves it: forbidden entries get a cost so large that the most pairs are matched first,
    then the total cost is minimised.

    >>> minimum_cost_matching(np.array([[1.0, np.nan], [0.5, 1.5]]))
    (array([0, 1]), array([0, 1]))
    """
    valid = np.isfinite(costs)
    if not valid.any():
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    large = 2 * min(costs.shape) * (np.abs(costs[valid]).max() + 1) + 1
    rows, cols = linear_sum_assignment(np.where(valid, costs, large))
    keep = valid[rows, cols]
    return rows[keep], cols[keep]
