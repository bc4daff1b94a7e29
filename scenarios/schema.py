"""The scenario schema: every key with its unit, validated strictly.

An unknown key, a wrong type or an impossible value is an error; a parameter that does not apply to the
chosen preset or traffic environment is an error too, never silently ignored.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, ValidationError, model_serializer, model_validator

from .base import FiniteFloat, NonNegativeFloat, PathName, PositiveFloat, Strict, set_keys
from .evaluation_schema import EvaluationConfig
from .layout_schema import Layout
from .perturbation_schema import Perturbation
from .sensor_schema import RenderConfig, SensorConfig
from .timing_schema import latency_beyond

TRAFFIC_ENVS = ("highway-v0", "merge-v0", "roundabout-v0", "intersection-v0")
RIG_PRESETS = ("surround6", "stereo", "ring", "custom")
ACTOR_CLASSES = ("car", "truck", "bus", "motorcycle")


Speed = Annotated[float, Field(gt=0, le=100, allow_inf_nan=False)]
"""[m/s] a vehicle speed: positive, at most 100 m/s (360 km/h)."""


class TrafficConfig(Strict):
    """Traffic around the ego vehicle.

    The number of other vehicles is held at ``vehicles`` inside a disc of ``window_radius_m`` around the ego:
    vehicles leaving the disc are removed, new ones appear between ``spawn_min_distance_m`` and the radius.
    """

    env: Literal["highway-v0", "merge-v0", "roundabout-v0", "intersection-v0"] = "highway-v0"
    lanes: Annotated[int, Field(ge=1, le=8)] = 4
    """[-] lanes of highway-v0 (only valid there: the other maps have a fixed layout)."""
    ego_lane: Annotated[int, Field(ge=0, le=7)] | None = None
    """[-] highway-v0 lane the ego starts in, 0 the leftmost; random (from the seed) when omitted."""
    vehicles: Annotated[int, Field(ge=0, le=200)] = 40
    """[-] other vehicles kept inside the window."""
    window_radius_m: Annotated[float, Field(gt=0, le=2000, allow_inf_nan=False)] = 150.0
    """[m] radius of the window around the ego in which traffic is kept."""
    spawn_min_distance_m: NonNegativeFloat = 100.0
    """[m] new vehicles appear at a distance from the ego between this and the radius."""
    initial_clearance_m: Annotated[float, Field(ge=0, le=2000, allow_inf_nan=False)] = 12.0
    """[m] no vehicle is placed closer than this to the ego at the start."""
    speed_range_mps: tuple[Speed, Speed] = (20.0, 30.0)
    """[m/s] target speeds of other vehicles are drawn uniformly from this range."""
    ego_speed_mps: Speed = 25.0
    """[m/s] target speed of the ego's IDM driver."""
    simulation_substeps: Annotated[int, Field(ge=1, le=20)] = 1
    """[-] highway-env integration steps per output frame."""
    crashes: Literal["allowed", "refused"] = "allowed"
    """``refused``: a collision between two road users other than the ego stops the generation with an error that
    names the seed, frame and vehicles (a bench records it as that cell's failure and goes on), so a dataset of
    this scenario never holds one. The ego's own collisions are always recorded: in a drive they are its outcome.
    ``allowed``: such vehicles leave the road with a ``vehicle_crashed`` event."""
    class_mix: dict[Literal["car", "truck", "bus", "motorcycle"], NonNegativeFloat] = Field(
        default_factory=lambda: {"car": 0.8, "truck": 0.1, "bus": 0.05, "motorcycle": 0.05}
    )
    """[-] relative frequency of each class among spawned vehicles (normalised)."""
    layout: Layout | None = None
    """A long road simrig builds in place of the environment's own (:mod:`~simrig.scenarios.layout_schema`: oncoming
    lanes, on-ramps, exits, crossings); only with ``env = "highway-v0"``, whose road it replaces."""

    @model_serializer(mode="wrap")
    def _without_absent_layout(self, handler):
        """A scenario without a layout dumps as it did before layouts existed, so its manifest, its content key
        and every dataset cache made for it stay the same; one with a layout dumps without highway-v0's ``lanes``
        and ``ego_lane``, which it does not use."""
        data = handler(self)
        if isinstance(data, dict):
            # a layout's road replaces highway-v0's: its lane count and start lane would only mislead a reader
            for key in ("layout",) if self.layout is None else ("lanes", "ego_lane"):
                data.pop(key, None)
        return data

    @model_validator(mode="after")
    def _check(self) -> TrafficConfig:
        if self.layout is not None:
            if self.env != "highway-v0":
                raise ValueError(f"layout: replaces highway-v0's road; env must be highway-v0, not {self.env}")
            for key in ("lanes", "ego_lane"):
                if key in set_keys(self) and (key == "lanes" or self.ego_lane is not None):
                    raise ValueError(f"{key}: not with a layout ({self.layout.kind} sets its own lanes and "
                                     "where the ego starts)")
        if "lanes" in set_keys(self) and self.env != "highway-v0":
            raise ValueError(f"lanes: only highway-v0 has a configurable lane count, not {self.env}")
        if self.ego_lane is not None and (self.env != "highway-v0" or self.ego_lane >= self.lanes):
            raise ValueError(f"ego_lane: must be a lane of highway-v0's {self.lanes} lanes (0 … {self.lanes - 1})")
        if self.spawn_min_distance_m > self.window_radius_m:
            raise ValueError(
                f"spawn_min_distance_m: {self.spawn_min_distance_m} m exceeds window_radius_m "
                f"{self.window_radius_m} m"
            )
        low, high = self.speed_range_mps
        if low > high:
            raise ValueError(f"speed_range_mps: lower bound {low} exceeds upper bound {high}")
        if not self.class_mix or sum(self.class_mix.values()) <= 0:
            raise ValueError("class_mix: needs at least one class with a positive share")
        return self


class CustomCamera(Strict):
    """One camera of a ``custom`` rig: pose on the ego [m, deg], horizontal field of view [deg], image [px]."""

    name: PathName
    """Names the camera's image folder (``images/NAME/``) and its rows; :mod:`simrig.names`'s rule."""
    x_m: FiniteFloat = 0.0
    y_m: FiniteFloat = 0.0
    z_m: FiniteFloat = 1.6
    yaw_deg: FiniteFloat = 0.0
    pitch_deg: Annotated[float, Field(ge=-89, le=89)] = 0.0
    hfov_deg: Annotated[float, Field(ge=1, lt=179)] = 60.0
    width_px: Annotated[int, Field(ge=16, le=8192)] = 1600
    height_px: Annotated[int, Field(ge=16, le=8192)] = 900


_PRESET_KEYS = {
    "surround6": {"overlap_deg", "image_width_px", "image_height_px", "mount_height_m"},
    "stereo": {"baseline_m", "hfov_deg", "image_width_px", "image_height_px", "mount_height_m"},
    "ring": {"cameras_count", "overlap_deg", "image_width_px", "image_height_px", "mount_height_m"},
    "custom": {"cameras"},
}


class RigConfig(Strict):
    """The camera rig. ``preset`` picks the layout; the other keys tune it and must fit the preset:

    * ``surround6`` — nuScenes-like ring of six (front, front-left/right at ±55°, back-left/right at
      ±110°, back at 180°); neighbours overlap by ``overlap_deg``, the back camera is wider.
    * ``stereo`` — KITTI-like pair ``left``/``right`` facing forward, ``baseline_m`` apart.
    * ``ring`` — ``cameras_count`` cameras evenly spaced; FOV = 360°/N + ``overlap_deg``.
    * ``custom`` — an explicit list of ``cameras``.
    """

    preset: Literal["surround6", "stereo", "ring", "custom"] = "surround6"
    overlap_deg: Annotated[float, Field(ge=0, le=60)] = 10.0
    """[deg] angular overlap between neighbouring cameras (surround6, ring)."""
    cameras_count: Annotated[int, Field(ge=2, le=16)] = 6
    """[-] cameras in a ring."""
    baseline_m: PositiveFloat = 0.54
    """[m] distance between the stereo pair's optical centres."""
    hfov_deg: Annotated[float, Field(ge=1, lt=179)] = 81.2
    """[deg] horizontal field of view of each stereo camera (KITTI: 1242 px at f = 721.5 px)."""
    image_width_px: Annotated[int, Field(ge=16, le=8192)] | None = None
    """[px] image width; preset default when omitted (1600 surround/ring, 1242 stereo)."""
    image_height_px: Annotated[int, Field(ge=16, le=8192)] | None = None
    """[px] image height; preset default when omitted (900 surround/ring, 375 stereo)."""
    mount_height_m: PositiveFloat = 1.6
    """[m] height of the optical centres above the road."""
    cameras: Annotated[tuple[CustomCamera, ...], Field(max_length=32)] = ()

    @model_validator(mode="after")
    def _check(self) -> RigConfig:
        allowed = _PRESET_KEYS[self.preset] | {"preset"}
        foreign = sorted(set_keys(self) - allowed)
        if foreign:
            raise ValueError(f"{', '.join(foreign)}: not a setting of the {self.preset!r} preset")
        if self.preset == "custom":
            if not self.cameras:
                raise ValueError("cameras: a custom rig needs at least one camera")
            names = [camera.name for camera in self.cameras]
            if len(set(names)) != len(names):
                raise ValueError(f"cameras: names must be unique, got {names}")
        if self.preset == "ring" and 360.0 / self.cameras_count + self.overlap_deg >= 179.0:
            raise ValueError(
                f"overlap_deg: {self.cameras_count} cameras with {self.overlap_deg}° overlap need a field of "
                "view of 179° or more, which a pinhole camera cannot have"
            )
        return self


class Scenario(Strict):
    """A named, fully resolved scenario: traffic, rig and timing."""

    @classmethod
    def model_validate(cls, obj, *args, **kwargs):
        """As pydantic's, with a ``[sensor] preset`` laid under the scenario's own sensor keys first (files get
        the same through :func:`simrig.scenarios.load_scenario`)."""
        from .sensor_presets import with_preset

        return super().model_validate(with_preset(obj) if isinstance(obj, dict) else obj, *args, **kwargs)

    name: PathName
    """Names the default run folder (``runs/NAME-seedN``); :mod:`simrig.names`'s rule."""
    description: str = ""
    frame_rate_hz: Annotated[float, Field(ge=0.1, le=100, allow_inf_nan=False)] = 10.0
    """[Hz] frames per second of ground truth and sensor output."""
    frames: Annotated[int, Field(ge=1, le=1_000_000)] = 200
    """[-] default number of frames to generate (``--frames`` overrides it)."""
    traffic: TrafficConfig = Field(default_factory=TrafficConfig)
    rig: RigConfig = Field(default_factory=RigConfig)
    render: RenderConfig = Field(default_factory=RenderConfig)
    sensor: SensorConfig = Field(default_factory=SensorConfig)
    perturbations: tuple[Perturbation, ...] = ()
    """Scheduled perturbations (:mod:`simrig.scenarios.perturbation_schema`), applied in the order given."""
    evaluation: EvaluationConfig = Field(default_factory=EvaluationConfig)
    """Which 2D ground truth is scored (:mod:`simrig.scenarios.evaluation_schema`); changes no dataset byte but the
    resolved scenario stored with it."""

    @property
    def frame_period_s(self) -> float:
        """[s] time between two frames."""
        return 1.0 / self.frame_rate_hz


    @model_validator(mode="after")
    def _check_windows(self) -> Scenario:
        """A perturbation whose window starts after the last frame can never take effect: an error, not a no-op."""
        for index, perturbation in enumerate(self.perturbations):
            first, _ = perturbation.frame_window(self.frame_rate_hz)
            if first >= self.frames:
                key = "frames" if perturbation.frames is not None else "seconds"
                raise ValueError(f"perturbations.{index}.{key}: the window starts at frame {first}, after the last "
                                 f"frame ({self.frames - 1}) of the run, so it would never take effect")
        return self

    @model_validator(mode="after")
    def _check_timing(self) -> Scenario:
        """Capture offsets fit in a frame period; a fixed latency shorter than the run (or nothing ever arrives)."""
        capture, period = self.sensor.capture, self.frame_period_s
        latest = max([capture.spread_s, *capture.offsets_s.values()]) + 3.0 * capture.jitter_s
        if latest >= period:
            key = ("jitter_s" if capture.jitter_s and latest - 3.0 * capture.jitter_s < period
                   else "offsets_s" if capture.trigger == "given" else "spread_s")
            raise ValueError(f"sensor.capture.{key}: the last capture of a frame would come {latest:g} s after its "
                             f"tick (offset + 3 σ of jitter), not within the frame period ({period:g} s = "
                             "1 / frame_rate_hz)")
        for name, rate in capture.rate_hz.items():
            every = self.frame_rate_hz / rate
            if rate > self.frame_rate_hz or abs(every - round(every)) > 1e-9:
                raise ValueError(f"sensor.capture.rate_hz.{name}: {rate:g} Hz does not divide the frame rate "
                                 f"({self.frame_rate_hz:g} Hz); a camera fires every n-th frame")
        problem = latency_beyond(self, self.frames)
        if problem:
            raise ValueError(problem)
        return self


def windows_outside(scenario: Scenario, frames: int) -> list[str]:
    """Perturbations of ``scenario`` whose window does not fit in the ``frames`` generated (a ``--frames``
    shorter than the scenario's own cuts them off): one message each, for a warning — no effect at all when the
    window starts at or after ``frames``, only its first part when it ends there or later."""
    messages = []
    for index, perturbation in enumerate(scenario.perturbations):
        first, last = perturbation.frame_window(scenario.frame_rate_hz)
        if first >= frames:
            messages.append(f"perturbations.{index} ({perturbation.kind}) starts at frame {first}, after the last "
                            f"of the {frames} frames generated: it has no effect")
        elif last >= frames:
            messages.append(f"perturbations.{index} ({perturbation.kind}) covers frames {first}–{last}, but only "
                            f"{frames} frames were generated: it applies to frames {first}–{frames - 1} only")
    return messages


def scenario_from_record(record: dict, source: str = "a recorded scenario") -> Scenario:
    """The :class:`Scenario` of a resolved dump (``model_dump(mode="json")``, as a dataset manifest records
    it): the keys a setting refuses when written by hand are dropped — the rig keys its preset does not take,
    and the lane count of a map other than highway-v0 or of a layout (the dump holds every field; their values
    there are the defaults, which the preset or map ignores) — everything else validated as usual. An invalid
    record (an edited manifest) is a :class:`~simrig.scenarios.ScenarioError` naming ``source`` and the setting."""
    from . import ScenarioError, describe_errors

    try:
        return _scenario_from_record(record)
    except ValidationError as error:
        raise ScenarioError(f"{source}: its scenario is not valid: {describe_errors(error)}") from None
    except (TypeError, AttributeError, ValueError) as error:  # not even a mapping where one belongs
        raise ScenarioError(f"{source}: its scenario is not valid: {error}") from None


def _scenario_from_record(record: dict) -> Scenario:
    rig = dict(record.get("rig", {}))
    allowed = _PRESET_KEYS.get(rig.get("preset", "surround6"), set()) | {"preset"}
    traffic = dict(record.get("traffic", {}))
    if traffic.get("env", "highway-v0") != "highway-v0" or traffic.get("layout") is not None:
        traffic.pop("lanes", None)
    return Scenario.model_validate({**record, "traffic": traffic,
                                    "rig": {key: value for key, value in rig.items() if key in allowed}})
