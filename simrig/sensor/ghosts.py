"""Ghosts: false positives with a life of their own, one 3D box each, seen consistently by every camera.

Once per frame (before the cameras) the ghost world advances: each ghost dies with probability
min(1, Δt / mean_life) (so lives are geometric with mean mean_life / Δt frames at any frame rate;
a shadow ghost also dies with its vehicle), then Poisson(birth_rate · Δt) ghosts are born. A static ghost
stands on the ground at a uniform point of the ring ``range_m`` around the ego, with a class from the
traffic's mix, that class's size, a uniform heading and zero velocity. A shadow ghost picks a vehicle
inside the ring and sits a fixed distance behind or ahead of it along its heading, with its class, size,
heading and velocity (a reflection, a split truck). Per camera that sees a ghost (its box projects into
the image), the camera reports it with probability ``probability``: the projection of the ghost's one box
as pixel box, that box as 3D estimate, a Beta(mean, concentration) score and a per-ghost embedding; cause
``ghost``. World draws come from the ghost stream, per-camera draws from a stream per camera.
"""

from __future__ import annotations

import numpy as np

from simrig.scenarios.sensor_schema import GhostConfig

from ..causes import Cause
from ..classes import CLASS_SPECS
from ..geometry import Projection, project_boxes
from ..seeding import RandomStreams
from ..types import ActorClass, EgoPose, Rig
from .batch import SensorBatch

_WORLD_STREAM = 12
_CAMERA_STREAM = 13
_EMBEDDING_STREAM = 14


class GhostWorld:
    """The living ghosts: ``ids``, ``labels``, world ``boxes`` ``(G, 9)``, shadowed actor (−1 static) and
    offset [m]; :meth:`advance` once per frame, then :meth:`apply` to the cameras' batch."""

    def __init__(self, config: GhostConfig, class_mix: dict[str, float], rig: Rig, period_s: float,
                 embedding_dimension: int, streams: RandomStreams, *, reported: bool = True):
        self.config = config
        self.reported = reported  # false: the ghosts live and are drawn, but no camera reports them
        self.rig = rig
        self.period_s = period_s
        self.dimension = embedding_dimension
        self._streams = streams
        self._world = streams.generator("sensor", _WORLD_STREAM)
        self._cameras: dict[int, np.random.Generator] = {}
        self.classes = np.array(list(class_mix), dtype=object)
        weights = np.array(list(class_mix.values()), dtype=float)
        self.weights = weights / weights.sum()
        self.ids = np.empty(0, dtype=np.int64)
        self.labels = np.empty(0, dtype=object)
        self.boxes = np.empty((0, 9))
        self.shadowed = np.empty(0, dtype=np.int64)
        self.offsets = np.empty(0)
        self.born = np.empty(0, dtype=np.int64)
        self.projection: Projection | None = None
        self._next_id = 0
        self._embeddings: dict[int, np.ndarray] = {}

    @property
    def enabled(self) -> bool:
        return self.config.birth_rate_hz > 0

    def advance(self, frame: int, ego: EgoPose, actor_ids: np.ndarray, classes: np.ndarray,
                boxes: np.ndarray) -> None:
        """Deaths, births and motion for ``frame``; then project every ghost into every camera."""
        c, rng = self.config, self._world
        g = len(self.ids)
        dies = rng.random(g) < min(1.0, self.period_s / c.mean_life_s)
        order = np.argsort(actor_ids, kind="stable")
        position = np.minimum(np.searchsorted(actor_ids[order], self.shadowed), max(len(actor_ids) - 1, 0))
        row = order[position] if len(actor_ids) else np.zeros(g, dtype=np.int64)
        shadow = self.shadowed >= 0
        alive_actor = (actor_ids[row] == self.shadowed) if len(actor_ids) else np.zeros(g, dtype=bool)
        keep = ~dies & (~shadow | alive_actor)
        self._keep(keep)
        row, shadow = row[keep], shadow[keep]
        if shadow.any():  # follow the vehicle
            self.boxes[shadow] = self._shadow_boxes(boxes[row[shadow]], self.offsets[shadow])
        self._births(frame, ego, actor_ids, classes, boxes)
        self.projection = project_boxes(self.boxes, self.rig, ego) if len(self.ids) else None

    def _keep(self, keep: np.ndarray) -> None:
        for name in ("ids", "labels", "boxes", "shadowed", "offsets", "born"):
            setattr(self, name, getattr(self, name)[keep])

    @staticmethod
    def _shadow_boxes(actor_boxes: np.ndarray, offsets: np.ndarray) -> np.ndarray:
        out = actor_boxes.copy()
        out[:, 0] += offsets * np.cos(actor_boxes[:, 6])
        out[:, 1] += offsets * np.sin(actor_boxes[:, 6])
        return out

    def _births(self, frame: int, ego: EgoPose, actor_ids: np.ndarray, classes: np.ndarray,
                boxes: np.ndarray) -> None:
        c, rng = self.config, self._world
        count = int(rng.poisson(c.birth_rate_hz * self.period_s))
        if count == 0:
            return
        shadow = rng.random(count) < c.shadow_fraction
        low, high = c.range_m
        radius = np.sqrt(rng.uniform(low**2, high**2, count))
        bearing = rng.uniform(-np.pi, np.pi, count)
        heading = rng.uniform(-np.pi, np.pi, count)
        labels = self.classes[rng.choice(len(self.classes), size=count, p=self.weights)]
        pick = rng.random(count)
        offsets = rng.uniform(*c.shadow_offset_m, count) * np.where(rng.random(count) < 0.5, -1.0, 1.0)
        distance = np.hypot(boxes[:, 0] - ego.x, boxes[:, 1] - ego.y) if len(boxes) else np.empty(0)
        near = np.nonzero((distance >= low) & (distance <= high))[0]
        new_boxes = np.zeros((count, 9))
        shadowed = np.full(count, -1, dtype=np.int64)
        for k in range(count):
            spec = CLASS_SPECS[ActorClass(labels[k])]
            if shadow[k] and len(near):
                j = near[min(int(pick[k] * len(near)), len(near) - 1)]
                shadowed[k], labels[k] = actor_ids[j], classes[j]
                new_boxes[k] = self._shadow_boxes(boxes[j:j + 1], offsets[k:k + 1])[0]
                new_boxes[k, 3:6] = boxes[j, 3:6]
            else:
                new_boxes[k] = (ego.x + radius[k] * np.cos(bearing[k]), ego.y + radius[k] * np.sin(bearing[k]),
                                ego.z + spec.height / 2, spec.length, spec.width, spec.height, heading[k], 0.0, 0.0)
        ids = np.arange(self._next_id, self._next_id + count, dtype=np.int64)
        self._next_id += count
        self.ids = np.concatenate([self.ids, ids])
        self.labels = np.concatenate([self.labels, labels])
        self.boxes = np.concatenate([self.boxes, new_boxes])
        self.shadowed = np.concatenate([self.shadowed, shadowed])
        self.offsets = np.concatenate([self.offsets, offsets])
        self.born = np.concatenate([self.born, np.full(count, frame, dtype=np.int64)])

    def embedding(self, ghost_id: int) -> np.ndarray:
        if ghost_id not in self._embeddings:
            vector = self._streams.generator("sensor", _EMBEDDING_STREAM, int(ghost_id)).standard_normal(self.dimension)
            self._embeddings[ghost_id] = (vector / np.linalg.norm(vector)).astype(np.float32)
        return self._embeddings[ghost_id]

    def apply(self, batch: SensorBatch) -> None:
        """Report the ghosts each camera sees (nothing from a silenced camera)."""
        for index in range(len(batch.cameras)):
            self.apply_camera(batch, index)

    def apply_camera(self, batch: SensorBatch, index: int) -> None:
        """Camera ``index``'s ghosts: a uniform and a score per living ghost from the camera's stream."""
        if index not in self._cameras:
            self._cameras[index] = self._streams.generator("sensor", _CAMERA_STREAM, index)
        rng = self._cameras[index]
        g = len(self.ids)
        u, scores = rng.random(g), rng.beta(*self._beta(), g) if g else np.empty(0)
        batch.ghost_ids[index] = np.empty(0, dtype=np.int64)
        if g == 0 or batch.silenced[index] or not self.reported:
            return
        in_view = self.projection.in_view[index]
        seen = np.nonzero(in_view & (u < self.config.probability))[0]
        batch.ghost_ids[index] = self.ids[seen]
        batch.add_false_positives(index, self.projection.boxes[index, seen], self.boxes[seen], scores[seen],
                                  self.labels[seen], np.array([self.embedding(i) for i in self.ids[seen]]).reshape(
                                      len(seen), self.dimension), Cause.GHOST)

    def _beta(self) -> tuple[float, float]:
        m, k = self.config.score_mean, self.config.score_concentration
        return m * k, (1.0 - m) * k
