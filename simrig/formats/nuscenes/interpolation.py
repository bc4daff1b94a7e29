"""Filling the gaps inside a 3D track before the AMOTA family, as the nuScenes devkit does.

The devkit (``nuscenes/eval/tracking/loaders.py``, ``interpolate_tracks``, nuscenes-devkit 1.2.0) fills every
sample missing inside a track's span — ground truth per instance, a tracker's boxes per ``tracking_id`` — with a
box interpolated linearly between the nearest boxes before (L) and after (R), after the class-range filter and
after the track score is averaged. The interpolated box takes R's class and id. Its weight on R is, as shipped,
``r = (t_R − t) / (t_R − t_L)``: the weight of the *nearer* box is given to the farther one (inverted; reported as
nutonomy/nuscenes-devkit issue 1141). For a one-sample gap both weights are ½ and the variants agree.

Variants (``interpolation``):

* ``devkit`` — as shipped, inverted weights: numbers that compare with the devkit and the leaderboard;
* ``corrected`` — ``r = (t − t_L) / (t_R − t_L)``, the linear interpolation the devkit means;
* ``none`` — no gap filled: every frame scored as the tracker gave it.

Frames are equally spaced, so ratios of frame numbers equal the devkit's ratios of timestamps.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

INTERPOLATIONS = ("devkit", "corrected", "none")
"""The gap-filling rules, the devkit's first."""


@dataclass(frozen=True)
class Gaps:
    """The rows that fill the gaps of a set of tracks: ``frame`` ``(g,)`` the missing frames, ``left`` and
    ``right`` ``(g,)`` the source rows before and after each, ``weight_right`` ``(g,)`` R's weight."""

    frame: np.ndarray
    left: np.ndarray
    right: np.ndarray
    weight_right: np.ndarray

    def blend(self, values: np.ndarray) -> np.ndarray:
        """``(1 − r)·values[left] + r·values[right]`` row by row, in the devkit's order of operations (so that
        equal values stay bit-for-bit equal where the devkit keeps them)."""
        values = np.asarray(values, dtype=float)
        weight = self.weight_right.reshape((-1,) + (1,) * (values.ndim - 1))
        return (1.0 - weight) * values[self.left] + weight * values[self.right]


def gaps(frame: np.ndarray, ident: np.ndarray, interpolation: str) -> Gaps:
    """The gaps of the tracks given by rows (``frame``, ``ident``; one row per frame and id), ordered as the
    devkit appends them: by frame, then by the order in which the ids first appear (frame, then row order)."""
    if interpolation not in INTERPOLATIONS:
        raise ValueError(f"interpolation {interpolation!r}: choose one of {', '.join(INTERPOLATIONS)}")
    frame, ident = np.asarray(frame, dtype=np.int64), np.asarray(ident)
    empty = Gaps(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0))
    if interpolation == "none" or len(frame) < 2:
        return empty
    order = np.lexsort((frame, ident))  # by id, then frame
    same = ident[order][1:] == ident[order][:-1]
    step = np.diff(frame[order])
    starts = np.nonzero(same & (step > 1))[0]
    if not len(starts):
        return empty
    counts = step[starts] - 1
    left = np.repeat(order[starts], counts)
    right = np.repeat(order[starts + 1], counts)
    missing = frame[left] + np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts) + 1
    span = (frame[right] - frame[left]).astype(float)
    weight = ((frame[right] - missing) if interpolation == "devkit" else (missing - frame[left])) / span
    by_appearance = np.lexsort((np.arange(len(frame)), frame))
    _, first = np.unique(ident[by_appearance], return_index=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    id_rank = rank[np.searchsorted(np.unique(ident), ident[right])]
    appended = np.lexsort((id_rank, missing))
    return Gaps(missing[appended], left[appended], right[appended], weight[appended])
