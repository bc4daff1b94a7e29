"""CLEAR MOT on pixel boxes, counted per sequence exactly as TrackEval's ``metrics/clear.py`` defines it, and
the events behind the errors (every miss, identity switch and fragmentation) for cause attribution.

Matching: IoU ≥ 0.5; where boxes are contested, a pair continuing the previous time step's match wins (score
+1000). An identity switch is a match whose tracker id differs from the ground truth's last match at any
earlier time. Only frames where both sides have boxes are time steps for continuity (TrackEval's rule), so a
frame with no tracker output does not break a segment. Frag = tracked segments − 1 per ground truth.
MT: tracked ratio > 0.8; PT: ≥ 0.2; ML: the rest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .assignment import contested, positive_matching
from .counts import Counts
from .ratios import clear_ratios
from .sequence import Sequence

_EPS = np.finfo(float).eps
IOU_THRESHOLD = 0.5
"""Minimum IoU of a CLEAR (and identity) match."""


@dataclass(frozen=True, eq=False)
class ClearEvents:
    """The errors behind the CLEAR counts of one sequence, as frame numbers and actor / track ids.

    misses: ``(n, 2)`` (frame, actor id) of every false negative. switches: ``(n, 5)`` (frame, actor id,
    track id, previous track id, frame of the previous match). fragmentations: ``(n, 3)`` (frame where
    tracking resumed, actor id, last frame tracked before the gap).
    """

    misses: np.ndarray
    switches: np.ndarray
    fragmentations: np.ndarray


class CLEAR:
    """CLEAR MOT counts (TP, FN, FP, IDSW, Frag, MT/PT/ML and the IoU sum behind MOTP)."""

    name = "clear"
    fields = ("CLR_TP", "CLR_FN", "CLR_FP", "IDSW", "Frag", "MT", "PT", "ML", "MOTP_sum", "CLR_Frames")
    outputs = ("MOTA", "MOTP", "MODA", "CLR_Re", "CLR_Pr", "IDSW", "Frag", "MT", "PT", "ML")

    def empty(self) -> Counts:
        """The counts of a sequence with nothing in it."""
        return dict.fromkeys(self.fields, 0.0)

    def ratios(self, counts: Counts) -> dict[str, float]:
        """Every value of the unit from (summed) counts: :func:`simrig.scoring.ratios.clear_ratios`."""
        return clear_ratios(counts)

    def count(self, seq: Sequence) -> Counts:
        """CLEAR counts of one sequence."""
        return self.count_with_events(seq)[0]

    def count_with_events(self, seq: Sequence) -> tuple[Counts, ClearEvents]:
        """CLEAR counts of one sequence and the events behind its errors."""
        matched = self._matches(seq)
        gt_row, tracker_row = seq.pair_gt[matched], seq.pair_tracker[matched]
        gt, tracker, position = seq.gt_id[gt_row], seq.tracker_id[tracker_row], seq.gt_frame[gt_row]
        step = self._time_steps(seq)[position]
        order = np.lexsort((position, gt))  # by ground truth, then time
        gt, tracker, position, step = gt[order], tracker[order], position[order], step[order]
        same_gt = np.concatenate([[False], gt[1:] == gt[:-1]])
        previous_tracker = np.where(same_gt, np.roll(tracker, 1), -1)
        previous_position = np.where(same_gt, np.roll(position, 1), -1)
        previous_step = np.where(same_gt, np.roll(step, 1), -10)
        switched = same_gt & (tracker != previous_tracker)
        resumed = same_gt & (step - previous_step != 1)  # a new segment after an earlier one

        frames, gt_labels, tracker_labels = seq.frames, seq.gt_labels, seq.tracker_labels
        gt_n = np.bincount(seq.gt_id, minlength=seq.num_gt_ids)
        ratio = np.bincount(gt, minlength=seq.num_gt_ids)[gt_n > 0] / gt_n[gt_n > 0]
        mostly_tracked = float(np.sum(ratio > 0.8))
        partly_tracked = float(np.sum(ratio >= 0.2)) - mostly_tracked
        n = float(len(matched))
        counts = {
            "CLR_TP": n,
            "CLR_FN": seq.num_gt_dets - n,
            "CLR_FP": seq.num_tracker_dets - n,
            "IDSW": float(switched.sum()),
            "Frag": float(resumed.sum()),
            "MT": mostly_tracked,
            "PT": partly_tracked,
            "ML": float(seq.num_gt_ids) - mostly_tracked - partly_tracked,
            "MOTP_sum": float(np.sum(seq.pair_similarity[matched])),
            "CLR_Frames": float(len(frames)),
        }
        missed = np.ones(seq.num_gt_dets, dtype=bool)
        missed[gt_row] = False
        events = ClearEvents(
            misses=np.column_stack([frames[seq.gt_frame[missed]], gt_labels[seq.gt_id[missed]]]).astype(np.int64),
            switches=np.column_stack([
                frames[position[switched]], gt_labels[gt[switched]], tracker_labels[tracker[switched]],
                tracker_labels[previous_tracker[switched]], frames[previous_position[switched]],
            ]).astype(np.int64).reshape(-1, 5),
            fragmentations=np.column_stack([
                frames[position[resumed]], gt_labels[gt[resumed]], frames[previous_position[resumed]]
            ]).astype(np.int64).reshape(-1, 3),
        )
        return counts, events

    @staticmethod
    def _time_steps(seq: Sequence) -> np.ndarray:
        """``(T,)`` index of each frame among the frames where both sides have boxes (−1 elsewhere)."""
        both = (np.diff(seq.gt_slices, axis=1)[:, 0] > 0) & (np.diff(seq.tracker_slices, axis=1)[:, 0] > 0)
        return np.where(both, np.cumsum(both) - 1, -1)

    @staticmethod
    def _matches(seq: Sequence) -> np.ndarray:
        """Indices of the matched pairs. Uncontested candidates (IoU ≥ 0.5) match whatever the history; a
        frame with contested candidates is solved in time order, with the previous time step's matches."""
        candidate = seq.pair_similarity >= IOU_THRESHOLD - _EPS
        candidates = np.nonzero(candidate)[0]
        disputed = contested(seq.pair_gt[candidates], seq.pair_tracker[candidates])
        matched = np.zeros(len(seq.pair_gt), dtype=bool)
        matched[candidates[~disputed]] = True
        disputed_positions = np.unique(seq.pair_frame[candidates[disputed]])
        if len(disputed_positions) == 0:
            return np.nonzero(matched)[0]
        steps = CLEAR._time_steps(seq)
        step_positions = np.nonzero(steps >= 0)[0]
        tracker_at_step = np.full(seq.num_gt_ids, -1)
        for position in disputed_positions:
            previous = step_positions[steps[position] - 1] if steps[position] > 0 else None
            tracker_at_step[:] = -1
            if previous is not None:
                p0, p1 = seq.pair_slices[previous]
                pairs = np.arange(p0, p1)[matched[p0:p1]]
                tracker_at_step[seq.gt_id[seq.pair_gt[pairs]]] = seq.tracker_id[seq.pair_tracker[pairs]]
            (g0, g1), (k0, k1) = seq.gt_slices[position], seq.tracker_slices[position]
            similarity = seq.frame_matrix(position, seq.pair_similarity)
            continuing = seq.tracker_id[k0:k1][None, :] == tracker_at_step[seq.gt_id[g0:g1]][:, None]
            score = 1000.0 * continuing + similarity
            score[similarity < IOU_THRESHOLD - _EPS] = 0.0
            rows, cols = positive_matching(score)
            keep = score[rows, cols] > _EPS
            matched[seq.frame_pair_index(position)[rows[keep], cols[keep]]] = True
        return np.nonzero(matched)[0]
