"""Capture timing: when each camera fires within a frame, when its detections reach the tracker, and the ego
pose the tracker is given (:mod:`simrig.scenarios.timing_schema` has the settings).

The world at a camera's capture time
------------------------------------
The traffic is simulated at the frame ticks. A camera firing ``δ`` seconds after frame ``k``'s tick sees every
actor, and is carried by the ego, at constant velocity from the tick: centre + v·δ, yaw and size unchanged.
This is exact for an actor at constant velocity; otherwise its error is at most ½·a·δ² (a the actor's
acceleration): 1.9 cm for the hardest braking highway-env's vehicles do (6 m/s²) at δ = 80 ms, 0.5 cm at the
nuScenes-like 42 ms spread. (Visibility is the one exception: the occlusion fraction is the one measured on the
frame tick's render, since rendering each camera at its own instant would multiply the render cost; in 80 ms it
changes only at an occluder's edge. An actor in a camera's view at its capture time but not at the tick has no
measured visibility there and counts as hidden, as an unmeasured actor does on a synchronous rig.)

Random draws
------------
Jitter, random latency and the ego-pose error each draw from their own stream (``capture``, ``latency``,
``ego_pose``) a fixed count per frame whether or not their cause group is removed, so switching any of them off
leaves every other draw of the run as it was.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from simrig.scenarios import ScenarioError
from simrig.scenarios.timing_schema import EgoPoseConfig, timing_camera_names, timing_tables_set

from ..geometry import as_estimated  # noqa: F401  (the sensor's name for it)
from ..seeding import RandomStreams
from ..types import EgoPose, Rig

TIMING_GROUPS: tuple[str, ...] = ("trigger", "latency", "ego_pose")
"""The cause groups of capture timing, in reporting order: the capture schedule (trigger offsets, jitter, clock
skew and cameras slower than the frame rate), the delivery delay, and the ego-pose error."""


@dataclass(frozen=True, eq=False)
class Captures:
    """The cameras' captures of one frame, in rig order: ``offsets`` ``(C,)`` [s] true capture time minus the
    frame's tick; ``reported`` ``(C,)`` [s] the capture timestamps the cameras report (true time + clock skew);
    ``arrival_frame`` ``(C,)`` the frame at whose step the camera's detections reach the tracker (frame count
    or more: never delivered); ``fired`` ``(C,)`` whether the camera takes an image at this frame (a camera
    running below the frame rate skips frames)."""

    tick: float
    offsets: np.ndarray
    reported: np.ndarray
    arrival_frame: np.ndarray
    fired: np.ndarray


def sweep_order(rig: Rig) -> tuple[str, ...]:
    """The rig's cameras clockwise from the one closest to straight ahead (the order a lidar spinning clockwise
    seen from above passes them; nuScenes: front, front right, back right, back, back left, front left)."""
    yaw = np.array([(math.degrees(camera.yaw) + 180.0) % 360.0 - 180.0 for camera in rig.cameras])
    first = int(np.argmin(np.abs(yaw)))
    clockwise = (yaw[first] - yaw) % 360.0
    return tuple(rig.cameras[i].name for i in np.lexsort((np.arange(len(yaw)), clockwise)))


def check_timing_cameras(sensor, rig: Rig) -> None:
    """A :class:`~simrig.scenarios.ScenarioError` naming the key when a timing table names a camera ``rig`` lacks,
    or a sweep's ``order`` leaves one of its cameras out."""
    for key, name in timing_camera_names(sensor):
        if name not in rig.camera_names:
            raise ScenarioError(f"{key}: rig {rig.name!r} has no camera {name!r}; cameras: "
                                f"{', '.join(rig.camera_names)}")
    order = sensor.capture.order
    if order and len(order) != len(rig.camera_names):
        missing = [name for name in rig.camera_names if name not in order]
        raise ScenarioError(f"sensor.capture.order: names {len(order)} of the rig's {len(rig.camera_names)} cameras "
                            f"(not {', '.join(missing)}); name every camera, or none for clockwise from the front")


class CaptureTiming:
    """The capture schedule and delivery delay of every camera of ``rig``, frame by frame.

    ``removed``: the timing cause groups switched off (``trigger``: every camera at the tick, every frame, with its
    true timestamp; ``latency``: every detection on time). The draws are made all the same."""

    def __init__(self, sensor, rig: Rig, frame_rate_hz: float, streams: RandomStreams,
                 removed: frozenset[str] = frozenset()):
        check_timing_cameras(sensor, rig)
        self.capture, self.latency = sensor.capture, sensor.latency
        self._configured = bool({"capture", "latency"} & set(timing_tables_set(sensor)))
        self.period = 1.0 / frame_rate_hz
        names = rig.camera_names
        c = len(names)
        base = np.zeros(c)
        if self.capture.trigger == "sweep":
            order = self.capture.order or sweep_order(rig)
            steps = self.capture.spread_s / max(len(order) - 1, 1)
            for position, name in enumerate(order):
                base[names.index(name)] = position * steps
        elif self.capture.trigger == "given":
            for name, offset in self.capture.offsets_s.items():
                base[names.index(name)] = offset
        self.base = base
        self.skew = np.array([self.capture.clock_skew_s.get(name, 0.0) for name in names])
        self.delay = self.latency.fixed_s + np.array([self.latency.by_camera_s.get(name, 0.0) for name in names])
        self.every = np.array([round(frame_rate_hz / self.capture.rate_hz[name]) if name in self.capture.rate_hz
                               else 1 for name in names])
        self.trigger_on = "trigger" not in removed
        self.latency_on = "latency" not in removed
        self._jitter = streams.generator("capture") if self.capture.jitter_s > 0 else None
        self._random_delay = streams.generator("latency") if self.latency.random_s > 0 else None
        self._cameras = c

    @property
    def configured(self) -> bool:
        """Whether the scenario sets any capture or latency setting (its datasets then hold a ``captures``
        table, with the groups removed or not)."""
        return self._configured

    def at(self, frame: int, tick: float) -> Captures:
        """The captures of ``frame`` (tick ``tick`` [s]); frames are asked for in order, from 0."""
        offsets = self.base.copy()
        if self._jitter is not None:
            sigma = self.capture.jitter_s
            offsets += np.clip(self._jitter.standard_normal(self._cameras) * sigma, -3 * sigma, 3 * sigma)
        delay = self.delay.copy()
        if self._random_delay is not None:
            delay += self._random_delay.exponential(self.latency.random_s, self._cameras)
        skew = self.skew
        if not self.trigger_on:
            offsets, skew = np.zeros(self._cameras), np.zeros(self._cameras)
        if not self.latency_on:
            delay = np.zeros(self._cameras)
        # a frame's step runs at the end of its period: on time when the detections arrive by tick + period
        late_by = offsets + delay - self.period
        arrival = frame + np.where(late_by > 1e-9, np.ceil(late_by / self.period - 1e-9), 0).astype(np.int64)
        fired = (frame % self.every == 0) if self.trigger_on else np.ones(self._cameras, dtype=bool)
        return Captures(tick=tick, offsets=offsets, reported=tick + offsets + skew, arrival_frame=arrival,
                        fired=fired)


def moved_boxes(boxes: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """``(C, N, 9)``: world-frame boxes ``(N, 9)`` at each camera's capture time, ``offsets`` ``(C,)`` [s] after
    the tick, moved at their own constant velocity (centre + v·δ; size, yaw and velocity unchanged)."""
    out = np.broadcast_to(boxes, (len(offsets), *boxes.shape)).copy()
    out[..., 0] += boxes[:, 7] * offsets[:, None]
    out[..., 1] += boxes[:, 8] * offsets[:, None]
    return out


def moved_egos(ego: EgoPose, offsets: np.ndarray) -> list[EgoPose]:
    """The ego pose at each capture time (constant velocity from the tick)."""
    return [ego.moved(float(offset)) for offset in offsets]


class EgoPoseEstimate:
    """The ego pose a tracker is given: true pose + bias + white noise, the bias a random walk from 0 at the
    first frame (position per axis in the world frame [m], yaw [rad]). ``enabled`` False (the ``ego_pose``
    group removed): the true pose, the draws made all the same."""

    def __init__(self, config: EgoPoseConfig, frame_rate_hz: float, streams: RandomStreams, *, enabled: bool = True):
        self.config = config
        self.period = 1.0 / frame_rate_hz
        self.enabled = enabled
        self._rng = streams.generator("ego_pose") if config != EgoPoseConfig() else None
        self._bias = np.zeros(3)
        self._walk = np.array([config.drift_m_per_sqrt_s, config.drift_m_per_sqrt_s,
                               math.radians(config.drift_yaw_deg_per_sqrt_s)])
        self._white = np.array([config.noise_m, config.noise_m, math.radians(config.noise_yaw_deg)])

    @property
    def configured(self) -> bool:
        """Whether the scenario sets an ego-pose error (its datasets then hold an ``ego_estimates`` table)."""
        return self._rng is not None

    def estimate(self, frame: int, ego: EgoPose) -> EgoPose:
        """The estimate of ``ego`` at ``frame`` (frames asked for in order, from 0)."""
        if self._rng is None:
            return ego
        draws = self._rng.standard_normal(6)
        if frame > 0:
            self._bias = self._bias + draws[:3] * self._walk * math.sqrt(self.period)
        error = self._bias + draws[3:] * self._white
        if not self.enabled:
            return ego
        c, s = math.cos(error[2]), math.sin(error[2])
        return EgoPose(ego.x + float(error[0]), ego.y + float(error[1]), ego.z, ego.yaw + float(error[2]),
                       c * ego.vx - s * ego.vy, s * ego.vx + c * ego.vy)


