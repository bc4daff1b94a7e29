"""CLEAR MOT in the bird's-eye view at one score threshold, as the nuScenes devkit counts it (py-motmetrics'
accumulator): the events behind MOTA, MOTAR, MOTP, IDS, FRAG, MT/ML and the velocity errors.

Per frame, among the tracker boxes whose track score ≥ the threshold and pairs closer than 2 m:
1. a ground truth keeps the track it was last matched to (at any earlier time) if that track is present and
   close enough;
2. the rest are matched by a minimum-distance assignment; a match to a track other than the ground truth's
   last one is an identity switch (SWITCH), otherwise a MATCH;
3. unmatched ground truth are misses (FN), unmatched tracker boxes false positives (FP).
TP counts MATCH events only (switches are matched but not TP, as in the devkit). FRAG counts, per ground
truth, the gaps inside its tracked span. MT: tracked in ≥ 80 % of its frames; ML: < 20 %.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .assignment import contested, minimum_cost_matching
from .bev import BevSequence


@dataclass(frozen=True, eq=False)
class Accumulation:
    """What happened at one threshold.

    matched: ``(k,)`` indices of matched pairs (into the sequence's pair arrays), by frame. switch: ``(k,)``
    whether each match is an identity switch. previous_track, previous_frame: ``(k,)`` the ground truth's
    last matched track (dense id) and frame position before this match (−1: none). kept_tracker_boxes:
    number of tracker boxes at or above the threshold.
    """

    matched: np.ndarray
    switch: np.ndarray
    previous_track: np.ndarray
    previous_frame: np.ndarray
    kept_tracker_boxes: int


def accumulate(seq: BevSequence, threshold: float | None) -> Accumulation:
    """Match ``seq`` keeping tracker boxes whose track score ≥ ``threshold`` (all of them for ``None``)."""
    keep_box = np.ones(len(seq.tracker_id), dtype=bool) if threshold is None else seq.tracker_score >= threshold
    pairs = np.nonzero(keep_box[seq.pair_tracker])[0]
    disputed_frames = np.unique(seq.pair_frame[pairs[contested(seq.pair_gt[pairs], seq.pair_tracker[pairs])]])
    in_disputed = np.isin(seq.pair_frame[pairs], disputed_frames)
    matched = np.zeros(len(seq.pair_gt), dtype=bool)
    matched[pairs[~in_disputed]] = True  # uncontested: every optimum contains them, whatever the history
    if len(disputed_frames):
        _resolve_contested(seq, pairs[~in_disputed], pairs[in_disputed], disputed_frames, matched)
    matched = np.nonzero(matched)[0]

    gt, track, position = seq.gt_id[seq.pair_gt[matched]], seq.tracker_id[seq.pair_tracker[matched]], \
        seq.pair_frame[matched]
    order = np.lexsort((position, gt))
    same_gt = np.concatenate([[False], gt[order][1:] == gt[order][:-1]])
    previous_track = np.full(len(matched), -1)
    previous_frame = np.full(len(matched), -1)
    previous_track[order] = np.where(same_gt, np.roll(track[order], 1), -1)
    previous_frame[order] = np.where(same_gt, np.roll(position[order], 1), -1)
    return Accumulation(
        matched=matched,
        switch=(previous_track >= 0) & (previous_track != track),
        previous_track=previous_track,
        previous_frame=previous_frame,
        kept_tracker_boxes=int(keep_box.sum()),
    )


def _resolve_contested(
    seq: BevSequence, fixed: np.ndarray, disputed: np.ndarray, frames: np.ndarray, matched: np.ndarray
) -> None:
    """Solve the contested ``frames`` in time order with motmetrics' rules, marking their matches in
    ``matched``. ``fixed``: the uncontested matched pairs; ``disputed``: the candidate pairs of contested
    frames (both sorted by frame). Each ground truth's last matched track is kept up to date on the way."""
    last_track = np.full(seq.num_gt_ids, -1)

    def remember(chosen: np.ndarray) -> None:
        gt = seq.gt_id[seq.pair_gt[chosen]]
        latest = len(gt) - 1 - np.unique(gt[::-1], return_index=True)[1]
        last_track[gt[latest]] = seq.tracker_id[seq.pair_tracker[chosen[latest]]]

    fixed_before = np.searchsorted(seq.pair_frame[fixed], frames)
    disputed_slices = np.column_stack([
        np.searchsorted(seq.pair_frame[disputed], frames), np.searchsorted(seq.pair_frame[disputed], frames, "right")
    ])
    applied = 0
    for position, stop, (d0, d1) in zip(frames, fixed_before, disputed_slices, strict=True):
        remember(fixed[applied:stop])
        applied = stop
        here = disputed[d0:d1]
        (g0, g1), (k0, k1) = seq.gt_slices[position], seq.tracker_slices[position]
        rows_here, cols_here = seq.pair_gt[here] - g0, seq.pair_tracker[here] - k0
        distance = np.full((g1 - g0, k1 - k0), np.nan)
        distance[rows_here, cols_here] = seq.pair_distance[here]
        pair_index = np.full((g1 - g0, k1 - k0), -1)
        pair_index[rows_here, cols_here] = here
        tracks = seq.tracker_id[k0:k1]
        chosen = []
        for row, gt in enumerate(seq.gt_id[g0:g1]):  # 1. keep last matches, in ground-truth order
            if last_track[gt] < 0:
                continue
            column = np.nonzero(tracks == last_track[gt])[0]
            if len(column) and np.isfinite(distance[row, column[0]]):
                chosen.append(pair_index[row, column[0]])
                distance[row, :] = np.nan
                distance[:, column[0]] = np.nan
        rows, cols = minimum_cost_matching(distance)  # 2. the rest
        chosen = np.sort(np.concatenate([np.array(chosen, dtype=np.int64), pair_index[rows, cols]]))
        matched[chosen] = True
        remember(chosen)


@dataclass(frozen=True)
class ClearCounts3D:
    """Counts at one threshold. gt: ground-truth boxes; tp: MATCH events; ids: SWITCH events; fn, fp;
    distance_sum [m] and velocity_error_sum [m/s] over matches and switches; mt, ml, frag."""

    gt: int
    tp: int
    ids: int
    fn: int
    fp: int
    frag: int
    mt: int
    ml: int
    gt_tracks: int
    distance_sum: float
    velocity_error_sum: float


def clear_counts(seq: BevSequence, result: Accumulation) -> ClearCounts3D:
    """CLEAR counts of one accumulation."""
    matched = result.matched
    gt_rows = seq.pair_gt[matched]
    tracked = np.zeros(seq.num_gt_dets, dtype=bool)
    tracked[gt_rows] = True
    present = np.bincount(seq.gt_id, minlength=seq.num_gt_ids)
    ratio = np.bincount(seq.gt_id[gt_rows], minlength=seq.num_gt_ids) / np.maximum(present, 1)
    velocity_error = np.linalg.norm(
        seq.tracker_velocity[seq.pair_tracker[matched]] - seq.gt_velocity[gt_rows], axis=1
    )
    switches = int(result.switch.sum())
    return ClearCounts3D(
        gt=seq.num_gt_dets,
        tp=len(matched) - switches,
        ids=switches,
        fn=seq.num_gt_dets - len(matched),
        fp=result.kept_tracker_boxes - len(matched),
        frag=len(fragmentations(seq, tracked)[0]),
        mt=int(np.sum((ratio >= 0.8) & (present > 0))),
        ml=int(np.sum((ratio < 0.2) & (present > 0))),
        gt_tracks=int(np.sum(present > 0)),
        distance_sum=float(np.sum(seq.pair_distance[matched])),
        velocity_error_sum=float(np.sum(velocity_error)),
    )


def fragmentations(seq: BevSequence, tracked: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gaps inside each ground truth's tracked span: ``(resume_rows, last_tracked_rows)``, ground-truth row
    indices of the box where tracking resumed and of the last tracked box before the gap."""
    order = np.lexsort((seq.gt_frame, seq.gt_id))
    gt, hit = seq.gt_id[order], tracked[order]
    same_gt = np.concatenate([[False], gt[1:] == gt[:-1]])
    # The last tracked row of the same ground truth at or before each row (−1: none yet).
    index = np.where(hit, np.arange(len(order)), -1)
    group_start = np.where(~same_gt, np.arange(len(order)), 0)
    group_start = np.maximum.accumulate(group_start)
    last_hit = np.maximum.accumulate(index)
    last_hit = np.where(last_hit >= group_start, last_hit, -1)
    previous_hit = np.concatenate([[-1], last_hit[:-1]])
    previous_hit = np.where(same_gt, previous_hit, -1)
    resumes = hit & (previous_hit >= 0) & (previous_hit != np.arange(len(order)) - 1)
    return order[resumes], order[previous_hit[resumes]]
