"""The decisions a tracker has to make, as arrays for training: per frame of a dataset, its detections with their
ground-truth identities, every (track, detection) pair the reference tracker weighed with its features
(:mod:`simrig.trackers.association_features`) and whether the two are the same object, and every pair of
detections from different cameras with theirs.

The tracks are those of the teacher — the reference Kalman tracker (``global_hungarian``'s filter, life rule,
Mahalanobis gate and Hungarian assignment) run over the dataset — so the pairs are the ones a tracker of that
family meets, with its own prediction errors. A track's identity is the actor of the detection that last updated
it (or started it); a pair is the same object when the detection's actor is the track's (clutter, actor −1,
never is). Pairs of different classes, or farther apart than ``prefilter_m``, are left out: no tracker would
weigh them.

Datasets with capture timing (late detections) are refused for now: their detections reach the tracker in
another order than the table's.
"""

from __future__ import annotations

import inspect
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from simrig.trackers.assignment import hungarian
from simrig.trackers.association_features import DETECTION_PAIR_FEATURES, TRACK_FEATURES, detection_pair_features
from simrig.trackers.detections import DetectionArrays
from simrig.trackers.global_hungarian import global_hungarian
from simrig.trackers.learned import AppearanceKalmanTracker
from simrig.trackers.settings import kalman_tracker_parts

from ..dataset import Dataset
from ..errors import DatasetError

PREFILTER_M = 10.0
"""[m] pairs farther apart than this are not recorded (nor weighed by the learned tracker)."""


@dataclass(frozen=True)
class FramePairs:
    """One frame's detections and decisions (M detections, P track pairs, Q camera pairs).

    ``boxes3d`` (M, 9) world frame [m, rad, m/s], ``labels``, ``scores``, ``cameras`` (M,), ``embeddings`` (M, D),
    ``actor_ids`` (M,) ground-truth identity (−1: clutter); ``track_features`` (P, F) in
    :data:`~simrig.trackers.association_features.TRACK_FEATURES` order, ``track_same`` (P,) bool, ``track_ids``
    (P,) the teacher's track ids, ``track_detections`` (P,) detection rows; ``camera_features`` (Q, G) in
    :data:`~simrig.trackers.association_features.DETECTION_PAIR_FEATURES` order, ``camera_same`` (Q,),
    ``camera_first``/``camera_second`` (Q,) detection rows (first < second, different cameras)."""

    sequence: int
    frame: int
    boxes3d: np.ndarray
    labels: np.ndarray
    scores: np.ndarray
    cameras: np.ndarray
    embeddings: np.ndarray
    actor_ids: np.ndarray
    track_features: np.ndarray
    track_same: np.ndarray
    track_ids: np.ndarray
    track_detections: np.ndarray
    camera_features: np.ndarray
    camera_same: np.ndarray
    camera_first: np.ndarray
    camera_second: np.ndarray


def detection_actor_ids(dataset: Dataset) -> np.ndarray:
    """(rows of the ``detections`` table,) the actor each detection came from (−1: clutter), via ``sensor_truth``."""
    cameras = {name: index for index, name in enumerate(dataset.rig.camera_names)}
    detections = dataset.columns("detections", ["frame", "camera", "index"])
    truth = dataset.columns("sensor_truth", ["frame", "camera", "actor_id", "detection"])
    made = truth.column("detection").to_numpy() >= 0

    def keys(table, index_column: str, rows=slice(None)) -> np.ndarray:
        frame = table.column("frame").to_numpy()[rows].astype(np.int64)
        camera = np.array([cameras[name] for name in np.asarray(table.column("camera").to_pylist())[rows]],
                          dtype=np.int64).reshape(-1)
        index = table.column(index_column).to_numpy()[rows].astype(np.int64)
        return (frame * len(cameras) + camera) * (1 << 20) + index

    wanted = keys(detections, "index")
    known = keys(truth, "detection", made)
    actors = truth.column("actor_id").to_numpy()[made]
    order = np.argsort(known)
    place = np.searchsorted(known[order], wanted)
    found = (place < len(known)) & (known[order][np.minimum(place, len(known) - 1)] == wanted)
    if not found.all():
        raise DatasetError(f"{dataset.path}: sensor_truth does not name the source of every detection")
    return actors[order][place]


class _Recorder(AppearanceKalmanTracker):
    """The teacher: records every weighed pair before it associates, and each track's identity as it updates."""

    def __init__(self, prefilter_m: float, **parts):
        super().__init__(**parts)
        self.prefilter_m = prefilter_m
        self.actors = np.zeros(0, dtype=np.int64)  # of the frame's detections, set before each step
        self.identity: dict[int, int] = {}
        self.recorded: tuple[np.ndarray, ...] = ()

    def associate(self, detections: DetectionArrays) -> np.ndarray:
        features = self.pair_features(detections)
        labels = np.array([track.label for track in self.tracks], dtype=np.int64)
        rows, cols = np.nonzero((labels[:, None] == detections.labels[None, :])
                                & (features[..., 1] <= self.prefilter_m))
        ids = np.array([track.track_id for track in self.tracks], dtype=np.int64)
        identity = np.array([self.identity.get(int(track_id), -2) for track_id in ids], dtype=np.int64)
        same = (identity[rows] == self.actors[cols]) & (self.actors[cols] >= 0)
        self.recorded = (features[rows, cols], same, ids[rows], cols.astype(np.int64))
        return super().associate(detections)

    def update(self, detections: DetectionArrays, owner: np.ndarray) -> dict[int, float]:
        scores = super().update(detections, owner)
        for j in np.flatnonzero(owner >= 0):
            self.identity[self.tracks[int(owner[j])].track_id] = int(self.actors[j])
        return scores

    def newborn(self, track, detections: DetectionArrays, source: int) -> None:
        super().newborn(track, detections, source)
        self.identity[track.track_id] = int(self.actors[source])


_TEACHER_SETTINGS = ("cost", "gate", "life", "min_hits", "max_age_s", "measurement_variance", "score_threshold")


def teacher(prefilter_m: float = PREFILTER_M) -> _Recorder:
    """The reference tracker whose decisions are recorded: ``global_hungarian``'s filter, life rule, gate and
    Hungarian assignment at its defaults (read from its signature, so that the two cannot drift apart)."""
    defaults = inspect.signature(global_hungarian).parameters
    parts = kalman_tracker_parts(**{name: defaults[name].default for name in _TEACHER_SETTINGS})
    return _Recorder(prefilter_m, **parts, assign=hungarian)


def _camera_pairs(arrays: DetectionArrays, actors: np.ndarray, ranges: np.ndarray,
                  prefilter_m: float) -> tuple[np.ndarray, ...]:
    features = detection_pair_features(arrays.boxes3d, arrays.scores, arrays.embeddings, ranges)
    first, second = np.nonzero(np.triu((arrays.cameras[:, None] != arrays.cameras[None, :])
                                       & (arrays.labels[:, None] == arrays.labels[None, :]), k=1)
                               & (features[..., 0] <= prefilter_m))
    same = (actors[first] == actors[second]) & (actors[first] >= 0)
    return features[first, second], same, first.astype(np.int64), second.astype(np.int64)


def sequence_pairs(dataset: Dataset, *, sequence: int = 0, prefilter_m: float = PREFILTER_M) -> Iterator[FramePairs]:
    """Every stepped frame of ``dataset`` as :class:`FramePairs` (``sequence`` is copied into each)."""
    if dataset.has_table("captures"):
        raise DatasetError(f"{dataset.path}: a dataset with capture timing (late detections) is not supported by the "
                           "training loader yet")
    if not dataset.has_3d:
        raise DatasetError(f"{dataset.path}: no 3D detections to pair")
    actors = detection_actor_ids(dataset)
    frames = dataset.columns("detections", ["frame"]).column("frame").to_numpy()
    recorder = teacher(prefilter_m)
    recorder.reset(rig=dataset.rig)
    for frame in dataset.sensor_frames():
        lo, hi = np.searchsorted(frames, [frame.frame, frame.frame + 1])
        arrays = frame.arrays
        recorder.actors = actors[lo:hi]
        recorder.recorded = (np.zeros((0, len(TRACK_FEATURES))), np.zeros(0, bool), np.zeros(0, np.int64),
                             np.zeros(0, np.int64))
        recorder.step(frame)
        ranges = np.hypot(arrays.boxes3d[:, 0] - frame.ego.x, arrays.boxes3d[:, 1] - frame.ego.y)
        camera = (_camera_pairs(arrays, recorder.actors, ranges, prefilter_m) if len(arrays) else
                  (np.zeros((0, len(DETECTION_PAIR_FEATURES))), np.zeros(0, bool), np.zeros(0, np.int64),
                   np.zeros(0, np.int64)))
        yield FramePairs(sequence, frame.frame, arrays.boxes3d, arrays.labels, arrays.scores, arrays.cameras,
                         arrays.embeddings, recorder.actors, *recorder.recorded, *camera)
