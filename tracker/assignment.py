"""One-to-one assignment of detections to tracks under a cost gate.

Every assigner returns ``owner`` (M,): for each detection the index of its track, or −1 when unmatched.
A pair is allowed only when its cost is finite and ``≤ gate``.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

UNMATCHED = -1


def assign_into(owner: np.ndarray, rows: np.ndarray, tracks, cost: np.ndarray, gate: float) -> None:
    """:func:`hungarian` on ``cost`` ``(len(tracks), len(rows))``; each detection row it matches gets its track's
    index (from ``tracks``) written into ``owner``.

    >>> owner = np.full(3, UNMATCHED)
    >>> assign_into(owner, np.array([0, 2]), [5, 7], np.array([[0.1, 0.9], [0.9, 0.2]]), 0.5)
    >>> owner.tolist()
    [5, -1, 7]
    """
    matched = hungarian(cost, gate)
    hit = matched != UNMATCHED
    owner[rows[hit]] = np.asarray(tracks)[matched[hit]]


def hungarian(cost: np.ndarray, gate: float) -> np.ndarray:
    """Minimum-cost one-to-one matching (scipy's ``linear_sum_assignment``) where leaving a track or a
    detection unmatched costs ``gate``/2 each, so a pair is worth matching only if its cost is below the gate
    (SORT/AB3DMOT's thresholded Hungarian, solved exactly on the (N+M) × (M+N) augmented matrix rather than
    matched first and thresholded after). Disallowed pairs (non-finite or above the gate) never match.

    >>> hungarian(np.array([[1.0, 0.5], [0.2, 9.0]]), gate=2.0).tolist()
    [1, 0]
    """
    n, m = cost.shape
    owner = np.full(m, UNMATCHED, dtype=np.int64)
    allowed = np.isfinite(cost) & (cost <= gate)
    if not allowed.any():
        return owner
    big = 2.0 * gate * (n + m) + 1.0  # dearer than leaving everything unmatched
    half = gate / 2.0
    augmented = np.full((n + m, m + n), big)
    augmented[:n, :m] = np.where(allowed, cost, big)
    augmented[np.arange(n), m + np.arange(n)] = half  # track i unmatched
    augmented[n + np.arange(m), np.arange(m)] = half  # detection j unmatched
    augmented[n:, m:] = 0.0
    rows, cols = linear_sum_assignment(augmented)
    pairs = (rows < n) & (cols < m)
    rows, cols = rows[pairs], cols[pairs]
    keep = allowed[rows, cols]
    owner[cols[keep]] = rows[keep]
    return owner


def greedy(cost: np.ndarray, gate: float) -> np.ndarray:
    """Take allowed pairs in increasing cost, skipping those whose track or detection is taken (AB3DMOT's
    nuScenes setting). Ties go to the lower track index, then the lower detection index.

    >>> greedy(np.array([[1.0, 0.5], [0.2, 9.0]]), gate=2.0).tolist()
    [1, 0]
    """
    n, m = cost.shape
    owner = np.full(m, UNMATCHED, dtype=np.int64)
    allowed = np.isfinite(cost) & (cost <= gate)
    rows, cols = np.nonzero(allowed)
    order = np.lexsort((cols, rows, cost[rows, cols]))
    track_taken = np.zeros(n, dtype=bool)
    for i, j in zip(rows[order].tolist(), cols[order].tolist(), strict=True):
        if not track_taken[i] and owner[j] == UNMATCHED:
            owner[j] = i
            track_taken[i] = True
    return owner
