"""One class's 3D matching input for the nuScenes-style metrics: ground-truth and tracker box centres in the
bird's-eye view, velocities, track scores, and every same-frame pair closer than 2 m.

Rows are flat and sorted by frame; ids are dense (``0 … G−1``, ``0 … K−1``) into ``gt_labels`` (actor ids)
and ``tracker_labels`` (track ids). World frame: x along the road, y left [m]; velocities [m/s].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .sequence import FramePairs, dense_ids, frame_slices, kept_pairs
from .similarity import bev_distance

MATCH_DISTANCE_M = 2.0
"""[m] a ground truth and a tracker box can match when their BEV centres are closer than this (strict)."""


@dataclass(frozen=True, eq=False)
class BevSequence(FramePairs):
    """3D matching input of one class.

    frames: ``(T,)`` frame numbers. gt_frame, gt_id: ``(n,)`` frame position and dense id of each ground-truth
    box; gt_velocity: ``(n, 2)`` [m/s]. tracker_frame, tracker_id, tracker_velocity likewise for ``(m,)``
    tracker boxes; tracker_score: ``(m,)`` the score of the box's track (the mean of its per-frame scores).
    pair_gt, pair_tracker, pair_distance: ``(p,)`` same-frame pairs closer than :data:`MATCH_DISTANCE_M`
    and their BEV centre distance [m], sorted by frame.
    """

    label: str
    frames: np.ndarray
    gt_frame: np.ndarray
    gt_id: np.ndarray
    gt_velocity: np.ndarray
    tracker_frame: np.ndarray
    tracker_id: np.ndarray
    tracker_velocity: np.ndarray
    tracker_score: np.ndarray
    pair_gt: np.ndarray
    pair_tracker: np.ndarray
    pair_distance: np.ndarray
    gt_labels: np.ndarray
    tracker_labels: np.ndarray


def bev_sequence(
    label: str,
    frames: np.ndarray,
    gt_frame: np.ndarray,
    gt_id: np.ndarray,
    gt_xy: np.ndarray,
    gt_velocity: np.ndarray,
    tracker_frame: np.ndarray,
    tracker_id: np.ndarray,
    tracker_xy: np.ndarray,
    tracker_velocity: np.ndarray,
    tracker_score: np.ndarray,
) -> BevSequence:
    """A :class:`BevSequence` from flat rows sorted by frame (frame numbers, ids, ``(·, 2)`` world-frame
    centres [m] and velocities [m/s], track scores); ``frames``: all frames of the sequence, in order."""
    frames = np.asarray(frames)
    gt_position = np.searchsorted(frames, np.asarray(gt_frame))
    tracker_position = np.searchsorted(frames, np.asarray(tracker_frame))
    positions = np.arange(len(frames))
    gt_xy = np.asarray(gt_xy, dtype=float).reshape(-1, 2)
    tracker_xy = np.asarray(tracker_xy, dtype=float).reshape(-1, 2)

    def near(pair_gt: np.ndarray, pair_tracker: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        distance = bev_distance(gt_xy[pair_gt], tracker_xy[pair_tracker])
        close = np.nonzero(distance < MATCH_DISTANCE_M)[0]
        return close, distance[close]

    pair_gt, pair_tracker, distance = kept_pairs(frame_slices(gt_position, positions),
                                                 frame_slices(tracker_position, positions), near)
    gt_labels, gt_dense = dense_ids(gt_id)
    tracker_labels, tracker_dense = dense_ids(tracker_id)
    return BevSequence(
        label=label,
        frames=frames,
        gt_frame=gt_position,
        gt_id=gt_dense,
        gt_velocity=np.asarray(gt_velocity, dtype=float).reshape(-1, 2),
        tracker_frame=tracker_position,
        tracker_id=tracker_dense,
        tracker_velocity=np.asarray(tracker_velocity, dtype=float).reshape(-1, 2),
        tracker_score=np.asarray(tracker_score, dtype=float),
        pair_gt=pair_gt,
        pair_tracker=pair_tracker,
        pair_distance=distance,
        gt_labels=gt_labels,
        tracker_labels=tracker_labels,
    )
