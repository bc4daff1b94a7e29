"""HOTA (Luiten et al. 2021), counted per sequence exactly as TrackEval's ``metrics/hota.py`` defines it.

One Hungarian match per frame on (global alignment score × IoU), then cut at each α in 0.05, 0.10 … 0.95
(19 values) — not a re-match per α. Counts are arrays over α; AssA, AssRe, AssPr and LocA are kept as sums
over true positives so that sequences combine by addition (TrackEval weights them by TP, the same thing).
"""

from __future__ import annotations

import numpy as np

from .assignment import contested, positive_matching
from .counts import Counts
from .ratios import hota_ratios
from .sequence import Sequence

ALPHAS = np.arange(0.05, 0.99, 0.05)
"""The 19 localisation thresholds α (TrackEval's ``array_labels``)."""
_EPS = np.finfo(float).eps


class HOTA:
    """HOTA, DetA, AssA, LocA and their recall/precision parts; counts are ``(19,)`` arrays over α."""

    name = "hota"
    fields = ("HOTA_TP", "HOTA_FN", "HOTA_FP", "AssA_sum", "AssRe_sum", "AssPr_sum", "LocA_sum")
    outputs = ("HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr")

    def empty(self) -> Counts:
        """The counts of a sequence with nothing in it."""
        return {name: np.zeros(len(ALPHAS)) for name in self.fields}

    def ratios(self, counts: Counts) -> dict[str, float]:
        """Every value of the unit from (summed) counts: :func:`simrig.scoring.ratios.hota_ratios`."""
        return hota_ratios(counts)

    def count(self, seq: Sequence) -> Counts:
        """HOTA counts of one sequence."""
        n_alpha = len(ALPHAS)
        gt_dets, tracker_dets = seq.num_gt_dets, seq.num_tracker_dets
        gt_n = np.bincount(seq.gt_id, minlength=seq.num_gt_ids).astype(float)
        tracker_n = np.bincount(seq.tracker_id, minlength=seq.num_tracker_ids).astype(float)
        g, k = seq.gt_id[seq.pair_gt], seq.tracker_id[seq.pair_tracker]
        sim = seq.pair_similarity
        # Global alignment: per frame, each pair's IoU over (its row sum + column sum − itself), summed per id pair.
        row_sum = np.bincount(seq.pair_gt, weights=sim, minlength=gt_dets)[seq.pair_gt]
        col_sum = np.bincount(seq.pair_tracker, weights=sim, minlength=tracker_dets)[seq.pair_tracker]
        key = g * seq.num_tracker_ids + k
        unique_keys, key_index = np.unique(key, return_inverse=True)
        potential = np.bincount(key_index, weights=sim / (row_sum + col_sum - sim), minlength=len(unique_keys))
        alignment = potential / (gt_n[unique_keys // max(1, seq.num_tracker_ids)]
                                 + tracker_n[unique_keys % max(1, seq.num_tracker_ids)] - potential)
        score = alignment[key_index] * sim

        matched = self._matches(seq, score)
        sims = sim[matched]
        passed = sims[None, :] >= ALPHAS[:, None] - _EPS  # (A, M)
        tp = passed.sum(axis=1).astype(float)
        pair_keys, pair_of_match = np.unique(key_index[matched], return_inverse=True)
        matches = np.zeros((n_alpha, len(pair_keys)))
        alpha_index, match_index = np.nonzero(passed)
        np.add.at(matches, (alpha_index, pair_of_match[match_index]), 1.0)
        gt_count = gt_n[unique_keys[pair_keys] // max(1, seq.num_tracker_ids)]
        tracker_count = tracker_n[unique_keys[pair_keys] % max(1, seq.num_tracker_ids)]
        return {
            "HOTA_TP": tp,
            "HOTA_FN": gt_dets - tp,
            "HOTA_FP": tracker_dets - tp,
            "AssA_sum": np.sum(matches * matches / np.maximum(1.0, gt_count + tracker_count - matches), axis=1),
            "AssRe_sum": np.sum(matches * matches / np.maximum(1.0, gt_count), axis=1),
            "AssPr_sum": np.sum(matches * matches / np.maximum(1.0, tracker_count), axis=1),
            "LocA_sum": np.where(passed, sims[None, :], 0.0).sum(axis=1),
        }

    @staticmethod
    def _matches(seq: Sequence, score: np.ndarray) -> np.ndarray:
        """Indices of the pairs matched by the per-frame maximum-score assignment."""
        disputed_frames = np.unique(seq.pair_frame[contested(seq.pair_gt, seq.pair_tracker)])
        matched = [np.nonzero(~np.isin(seq.pair_frame, disputed_frames))[0]]
        for position in disputed_frames:
            rows, cols = positive_matching(seq.frame_matrix(position, score))
            matched.append(seq.frame_pair_index(position)[rows, cols])
        return np.sort(np.concatenate(matched))
