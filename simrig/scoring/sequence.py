"""One scored sequence for the 2D metrics: which ground-truth and tracker ids are present in each frame and
how similar each overlapping pair is. Built once and read by every metric unit (HOTA, CLEAR, Identity).

A sequence is one (camera, class). Rows are flat and sorted by frame; ids are dense indices ``0 … G−1`` and
``0 … K−1`` into ``gt_labels`` (actor ids) and ``tracker_labels`` (track ids). Only pairs with a positive
IoU are stored (every metric ignores the others), sorted by frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .similarity import intersects, iou


class FramePairs:
    """What every matching input shares, and the per-frame slices derived from it. The dataclasses built on it
    have the fields: flat ground-truth and tracker rows sorted by frame position (``gt_frame``, ``gt_id``,
    ``tracker_frame``, ``tracker_id``), same-frame pairs sorted by frame (``pair_gt``, ``pair_tracker``),
    ``frames`` and the id labels (``gt_labels``, ``tracker_labels``)."""

    @property
    def num_gt_ids(self) -> int:
        return len(self.gt_labels)

    @property
    def num_tracker_ids(self) -> int:
        return len(self.tracker_labels)

    @property
    def num_gt_dets(self) -> int:
        return len(self.gt_id)

    @property
    def num_tracker_dets(self) -> int:
        return len(self.tracker_id)

    @cached_property
    def gt_slices(self) -> np.ndarray:
        """``(T, 2)`` [start, stop) of each frame's ground-truth rows."""
        return frame_slices(self.gt_frame, np.arange(len(self.frames)))

    @cached_property
    def tracker_slices(self) -> np.ndarray:
        """``(T, 2)`` [start, stop) of each frame's tracker rows."""
        return frame_slices(self.tracker_frame, np.arange(len(self.frames)))

    @cached_property
    def pair_frame(self) -> np.ndarray:
        """``(p,)`` frame position of each pair (non-decreasing)."""
        return self.gt_frame[self.pair_gt]

    @cached_property
    def pair_slices(self) -> np.ndarray:
        """``(T, 2)`` [start, stop) of each frame's pairs."""
        return frame_slices(self.pair_frame, np.arange(len(self.frames)))


@dataclass(frozen=True, eq=False)
class Sequence(FramePairs):
    """Matching input of one (camera, class).

    frames: ``(T,)`` frame numbers. gt_frame, gt_id: ``(n,)`` frame position (index into ``frames``) and dense
    id of each ground-truth box; tracker_frame, tracker_id: ``(m,)`` the same for tracker boxes.
    pair_gt, pair_tracker: ``(p,)`` row indices of every overlapping pair in the same frame; pair_similarity:
    ``(p,)`` their IoU (> 0). gt_labels: ``(G,)`` actor ids; tracker_labels: ``(K,)`` track ids.
    Ground truth ignored by the evaluation region is not in it (:mod:`simrig.scoring.distractors`).
    """

    camera: str
    label: str
    frames: np.ndarray
    gt_frame: np.ndarray
    gt_id: np.ndarray
    tracker_frame: np.ndarray
    tracker_id: np.ndarray
    pair_gt: np.ndarray
    pair_tracker: np.ndarray
    pair_similarity: np.ndarray
    gt_labels: np.ndarray
    tracker_labels: np.ndarray
    ignored_misses: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int64))
    """``(n, 2)`` (frame number, actor id) of the ignored ground truth no tracker box was matched to (not
    scored; kept so that a report can say what was not scored and why)."""

    @property
    def name(self) -> str:
        return f"{self.camera}/{self.label}"

    def frame_matrix(self, position: int, values: np.ndarray, fill=0.0) -> np.ndarray:
        """Dense ``(n_t, m_t)`` matrix of frame ``position``: ``values`` (one per pair of the whole sequence) at
        that frame's pairs, ``fill`` elsewhere. Rows and columns are the frame's gt and tracker rows in order."""
        (g0, g1), (k0, k1) = self.gt_slices[position], self.tracker_slices[position]
        p0, p1 = self.pair_slices[position]
        matrix = np.full((g1 - g0, k1 - k0), fill, dtype=np.asarray(values).dtype)
        matrix[self.pair_gt[p0:p1] - g0, self.pair_tracker[p0:p1] - k0] = values[p0:p1]
        return matrix

    def frame_pair_index(self, position: int) -> np.ndarray:
        """Dense ``(n_t, m_t)`` matrix of the pair index of each entry of frame ``position`` (−1: no pair)."""
        return self.frame_matrix(position, np.arange(len(self.pair_gt)), fill=-1)


def dense_ids(labels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(unique labels, dense index of each label)``: ids 0 … G−1 in sorted label order.

    >>> dense_ids(np.array([7, 3, 7]))
    (array([3, 7]), array([1, 0, 1]))
    """
    unique, inverse = np.unique(np.asarray(labels), return_inverse=True)
    return unique, inverse.reshape(-1)


def frame_slices(row_frames: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """``(T, 2)`` [start, stop) row ranges of each of ``frames`` in rows sorted by frame.

    >>> frame_slices(np.array([0, 0, 2]), np.array([0, 1, 2])).tolist()
    [[0, 2], [2, 2], [2, 3]]
    """
    return np.column_stack([
        np.searchsorted(row_frames, frames, side="left"), np.searchsorted(row_frames, frames, side="right")
    ])


def _same_frame_pairs(gt_slices: np.ndarray, tracker_slices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every (ground-truth row, tracker row) pair that shares a frame, frame by frame, gt-major.

    >>> _same_frame_pairs(np.array([[0, 2], [2, 3]]), np.array([[0, 1], [1, 3]]))
    (array([0, 1, 2, 2]), array([0, 0, 1, 2]))
    """
    n_gt = gt_slices[:, 1] - gt_slices[:, 0]
    n_tracker = tracker_slices[:, 1] - tracker_slices[:, 0]
    gt_rows = np.arange(gt_slices[0, 0], gt_slices[-1, 1]) if len(gt_slices) else np.zeros(0, dtype=np.int64)
    per_gt_row = np.repeat(n_tracker, n_gt)  # partners of each gt row
    first_partner = np.repeat(tracker_slices[:, 0], n_gt)
    pair_gt = np.repeat(gt_rows, per_gt_row)
    offsets = np.arange(len(pair_gt)) - np.repeat(np.cumsum(per_gt_row) - per_gt_row, per_gt_row)
    return pair_gt, np.repeat(first_partner, per_gt_row) + offsets


FRAMES_PER_BLOCK = 256
"""Frames whose candidate pairs are formed and measured at once: a long sequence's every same-frame pair is
never held together, only those kept."""


def kept_pairs(gt_slices: np.ndarray, tracker_slices: np.ndarray, measure) -> tuple[np.ndarray, ...]:
    """The same-frame pairs that ``measure`` keeps, in :func:`_same_frame_pairs` order, with their values.

    ``measure(pair_gt, pair_tracker) -> (kept, values)``: of candidate pairs (row indices), the positions of
    those to keep (increasing) and one value each. Candidates are formed :data:`FRAMES_PER_BLOCK` frames at a
    time, so memory follows the pairs kept, not every same-frame pair of the sequence.

    >>> gt, tracker, value = kept_pairs(np.array([[0, 2], [2, 3]]), np.array([[0, 1], [1, 3]]),
    ...                                 lambda g, t: (np.nonzero(g == t)[0], (g + t)[g == t]))
    >>> gt.tolist(), tracker.tolist(), value.tolist()
    ([0, 2], [0, 2], [0, 4])
    """
    parts: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    for start in range(0, max(len(gt_slices), 1), FRAMES_PER_BLOCK):
        pair_gt, pair_tracker = _same_frame_pairs(gt_slices[start:start + FRAMES_PER_BLOCK],
                                                 tracker_slices[start:start + FRAMES_PER_BLOCK])
        kept, values = measure(pair_gt, pair_tracker)
        parts.append((pair_gt[kept], pair_tracker[kept], values))
    return tuple(np.concatenate(column) for column in zip(*parts, strict=True))


def sequence_from_rows(
    camera: str,
    label: str,
    frames: np.ndarray,
    gt_frame: np.ndarray,
    gt_id: np.ndarray,
    gt_box: np.ndarray,
    tracker_frame: np.ndarray,
    tracker_id: np.ndarray,
    tracker_box: np.ndarray,
) -> Sequence:
    """A :class:`Sequence` from flat rows: ground truth (frame number, actor id, ``(4,)`` pixel box) and tracker
    output (frame number, track id, box), each sorted by frame, ids unique within a frame, every frame number
    one of ``frames`` (all frames of the sequence in increasing order, empty ones included)."""
    frames = np.asarray(frames)
    gt_position = np.searchsorted(frames, np.asarray(gt_frame))
    tracker_position = np.searchsorted(frames, np.asarray(tracker_frame))
    gt_labels, gt_dense = dense_ids(gt_id)
    tracker_labels, tracker_dense = dense_ids(tracker_id)
    positions = np.arange(len(frames))
    gt_box = np.asarray(gt_box, dtype=float).reshape(-1, 4)
    tracker_box = np.asarray(tracker_box, dtype=float).reshape(-1, 4)

    def overlapping(pair_gt: np.ndarray, pair_tracker: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        candidates = np.nonzero(intersects(gt_box[pair_gt], tracker_box[pair_tracker]))[0]
        similarity = iou(gt_box[pair_gt[candidates]], tracker_box[pair_tracker[candidates]])
        return candidates[similarity > 0.0], similarity[similarity > 0.0]

    pair_gt, pair_tracker, similarity = kept_pairs(frame_slices(gt_position, positions),
                                                   frame_slices(tracker_position, positions), overlapping)
    return Sequence(
        camera=camera,
        label=label,
        frames=frames,
        gt_frame=gt_position,
        gt_id=gt_dense,
        tracker_frame=tracker_position,
        tracker_id=tracker_dense,
        pair_gt=pair_gt,
        pair_tracker=pair_tracker,
        pair_similarity=similarity,
        gt_labels=gt_labels,
        tracker_labels=tracker_labels,
    )
