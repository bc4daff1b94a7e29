"""Local tracklet resurfacing (Ninh and Kim, IEEE Access 2024, §III-D, before Alg. 1).

A single-camera tracker may revive a lost tracklet T_lost after CollabMOT has connected it, through the global
id, to a newer tracklet T_current of the same camera: both are then reported with one global id. Counting the
frames where both are reported (co-appearances) whose boxes overlap with IoU > λ_merged_iou: fewer than
λ_coapp and the two are kept connected and their co-appearing boxes merged in the output; otherwise the
connection is revoked, and it is revoked at once when more than one lost tracklet resurfaces under the same id.
Choices where the paper is silent: a co-appearance whose boxes do not overlap (IoU ≤ λ_merged_iou) is two
objects and revokes at once too; revoking takes the global id from the newer tracklet (the one that
inherited it), so the single-camera tracker's own continuity wins.
"""

from __future__ import annotations

from collections import defaultdict

import numpy as np

from ..boxes2d import iou
from .tracklets import NO_ID, Tracklet


def _co_appearances(a: Tracklet, b: Tracklet, merged_iou: float) -> tuple[int, int]:
    """(overlapping, apart): the frames where both have a box, split by IoU > ``merged_iou``."""
    common = sorted(set(a.boxes) & set(b.boxes))
    if not common:
        return 0, 0
    values = np.diag(iou(np.stack([a.boxes[f] for f in common]), np.stack([b.boxes[f] for f in common])))
    overlapping = int(np.sum(values > merged_iou))
    return overlapping, len(common) - overlapping


def resurface(present: list[Tracklet], *, merged_iou: float, coappearance_limit: int) -> list[Tracklet]:
    """Apply the rule to the tracklets of one camera ``present`` at this frame; returns those whose global id
    was revoked (their 𝒢 is set to −1)."""
    groups: dict[int, list[Tracklet]] = defaultdict(list)
    for tracklet in present:
        if tracklet.global_id > 0:
            groups[tracklet.global_id].append(tracklet)
    revoked: list[Tracklet] = []
    for members in groups.values():
        if len(members) < 2:
            continue
        members.sort(key=lambda t: (t.first, t.local_id))
        oldest, newer = members[0], members[1:]
        if len(newer) == 1:
            overlapping, apart = _co_appearances(oldest, newer[0], merged_iou)
            if apart == 0 and overlapping < coappearance_limit:
                continue  # kept: the output merges their boxes
        for tracklet in newer:
            tracklet.global_id, tracklet.partner, tracklet.min_cost = NO_ID, None, np.inf
            revoked.append(tracklet)
    return revoked
