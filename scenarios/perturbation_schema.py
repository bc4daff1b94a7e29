"""Scheduled perturbations: what goes wrong, where and when.

Every perturbation has a window, ``frames = [first, last]`` or ``seconds = [first, last]`` (both inclusive;
seconds are rounded to the nearest frame at the scenario's frame rate). ``cameras = []`` means every camera
of the rig; camera names are checked against the rig when the sensor is built. Actors are chosen by id
(``actors = [3, 7]``) or as the ``nearest = k`` actors to the ego at the window's first frame (chosen once
for the whole window).

Sensor perturbations change what the detector reports; world perturbations (``occluder``, ``cut_in``) add
a real vehicle to the traffic, which then occludes and is seen like any other.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from .base import FiniteFloat, NonNegativeFloat, PositiveFloat, Strict

Fraction = Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)]
LaneOffset = Annotated[int, Field(ge=-3, le=3)]


class _Window(Strict):
    frames: tuple[Annotated[int, Field(ge=0)], Annotated[int, Field(ge=0)]] | None = None
    """[frame] first and last frame of the window (inclusive)."""
    seconds: tuple[NonNegativeFloat, NonNegativeFloat] | None = None
    """[s] first and last time of the window (inclusive), as an alternative to ``frames``."""

    @model_validator(mode="after")
    def _check_window(self):
        if (self.frames is None) == (self.seconds is None):
            raise ValueError("frames: give exactly one of frames = [first, last] or seconds = [first, last]")
        first, last = self.frames if self.frames is not None else self.seconds
        if first > last:
            key = "frames" if self.frames is not None else "seconds"
            raise ValueError(f"{key}: first {first} is after last {last}")
        return self

    def frame_window(self, frame_rate_hz: float) -> tuple[int, int]:
        """[frame] the inclusive window in frames."""
        if self.frames is not None:
            return self.frames
        return round(self.seconds[0] * frame_rate_hz), round(self.seconds[1] * frame_rate_hz)


class _Cameras(Strict):
    cameras: tuple[str, ...] = ()
    """Camera names affected; empty means every camera."""


class _Actors(Strict):
    actors: tuple[Annotated[int, Field(ge=0)], ...] = ()
    """Actor ids affected."""
    nearest: Annotated[int, Field(ge=1)] | None = None
    """[-] or the k actors nearest to the ego at the window's first frame."""

    @model_validator(mode="after")
    def _check_actors(self):
        if self.actors and self.nearest is not None:
            raise ValueError("actors: give actors or nearest, not both")
        return self


class Occlude(_Window, _Cameras, _Actors):
    """The chosen actors are hidden from the chosen cameras: visible fraction 0, never detected."""

    kind: Literal["occlude"]

    @model_validator(mode="after")
    def _needs_actors(self):
        if not self.actors and self.nearest is None:
            raise ValueError("actors: occlude needs actors = [...] or nearest = k")
        return self


class MissBurst(_Window, _Cameras, _Actors):
    """The detector misses the chosen actors (all actors when none are named) with ``probability``."""

    kind: Literal["miss_burst"]
    probability: Fraction = 1.0
    """[-] probability of a miss in each frame of the window."""


class Blackout(_Window, _Cameras):
    """The chosen cameras report nothing at all (no detections, no clutter)."""

    kind: Literal["blackout"]


class DropFrames(_Window):
    """Whole sensor frames are lost: no camera reports and the tracker is not stepped for that frame."""

    kind: Literal["drop_frames"]
    probability: Fraction = 1.0
    """[-] probability that each frame of the window is dropped."""


class Calibration(_Window, _Cameras):
    """The extrinsic calibration used to lift detections to 3D is off by a yaw rotation: every 3D estimate
    of the chosen cameras is rotated by ``yaw_offset_deg`` about the vertical axis through the camera.
    Pixel boxes are unaffected (the camera itself did not move)."""

    kind: Literal["calibration"]
    yaw_offset_deg: FiniteFloat = 2.0
    """[deg] the calibration error, counter-clockwise seen from above."""


class Noise(_Window, _Cameras):
    """All noise σ of the chosen cameras (2D box, 3D estimate, embedding) multiplied by ``factor``."""

    kind: Literal["noise"]
    factor: NonNegativeFloat = 3.0
    """[-] multiplier of every noise standard deviation."""


class _PlacedVehicle(_Window):
    lane_offset: LaneOffset = 1
    """[lanes] the vehicle's lane relative to the ego's (+1: next lane to the left, −1: to the right)."""
    offset_m: FiniteFloat = 0.0
    """[m] where it appears, along the road from the ego (positive ahead)."""
    relative_speed_mps: FiniteFloat = 0.0
    """[m/s] its target speed minus the ego's target speed."""


class _ScriptedVehicle(_PlacedVehicle):
    @model_validator(mode="after")
    def _check_lane(self):
        if self.lane_offset == 0:
            raise ValueError("lane_offset: must name another lane than the ego's (±1, ±2, ...)")
        return self


class _VehicleAhead(_PlacedVehicle):
    lane_offset: LaneOffset = 0
    """[lanes] the vehicle's lane relative to the ego's (0: the ego's own lane; +1: next lane to the left)."""
    offset_m: PositiveFloat = 30.0
    """[m] how far ahead of the ego, along the road, it appears (centre to centre)."""


class Occluder(_ScriptedVehicle):
    """A vehicle (a truck by default) appears at the window's first frame in the lane ``lane_offset`` from
    the ego, drives there without changing lanes, and leaves after the window's last frame."""

    kind: Literal["occluder"]
    actor_class: Literal["car", "truck", "bus", "motorcycle"] = "truck"


class CutIn(_ScriptedVehicle):
    """A vehicle appears at the window's first frame in the lane ``lane_offset`` from the ego and, at the
    window's last frame, changes into the ego's lane."""

    kind: Literal["cut_in"]
    actor_class: Literal["car", "truck", "bus", "motorcycle"] = "car"


class LeadBrake(_VehicleAhead):
    """A vehicle appears at the window's first frame ``offset_m`` ahead of the ego in its lane (or ``lane_offset``
    lanes from it), drives there at the ego's target speed + ``relative_speed_mps`` without changing lanes, and at
    the window's last frame brakes to a stop at ``deceleration_mps2``; it stays stopped for the rest of the run."""

    kind: Literal["lead_brake"]
    actor_class: Literal["car", "truck", "bus", "motorcycle"] = "car"
    deceleration_mps2: Annotated[float, Field(gt=0, le=10, allow_inf_nan=False)] = 6.0
    """[m/s²] its braking (6 m/s²: the hardest the simulated vehicles brake otherwise; ~10 m/s² is an emergency
    stop on dry asphalt)."""


class Stalled(_VehicleAhead):
    """A vehicle standing still from the window's first frame to its last, ``offset_m`` ahead of the ego in its lane
    (or ``lane_offset`` lanes from it): a breakdown the traffic, and the ego, must go around or stop behind."""

    kind: Literal["stalled"]
    actor_class: Literal["car", "truck", "bus", "motorcycle"] = "car"
    offset_m: PositiveFloat = 150.0
    """[m] how far ahead of the ego, along the road, it stands (centre to centre)."""
    relative_speed_mps: Literal[0.0] = 0.0
    """[m/s] not settable: a stalled vehicle does not move."""


Perturbation = Annotated[
    Occlude | MissBurst | Blackout | DropFrames | Calibration | Noise | Occluder | CutIn | LeadBrake | Stalled,
    Field(discriminator="kind"),
]
WORLD_KINDS = ("occluder", "cut_in", "lead_brake", "stalled")
"""Perturbations that act on the traffic rather than on the sensor."""
