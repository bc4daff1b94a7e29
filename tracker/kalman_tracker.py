"""The coordinator of the Kalman-filter trackers: predict, cost, associate, update, birth, death, report.

Each part is pluggable: the cost model (:mod:`.cost_models`), the assigner (a function ``(cost, gate) →
owner`` from :mod:`.assignment` or :mod:`.fota`), the life rule (:mod:`.life`). Tracks live in the world
frame, so the ego's motion needs no compensation (MUTR3D's Eq. 7 reference-point update is the identity
here); the time step is the real one, from the frames' timestamps [s].

Motion compensation: a detection taken at its camera's capture time, not at the frame's (trigger offsets, late
delivery: :mod:`simrig.scenarios.timing_schema`), is compared with each track predicted to that capture time
(centre + v·δ, δ = capture time − frame time, the track's own velocity), and updates the track as the
measurement moved back to the frame time with the track's velocity; a track born from it starts at its centre
moved with the detection's own velocity. ``motion_compensation=False`` treats every detection as taken at the
frame's time, to measure what ignoring the timing costs. Detections without a capture time (a synchronous rig)
take the plain path.

Fusion: when several detections are assigned to one track (FOTA, one object seen by two cameras) they are
applied as sequential Kalman updates, highest score first. With independent measurement noise this equals
one update with the stacked measurements (the information-filter sum), needs no new equations on top of
filterpy, and keeps the orientation correction per detection.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from filterpy.kalman import KalmanFilter

from simrig.types import ActorClass, Box3D, Rig, SensorFrame, Track

from . import motion
from .assignment import UNMATCHED
from .clock import FrameClock
from .costs import may_overlap, pair_iou
from .detections import LABELS, DetectionArrays, detection_arrays
from .life import HitsAndAge, TrackLife

Assigner = Callable[[np.ndarray, float], np.ndarray]


@dataclass
class KalmanTrack:
    """One live track: id, class code, filter, life counters, the cameras it was updated from, and its motion
    model (:mod:`.motion`'s constant velocity unless the tracker chooses per class)."""

    track_id: int
    label: int
    kf: KalmanFilter
    life: TrackLife
    cameras: set[int] = field(default_factory=set)
    model: Any = motion

    def box(self) -> Box3D:
        """The filter's state as a world-frame box (velocity from the state) [m, rad, m/s]."""
        x = self.kf.x[:, 0]
        vx, vy = self.model.velocity(x)
        return Box3D(*(float(v) for v in x[:7]), vx=vx, vy=vy)

    def output(self) -> Track:
        return Track(track_id=self.track_id, label=ActorClass(LABELS[self.label]), score=self.life.score,
                     box3d=self.box())


class KalmanTracker:
    """A tracking-by-detection tracker on world-frame 3D detections from every camera of the rig.

    cost: a cost model (with ``gate``); assign: ``(cost, gate) → owner`` per detection; life: a life rule;
    kalman: the filter's noise settings; score_threshold: detections below it are ignored [-];
    birth_merge_m: unmatched detections of one class from different cameras whose centres are within this
    distance [m] start one track, not several (0 disables: every unmatched detection starts its own track);
    duplicate_iou: two tracks of one class whose footprints overlap by at least this bird's-eye-view IoU are
    one object (two vehicles cannot share road): the one with fewer updates is dropped (0 disables);
    motion_compensation: predict tracks to each detection's capture time (module docstring).
    """

    def __init__(
        self,
        *,
        cost,
        assign: Assigner,
        life=None,
        kalman: motion.KalmanConfig | None = None,
        score_threshold: float = 0.0,
        birth_merge_m: float = 0.0,
        duplicate_iou: float = 0.0,
        motion_compensation: bool = True,
    ):
        self.cost = cost
        self.motion_compensation = bool(motion_compensation)
        self._now: float | None = None
        self.assign = assign
        self.life = life if life is not None else HitsAndAge()
        self.kalman = kalman if kalman is not None else motion.KalmanConfig()
        if not 0 <= score_threshold <= 1:
            raise ValueError(f"score_threshold must be in [0, 1], got {score_threshold}")
        if birth_merge_m < 0:
            raise ValueError(f"birth_merge_m must be ≥ 0, got {birth_merge_m}")
        if not 0 <= duplicate_iou <= 1:
            raise ValueError(f"duplicate_iou must be in [0, 1], got {duplicate_iou}")
        self.score_threshold = score_threshold
        self.birth_merge_m = birth_merge_m
        self.duplicate_iou = duplicate_iou
        self.tracks: list[KalmanTrack] = []
        self._next_id = 1
        self.clock = FrameClock()

    # -- the Tracker protocol ------------------------------------------------------------------------
    def reset(self, *, rig: Rig, seed: int | None = None) -> None:
        """Forget every track; ids start again at 1. The trackers are deterministic: ``seed`` is unused."""
        self.tracks = []
        self._next_id = 1
        self.clock.reset()

    def step(self, frame: SensorFrame) -> list[Track]:
        """Consume one frame; return the tracks reported at it."""
        detections = self.select(detection_arrays(frame))
        dt = self.clock.advance(frame)
        self._now = frame.timestamp
        self.step_arrays(detections, dt)
        return [track.output() for track in self.tracks if self.life.is_reported(track.life)]

    def capture_offsets(self, detections: DetectionArrays) -> np.ndarray:
        """(M,) [s] each detection's capture time minus the frame's time: 0 where it has none, and for every
        detection without motion compensation."""
        if not self.motion_compensation or self._now is None:
            return np.zeros(len(detections))
        offsets = detections.capture_times - self._now
        return np.where(np.isfinite(offsets), offsets, 0.0)

    @staticmethod
    def _velocities(tracks: list[KalmanTrack]) -> np.ndarray:
        """(N, 2) world-frame velocities [m/s] of ``tracks``' states."""
        return np.array([track.model.velocity(track.kf.x[:, 0]) for track in tracks], dtype=float).reshape(-1, 2)

    # -- the steps -------------------------------------------------------------------------------------
    def select(self, detections: DetectionArrays) -> DetectionArrays:
        """Detections used this frame (score threshold; subclasses add e.g. NMS)."""
        if self.score_threshold > 0:
            return detections.take(detections.scores >= self.score_threshold)
        return detections

    def step_arrays(self, detections: DetectionArrays, dt: float) -> None:
        """Predict by ``dt`` seconds, associate, update, start and end tracks."""
        for track in self.tracks:
            track.model.predict(track.kf, dt, self.kalman)
        owner = self.associate(detections)
        scores = self.update(detections, owner)
        for index, track in enumerate(self.tracks):
            self.life.observe(track.life, scores.get(index), dt)
        self.keep_alive(detections, owner, scores)
        self.tracks = [track for track in self.tracks if not self.life.is_dead(track.life)]
        self.births(detections, owner)
        if self.duplicate_iou > 0:
            self.drop_duplicates()

    def cost_matrix(self, detections: DetectionArrays, tracks: list[KalmanTrack] | None = None) -> np.ndarray:
        """(N, M) cost of ``tracks`` (default: every live track) against every detection; +inf across
        classes."""
        tracks = self.tracks if tracks is None else tracks
        n, m = len(tracks), len(detections)
        if n == 0 or m == 0:
            return np.zeros((n, m))
        cost = np.empty((n, m))
        for columns, predicted, innovation in self.predictions(detections, tracks):
            cost[:, columns] = self.cost(predicted, innovation, detections.boxes3d[columns])
        labels = np.array([track.label for track in tracks])
        return np.where(labels[:, None] == detections.labels[None, :], cost, np.inf)

    def predictions(self, detections: DetectionArrays,
                    tracks: list[KalmanTrack]) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """(columns, predicted boxes ẑ (N, 7), innovation covariances S (N, 7, 7)) per distinct capture time of
        ``detections`` (``columns``: the (M,) mask of the detections taken then): every track predicted to that
        time with its velocity — one block when no detection has a capture offset."""
        predicted = np.stack([track.kf.x[:7, 0] for track in tracks])
        innovation = motion.innovation_covariances(np.stack([track.kf.P for track in tracks]), self.kalman)
        offsets = self.capture_offsets(detections)
        if not offsets.any():
            yield np.ones(len(detections), dtype=bool), predicted, innovation
            return
        velocities = self._velocities(tracks)
        for offset in np.unique(offsets):
            moved = predicted.copy()
            moved[:, :2] += velocities * offset
            yield offsets == offset, moved, innovation

    def associate(self, detections: DetectionArrays) -> np.ndarray:
        """owner (M,): the track index each detection is assigned to, or −1."""
        if not self.tracks or len(detections) == 0:
            return np.full(len(detections), UNMATCHED, dtype=np.int64)
        return self.assign(self.cost_matrix(detections), self.cost.gate)

    def update(self, detections: DetectionArrays, owner: np.ndarray) -> dict[int, float]:
        """Apply every assigned detection to its track (sequential updates, highest score first); returns the
        frame's score per updated track index (its best detection's score)."""
        scores: dict[int, float] = {}
        offsets = self.capture_offsets(detections)
        for j in np.lexsort((np.arange(len(owner)), -detections.scores)):
            i = int(owner[j])
            if i == UNMATCHED:
                continue
            track = self.tracks[i]
            z = detections.boxes3d[j, :7]
            if offsets[j]:  # the measurement moved back to the frame time with the track's velocity
                z = z.copy()
                z[:2] -= np.array(track.model.velocity(track.kf.x[:, 0])) * offsets[j]
            track.model.update(track.kf, z)
            track.cameras.add(int(detections.cameras[j]))
            scores[i] = max(scores.get(i, 0.0), float(detections.scores[j]))
        return scores

    def motion_model(self, label: int):
        """The motion model of a new track of class ``label``: constant velocity (:mod:`.motion`) here."""
        return motion

    def keep_alive(self, detections: DetectionArrays, owner: np.ndarray, updated: dict[int, float]) -> None:
        """A hook after the life rule has seen the frame, for trackers that keep unmatched tracks alive
        (SimpleTrack's second stage); ``updated`` maps the updated track indices to their scores."""

    def drop_duplicates(self) -> None:
        """Drop the younger (fewer updates; then the later id) of every pair of same-class tracks whose
        footprints overlap by ``duplicate_iou`` or more."""
        if len(self.tracks) < 2:
            return
        boxes = np.stack([track.kf.x[:7, 0] for track in self.tracks])
        labels = np.array([track.label for track in self.tracks])
        same_class = labels[:, None] == labels[None, :]
        rows, cols = np.nonzero(np.triu(may_overlap(boxes, boxes), k=1) & same_class)  # each pair once
        duplicate = pair_iou(boxes, boxes, rows, cols, bev=True) >= self.duplicate_iou
        rows, cols = rows[duplicate], cols[duplicate]
        if len(rows) == 0:
            return
        rank = sorted(range(len(self.tracks)), key=lambda i: (-self.tracks[i].life.hits, self.tracks[i].track_id))
        seniority = np.empty(len(self.tracks), dtype=np.int64)
        seniority[rank] = np.arange(len(rank))
        dropped: set[int] = set()
        for i, j in sorted(zip(rows.tolist(), cols.tolist(), strict=True),
                           key=lambda pair: min(seniority[pair[0]], seniority[pair[1]])):
            if i in dropped or j in dropped:
                continue
            dropped.add(i if seniority[i] > seniority[j] else j)
        self.tracks = [track for k, track in enumerate(self.tracks) if k not in dropped]

    def births(self, detections: DetectionArrays, owner: np.ndarray) -> None:
        """Start tracks from unmatched detections, best score first; with ``birth_merge_m`` a detection from
        another camera near a track born this frame updates it instead of starting a duplicate."""
        newborn: list[KalmanTrack] = []
        offsets = self.capture_offsets(detections)
        for j in np.lexsort((np.arange(len(owner)), -detections.scores)):
            if owner[j] != UNMATCHED or not self.life.may_start(float(detections.scores[j])):
                continue
            box, camera, label = detections.boxes3d[j], int(detections.cameras[j]), int(detections.labels[j])
            if offsets[j]:  # moved to the frame time with its own velocity
                box = box.copy()
                box[:2] -= np.nan_to_num(box[7:9]) * offsets[j]
            twin = self._birth_twin(newborn, box, camera, label)
            if twin is not None:
                twin.model.update(twin.kf, box[:7])
                twin.cameras.add(camera)
                continue
            model = self.motion_model(label)
            kf = model.new_filter(box, self.kalman)
            track = KalmanTrack(self._next_id, label, kf, TrackLife(score=float(detections.scores[j])), {camera},
                                model)
            self._next_id += 1
            newborn.append(track)
        self.tracks.extend(newborn)

    def _birth_twin(self, newborn: list[KalmanTrack], box: np.ndarray, camera: int, label: int) -> KalmanTrack | None:
        if self.birth_merge_m <= 0:
            return None
        best, best_distance = None, self.birth_merge_m
        for track in newborn:
            if track.label != label or camera in track.cameras:
                continue
            distance = float(np.hypot(track.kf.x[0, 0] - box[0], track.kf.x[1, 0] - box[1]))
            if distance <= best_distance:
                best, best_distance = track, distance
        return best
