"""Identity metrics (IDF1, IDP, IDR; Ristani et al. 2016), counted per sequence as TrackEval defines them.

A ground-truth id and a tracker id are paired once for the whole sequence so as to maximise the number of
frames where they overlap with IoU ≥ 0.5 (a global min-cost assignment; the optimum value is unique, so the
rectangular maximum-weight matching used here gives TrackEval's IDTP exactly).
"""

from __future__ import annotations

import numpy as np

from .clear import IOU_THRESHOLD
from .counts import Counts
from .hungarian import linear_sum_assignment
from .ratios import identity_ratios
from .sequence import Sequence


class Identity:
    """IDTP, IDFN, IDFP."""

    name = "identity"
    fields = ("IDTP", "IDFN", "IDFP")
    outputs = ("IDF1", "IDP", "IDR")

    def empty(self) -> Counts:
        """The counts of a sequence with nothing in it."""
        return dict.fromkeys(self.fields, 0.0)

    def ratios(self, counts: Counts) -> dict[str, float]:
        """Every value of the unit from (summed) counts: :func:`simrig.scoring.ratios.identity_ratios`."""
        return identity_ratios(counts)

    def count(self, seq: Sequence) -> Counts:
        """Identity counts of one sequence."""
        gt_dets, tracker_dets = seq.num_gt_dets, seq.num_tracker_dets
        overlapping = seq.pair_similarity >= IOU_THRESHOLD
        gt_of_pair = seq.gt_id[seq.pair_gt[overlapping]]
        tracker_of_pair = seq.tracker_id[seq.pair_tracker[overlapping]]
        id_tp = 0.0
        if len(gt_of_pair):
            gt_index, gt_dense = np.unique(gt_of_pair, return_inverse=True)
            tracker_index, tracker_dense = np.unique(tracker_of_pair, return_inverse=True)
            weight = np.zeros((len(gt_index), len(tracker_index)))
            np.add.at(weight, (gt_dense, tracker_dense), 1.0)
            rows, cols = linear_sum_assignment(-weight)
            id_tp = float(weight[rows, cols].sum())
        return {"IDTP": id_tp, "IDFN": gt_dets - id_tp, "IDFP": tracker_dets - id_tp}
