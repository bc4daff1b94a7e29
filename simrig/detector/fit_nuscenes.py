"""``simrig detector fit`` on a user's own log: a nuScenes detection-results JSON against nuScenes ground truth.

**Input.** Detections: the devkit's detection-results JSON (``{"meta": …, "results": {sample_token: [box,
…]}}``, each box ``translation``, ``size``, ``rotation``, ``velocity``, ``detection_name``,
``detection_score``), read by :func:`simrig.formats.nuscenes.tracks.read_results`; boxes of classes simrig
has none of (``trailer``, ``construction_vehicle``, ``barrier``, ``traffic_cone``) are left out. Ground truth:
the folder of the devkit's database tables (or the data root above it), read by
:func:`simrig.formats.nuscenes.ground_truth.read_nuscenes_truth` as ``simrig import --format nuscenes`` reads it
(an object is its ``instance_token``; boxes without lidar or radar points dropped), or a simrig dataset with 3D
ground truth (an import of nuScenes keeps its sample tokens; a generated one has ``SCENARIO-seedN-FFFFFF``).
Only the samples the results JSON has a key for count (a val-split result against trainval tables).

**Matching**, as the devkit's detection evaluation: ground truth and detections at or beyond the class range
from the ego (BEV; 50 m for car, truck, bus, 40 m for motorcycle, bicycle, pedestrian) are dropped, then per
class the detections, greedy by descending score, take the nearest free ground truth of their sample when the
BEV centre distance is below 2 m (:func:`.nuscenes_metrics.match_class`).

**Estimates** (:mod:`.estimators`, the same as for a simrig dataset, same TOML keys) on the matched pairs:

* σ of depth, lateral, size, yaw and velocity errors by 10 m range band, along the horizontal line of sight
  from the ego pose's position (the log has no cameras; at the box centre's height);
* ``correlation_time_s``, ``size_correlation_time_s``, ``yaw_flip_duration_s`` from pairs of one instance's
  matches in consecutive samples, Δt the median time between those samples (0.5 s for nuScenes key frames);
* ``detection``: the Gilbert–Elliott moments of each instance's misses (not matched) over the samples where it
  is in range;
* ``score``: least squares on [1, 1 − exp(−e / 1 m), min(1, d / 60 m)], no visibility term;
* ``clutter.rate_per_frame``: unmatched in-range detections per sample divided by ``cameras`` (the number of
  cameras of the rig the fitted model will run on; 6 for nuScenes).

What is not fitted, and why, is listed in the written file's notes (:func:`fit_nuscenes`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from simrig.formats.imported_truth import SourceError
from simrig.formats.nuscenes.ground_truth import read_nuscenes_truth, table_folder
from simrig.formats.nuscenes.samples import sample_tokens
from simrig.formats.nuscenes.tracks import read_results

from ..classes import ActorClass
from ..dataset import Dataset
from ..errors import DatasetError, SimrigError
from ..scenarios.evaluation_schema import NUSCENES_CLASS_RANGE_M
from .estimators import Fit, box_errors, fit_box3d, fit_scores, gilbert_elliott
from .measure import consecutive_pairs
from .nuscenes_metrics import TP_THRESHOLD, match_class

NUSCENES_CAMERAS = 6
"""Cameras of the nuScenes rig: the default divisor of the per-sample clutter rate."""
MIN_MATCHES = 100


@dataclass(frozen=True, eq=False)
class LogTruth:
    """Ground truth of a log by frame index (0 … F − 1): ``tokens`` sample token → frame; ``timestamps``
    ``(F,)`` [s]; ``ego`` ``(F, 3)`` world-frame ego position [m]; rows ``frame``, ``actor``, ``label`` ``(R,)``
    and world ``boxes`` ``(R, 9)`` (:data:`~simrig.types.BOX3D_FIELDS`)."""

    tokens: dict[str, int]
    timestamps: np.ndarray
    ego: np.ndarray
    frame: np.ndarray
    actor: np.ndarray
    label: np.ndarray
    boxes: np.ndarray


def _read_log_truth(path: Path) -> LogTruth:
    """The ground truth at ``path``: nuScenes tables, or a simrig dataset with 3D ground truth."""
    try:
        folder = table_folder(path)
    except SourceError:
        folder = None
    if folder is not None:
        truth = read_nuscenes_truth(folder)
        return LogTruth({token: k for k, token in enumerate(truth.tokens)}, np.asarray(truth.timestamps),
                        truth.egos[:, :3], truth.frame, truth.actor_id, truth.label, truth.boxes)
    try:
        dataset = Dataset.open(path)
    except DatasetError:
        raise SimrigError(f"--truth {str(path)!r}: neither nuScenes tables (a folder holding scene.json, "
                          "sample.json, …, or a data root with one such folder) nor a simrig dataset") from None
    if not dataset.has_3d:
        raise SimrigError(f"--truth {str(path)!r}: its ground truth has no 3D boxes (imported from 2D labels)")
    truth = dataset.ground_truth
    index = {int(f): k for k, f in enumerate(truth.frames)}
    return LogTruth({token: index[f] for token, f in sample_tokens(dataset).items()},
                    np.asarray(truth.timestamps, dtype=float),
                    np.array([[e.x, e.y, e.z] for e in truth.egos], dtype=float).reshape(-1, 3),
                    np.array([index[int(f)] for f in truth.frame], dtype=np.int64), truth.actor_id,
                    np.asarray(truth.label, dtype=object), truth.boxes)


def _in_range(boxes: np.ndarray, frame: np.ndarray, label: np.ndarray, ego: np.ndarray) -> np.ndarray:
    """The devkit's ``filter_eval_boxes`` range test: BEV distance from the ego strictly below the class range."""
    distance = np.hypot(*(boxes[:, :2] - ego[frame, :2]).T) if len(frame) else np.zeros(0)
    limit = np.array([NUSCENES_CLASS_RANGE_M[name] for name in label]) if len(label) else np.zeros(0)
    return distance < limit


def _matched_rows(log, gt_keep: np.ndarray, det_keep: np.ndarray, det_frame: np.ndarray, det_label: np.ndarray,
                  det_score: np.ndarray, det_boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(ground-truth rows, detection rows) of the pairs the devkit's matching makes, class by class (greedy by
    score, BEV centre distance below the TP threshold, same sample), among the rows kept."""
    gt_rows, det_rows = [], []
    for name in (c.value for c in ActorClass):
        g = np.nonzero(gt_keep & (log.label == name))[0]
        p = np.nonzero(det_keep & (det_label == name))[0]
        if not len(g) or not len(p):
            continue
        matched = match_class(log.frame[g], log.boxes[g], det_frame[p], det_boxes[p], det_score[p],
                              TP_THRESHOLD).matched_gt
        gt_rows.append(g[matched[matched >= 0]])
        det_rows.append(p[matched >= 0])
    gt_row = np.concatenate(gt_rows) if gt_rows else np.zeros(0, dtype=np.int64)
    det_row = np.concatenate(det_rows) if det_rows else np.zeros(0, dtype=np.int64)
    return gt_row, det_row


def _clutter(false: int, samples: int, cameras: int) -> tuple[float, str]:
    """(clutter rate per camera and frame, its note) of ``false`` unmatched in-range detections in ``samples``."""
    note = (f"clutter.rate_per_frame: {false} unmatched in-range detections over {samples} samples = "
            f"{false / samples:.3f} per sample, divided by --cameras {cameras} (the log's boxes are per "
            "sample, simrig's clutter per camera and frame); clutter, ghosts, duplicates, class confusions and "
            "every low-score box in the JSON all count (threshold the JSON first if your tracker does)")
    return false / (samples * cameras), note


def fit_nuscenes(detections: Path, truth: Path, cameras: int = NUSCENES_CAMERAS) -> Fit:
    """Fit the detector model of the detection-results JSON ``detections`` against the ground truth at
    ``truth`` (see the module docstring); ``cameras`` divides the per-sample clutter rate."""
    if cameras < 1:
        raise SimrigError(f"--cameras {cameras}: must be at least 1")
    log = _read_log_truth(Path(truth))
    rows, frames = read_results(Path(detections), tokens=log.tokens, kind="detection", error=SimrigError)
    samples = np.unique(np.asarray(frames, dtype=np.int64))
    if not len(samples):
        raise SimrigError(f"{detections}: \"results\" holds no sample")
    det_frame = np.array([r[0] for r in rows], dtype=np.int64)
    det_label = np.array([r[2] for r in rows], dtype=object)
    det_score = np.array([r[3] for r in rows], dtype=float)
    det_boxes = np.array([r[4:] for r in rows], dtype=float).reshape(-1, 9)
    det_keep = _in_range(det_boxes, det_frame, det_label, log.ego)
    gt_keep = np.isin(log.frame, samples) & _in_range(log.boxes, log.frame, log.label, log.ego)

    gt_row, det_row = _matched_rows(log, gt_keep, det_keep, det_frame, det_label, det_score, det_boxes)
    if len(gt_row) < MIN_MATCHES:
        raise SimrigError(f"{detections}: only {len(gt_row)} detections match ground truth in {truth} (BEV centre "
                          f"< {TP_THRESHOLD:g} m, same class, same sample); too few to fit a detector")
    notes = [f"matching: the nuScenes devkit's (per class, greedy by score, BEV centre distance < {TP_THRESHOLD:g} m;"
             " ground truth and detections at or beyond the class range from the ego dropped): "
             f"{len(samples)} samples, {int(gt_keep.sum())} ground-truth boxes, {int(det_keep.sum())} detections, "
             f"{len(gt_row)} matched; detections of classes simrig lacks left out",
             "box3d: the log has no cameras, so depth and lateral errors are taken along the horizontal line of "
             "sight from the ego pose's position, not from the camera that saw the object (the ranges differ by at "
             "most the camera's offset from the ego origin); errors beyond the 2 m match count as a miss and a "
             "clutter detection, so where σ(d) nears 1 m the fitted σ is biased low"]

    frame, actor = log.frame[gt_row], log.actor[gt_row]
    estimate, true = det_boxes[det_row], log.boxes[gt_row]
    centre = np.column_stack([log.ego[frame, :2], true[:, 2]])
    errors = box_errors(true, estimate, centre)
    pairs = consecutive_pairs(frame, np.zeros(len(frame), dtype=np.int64), actor)
    steps = log.timestamps[frame[pairs[1]]] - log.timestamps[frame[pairs[0]]]
    sample_steps = np.diff(log.timestamps[samples])
    sample_steps = sample_steps[sample_steps > 0]
    period = float(np.median(steps) if len(steps) else np.median(sample_steps) if len(sample_steps) else 0.5)
    box3d, _ = fit_box3d(errors, pairs, period, notes)
    notes.append("shared_fraction: not fitted (default): it needs one object seen by two cameras at once, and the "
                 "log has one box per object")

    hit = np.zeros(len(log.frame), dtype=bool)
    hit[gt_row] = True
    eligible = np.nonzero(gt_keep)[0]
    detection, burst_note = gilbert_elliott(log.actor[eligible], log.frame[eligible], ~hit[eligible], period,
                                            "in-range (instance, sample) boxes")
    notes.append(burst_note + "; per instance over the cameras together (simrig draws misses per (actor, camera)) "
                 "and every in-range box counts, occluded ones too (no visibility in the log)")
    notes.append("detection ramps not fitted (defaults): min/full_visible_fraction, full/max_truncation (the log "
                 "records no visibility or truncation) and full/max_range_m (misses by range are in probability)")

    error = np.hypot(*(estimate[:, :2] - true[:, :2]).T)
    score = fit_scores(det_score[det_row], error, errors["distance"], None)
    notes.append("score: least squares on [1, 1 − exp(−e / 1 m), min(1, d / 60 m)], d the range from the ego; "
                 "gain (the visible-fraction × (1 − truncation) term) not fitted: the log has neither, so gain = 0 "
                 "and base is the fitted intercept; error_scale_m and distance_scale_m fixed by the fit's design")

    clutter_rate, clutter_note = _clutter(int(det_keep.sum()) - len(det_row), len(samples), cameras)
    notes.append(clutter_note)
    notes.append("not fitted (defaults): box2d (no image boxes), embedding (no features), ghosts, duplicates and "
                 "confusion (not separable from clutter by matching per class), clutter score/size/depth ranges")
    sensor = {"detection": detection, "box3d": {k: round(float(v), 6) for k, v in box3d.items()},
              "score": score, "clutter": {"rate_per_frame": round(clutter_rate, 6)}}
    return Fit(sensor, notes)
