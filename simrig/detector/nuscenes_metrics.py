"""nuScenes detection metrics with the devkit's definitions (``nuscenes/eval/detection/algo.py``).

Per class, predictions of all samples are sorted by descending score (ties: the later prediction first,
as the devkit's ``sorted(...)[::-1]``) and each is matched greedily to the nearest not-yet-taken ground
truth box of its class in its sample by bird's-eye-view centre distance, a match if below the threshold.
True-positive errors at the 2 m threshold: ATE the centre distance [m], ASE 1 − 3D IoU after aligning
centres and yaw, AOE the smallest yaw difference [rad] (period 2π), AVE the L2 velocity error [m/s]. Each
is a running mean over matches in score order, interpolated on recall (101 points) and averaged over the
recall range from 0.1 to the highest recall reached (``calc_tp``); AP is the mean of the interpolated
precision above 0.1 over recall ≥ 0.1, rescaled (``calc_ap``). Class means ignore classes without ground
truth. Boxes are rows in :data:`~simrig.types.BOX3D_FIELDS` order.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

TP_METRICS = ("trans_err", "scale_err", "orient_err", "vel_err")
DIST_THRESHOLDS = (0.5, 1.0, 2.0, 4.0)
TP_THRESHOLD = 2.0
_RECALL = np.linspace(0.0, 1.0, 101)
_FIRST = round(100 * 0.1) + 1


def _cummean(x: np.ndarray) -> np.ndarray:
    """Running mean ignoring NaN (the devkit's ``cummean``)."""
    if np.all(np.isnan(x)):
        return np.ones(len(x))
    return np.nancumsum(x) / np.cumsum(~np.isnan(x))


def _angle_diff(a: np.ndarray, b: np.ndarray, period: float = 2 * np.pi) -> np.ndarray:
    diff = (a - b + period / 2) % period - period / 2
    return np.where(diff > np.pi, diff - 2 * np.pi, diff)


def _scale_iou(gt: np.ndarray, pred: np.ndarray) -> np.ndarray:
    """3D IoU of boxes with aligned centres and yaw from their sizes ``(N, 3)``."""
    intersection = np.prod(np.minimum(gt, pred), axis=-1)
    return intersection / (np.prod(gt, axis=-1) + np.prod(pred, axis=-1) - intersection)


@dataclass
class ClassMatches:
    """The matching of one class at one threshold: per prediction in score order whether it matched,
    its score, and the matched pairs' errors; ``npos`` ground-truth boxes; ``matched_gt`` ground-truth row
    of each prediction (−1 for a false positive) and ``order`` the prediction rows in score order."""

    npos: int
    tp: np.ndarray
    conf: np.ndarray
    errors: dict[str, np.ndarray] = field(default_factory=dict)
    matched_gt: np.ndarray | None = None
    order: np.ndarray | None = None


def match_class(gt_sample: np.ndarray, gt_boxes: np.ndarray, pred_sample: np.ndarray, pred_boxes: np.ndarray,
                pred_scores: np.ndarray, threshold: float) -> ClassMatches:
    """Greedy devkit matching of one class's predictions to its ground truth (rows of one class)."""
    order = np.lexsort((np.arange(len(pred_scores)), pred_scores))[::-1]
    by_sample: dict[int, np.ndarray] = {}
    for sample in np.unique(gt_sample):
        by_sample[int(sample)] = np.nonzero(gt_sample == sample)[0]
    taken = np.zeros(len(gt_boxes), dtype=bool)
    matched = np.full(len(pred_scores), -1, dtype=np.int64)
    for row in order:
        candidates = by_sample.get(int(pred_sample[row]))
        if candidates is None:
            continue
        free = candidates[~taken[candidates]]
        if not len(free):
            continue
        distance = np.hypot(gt_boxes[free, 0] - pred_boxes[row, 0], gt_boxes[free, 1] - pred_boxes[row, 1])
        best = int(np.argmin(distance))
        if distance[best] < threshold:
            taken[free[best]] = True
            matched[row] = free[best]
    tp = matched[order] >= 0
    pairs = order[tp]
    gt, pred = gt_boxes[matched[pairs]], pred_boxes[pairs]
    errors = {
        "trans_err": np.hypot(gt[:, 0] - pred[:, 0], gt[:, 1] - pred[:, 1]),
        "scale_err": 1.0 - _scale_iou(gt[:, [4, 3, 5]], pred[:, [4, 3, 5]]),
        "orient_err": np.abs(_angle_diff(gt[:, 6], pred[:, 6])),
        "vel_err": np.hypot(gt[:, 7] - pred[:, 7], gt[:, 8] - pred[:, 8]),
    }
    return ClassMatches(len(gt_boxes), tp, pred_scores[order], errors, matched, order)


def accumulate(matches: ClassMatches) -> dict[str, np.ndarray] | None:
    """The devkit's ``accumulate``: precision, confidence and running-mean TP errors on the recall grid;
    None when nothing matched."""
    if not matches.tp.any() or matches.npos == 0:
        return None
    tp = np.cumsum(matches.tp).astype(float)
    fp = np.cumsum(~matches.tp).astype(float)
    precision = tp / (fp + tp)
    recall = tp / float(matches.npos)
    out = {"precision": np.interp(_RECALL, recall, precision, right=0),
           "confidence": np.interp(_RECALL, recall, matches.conf, right=0)}
    match_conf = matches.conf[matches.tp]
    for key, values in matches.errors.items():
        running = _cummean(values)
        out[key] = np.interp(out["confidence"][::-1], match_conf[::-1], running[::-1])[::-1]
    return out


def calc_ap(data: dict[str, np.ndarray] | None, min_precision: float = 0.1) -> float:
    if data is None:
        return 0.0
    precision = np.clip(data["precision"][_FIRST:] - min_precision, 0.0, None)
    return float(np.mean(precision) / (1.0 - min_precision))


def calc_tp(data: dict[str, np.ndarray] | None, metric: str) -> float:
    if data is None:
        return 1.0
    nonzero = np.nonzero(data["confidence"])[0]
    last = int(nonzero[-1]) if len(nonzero) else -1
    if last < _FIRST:
        return 1.0
    return float(np.mean(data[metric][_FIRST:last + 1]))
