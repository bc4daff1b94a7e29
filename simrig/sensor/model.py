"""The sensor: ground truth + visibility in, per-camera detections (and why each actor was or was not
detected) out. Assembles the effects of :mod:`.effects` and :mod:`.perturbations` in their fixed order."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simrig.scenarios import Scenario
from simrig.scenarios.perturbation_schema import WORLD_KINDS, DropFrames

from ..geometry import Projection, camera_from_world, cameras_from_world_at, project_boxes_per_camera
from ..render.visibility import Visibility
from ..seeding import RandomStreams
from ..types import EgoPose, GroundTruthFrame, Rig
from .appearance import Embeddings
from .batch import FrameContext, SensorBatch
from .capture import Captures, CaptureTiming, EgoPoseEstimate, as_estimated, moved_boxes, moved_egos
from .effects import (
    Box2DNoise,
    Clutter,
    Confusion,
    DetectionDraw,
    DetectionOrder,
    DetectionProbability,
    Duplicates,
    MissBursts,
    Monocular3D,
    Scores,
    SensorEffect,
)
from .ghosts import GhostWorld
from .groups import DETECTOR_GROUPS, check_groups
from .perturbations import PERTURBATION_EFFECTS, DroppedFrames, Scheduled, ScheduledOcclusion


@dataclass(frozen=True, eq=False)
class SensorOutput:
    """One frame of sensor output: the cameras' batch, whether the frame was dropped, the scheduled
    perturbations active at the frame (event strings), the projection of the ground truth each camera saw (at
    its capture time: the frame's own projection for a synchronous rig), and, when the scenario sets them, the
    cameras' captures (:class:`~simrig.sensor.capture.Captures`) and the ego pose the tracker is given."""

    batch: SensorBatch
    dropped: bool
    events: tuple[str, ...]
    projection: Projection
    captures: Captures | None = None
    ego_estimate: EgoPose | None = None


class SensorModel:
    """The detector of every camera of ``rig`` as configured by ``scenario`` (its ``sensor`` tables and its
    sensor ``perturbations``), drawing from ``streams``.

    ``removed``: cause groups switched off (:mod:`.groups`) for a counterfactual run; every effect still
    draws what it draws with them on, so the remaining causes' draws are bit-identical. Empty: the detector
    as configured (the dataset's bytes do not depend on this option)."""

    def __init__(self, scenario: Scenario, rig: Rig, streams: RandomStreams, *,
                 removed: frozenset[str] = frozenset()):
        self.rig = rig
        removed = check_groups(removed, scenario)
        self.removed = removed
        on = {name: name not in removed for name in DETECTOR_GROUPS}
        sensor = scenario.sensor
        rate = scenario.frame_rate_hz
        period = 1.0 / rate
        self.scheduled: list[Scheduled] = []
        occlusions, others = [], []
        self.drops: list[DroppedFrames] = []
        for index, config in enumerate(scenario.perturbations):
            if config.kind in WORLD_KINDS or f"{config.kind}#{index}" in removed:
                continue
            if isinstance(config, DropFrames):
                effect = DroppedFrames(config, index, rig, rate, streams)
                self.drops.append(effect)
            else:
                effect = PERTURBATION_EFFECTS[type(config)](config, index, rig, rate)
            (occlusions if isinstance(effect, ScheduledOcclusion) else others).append(effect)
            self.scheduled.append(effect)
        class_mix = scenario.traffic.class_mix
        self.embeddings = Embeddings(streams, sensor.embedding, class_mix, enabled=on["reid"], period_s=period)
        self.ghosts = GhostWorld(sensor.ghosts, class_mix, rig, period, sensor.embedding.dimension, streams,
                                 reported=on["false_positives"])
        seen_as: list[SensorEffect] = [] if on["occlusion"] and on["truncation"] else [
            SeenUnhindered(occlusion=not on["occlusion"], truncation=not on["truncation"])]
        self.effects: list[SensorEffect] = [
            *seen_as,
            *occlusions,  # before the probability: they set the visible fraction
            DetectionProbability(sensor.detection, range_falloff=on["far_range"], random_misses=on["random_misses"]),
            *others,
            MissBursts(streams, sensor.detection, period, enabled=on["random_misses"]),
            DetectionDraw(streams),
            Box2DNoise(streams, sensor.box2d, enabled=on["localisation"]),
            Monocular3D(streams, sensor.box3d, period, enabled=on["localisation"]),
            Scores(streams, sensor.score),
            Confusion(streams, sensor.confusion, enabled=on["confusion"]),
            self.embeddings,
            Clutter(sensor.clutter, class_mix, sensor.embedding.dimension, streams, enabled=on["false_positives"]),
            self.ghosts,
        ]
        # per camera in this order; then, across cameras, the cross-camera filter when removed; then finishing
        self.cross_camera = not on["cross_camera"]
        self.finishing: list[SensorEffect] = [
            Duplicates(streams, sensor.duplicates, enabled=on["duplicates"]),
            DetectionOrder(streams),
        ]
        self.timing = CaptureTiming(sensor, rig, rate, streams, removed)
        self.ego_estimate = EgoPoseEstimate(sensor.ego_pose, rate, streams, enabled="ego_pose" not in removed)

    def observe(self, state: GroundTruthFrame, projection: Projection, visibility: Visibility) -> SensorOutput:
        """Run every effect on every camera for one frame (``projection`` and ``visibility`` of ``state``)."""
        ego = state.ego
        context = FrameContext(
            frame=state.frame,
            timestamp=state.timestamp,
            ego_yaw=ego.yaw,
            actor_ids=state.actor_ids,
            ego_distance=np.hypot(state.boxes[:, 0] - ego.x, state.boxes[:, 1] - ego.y),
        )
        boxes = np.asarray(state.boxes)
        captures = self.timing.at(state.frame, state.timestamp) if self.timing.configured else None
        # the visible fraction measured at the tick (for every camera, whenever it fires: .capture's docstring);
        # unmeasured (not in view at the tick, or no pixel at the render's resolution): seen as hidden
        visible_fraction = np.nan_to_num(1.0 - visibility.occlusion, nan=0.0)
        if captures is None or not captures.offsets.any():
            world_from_camera = np.linalg.inv(camera_from_world(self.rig, ego))
            seen = np.broadcast_to(boxes, (len(self.rig.cameras), *boxes.shape))
        else:  # each camera sees the world at its own capture time (module docstring of .capture)
            seen = moved_boxes(boxes, captures.offsets)
            egos = moved_egos(ego, captures.offsets)
            world_from_camera = np.linalg.inv(cameras_from_world_at(self.rig, egos))
            projection = project_boxes_per_camera(boxes, self.rig, egos, seen[..., :3] - boxes[:, :3])
        if captures is not None and not captures.fired.all():  # no image: nothing in view, nothing reported
            projection = _without_cameras(projection, ~captures.fired)
        if self.ghosts.enabled:
            self.ghosts.advance(state.frame, ego, state.actor_ids, state.classes, boxes)
        batch = SensorBatch(
            context=context,
            cameras=self.rig.cameras,
            world_from_camera=world_from_camera,
            classes=state.classes,
            boxes3d=seen,
            boxes2d=projection.boxes,
            truncation=projection.truncation,
            visible_fraction=np.where(projection.in_view, visible_fraction, 0.0),
            distance=np.linalg.norm(seen[..., :3] - world_from_camera[:, None, :3, 3], axis=-1),
            in_view=projection.in_view,
        )
        if captures is not None:
            batch.silenced = ~captures.fired
        for effect in self.effects:
            effect.apply(batch)
        if self.cross_camera:
            _keep_best_camera(batch)
        for effect in self.finishing:
            effect.apply(batch)
        estimate = self.ego_estimate.estimate(state.frame, ego) if self.ego_estimate.configured else None
        if estimate is not None and estimate != ego:
            batch.det_boxes3d = as_estimated(batch.det_boxes3d, ego, estimate)
            for clutter in batch.clutter:
                if clutter:
                    clutter["boxes3d"] = as_estimated(clutter["boxes3d"], ego, estimate)
        dropped = any(drop.dropped(state.frame) for drop in self.drops)
        events = tuple(effect.describe(context) for effect in self.scheduled if effect.active(state.frame))
        return SensorOutput(batch, dropped, events, projection, captures, estimate)


def _without_cameras(projection: Projection, off: np.ndarray) -> Projection:
    """``projection`` with the cameras ``off`` ``(C,)`` seeing nothing (no box, no truncation, nothing in view)."""
    gone = off[:, None]
    return Projection(boxes=np.where(gone[..., None], np.nan, projection.boxes),
                      unclipped=np.where(gone[..., None], np.nan, projection.unclipped),
                      truncation=np.where(gone, np.nan, projection.truncation), depth=projection.depth,
                      in_view=projection.in_view & ~gone)


class SeenUnhindered:
    """Counterfactual: every actor in view is seen as fully visible (``occlusion``) and/or untruncated
    (``truncation``) — the rendered hindrance removed before any other effect reads it."""

    def __init__(self, *, occlusion: bool, truncation: bool):
        self.occlusion, self.truncation = occlusion, truncation

    def apply(self, batch: SensorBatch) -> None:
        if self.occlusion:
            batch.visible_fraction = np.where(batch.in_view, 1.0, batch.visible_fraction)
        if self.truncation:
            batch.truncation = np.where(batch.in_view, 0.0, batch.truncation)


def _keep_best_camera(batch: SensorBatch) -> None:
    """Counterfactual ``cross_camera``: an actor detected by several cameras stays detected only in the best
    one — largest visible fraction × (1 − truncation), then largest true pixel box, then rig order."""
    if not len(batch):
        return
    detected = batch.detected  # (C, N)
    quality = batch.visible_fraction * (1.0 - np.nan_to_num(batch.truncation, nan=1.0))
    boxes = batch.boxes2d
    area = np.nan_to_num((boxes[..., 2] - boxes[..., 0]) * (boxes[..., 3] - boxes[..., 1]))
    cameras = np.arange(len(batch.cameras))[:, None] * np.ones_like(quality)
    # lexicographic best per actor among the detecting cameras: quality, area (both descending), camera index
    best = np.lexsort((cameras, -area, -quality, ~detected), axis=0)[0]
    drop = detected & (best != np.arange(len(batch.cameras))[:, None])
    batch.detected = detected & ~drop
    batch.det_boxes2d = np.where(drop[..., None], np.nan, batch.det_boxes2d)
    batch.det_boxes3d = np.where(drop[..., None], np.nan, batch.det_boxes3d)
    batch.scores = np.where(drop, np.nan, batch.scores)
    if batch.embeddings is not None:
        batch.embeddings = np.where(drop[..., None], np.float32(np.nan), batch.embeddings)
