"""Per-camera 2D tracking: one single-camera tracker per camera of the rig, run independently.

A single-camera tracker (``sort``, ``deepsort``) works on one camera's detections and reports
:class:`LocalTrack`\\ s; :class:`PerCameraTracking` makes a rig-level :class:`~simrig.trackers.protocol.Tracker` of it
whose output tracks carry one pixel box each, for the camera that saw them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from simrig.types import Box2D, EgoPose, Rig, SensorFrame, Track

from .clock import FrameClock
from .detections import LABELS, DetectionArrays, detection_arrays


@dataclass(frozen=True, eq=False)
class LocalTrack:
    """What a single-camera tracker reports for one track at one frame.

    track_id: unique within the camera; box: ``(4,)`` pixel box (x1, y1, x2, y2) [px]; score: the confidence
    in [0, 1]; label: class code into :data:`~simrig.trackers.detections.LABELS`; detection: the row, in the camera's
    detections of this frame, that updated the track (−1 when the box is the filter's prediction).
    """

    track_id: int
    box: np.ndarray
    score: float
    label: int
    detection: int


class CameraTracker(Protocol):
    """A single-camera tracker: ``step(detections, frames)`` takes one camera's detections of a frame and the
    number of frames since the last call (1 normally, more after dropped frames) and returns its reports."""

    def step(self, detections: DetectionArrays, frames: int) -> list[LocalTrack]: ...


class FrameCounter:
    """Frames elapsed between calls, from the frame index (dropped frames count), checked by a
    :class:`~simrig.trackers.clock.FrameClock`."""

    def __init__(self) -> None:
        self.clock = FrameClock()
        self._frame: int | None = None

    def reset(self) -> None:
        self.clock.reset()
        self._frame = None

    def advance(self, frame: SensorFrame) -> int:
        self.clock.advance(frame)
        frames = 1 if self._frame is None else max(1, frame.frame - self._frame)
        self._frame = frame.frame
        return frames


def _camera_track(track: LocalTrack, camera: str, track_id: int) -> Track:
    """A :class:`~simrig.types.Track` with ``track``'s box in ``camera``, under ``track_id``."""
    x1, y1, x2, y2 = (float(v) for v in track.box)
    return Track(track_id, LABELS[track.label], float(track.score), boxes2d={camera: Box2D(x1, y1, x2, y2)})


class PerCameraTracking:
    """Runs ``make()`` — a fresh single-camera tracker — on every camera of the rig (or on ``cameras`` only).
    Output ids are unique across cameras: a (camera, local id) pair gets the next id the first time it is
    reported. With ``motion`` (rig, pose before, pose now → ``(C, 3, 3)`` image homographies), each camera's
    tracker is told how its camera moved since the last frame (``tracker.compensate(H)``) before it steps."""

    def __init__(self, make: Callable[[], CameraTracker], cameras: tuple[str, ...] | None = None, *,
                 motion: Callable[[Rig, EgoPose, EgoPose], np.ndarray] | None = None):
        self.make = make
        self.only = tuple(cameras) if cameras else None
        self.trackers: dict[str, CameraTracker] = {}
        self.counter = FrameCounter()
        self._ids: dict[tuple[str, int], int] = {}
        self.motion = motion
        self._previous_ego: EgoPose | None = None

    def reset(self, *, rig: Rig, seed: int | None = None) -> None:
        """Fresh trackers for the rig's cameras; ``seed`` is unused (the trackers are deterministic)."""
        names = rig.camera_names
        if self.only is not None:
            missing = [name for name in self.only if name not in names]
            if missing:
                raise ValueError(f"camera {missing[0]!r} is not in rig {rig.name!r} (cameras: {', '.join(names)})")
        self.trackers = {name: self.make() for name in (self.only or names)}
        self.counter.reset()
        self._ids = {}
        self._previous_ego = None

    def step(self, frame: SensorFrame) -> list[Track]:
        detections = detection_arrays(frame, require_3d=False)
        frames = self.counter.advance(frame)
        homographies = (self.motion(frame.rig, self._previous_ego, frame.ego)
                        if self.motion is not None and self._previous_ego is not None else None)
        self._previous_ego = frame.ego
        out: list[Track] = []
        for index, name in enumerate(frame.rig.camera_names):
            if name not in self.trackers:
                continue
            if homographies is not None:
                self.trackers[name].compensate(homographies[index])
            for local in self.trackers[name].step(detections.take(detections.cameras == index), frames):
                key = (name, local.track_id)
                if key not in self._ids:
                    self._ids[key] = len(self._ids) + 1
                out.append(_camera_track(local, name, self._ids[key]))
        return out
