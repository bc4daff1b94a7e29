"""Scenario keys of capture timing: when each camera fires, when its detections reach the tracker, and how
well the ego knows its own pose. Each is a table under ``[sensor]`` and a cause group of ``simrig explain``
(``trigger``, ``latency``, ``ego_pose``). Their defaults are the ideal rig (every camera fires at the frame's
tick, nothing is late, the pose is exact), and a scenario that leaves them at their defaults stores no trace of
them: its dataset's bytes are those of a rig without the tables.

Times are seconds; a camera's *capture time* is the frame's tick plus its trigger offset plus jitter, and a
frame's tracker step runs at the end of the frame period (just before the next tick): a detection is on time
when it arrives by then, late (delivered and marked in a later frame) when it arrives after.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from .base import NonNegativeFloat, PositiveFloat, Strict

Seconds = Annotated[float, Field(ge=0, le=10, allow_inf_nan=False)]
"""[s] a non-negative time of at most 10 s."""
SignedSeconds = Annotated[float, Field(ge=-1, le=1, allow_inf_nan=False)]
"""[s] a clock error, within ±1 s."""


class CaptureConfig(Strict):
    """When each camera takes its image within a frame.

    ``trigger``: ``synchronous`` — every camera at the frame's tick; ``sweep`` — one after the other in
    ``order``, evenly spread over ``spread_s`` (the first at the tick, the last ``spread_s`` after it), as the
    nuScenes cameras are triggered when the top lidar sweeps past each camera's field of view; ``given`` —
    ``offsets_s`` per camera. ``jitter_s``: σ of a Gaussian added to every capture time (clipped to ±3σ).
    ``clock_skew_s``: per camera, a constant error of the timestamp the camera reports (the true capture time
    is unchanged: ground truth is taken at the true time, a tracker reads the reported one). ``rate_hz``: per
    camera, a rate below the frame rate (dividing it): the camera fires every n-th frame, from frame 0.
    """

    trigger: Literal["synchronous", "sweep", "given"] = "synchronous"
    order: tuple[str, ...] = ()
    """Every camera of the rig, in firing order, for ``sweep``; empty: clockwise from the front camera (the rig's
    cameras by decreasing yaw, starting from the one closest to straight ahead)."""
    spread_s: Seconds = 0.0
    """[s] time from the first camera's trigger to the last one's (``sweep``)."""
    offsets_s: dict[str, Seconds] = Field(default_factory=dict)
    """[s] per camera name, its trigger offset after the frame's tick (``given``; a camera not named: 0)."""
    jitter_s: Seconds = 0.0
    """[s] σ of the random part of each capture time."""
    clock_skew_s: dict[str, SignedSeconds] = Field(default_factory=dict)
    """[s] per camera name, the constant error of its reported timestamps."""
    rate_hz: dict[str, PositiveFloat] = Field(default_factory=dict)
    """[Hz] per camera name, its frame rate when below the scenario's (which it must divide: a camera fires every
    n-th frame); a camera not named fires every frame. At a frame it does not fire it takes no image: no
    detections, and no ground truth in its view."""

    @model_validator(mode="after")
    def _check(self) -> CaptureConfig:
        seen: set[str] = set()
        for name in self.order:
            if name in seen:
                raise ValueError(f"order: camera {name!r} named twice")
            seen.add(name)
        if self.trigger != "sweep" and (self.order or self.spread_s):
            key = "order" if self.order else "spread_s"
            raise ValueError(f"{key}: only a 'sweep' trigger takes it (trigger is {self.trigger!r})")
        if self.trigger != "given" and self.offsets_s:
            raise ValueError(f"offsets_s: only a 'given' trigger takes it (trigger is {self.trigger!r})")
        if self.trigger == "given" and not self.offsets_s:
            raise ValueError("offsets_s: a 'given' trigger needs the offset of at least one camera")
        return self


class LatencyConfig(Strict):
    """Delay from a camera's capture to the moment its detections reach the tracker: ``fixed_s`` for every
    camera, plus ``by_camera_s`` for the named cameras, plus a random part, exponential with mean ``random_s``
    (drawn per camera and frame: one image's detections arrive together)."""

    fixed_s: NonNegativeFloat = 0.0
    """[s] delay of every camera's detections (shorter than the run)."""
    by_camera_s: dict[str, NonNegativeFloat] = Field(default_factory=dict)
    """[s] per camera name, an extra delay."""
    random_s: NonNegativeFloat = 0.0
    """[s] mean of the exponential random delay (0: none)."""


class EgoPoseConfig(Strict):
    """The ego pose a tracker is given is an estimate: the true pose plus a drifting bias (a random walk, as
    odometry drifts) plus white noise per frame. Detections are measured relative to the ego, so their
    world-frame boxes move with the estimate's error; ground truth keeps the true pose."""

    noise_m: NonNegativeFloat = 0.0
    """[m] σ of the white position noise per frame and axis."""
    noise_yaw_deg: NonNegativeFloat = 0.0
    """[deg] σ of the white yaw noise per frame."""
    drift_m_per_sqrt_s: NonNegativeFloat = 0.0
    """[m/√s] random-walk σ of the position bias per axis: after t seconds its σ is this × √t."""
    drift_yaw_deg_per_sqrt_s: NonNegativeFloat = 0.0
    """[deg/√s] random-walk σ of the yaw bias."""


TIMING_TABLES: dict[str, type[Strict]] = {"capture": CaptureConfig, "latency": LatencyConfig,
                                          "ego_pose": EgoPoseConfig}
"""The timing tables under ``[sensor]``, in the order of their cause groups (``trigger``, ``latency``,
``ego_pose``)."""


def timing_tables_set(sensor) -> tuple[str, ...]:
    """The timing tables of ``sensor`` that differ from their defaults (an ideal rig sets none)."""
    return tuple(name for name, model in TIMING_TABLES.items() if getattr(sensor, name) != model())


def latency_beyond(scenario, frames: int) -> str | None:
    """The message for a fixed latency of ``scenario`` at least as long as a run of ``frames`` frames (no detection
    would ever arrive), naming its key; ``None`` when every camera's fixed latency is shorter."""
    latency, run = scenario.sensor.latency, frames / scenario.frame_rate_hz
    for key, delay in [("fixed_s", latency.fixed_s)] + [
            (f"by_camera_s.{name}", latency.fixed_s + value) for name, value in latency.by_camera_s.items()]:
        if delay >= run:
            return (f"sensor.latency.{key}: a latency of {delay:g} s is longer than the run ({frames} frames, "
                    f"{run:g} s): no detection would ever arrive")
    return None


def timing_camera_names(sensor) -> list[tuple[str, str]]:
    """(key, camera name) of every camera the timing tables of ``sensor`` name, for the check against the rig."""
    capture, latency = sensor.capture, sensor.latency
    return ([("sensor.capture.order", name) for name in capture.order]
            + [("sensor.capture.offsets_s", name) for name in capture.offsets_s]
            + [("sensor.capture.clock_skew_s", name) for name in capture.clock_skew_s]
            + [("sensor.capture.rate_hz", name) for name in capture.rate_hz]
            + [("sensor.latency.by_camera_s", name) for name in latency.by_camera_s])
