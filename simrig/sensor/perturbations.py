"""Scheduled sensor perturbations as effects: each checks its window, cameras and actors, and changes one
thing in the batch (see :mod:`scenarios.perturbation_schema` for the scenario keys)."""

from __future__ import annotations

import numpy as np

from simrig.scenarios import ScenarioError
from simrig.scenarios.perturbation_schema import Blackout, Calibration, MissBurst, Noise, Occlude

from ..causes import Cause
from ..seeding import RandomStreams
from ..types import Rig
from .batch import CameraBatch, FrameContext


class Scheduled:
    """A perturbation's window, cameras and actors, resolved against the rig and the frame rate."""

    def __init__(self, config, index: int, rig: Rig, frame_rate_hz: float):
        self.config = config
        self.index = index
        self.first, self.last = config.frame_window(frame_rate_hz)
        names = getattr(config, "cameras", ())
        unknown = [name for name in names if name not in rig.camera_names]
        if unknown:
            raise ScenarioError(
                f"perturbations[{index}].cameras: rig {rig.name!r} has no camera {', '.join(map(repr, unknown))}; "
                f"cameras: {', '.join(rig.camera_names)}"
            )
        self.cameras = frozenset(rig.camera_names.index(name) for name in names) if names else None
        self._chosen: np.ndarray | None = None

    def active(self, frame: int) -> bool:
        return self.first <= frame <= self.last

    def applies(self, batch: CameraBatch) -> bool:
        """Whether the window covers the batch's frame and the batch's camera is affected."""
        return self.active(batch.context.frame) and (self.cameras is None or batch.camera_index in self.cameras)

    def chosen_actors(self, context: FrameContext) -> np.ndarray | None:
        """Ids of the affected actors (None: every actor); ``nearest = k`` is decided on the first frame of
        the window that is processed and kept for the rest of it."""
        actors, nearest = getattr(self.config, "actors", ()), getattr(self.config, "nearest", None)
        if actors:
            return np.asarray(actors, dtype=np.int64)
        if nearest is None:
            return None
        if self._chosen is None:
            order = np.argsort(context.ego_distance, kind="stable")[:nearest]
            self._chosen = np.sort(context.actor_ids[order])
        return self._chosen

    def actor_mask(self, batch: CameraBatch) -> np.ndarray:
        chosen = self.chosen_actors(batch.context)
        return np.ones(len(batch), dtype=bool) if chosen is None else np.isin(batch.actor_ids, chosen)

    def describe(self, context: FrameContext) -> str:
        """A short event string for the frames table, e.g. ``occlude#0 actors=3,7 cameras=all``."""
        parts = [f"{self.config.kind}#{self.index}"]
        if hasattr(self.config, "actors"):
            chosen = self.chosen_actors(context)
            parts.append("actors=" + ("all" if chosen is None else ",".join(map(str, chosen.tolist()))))
        if hasattr(self.config, "cameras"):
            parts.append("cameras=" + (",".join(self.config.cameras) or "all"))
        return " ".join(parts)


class ScheduledOcclusion(Scheduled):
    """``occlude``: the actors' visible fraction becomes 0 (so p becomes 0), causes occluded + scheduled."""

    def apply(self, batch: CameraBatch) -> None:
        if not self.applies(batch):
            return
        hit = self.actor_mask(batch) & batch.in_view
        batch.visible_fraction = np.where(hit, 0.0, batch.visible_fraction)
        batch.causes |= np.where(hit, int(Cause.OCCLUDED | Cause.SCHEDULED_OCCLUSION), 0)


class ScheduledMisses(Scheduled):
    """``miss_burst``: p ← p · (1 − probability) for the chosen actors in view, cause scheduled_miss."""

    def apply(self, batch: CameraBatch) -> None:
        if not self.applies(batch):
            return
        hit = self.actor_mask(batch) & batch.in_view
        batch.probability = np.where(hit, batch.probability * (1.0 - self.config.probability), batch.probability)
        batch.causes |= np.where(hit, int(Cause.SCHEDULED_MISS), 0)


class CameraBlackout(Scheduled):
    """``blackout``: the camera reports nothing, cause blackout on every actor in its view."""

    def apply(self, batch: CameraBatch) -> None:
        if not self.applies(batch):
            return
        batch.silenced = True
        batch.probability = np.zeros(len(batch))
        batch.causes |= np.where(batch.in_view, int(Cause.BLACKOUT), 0)


class DroppedFrames(Scheduled):
    """``drop_frames``: frames of the window are lost with the configured probability (one draw per frame
    from the ``perturbations`` stream); a lost frame silences every camera, cause dropped_frame."""

    def __init__(self, config, index: int, rig: Rig, frame_rate_hz: float, streams: RandomStreams):
        super().__init__(config, index, rig, frame_rate_hz)
        self._streams = streams

    def dropped(self, frame: int) -> bool:
        if not self.active(frame):
            return False
        return bool(self._streams.generator("perturbations", self.index, frame).random() < self.config.probability)

    def apply(self, batch: CameraBatch) -> None:
        if not self.dropped(batch.context.frame):
            return
        batch.silenced = True
        batch.probability = np.zeros(len(batch))
        batch.causes |= np.where(batch.in_view, int(Cause.DROPPED_FRAME), 0)


class CalibrationError(Scheduled):
    """``calibration``: the camera's 3D estimates are lifted with a yaw offset, cause calibration."""

    def apply(self, batch: CameraBatch) -> None:
        if not self.applies(batch):
            return
        batch.yaw_offset += np.radians(self.config.yaw_offset_deg)
        batch.causes |= np.where(batch.in_view, int(Cause.CALIBRATION), 0)


class IncreasedNoise(Scheduled):
    """``noise``: every noise σ of the camera multiplied by ``factor``, cause noise."""

    def apply(self, batch: CameraBatch) -> None:
        if not self.applies(batch):
            return
        batch.noise_factor = batch.noise_factor * self.config.factor
        batch.causes |= np.where(batch.in_view, int(Cause.NOISE), 0)


PERTURBATION_EFFECTS = {
    Occlude: ScheduledOcclusion,
    MissBurst: ScheduledMisses,
    Blackout: CameraBlackout,
    Calibration: CalibrationError,
    Noise: IncreasedNoise,
}
"""Sensor perturbation config type → effect class (``drop_frames`` is built separately: it needs a stream)."""
