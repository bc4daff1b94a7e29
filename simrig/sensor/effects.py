"""The detector model as small effects, each with one job, applied in order to a :class:`.batch.SensorBatch`
(every camera of the rig at once, vectorised over cameras × actors).

An effect is an object with ``apply(batch)``; random effects draw from their own stream per camera
(``RandomStreams.generator("sensor", effect_key, camera_index)``), so changing one effect's parameters never
changes another effect's draws, and a camera's draws do not depend on the other cameras.
:class:`simrig.sensor.model.SensorModel` puts them in order: visibility-based probability, scheduled
perturbations, the detection draw, then the outputs of detected actors (2D box, 3D estimate, score,
embedding) and finally clutter.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from simrig.scenarios.sensor_schema import (
    Box3DNoiseConfig,
    ClutterConfig,
    ConfusionConfig,
    DetectionConfig,
    DuplicateConfig,
)

from ..causes import Cause
from ..classes import CLASS_SPECS
from ..seeding import RandomStreams
from ..types import ActorClass
from .batch import SensorBatch
from .processes import GaussMarkov, TwoStateMarkov, ar1_coefficient

SHARED = 999
"""Sub-stream number of a process shared by all cameras (camera indices are below it)."""


class SensorEffect(Protocol):
    def apply(self, batch: SensorBatch) -> None:
        """Read and update ``batch`` in place."""


class _Random:
    """Per-camera random streams of one effect (``stream_key`` is fixed per effect class; never renumber).

    ``enabled`` false: the effect still draws every number it would draw (so no other draw moves) but its
    imperfection is removed (a counterfactual run, :mod:`simrig.sensor.groups`)."""

    stream_key: int = -1

    def __init__(self, streams: RandomStreams, config=None, *, enabled: bool = True):
        self._streams = streams
        self.config = config
        self.enabled = enabled
        self._generators: dict[int, np.random.Generator] = {}

    def rng(self, camera_index: int) -> np.random.Generator:
        if camera_index not in self._generators:
            self._generators[camera_index] = self._streams.generator("sensor", self.stream_key, camera_index)
        return self._generators[camera_index]

    def draw(self, batch: SensorBatch, method: str, *shape: int) -> np.ndarray:
        """``Generator.method(size=(N, *shape))`` from each camera's stream, stacked ``(C, N, *shape)``."""
        size = (len(batch), *shape)
        return np.stack([getattr(self.rng(index), method)(size) for index in range(len(batch.cameras))])


def ramp(value: np.ndarray, zero_at: float, one_at: float) -> np.ndarray:
    """Linear ramp from 0 at ``zero_at`` to 1 at ``one_at`` (either order), clipped to [0, 1].

    >>> ramp(np.array([0.0, 0.3, 1.0]), 0.1, 0.5).round(2).tolist()
    [0.0, 0.5, 1.0]
    >>> ramp(np.array([50.0, 80.0, 120.0]), 100.0, 60.0).round(2).tolist()
    [1.0, 0.5, 0.0]
    """
    return np.clip((np.asarray(value, dtype=float) - zero_at) / (one_at - zero_at), 0.0, 1.0)


class DetectionProbability:
    """p = p_max · ramp(visible fraction) · ramp(truncation) · ramp(distance); 0 out of view. Marks the
    causes that lowered p: ``occluded``, ``truncated``, ``far``, ``out_of_view``. ``range_falloff`` false: no
    distance ramp; ``random_misses`` false: p_max = 1 (counterfactual runs)."""

    def __init__(self, config: DetectionConfig, *, range_falloff: bool = True, random_misses: bool = True):
        self.config = config
        self.range_falloff = range_falloff
        self.random_misses = random_misses

    def apply(self, batch: SensorBatch) -> None:
        c = self.config
        g_visible = ramp(batch.visible_fraction, c.min_visible_fraction, c.full_visible_fraction)
        g_truncation = ramp(np.nan_to_num(batch.truncation, nan=1.0), c.max_truncation, c.full_truncation)
        g_distance = (ramp(batch.distance, c.max_range_m, c.full_range_m) if self.range_falloff
                      else np.ones(batch.distance.shape))
        in_view = batch.in_view
        p = (c.probability if self.random_misses else 1.0) * g_visible * g_truncation * g_distance
        batch.probability = batch.probability * np.where(in_view, p, 0.0)
        batch.causes |= np.where(~in_view, int(Cause.OUT_OF_VIEW), 0)
        batch.causes |= np.where(in_view & (g_visible < 1.0), int(Cause.OCCLUDED), 0)
        batch.causes |= np.where(in_view & (g_truncation < 1.0), int(Cause.TRUNCATED), 0)
        batch.causes |= np.where(in_view & (g_distance < 1.0), int(Cause.FAR), 0)


class DetectionDraw(_Random):
    """``detected`` = a Bernoulli draw with each actor's probability (one draw per actor, always)."""

    stream_key = 0

    def apply(self, batch: SensorBatch) -> None:
        draws = self.draw(batch, "random")
        batch.detected = (draws < batch.probability) & ~batch.silenced[:, None]


class MissBursts(_Random):
    """Gilbert–Elliott misses: a two-state chain per (actor, camera) (:class:`.processes.TwoStateMarkov`,
    one uniform draw per actor, camera and frame); in the bad state p = 0 for an actor in view, cause ``burst``."""

    stream_key = 7

    def __init__(self, streams: RandomStreams, config: DetectionConfig, period_s: float, *, enabled: bool = True):
        super().__init__(streams, config, enabled=enabled)
        self.period_s = period_s
        self._chain: TwoStateMarkov | None = None

    def apply(self, batch: SensorBatch) -> None:
        c = self.config
        if c.burst_fraction <= 0:
            return
        if self._chain is None:
            self._chain = TwoStateMarkov(c.burst_fraction, c.burst_mean_s, self.period_s)
        bad = self._chain.step(batch.actor_ids, self.draw(batch, "random").T).T
        if not self.enabled:
            return
        hit = bad & batch.in_view
        batch.probability = np.where(hit, 0.0, batch.probability)
        batch.causes |= np.where(hit, int(Cause.BURST), 0)


class Box2DNoise(_Random):
    """Each edge of a detected box moves by N(0, (k · size · noise factor)²), size the true box's width for
    x1, x2 and height for y1, y2; the result is ordered and clipped to the image."""

    stream_key = 1

    def apply(self, batch: SensorBatch) -> None:
        noise = self.draw(batch, "standard_normal", 4)
        boxes = batch.boxes2d
        size = np.stack([boxes[..., 2] - boxes[..., 0], boxes[..., 3] - boxes[..., 1]], axis=-1)[..., [0, 1, 0, 1]]
        sigma = (self.config.relative_sigma if self.enabled else 0.0) * size * batch.noise_factor[..., None]
        noisy = boxes + noise * sigma
        inside = _ordered_in_image(noisy, batch.image_width[:, None, None], batch.image_height[:, None, None])
        batch.det_boxes2d = np.where(batch.detected[..., None], inside, np.nan)


def _ordered_in_image(boxes: np.ndarray, width, height) -> np.ndarray:
    """Pixel boxes ``(…, 4)`` with each pair of edges ordered and clipped to the image, ``width`` × ``height``
    [px] (broadcast against the boxes' leading axes)."""
    x = np.sort(boxes[..., [0, 2]], axis=-1).clip(0.0, width)
    y = np.sort(boxes[..., [1, 3]], axis=-1).clip(0.0, height)
    return np.stack([x[..., 0], y[..., 0], x[..., 1], y[..., 1]], axis=-1)


def _wrap(angle: np.ndarray) -> np.ndarray:
    """Angles wrapped to [−π, π)."""
    return (angle + np.pi) % (2.0 * np.pi) - np.pi


class Monocular3D(_Random):
    """A monocular 3D estimate in the world frame. In the camera frame the box centre moves along its ray
    by e_d · σ_d(d), σ_d(d) = a + b·d with d its range [m], and across the ray by e_l · σ_l(d) in two
    directions; sizes are scaled by 1 + e_s · σ_s(d); yaw gets e_y · σ_yaw(d) and flips by 180° while a
    two-state flip chain is on; velocity gets e_v · σ_v(d) per component. Every e is a unit-variance
    Ornstein–Uhlenbeck process per (actor, camera) (:class:`.processes.GaussMarkov`), optionally mixed
    with a per-actor one shared by all cameras; σ(d) = σ · (1 + d / D) for the errors other than depth
    (:class:`~simrig.scenarios.sensor_schema.Box3DNoiseConfig`). All σ are multiplied by the actor's noise factor.
    A calibration yaw offset then rotates centre, yaw and velocity about the vertical axis through the
    camera (the detector lifts to the world with the wrong extrinsics)."""

    stream_key = 2
    WIDTH = 9  # depth, lateral ×2, size ×3, yaw, velocity ×2
    BLOCKS = (1, 2, 3, 1, 2)  # the columns drawn together, in draw order

    def __init__(self, streams: RandomStreams, config: Box3DNoiseConfig, period_s: float = 0.1, *,
                 enabled: bool = True):
        super().__init__(streams, config, enabled=enabled)
        self.period_s = period_s
        phi, phi_size = (ar1_coefficient(period_s, t) for t in (config.correlation_time_s,
                                                                 config.size_correlation_time_s))
        self._phi = np.array([phi, phi, phi, phi_size, phi_size, phi_size, phi, phi, phi])
        self._errors = GaussMarkov(self._phi)  # per (actor, camera)
        self._flips: TwoStateMarkov | None = None  # per (actor, camera)
        self._shared = GaussMarkov(self._phi)  # per actor, common to all cameras

    def errors(self, batch: SensorBatch) -> tuple[np.ndarray, np.ndarray]:
        """Unit-variance errors ``(C, N, 9)`` and the flip states ``(C, N)`` of the cameras' actors at this
        frame. Each camera draws 9·N normals (depth, lateral, size, yaw, velocity: column block by column
        block) then N uniforms from its stream; the shared process 9·N normals from its own."""
        c = self.config
        n = len(batch)
        z, u = [], []
        for index in range(len(batch.cameras)):
            rng = self.rng(index)
            draws = rng.standard_normal(self.WIDTH * n)
            blocks = np.split(draws, np.cumsum(self.BLOCKS[:-1]) * n)
            z.append(np.concatenate([block.reshape(n, width) for block, width in zip(blocks, self.BLOCKS, strict=True)],
                                    axis=1))
            u.append(rng.random(n))
        errors = self._errors.step(batch.actor_ids, np.stack(z, axis=1))  # (N, C, 9)
        if c.shared_fraction > 0:
            shared = self._shared.step(batch.actor_ids, self.rng(SHARED).standard_normal((n, self.WIDTH)))
            errors = np.sqrt(1.0 - c.shared_fraction) * errors + np.sqrt(c.shared_fraction) * shared[:, None, :]
        u = np.stack(u, axis=1)  # (N, C)
        if c.yaw_flip_duration_s > 0:
            if self._flips is None:
                self._flips = TwoStateMarkov(c.yaw_flip_probability, c.yaw_flip_duration_s, self.period_s)
            flips = self._flips.step(batch.actor_ids, u)
        else:
            flips = u < c.yaw_flip_probability
        return errors.transpose(1, 0, 2), flips.T

    def apply(self, batch: SensorBatch) -> None:
        c = self.config
        errors, flips = self.errors(batch)
        factor = batch.noise_factor
        camera_centre = batch.world_from_camera[:, None, :3, 3]  # (C, 1, 3)
        true = batch.boxes3d
        ray = true[..., :3] - camera_centre  # world-frame ray to the centre [m], (C, N, 3)
        distance = np.linalg.norm(ray, axis=-1)
        unit = ray / np.maximum(distance, 1e-9)[..., None]
        # Two directions across the ray: horizontal (world z × ray) and the one perpendicular to both.
        horizontal = np.maximum(np.hypot(unit[..., 0], unit[..., 1]), 1e-9)
        across = np.stack([-unit[..., 1] / horizontal, unit[..., 0] / horizontal, np.zeros(unit.shape[:2])], axis=-1)
        up = np.stack([-unit[..., 2] * across[..., 1], unit[..., 2] * across[..., 0],
                       unit[..., 0] * across[..., 1] - unit[..., 1] * across[..., 0]], axis=-1)
        growth = factor * (1.0 + distance / c.distance_scale_m if c.distance_scale_m else 1.0)
        depth = distance + errors[..., 0] * (c.depth_sigma_m + c.depth_sigma_per_m * distance) * factor
        lateral = errors[..., 1:3] * (c.lateral_sigma_m * growth)[..., None]
        centre = camera_centre + unit * depth[..., None] + across * lateral[..., :1] + up * lateral[..., 1:]
        out = np.empty(centre.shape[:2] + (9,))
        out[..., :3] = centre
        out[..., 3:6] = true[..., 3:6] * np.maximum(0.1, 1.0 + errors[..., 3:6] * (c.size_sigma * growth)[..., None])
        out[..., 6] = true[..., 6] + errors[..., 6] * np.radians(c.yaw_sigma_deg) * growth + np.where(flips, np.pi, 0.0)
        out[..., 7:9] = true[..., 7:9] + errors[..., 7:9] * (c.velocity_sigma_mps * growth)[..., None]
        if not self.enabled:  # the errors were drawn (and their processes advanced) all the same
            out[:] = true
        for index in np.nonzero(batch.yaw_offset)[0]:
            offset = batch.yaw_offset[index]
            cos, sin = np.cos(offset), np.sin(offset)
            rotation = np.array([[cos, -sin], [sin, cos]])
            centre_xy = camera_centre[index, 0, :2]
            out[index, :, :2] = (out[index, :, :2] - centre_xy) @ rotation.T + centre_xy
            out[index, :, 7:9] = out[index, :, 7:9] @ rotation.T
            out[index, :, 6] += offset
        out[..., 6] = _wrap(out[..., 6])
        batch.det_boxes3d = np.where(batch.detected[..., None], out, np.nan)


class Scores(_Random):
    """score = clip(base + gain · q − error_gain · (1 − exp(−e / error_scale)) − distance_gain ·
    min(1, d / distance_scale) + N(0, σ²), floor, 1); q = visible fraction · (1 − truncation), e the
    bird's-eye-view centre error of the 3D estimate [m], d the range from the camera [m]."""

    stream_key = 3

    def apply(self, batch: SensorBatch) -> None:
        c = self.config
        quality = batch.visible_fraction * (1.0 - np.nan_to_num(batch.truncation, nan=1.0))
        noise = self.draw(batch, "standard_normal") * c.sigma
        score = c.base + c.gain * quality + noise
        if c.error_gain:
            offset = batch.det_boxes3d[..., :2] - batch.boxes3d[..., :2]
            error = np.nan_to_num(np.hypot(offset[..., 0], offset[..., 1]))
            score -= c.error_gain * (1.0 - np.exp(-error / c.error_scale_m))
        if c.distance_gain:
            score -= c.distance_gain * np.minimum(1.0, batch.distance / c.distance_scale_m)
        batch.scores = np.where(batch.detected, np.clip(score, c.floor, 1.0), np.nan)


def _unit_rows(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.maximum(np.linalg.norm(vectors, axis=-1, keepdims=True), 1e-12)


class Confusion(_Random):
    """Class confusion: each detected actor's reported label is drawn from its true class's row of the
    confusion matrix (one uniform draw per actor, always); a changed label adds cause ``confused``."""

    stream_key = 8

    def __init__(self, streams: RandomStreams, config: ConfusionConfig, *, enabled: bool = True):
        super().__init__(streams, config, enabled=enabled)
        self.rows = {true: (np.array(list(row), dtype=object), np.cumsum(list(row.values())))
                     for true, row in config.matrix.items()}

    def apply(self, batch: SensorBatch) -> None:
        if not self.rows:
            return
        u = self.draw(batch, "random")
        if not self.enabled:
            return
        labels = np.tile(np.asarray(batch.classes, dtype=object), (len(batch.cameras), 1))
        for true, (names, cumulative) in self.rows.items():
            mine = batch.classes == true
            if mine.any():
                pick = np.minimum(np.searchsorted(cumulative, u[:, mine] * cumulative[-1], side="right"),
                                  len(names) - 1)
                labels[:, mine] = names[pick]
        confused = batch.detected & (labels != batch.classes)
        batch.labels = labels
        batch.causes |= np.where(confused, int(Cause.CONFUSED), 0)


class Clutter(_Random):
    """False positives: Poisson(rate) boxes per camera and frame anywhere in the image, classes drawn from the
    traffic's class mix, scores uniform in ``score_range``, a 3D estimate on the box centre's ray at a range
    uniform in ``depth_range_m`` with the class's size and the ego's heading, and a random unit embedding."""

    stream_key = 5

    def __init__(self, config: ClutterConfig, class_mix: dict[str, float], embedding_dimension: int,
                 streams: RandomStreams, *, enabled: bool = True):
        super().__init__(streams, config, enabled=enabled)
        self.classes = np.array(list(class_mix), dtype=object)
        weights = np.array(list(class_mix.values()), dtype=float)
        self.weights = weights / weights.sum()
        self.sizes = np.array([[CLASS_SPECS[ActorClass(name)].length, CLASS_SPECS[ActorClass(name)].width,
                                CLASS_SPECS[ActorClass(name)].height] for name in self.classes]).reshape(-1, 3)
        self.dimension = embedding_dimension
        self._none = (np.empty((0, 4)), np.empty((0, 9)), np.empty(0), np.empty(0, dtype=object),
                      np.empty((0, embedding_dimension), dtype=np.float32))

    def apply(self, batch: SensorBatch) -> None:
        for index in range(len(batch.cameras)):
            self.apply_camera(batch, index)

    def apply_camera(self, batch: SensorBatch, index: int) -> None:
        """Camera ``index``'s clutter (a count, then a variable number of draws from its stream)."""
        c = self.config
        rng = self.rng(index)
        count = int(rng.poisson(c.rate_per_frame))
        if count == 0:  # an empty draw draws nothing more: the stream stays where it would be
            batch.add_false_positives(index, *self._none, Cause.CLUTTER)
            return
        camera = batch.cameras[index]
        height = np.exp(rng.uniform(*np.log(c.height_range_px), count))
        width = height * rng.uniform(*c.aspect_range, count)
        centre = np.stack([rng.uniform(0, camera.width, count), rng.uniform(0, camera.height, count)], axis=1)
        kinds = rng.choice(len(self.classes), size=count, p=self.weights)
        labels = self.classes[kinds]
        scores = rng.uniform(*c.score_range, count)
        ranges = rng.uniform(*c.depth_range_m, count)
        embeddings = _unit_rows(rng.standard_normal((count, self.dimension))).astype(np.float32)
        if batch.silenced[index] or not self.enabled:
            batch.add_false_positives(index, *self._none, Cause.CLUTTER)
            return
        boxes = np.stack([
            np.clip(centre[:, 0] - width / 2, 0, camera.width), np.clip(centre[:, 1] - height / 2, 0, camera.height),
            np.clip(centre[:, 0] + width / 2, 0, camera.width), np.clip(centre[:, 1] + height / 2, 0, camera.height),
        ], axis=1)
        rays = np.stack([(centre[:, 0] - camera.cx) / camera.fx, (centre[:, 1] - camera.cy) / camera.fy,
                         np.ones(len(centre))], axis=1)
        rays /= np.linalg.norm(rays, axis=1, keepdims=True)
        world_from_camera = batch.world_from_camera[index]
        points = rays * ranges[:, None] @ world_from_camera[:3, :3].T + world_from_camera[:3, 3]
        boxes3d = np.concatenate([points, self.sizes[kinds], np.full((len(points), 1), batch.context.ego_yaw),
                                  np.zeros((len(points), 2))], axis=1)
        batch.add_false_positives(index, boxes, boxes3d, scores, labels, embeddings, Cause.CLUTTER)


class Duplicates(_Random):
    """Failed NMS: with the configured probability a detected actor gets a second box in the same camera,
    its edges moved by N(0, (k · size)²), its 3D centre by N(0, σ²) per horizontal axis, its score scaled,
    its label and embedding the detection's; cause ``duplicate``. Draws a fixed number per actor."""

    stream_key = 9

    def __init__(self, streams: RandomStreams, config: DuplicateConfig, *, enabled: bool = True):
        super().__init__(streams, config, enabled=enabled)

    def apply(self, batch: SensorBatch) -> None:
        c = self.config
        if c.probability <= 0:
            return
        n = len(batch)
        for index, camera in enumerate(batch.cameras):
            rng = self.rng(index)
            u, edges, offsets = rng.random(n), rng.standard_normal((n, 4)), rng.standard_normal((n, 2))
            hit = batch.detected[index] & (u < c.probability)
            if not hit.any() or not self.enabled:
                continue
            boxes = batch.det_boxes2d[index][hit]
            size = np.stack([boxes[:, 2] - boxes[:, 0], boxes[:, 3] - boxes[:, 1]], axis=1)[:, [0, 1, 0, 1]]
            moved = boxes + edges[hit] * c.relative_sigma * size
            boxes3d = batch.det_boxes3d[index][hit].copy()
            boxes3d[:, :2] += offsets[hit] * c.offset_sigma_m
            batch.add_false_positives(index, _ordered_in_image(moved, camera.width, camera.height), boxes3d,
                                      batch.scores[index][hit] * c.score_factor, batch.labels[index][hit],
                                      batch.embeddings[index][hit], Cause.DUPLICATE)


class DetectionOrder(_Random):
    """Numbers each camera's detections (detected actors and clutter) in a random order, so that a tracker
    cannot tell clutter or identity from the position of a detection in the list."""

    stream_key = 6

    def apply(self, batch: SensorBatch) -> None:
        batch.detection_index = np.full(batch.detected.shape, -1, dtype=np.int64)
        for index in range(len(batch.cameras)):
            detected = np.nonzero(batch.detected[index])[0]
            clutter = len(batch.clutter[index].get("scores", ()))  # clutter, ghosts and duplicates
            order = self.rng(index).permutation(len(detected) + clutter)
            batch.detection_index[index, detected] = order[: len(detected)]
            batch.clutter_index[index] = order[len(detected):].astype(np.int64)
