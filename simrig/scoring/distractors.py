"""Ignored ground truth as TrackEval's ``MotChallenge2DBox`` preprocessing treats distractors
(``get_preprocessed_seq_data``, TrackEval 1.3): per frame, every tracker box is matched to *all* ground truth of
the sequence, ignored boxes included, by a Hungarian on IoU with scores below 0.5 − ε set to 0 (only positive
matches kept); a tracker box matched to an ignored box is removed; then the ignored boxes are removed. What is
left is scored as usual, so an untracked ignored box is no miss and a tracker box on one is no false positive.
"""

from __future__ import annotations

import numpy as np

from .assignment import contested, positive_matching
from .sequence import Sequence

_EPS = np.finfo(float).eps
MATCH_IOU = 0.5
"""Minimum IoU of the preprocessing match (TrackEval's, the same as CLEAR's)."""


def _preprocessing_matches(seq: Sequence) -> np.ndarray:
    """Indices of the pairs of ``seq`` that TrackEval's preprocessing Hungarian matches (IoU ≥ 0.5 − ε)."""
    candidate = seq.pair_similarity >= MATCH_IOU - _EPS
    candidates = np.nonzero(candidate)[0]
    disputed = contested(seq.pair_gt[candidates], seq.pair_tracker[candidates])
    matched = [candidates[~disputed]]
    score = np.where(candidate, seq.pair_similarity, 0.0)
    for position in np.unique(seq.pair_frame[candidates[disputed]]):
        rows, cols = positive_matching(seq.frame_matrix(position, score))
        matched.append(seq.frame_pair_index(position)[rows, cols])
    return np.sort(np.concatenate(matched))


def split_distractors(seq: Sequence, ignored: np.ndarray, removes: np.ndarray | None = None
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For ``seq`` built on all ground truth and ``ignored`` ``(n,)`` its ignored gt rows: (gt rows to keep,
    tracker rows to keep, ignored gt rows that no tracker box was matched to), all as row indices of ``seq``.
    ``removes`` ``(n,)``: the ignored rows whose matched tracker box is removed (default: all of them; a row
    the source does not evaluate keeps its match, a false positive, as TrackEval keeps a box matched to ground
    truth of another class)."""
    matched = _preprocessing_matches(seq)
    on_ignored = (ignored if removes is None else removes & ignored)[seq.pair_gt[matched]]
    keep_tracker = np.ones(seq.num_tracker_dets, dtype=bool)
    keep_tracker[seq.pair_tracker[matched[on_ignored]]] = False
    tracked = np.zeros(seq.num_gt_dets, dtype=bool)
    tracked[seq.pair_gt[matched]] = True
    return np.nonzero(~ignored)[0], np.nonzero(keep_tracker)[0], np.nonzero(ignored & ~tracked)[0]
