"""CollabMOT's affinity cost between ego and remote tracklets (Ninh and Kim, IEEE Access 2024, §III-C, Eq. 2, 5,
8, 9, Table 10).

S = Sa·ω_a + Sp·ω_p; Sa is the cosine distance of the two EMA features, ∞ above λ_appearance or when either
has no feature; Sp is ∞ for the layouts Table 10 rules out, 0 otherwise.
"""

from __future__ import annotations

import numpy as np

from simrig.types import Camera

from .tracklets import Tracklet

LEFT, RIGHT, CENTRE = 0, 1, 2
"""RelB values (Eq. 9) and RelP values (Eq. 8: 0 = remote on the ego's left, 1 = on its right)."""


def remote_side(ego: Camera, remote: Camera) -> int:
    """Eq. 8, RelP^{e←r}: 0 if the remote camera's optical centre is on the ego camera's left (negative x
    in the ego camera's frame), 1 if on its right."""
    position = np.linalg.inv(ego.ego_from_camera()) @ np.array([*remote.position, 1.0])
    return LEFT if position[0] < 0 else RIGHT


def box_side(boxes: np.ndarray, centreline: float, margin: float) -> np.ndarray:
    """Eq. 9, RelB of each box (N, 4) [px] against the vertical ``centreline`` [px] (the camera's principal
    point cx) with ``margin`` λ_bbox [px], x being the box centre and w its width as the paper states:
    0 (left) if x + w/2 < centreline − margin, 1 (right) if x > centreline + margin, else 2 (centre).

    >>> box_side(np.array([[0, 0, 80, 10], [95, 0, 120, 10], [115, 0, 200, 10]]), 100.0, 10.0).tolist()
    [0, 2, 1]
    """
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    x = (boxes[:, 0] + boxes[:, 2]) / 2
    w = boxes[:, 2] - boxes[:, 0]
    return np.where(x + w / 2 < centreline - margin, LEFT, np.where(x > centreline + margin, RIGHT, CENTRE))


def position_cost(relp: int, ego_sides: np.ndarray, remote_sides: np.ndarray) -> np.ndarray:
    """Sp (N, M): ∞ for the Table 10 rows — (RelP 0, RelB^e 1, RelB^r 0) and (RelP 1, RelB^e 0, RelB^r 1) —
    0 otherwise. (An object lies further right in the left camera's image than in the right camera's.)"""
    ruled_out = (ego_sides[:, None] == 1 - relp) & (remote_sides[None, :] == relp)
    return np.where(ruled_out, np.inf, 0.0)


def _cosine_distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N, M) 1 − cos of every pair of rows."""
    a = a / np.maximum(np.linalg.norm(a, axis=1, keepdims=True), 1e-12)
    b = b / np.maximum(np.linalg.norm(b, axis=1, keepdims=True), 1e-12)
    return 1.0 - a @ b.T


def appearance_cost(ego: list[Tracklet], remote: list[Tracklet], limit: float) -> np.ndarray:
    """Sa (N, M), Eq. 5: the cosine distance of the EMA features, ∞ where either is missing or the distance
    exceeds ``limit`` (λ_appearance)."""
    cost = np.full((len(ego), len(remote)), np.inf)
    rows = [i for i, t in enumerate(ego) if t.feature is not None]
    cols = [j for j, t in enumerate(remote) if t.feature is not None]
    if rows and cols:
        distance = _cosine_distances(np.stack([ego[i].feature for i in rows]),
                                    np.stack([remote[j].feature for j in cols]))
        cost[np.ix_(rows, cols)] = np.where(distance > limit, np.inf, distance)
    return cost


def affinity(ego: list[Tracklet], remote: list[Tracklet], frame: int, *, relp: int, ego_camera: Camera,
             remote_camera: Camera, appearance_limit: float, margin: float, weight_appearance: float = 1.0,
             weight_position: float = 1.0) -> np.ndarray:
    """S (N, M), Eq. 2, between the candidates ``ego`` and ``remote`` at ``frame`` (their boxes there)."""
    if not ego or not remote:
        return np.zeros((len(ego), len(remote)))
    sa = appearance_cost(ego, remote, appearance_limit)
    ego_sides = box_side(np.stack([t.boxes[frame] for t in ego]), ego_camera.cx, margin)
    remote_sides = box_side(np.stack([t.boxes[frame] for t in remote]), remote_camera.cx, margin)
    sp = position_cost(relp, ego_sides, remote_sides)
    with np.errstate(invalid="ignore"):
        return sa * weight_appearance + sp * weight_position
