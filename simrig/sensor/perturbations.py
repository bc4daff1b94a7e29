"""Scheduled sensor perturbations as effects: each checks its window, cameras and actors, and changes one
thing in the batch (see :mod:`simrig.scenarios.perturbation_schema` for the scenario keys)."""

from __future__ import annotations

import numpy as np

from simrig.scenarios import ScenarioError
from simrig.scenarios.perturbation_schema import Blackout, Calibration, MissBurst, Noise, Occlude

from ..causes import Cause
from ..seeding import RandomStreams
from ..types import Rig
from .batch import FrameContext, SensorBatch


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
                f"perturbations.{index}.cameras: rig {rig.name!r} has no camera {', '.join(map(repr, unknown))}; "
                f"cameras: {', '.join(rig.camera_names)}"
            )
        affected = {rig.camera_names.index(name) for name in names}
        self._camera_mask = np.array([not names or index in affected for index in range(len(rig.cameras))])
        self._chosen: np.ndarray | None = None

    def active(self, frame: int) -> bool:
        return self.first <= frame <= self.last

    def applies(self, batch: SensorBatch) -> np.ndarray | None:
        """The affected cameras ``(C, 1)`` (a mask to broadcast over actors) when the window covers the
        batch's frame, else None."""
        return self._camera_mask[:, None] if self.active(batch.context.frame) else None

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

    def actor_mask(self, batch: SensorBatch) -> np.ndarray:
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

    def apply(self, batch: SensorBatch) -> None:
        cameras = self.applies(batch)
        if cameras is None:
            return
        hit = cameras & self.actor_mask(batch) & batch.in_view
        batch.visible_fraction = np.where(hit, 0.0, batch.visible_fraction)
        batch.causes |= np.where(hit, int(Cause.OCCLUDED | Cause.SCHEDULED_OCCLUSION), 0)


class ScheduledMisses(Scheduled):
    """``miss_burst``: p ← p · (1 − probability) for the chosen actors in view, cause scheduled_miss."""

    def apply(self, batch: SensorBatch) -> None:
        cameras = self.applies(batch)
        if cameras is None:
            return
        hit = cameras & self.actor_mask(batch) & batch.in_view
        batch.probability = np.where(hit, batch.probability * (1.0 - self.config.probability), batch.probability)
        batch.causes |= np.where(hit, int(Cause.SCHEDULED_MISS), 0)


class CameraBlackout(Scheduled):
    """``blackout``: the camera reports nothing, cause blackout on every actor in its view."""

    def apply(self, batch: SensorBatch) -> None:
        cameras = self.applies(batch)
        if cameras is None:
            return
        _silence(batch, cameras, Cause.BLACKOUT)


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

    def apply(self, batch: SensorBatch) -> None:
        if not self.dropped(batch.context.frame):
            return
        _silence(batch, self._camera_mask[:, None], Cause.DROPPED_FRAME)


class CalibrationError(Scheduled):
    """``calibration``: the camera's 3D estimates are lifted with a yaw offset, cause calibration."""

    def apply(self, batch: SensorBatch) -> None:
        cameras = self.applies(batch)
        if cameras is None:
            return
        batch.yaw_offset = np.where(cameras[:, 0], batch.yaw_offset + np.radians(self.config.yaw_offset_deg),
                                    batch.yaw_offset)
        batch.causes |= np.where(cameras & batch.in_view, int(Cause.CALIBRATION), 0)


class IncreasedNoise(Scheduled):
    """``noise``: every noise σ of the camera multiplied by ``factor``, cause noise."""

    def apply(self, batch: SensorBatch) -> None:
        cameras = self.applies(batch)
        if cameras is None:
            return
        batch.noise_factor = np.where(cameras, batch.noise_factor * self.config.factor, batch.noise_factor)
        batch.causes |= np.where(cameras & batch.in_view, int(Cause.NOISE), 0)


def _silence(batch: SensorBatch, cameras: np.ndarray, cause: Cause) -> None:
    """The ``cameras`` (a ``(C, 1)`` mask) report nothing: p = 0, ``cause`` on every actor in their view."""
    batch.silenced = batch.silenced | cameras[:, 0]
    batch.probability = np.where(cameras, 0.0, batch.probability)
    batch.causes |= np.where(cameras & batch.in_view, int(cause), 0)


PERTURBATION_EFFECTS = {
    Occlude: ScheduledOcclusion,
    MissBurst: ScheduledMisses,
    Blackout: CameraBlackout,
    Calibration: CalibrationError,
    Noise: IncreasedNoise,
}
"""Sensor perturbation config type → effect class (``drop_frames`` is built separately: it needs a stream)."""
