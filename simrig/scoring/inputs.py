"""From a dataset's ground truth and a tracker's rows to the sequences the metrics read.

2D: one :class:`~simrig.scoring.sequence.Sequence` per (camera, class), or per camera class-agnostic. Ground
truth: every actor in the camera's view (its clipped silhouette box) that the evaluation region does not ignore
(:mod:`simrig.formats.evaluation`). Tracker boxes: the tracker's own 2D rows, or — for a 3D-only tracker — its
3D boxes projected through the rig with the ground truth's geometry
(:func:`simrig.dataset.ground_truth.project_tracks`), so that 3D and 2D trackers are compared on the same
camera; those matched to an ignored box are removed (TrackEval's preprocessing).

3D: one :class:`~simrig.scoring.bev.BevSequence` per class. Ground truth and tracker boxes count only closer to
the ego than the class range (strict, BEV): :data:`CLASS_RANGE_M`. A track's score is the mean of its
per-frame scores over its boxes in range (nuScenes).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from simrig.dataset.tracks_file import TrackRows
from simrig.formats.evaluation import KEEPS_MATCHES
from simrig.formats.nuscenes.interpolation import gaps
from simrig.scenarios.evaluation_schema import NUSCENES_CLASS_RANGE_M

from ..dataset.ground_truth import GroundTruth, per_label
from ..types import ActorClass
from .bev import BevSequence, bev_sequence
from .distractors import split_distractors
from .sequence import Sequence, sequence_from_rows

CLASS_RANGE_M = {ActorClass(name): value for name, value in NUSCENES_CLASS_RANGE_M.items()}
"""[m] nuScenes' evaluation range per class (car, truck, bus 50 m; motorcycle 40 m), BEV distance from the ego."""
ANY_CLASS = "any"
"""The label of a class-agnostic sequence (``classes = "any"``)."""


def camera_sequences(truth: GroundTruth, tracks2d: TrackRows, cameras: tuple[str, ...] | None = None, *,
                     ignored: np.ndarray | None = None, classes: str = "each") -> list[Sequence]:
    """One sequence per (camera, class) for every camera of the rig (or of ``cameras``) and every class present
    on either side; with ``classes="any"`` one per camera, every class together (label ``any``).

    ``ignored``: ``(R, C)`` :class:`~simrig.formats.evaluation.IgnoreRule` bits, non-zero where a ground-truth
    box is ignored; such boxes are removed together with the tracker boxes matched to them, as TrackEval's
    preprocessing does (:mod:`simrig.scoring.distractors`), except that a box ignored only by a rule in
    :data:`~simrig.formats.evaluation.KEEPS_MATCHES` leaves its matched tracker box in place."""
    sequences = []
    for c, camera in enumerate(truth.rig.camera_names):
        if cameras is not None and camera not in cameras:
            continue
        gt_rows = np.nonzero(truth.in_view[:, c])[0]
        track_rows = np.nonzero(tracks2d.camera == camera)[0]
        if classes == ANY_CLASS:
            groups = [(ANY_CLASS, gt_rows, track_rows)] if len(gt_rows) or len(track_rows) else []
        else:
            labels = sorted(set(truth.label[gt_rows].tolist()) | set(tracks2d.label[track_rows].tolist()))
            groups = [(label, gt_rows[truth.label[gt_rows] == label], track_rows[tracks2d.label[track_rows] == label])
                      for label in labels]
        for label, g, t in groups:
            seq = _sequence(truth, tracks2d, camera, c, label, g, t)
            if ignored is not None and np.any(ignored[g, c]):
                rules = np.asarray(ignored[g, c], dtype=np.int64)
                keep_g, keep_t, untracked = split_distractors(seq, rules != 0, removes=(rules & ~KEEPS_MATCHES) != 0)
                seq = replace(_sequence(truth, tracks2d, camera, c, label, g[keep_g], t[keep_t]),
                              ignored_misses=np.column_stack([truth.frame[g[untracked]],
                                                              truth.actor_id[g[untracked]]]).astype(np.int64))
            sequences.append(seq)
    return sequences


def _sequence(truth: GroundTruth, tracks2d: TrackRows, camera: str, c: int, label: str, g: np.ndarray,
              t: np.ndarray) -> Sequence:
    return sequence_from_rows(camera, label, truth.frames, truth.frame[g], truth.actor_id[g], truth.boxes2d_in(g, c),
                              tracks2d.frame[t], tracks2d.track_id[t], tracks2d.boxes[t])


def in_class_range(truth: GroundTruth, frame: np.ndarray, label: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """Which rows (frame numbers, class names ``(n,)``, world boxes ``(n, ≥2)``) lie within their class's evaluation
    range of the ego (:data:`CLASS_RANGE_M`, as the nuScenes devkit keeps them)."""
    return truth.distance_from_ego(frame, boxes[:, :2]) < class_ranges(label)


def class_ranges(label: np.ndarray) -> np.ndarray:
    """``(n,)`` [m] the evaluation range of each class name (:data:`CLASS_RANGE_M`)."""
    return per_label(label, lambda name: CLASS_RANGE_M[ActorClass(name)])


def class_sequences(truth: GroundTruth, tracks3d: TrackRows, interpolation: str = "none") -> list[BevSequence]:
    """One BEV sequence per class present on either side (within the class range). ``interpolation``: how the
    gaps inside each ground-truth and tracker track are filled first (:mod:`simrig.formats.nuscenes.interpolation`;
    ``devkit``: as the nuScenes devkit as shipped)."""
    gt_keep = np.nonzero(in_class_range(truth, truth.frame, truth.label, truth.boxes))[0]
    track_keep = np.nonzero(in_class_range(truth, tracks3d.frame, tracks3d.label, tracks3d.boxes))[0]
    track_ids, inverse = np.unique(tracks3d.track_id[track_keep], return_inverse=True)
    mean_score = _track_means(inverse, tracks3d.score[track_keep], len(track_ids))
    gt = _Rows(truth.frame[gt_keep], truth.actor_id[gt_keep], truth.label[gt_keep], truth.boxes[gt_keep][:, :2],
               truth.boxes[gt_keep][:, 7:9], np.ones(len(gt_keep))).filled(interpolation)
    tracked = _Rows(tracks3d.frame[track_keep], tracks3d.track_id[track_keep], tracks3d.label[track_keep],
                    tracks3d.boxes[track_keep][:, :2], tracks3d.boxes[track_keep][:, 7:9],
                    mean_score[inverse]).filled(interpolation)
    labels = sorted(set(gt.label.tolist()) | set(tracked.label.tolist()))
    sequences = []
    for label in labels:
        g, t = gt.label == label, tracked.label == label
        sequences.append(bev_sequence(label, truth.frames, gt.frame[g], gt.ident[g], gt.xy[g], gt.velocity[g],
                                      tracked.frame[t], tracked.ident[t], tracked.xy[t], tracked.velocity[t],
                                      tracked.score[t]))
    return sequences


def _track_means(track: np.ndarray, score: np.ndarray, tracks: int) -> np.ndarray:
    """``(tracks,)`` mean score of each track (``track``: each row's track index), each summed as ``np.mean``
    sums (pairwise, in row order), so that a track's mean is bit-for-bit the devkit's: a score threshold that
    falls exactly on it keeps or drops the same boxes."""
    order = np.argsort(track, kind="stable")
    bounds = np.searchsorted(track[order], np.arange(tracks + 1))
    return np.array([np.mean(score[order[start:stop]]) for start, stop in zip(bounds[:-1], bounds[1:], strict=True)])


@dataclass(frozen=True)
class _Rows:
    """BEV rows of one side: frame, id, class, centre ``(n, 2)`` [m], velocity ``(n, 2)`` [m/s], score."""

    frame: np.ndarray
    ident: np.ndarray
    label: np.ndarray
    xy: np.ndarray
    velocity: np.ndarray
    score: np.ndarray

    def filled(self, interpolation: str) -> _Rows:
        """These rows with the gaps of every track filled (:func:`~simrig.formats.nuscenes.interpolation.gaps`),
        sorted by frame: a frame's own rows first, then its filled ones in the devkit's order."""
        added = gaps(self.frame, self.ident, interpolation)
        joined = _Rows(np.concatenate([self.frame, added.frame]), np.concatenate([self.ident, self.ident[added.right]]),
                       np.concatenate([self.label, self.label[added.right]]),
                       np.concatenate([self.xy, added.blend(self.xy)]),
                       np.concatenate([self.velocity, added.blend(self.velocity)]),
                       np.concatenate([self.score, added.blend(self.score)]))
        order = np.argsort(joined.frame, kind="stable")
        return _Rows(*(getattr(joined, name)[order] for name in ("frame", "ident", "label", "xy", "velocity", "score")))
