"""The sensor: ground truth + visibility in, per-camera detections (and why each actor was or was not
detected) out. Assembles the effects of :mod:`.effects` and :mod:`.perturbations` in their fixed order."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simrig.scenarios import Scenario
from simrig.scenarios.perturbation_schema import WORLD_KINDS, DropFrames

from ..geometry import Projection, camera_from_world
from ..render.visibility import Visibility
from ..seeding import RandomStreams
from ..types import GroundTruthFrame, Rig
from .appearance import Embeddings
from .batch import CameraBatch, FrameContext
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
from .perturbations import PERTURBATION_EFFECTS, DroppedFrames, Scheduled, ScheduledOcclusion


@dataclass(frozen=True, eq=False)
class SensorOutput:
    """One frame of sensor output: a batch per camera (rig order), whether the frame was dropped, and the
    scheduled perturbations active at the frame (event strings)."""

    batches: tuple[CameraBatch, ...]
    dropped: bool
    events: tuple[str, ...]


class SensorModel:
    """The detector of every camera of ``rig`` as configured by ``scenario`` (its ``sensor`` tables and its
    sensor ``perturbations``), drawing from ``streams``."""

    def __init__(self, scenario: Scenario, rig: Rig, streams: RandomStreams):
        self.rig = rig
        sensor = scenario.sensor
        rate = scenario.frame_rate_hz
        period = 1.0 / rate
        self.scheduled: list[Scheduled] = []
        occlusions, others = [], []
        self.drops: list[DroppedFrames] = []
        for index, config in enumerate(scenario.perturbations):
            if config.kind in WORLD_KINDS:
                continue
            if isinstance(config, DropFrames):
                effect = DroppedFrames(config, index, rig, rate, streams)
                self.drops.append(effect)
            else:
                effect = PERTURBATION_EFFECTS[type(config)](config, index, rig, rate)
            (occlusions if isinstance(effect, ScheduledOcclusion) else others).append(effect)
            self.scheduled.append(effect)
        class_mix = scenario.traffic.class_mix
        self.embeddings = Embeddings(streams, sensor.embedding, class_mix)
        self.ghosts = GhostWorld(sensor.ghosts, class_mix, rig, period, sensor.embedding.dimension, streams)
        self.effects: list[SensorEffect] = [
            *occlusions,  # before the probability: they set the visible fraction
            DetectionProbability(sensor.detection),
            *others,
            MissBursts(streams, sensor.detection, period),
            DetectionDraw(streams),
            Box2DNoise(streams, sensor.box2d),
            Monocular3D(streams, sensor.box3d, period),
            Scores(streams, sensor.score),
            Confusion(streams, sensor.confusion),
            self.embeddings,
            Clutter(sensor.clutter, class_mix, sensor.embedding.dimension, streams),
            self.ghosts,
            Duplicates(streams, sensor.duplicates),
            DetectionOrder(streams),
        ]

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
        world_from_camera = np.linalg.inv(camera_from_world(self.rig, ego))
        visible_fraction = np.nan_to_num(1.0 - visibility.occlusion, nan=0.0)
        if self.ghosts.enabled:
            self.ghosts.advance(state.frame, ego, state.actor_ids, state.classes, np.asarray(state.boxes))
        batches = []
        for index, camera in enumerate(self.rig.cameras):
            centre = world_from_camera[index, :3, 3]
            batch = CameraBatch(
                context=context,
                camera=camera,
                camera_index=index,
                world_from_camera=world_from_camera[index],
                classes=state.classes,
                boxes3d=np.asarray(state.boxes),
                boxes2d=projection.boxes[index],
                truncation=projection.truncation[index],
                visible_fraction=np.where(projection.in_view[index], visible_fraction[index], 0.0),
                distance=np.linalg.norm(state.boxes[:, :3] - centre, axis=1),
                in_view=projection.in_view[index],
            )
            for effect in self.effects:
                effect.apply(batch)
            batches.append(batch)
        dropped = any(drop.dropped(state.frame) for drop in self.drops)
        events = tuple(effect.describe(context) for effect in self.scheduled if effect.active(state.frame))
        return SensorOutput(tuple(batches), dropped, events)
