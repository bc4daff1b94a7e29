"""The nuScenes tracking metrics of one class (AMOTA, AMOTP, MOTAR, MOTA, MOTP, RECALL, IDS, FRAG, MT, ML, TP,
FP, FN) and MUTR3D's velocity errors (ATVE, TVE; Eq. 11 of "MUTR3D: A Multi-camera Tracking Framework via
3D-to-2D Queries", Zhang et al., 2022), following the devkit's algorithm on exact per-frame ground truth (no
interpolation of either side).

1. Match with every tracker box kept; the track scores of the MATCH events, sorted, give the recall reached
   at each score. 40 recall levels ``linspace(0.1, 1, 40)``: a level's score threshold is interpolated from
   those scores; a level above the highest recall reached is not reached.
2. At each distinct threshold, keep tracker boxes whose track score ≥ it and count CLEAR events
   (:mod:`simrig.scoring.clear3d`).
3. MOTAR_r = max(0, 1 − (IDS + FP + FN − (1 − r)·P) / (r·P)) with P the ground-truth boxes and r = TP/P the
   measured recall (TP counts MATCH events, not switches, as the devkit does; algebraically this is
   max(0, 1 − FP/TP)). A class with ground truth that reaches no level gets the devkit's worst values
   (``metric_worst``: MOTAR 0, MOTA 0, MOTP 2 m, RECALL 0), so it lowers the overall mean.
   AMOTA = mean of MOTAR_r over the 40 levels (0 where unreached); AMOTP = mean of
   MOTP_r [m] (2 m where unreached). ATVE = mean over the reached levels of the mean velocity error [m/s] of
   matched pairs (no worst value is defined for it; NaN when no level is reached).
4. MOTA (clipped at 0), MOTP, RECALL (matches incl. switches / P), IDS, FRAG, MT, ML, TP, FP, FN and TVE are
   read at the level with the highest MOTA; ties go to the highest recall.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .bev import BevSequence
from .clear3d import Accumulation, ClearCounts3D, accumulate, clear_counts
from .results import COUNT_METRICS

RECALL_LEVELS = np.linspace(0.1, 1.0, 40).round(12)
"""The 40 recall levels r of AMOTA (the devkit's ``min_recall`` 0.1 to 1)."""
WORST_MOTP_M = 2.0
"""[m] MOTP counted for an unreached recall level in AMOTP."""


@dataclass(frozen=True)
class LevelResult:
    """One recall level: its hypothetical recall, score threshold (NaN: unreached) and counts (None: unreached)."""

    recall: float
    threshold: float
    counts: ClearCounts3D | None


@dataclass(frozen=True)
class AmotaResult:
    """A class's AMOTA family: ``metrics`` (name → value; NaN where undefined), the 40 ``levels`` and the
    accumulation at the best-MOTA threshold (``None`` when no level is reached)."""

    metrics: dict[str, float]
    levels: tuple[LevelResult, ...]
    best: Accumulation | None
    best_threshold: float


def _score_thresholds(seq: BevSequence) -> np.ndarray:
    """``(40,)`` score threshold of each recall level in :data:`RECALL_LEVELS` order (NaN: not reached)."""
    if seq.num_gt_dets == 0:
        return np.full(len(RECALL_LEVELS), np.nan)
    everything = accumulate(seq, None)
    true_positives = everything.matched[~everything.switch]
    scores = np.sort(seq.tracker_score[seq.pair_tracker[true_positives]])[::-1]
    if len(scores) == 0:
        return np.full(len(RECALL_LEVELS), np.nan)
    recall = np.arange(1, len(scores) + 1) / seq.num_gt_dets
    thresholds = np.interp(RECALL_LEVELS, recall, scores, right=0)
    thresholds[RECALL_LEVELS > recall.max()] = np.nan
    return thresholds


def motar(c: ClearCounts3D) -> float:
    """MOTAR of one level's counts (NaN when nothing was matched)."""
    r = c.tp / c.gt
    if r == 0:
        return float("nan")
    return float(max(0.0, 1.0 - (c.ids + c.fp + c.fn - (1.0 - r) * c.gt) / (r * c.gt)))


def _level_values(c: ClearCounts3D) -> dict[str, float]:
    """Every per-level metric of one level's counts."""
    matched = c.tp + c.ids
    return {
        "MOTAR": motar(c),
        "MOTA": float(max(0.0, 1.0 - (c.fn + c.ids + c.fp) / c.gt)),
        "MOTP": c.distance_sum / matched if matched else float("nan"),
        "RECALL": matched / c.gt,
        "TVE": c.velocity_error_sum / matched if matched else float("nan"),
        "IDS": c.ids, "FRAG": c.frag, "MT": c.mt, "ML": c.ml, "TP": c.tp, "FP": c.fp, "FN": c.fn,
    }


def amota_family(seq: BevSequence) -> AmotaResult:
    """The AMOTA family of one class; all NaN when the class has no ground truth."""
    thresholds = _score_thresholds(seq)
    cache: dict[float, ClearCounts3D] = {}  # counts only: a long sequence's matches at 40 levels are large
    levels = []
    for recall, threshold in zip(RECALL_LEVELS, thresholds, strict=True):
        if np.isnan(threshold):
            levels.append(LevelResult(float(recall), float("nan"), None))
            continue
        if threshold not in cache:
            cache[threshold] = clear_counts(seq, accumulate(seq, float(threshold)))
        levels.append(LevelResult(float(recall), float(threshold), cache[threshold]))
    names = ("AMOTA", "AMOTP", "ATVE", "MOTAR", "MOTA", "MOTP", "RECALL", "TVE",
             "IDS", "FRAG", "MT", "ML", "TP", "FP", "FN")
    metrics = dict.fromkeys(names, float("nan"))
    if seq.num_gt_dets == 0:
        return AmotaResult(metrics, tuple(levels), None, float("nan"))
    reached = [level for level in levels if level.counts is not None]
    values = [_level_values(level.counts) for level in reached]
    unreached = len(levels) - len(reached)
    motars = [v["MOTAR"] for v in values]
    metrics["AMOTA"] = float(np.sum(np.nan_to_num(motars, nan=0.0)) / len(levels))
    metrics["AMOTP"] = float((np.sum(np.nan_to_num([v["MOTP"] for v in values], nan=WORST_MOTP_M))
                              + unreached * WORST_MOTP_M) / len(levels))
    velocity = [v["TVE"] for v in values if not np.isnan(v["TVE"])]
    metrics["ATVE"] = float(np.mean(velocity)) if velocity else float("nan")
    if not reached:
        gt_tracks = int(len(np.unique(seq.gt_id)))
        # The devkit's metric_worst for a class with ground truth that reaches no recall level.
        metrics.update(MOTAR=0.0, MOTA=0.0, MOTP=WORST_MOTP_M, RECALL=0.0, TP=0, MT=0, ML=gt_tracks,
                       FN=seq.num_gt_dets)
        return AmotaResult(metrics, tuple(levels), None, float("nan"))
    # Levels run from the lowest recall up; the devkit lists them from the highest down and takes the first
    # maximum, so ties go to the highest recall.
    mota = np.array([v["MOTA"] for v in values])
    best = len(values) - 1 - int(np.argmax(mota[::-1]))
    metrics.update({name: values[best][name] for name in
                    ("MOTAR", "MOTA", "MOTP", "RECALL", "TVE", "IDS", "FRAG", "MT", "ML", "TP", "FP", "FN")})
    best_threshold = reached[best].threshold
    return AmotaResult(metrics, tuple(levels), accumulate(seq, best_threshold), best_threshold)


def combine_classes(per_class: dict[str, dict[str, float]], names: tuple[str, ...] | None = None
                    ) -> dict[str, float]:
    """Overall 3D metrics from per-class ones, the devkit's rule by name: counts summed over the classes (0 when
    nothing was scored), every other metric the mean over the classes where it is defined (NaN when none is:
    no class has ground truth). A class with ground truth and no reached recall level has MOTAR 0, so it counts.
    ``names``: the metrics to combine (default: those of the classes).

    >>> combine_classes({"car": {"MOTAR": 1.0, "IDS": 2}, "truck": {"MOTAR": 0.0, "IDS": 1}})
    {'MOTAR': 0.5, 'IDS': 3.0}
    """
    if names is None:
        names = tuple(dict.fromkeys(name for values in per_class.values() for name in values))
    overall = {}
    for name in names:
        values = np.array([values[name] for values in per_class.values()], dtype=float).reshape(-1)
        present = values[~np.isnan(values)]
        if name in COUNT_METRICS:
            overall[name] = float(present.sum())
        else:
            overall[name] = float(present.mean()) if len(present) else float("nan")
    return overall
