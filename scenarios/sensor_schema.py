"""Scenario keys of the visibility render and of the detector model, each with its unit.

Each ``[sensor.*]`` table configures one sensor effect (:mod:`simrig.sensor.effects`).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, field_validator, model_serializer, model_validator

from .base import FiniteFloat, NonNegativeFloat, PositiveFloat, Strict
from .timing_schema import TIMING_TABLES, CaptureConfig, EgoPoseConfig, LatencyConfig, timing_tables_set

Fraction = Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)]


class RenderConfig(Strict):
    """pyrender visibility: per camera and frame an instance-segmentation render gives each actor's visible
    pixels; its occlusion ratio is ``1 − visible / unoccluded silhouette``."""

    visibility: bool = True
    """Measure occlusion by rendering; when false every actor in view counts as unoccluded (faster)."""
    visibility_scale: Annotated[float, Field(ge=0.05, le=1, allow_inf_nan=False)] = 0.5
    """[-] visibility render resolution relative to the image (0.5: 800×450 for a 1600×900 camera); at least
    0.05, below which small actors cover no pixel and read as fully occluded."""


class DetectionConfig(Strict):
    """Detection probability p = p_max · g(visible fraction) · g(truncation) · g(distance), each g a linear
    ramp between two thresholds: 1 on the good side, 0 on the bad side."""

    probability: Fraction = 0.95
    """[-] p_max: probability of detecting a fully visible, untruncated object within ``full_range_m``."""
    min_visible_fraction: Fraction = 0.1
    """[-] at or below this visible fraction (1 − occlusion) an object is never detected."""
    full_visible_fraction: Fraction = 0.5
    """[-] at or above this visible fraction occlusion does not lower p."""
    full_truncation: Fraction = 0.3
    """[-] up to this truncation p is not lowered."""
    max_truncation: Fraction = 0.9
    """[-] at or above this truncation an object is never detected."""
    full_range_m: PositiveFloat = 60.0
    """[m] up to this distance from the camera p is not lowered."""
    max_range_m: PositiveFloat = 100.0
    """[m] at or beyond this distance an object is never detected."""
    burst_fraction: Annotated[float, Field(ge=0, lt=1, allow_inf_nan=False)] = 0.0
    """[-] Gilbert–Elliott miss process: long-run fraction of frames an (actor, camera) pair spends in the
    bad state, where it is never detected (cause ``burst``). 0 switches the process off."""
    burst_mean_s: PositiveFloat = 0.5
    """[s] mean length of one stay in the bad state (a miss burst); the same in seconds at any frame rate."""

    @model_validator(mode="after")
    def _check(self) -> DetectionConfig:
        for low, high in (
            ("min_visible_fraction", "full_visible_fraction"),
            ("full_truncation", "max_truncation"),
            ("full_range_m", "max_range_m"),
        ):
            if getattr(self, low) >= getattr(self, high):
                raise ValueError(f"{low}: must be below {high} ({getattr(self, low)} ≥ {getattr(self, high)})")
        return self


class Box2DNoiseConfig(Strict):
    """Pixel box noise: each edge moves by N(0, σ²) with σ = ``relative_sigma`` × the box's width (x1, x2)
    or height (y1, y2)."""

    relative_sigma: NonNegativeFloat = 0.03
    """[-] σ of each edge as a fraction of the box size."""


class Box3DNoiseConfig(Strict):
    """The monocular 3D estimate in the world frame, built in the camera's frame from the true box.

    Every error is a stationary Ornstein–Uhlenbeck process per (actor, camera): sampled every frame
    period Δt it is AR(1) with lag-1 correlation φ = exp(−Δt / τ), so the correlation time τ [s] (not the
    lag-1 correlation) is what a frame-rate change keeps. The σ below are the processes' stationary
    standard deviations. ``shared_fraction`` of each error's variance is common to all cameras of one
    actor (a per-actor process with the same τ). Errors other than depth grow with the range d [m]
    from the camera: σ(d) = σ · (1 + d / ``distance_scale_m``)."""

    depth_sigma_m: NonNegativeFloat = 0.2
    """[m] a in σ(d) = a + b·d: error of the range d from the camera to the box centre, along the ray."""
    depth_sigma_per_m: NonNegativeFloat = 0.03
    """[m/m] b in σ(d) = a + b·d."""
    lateral_sigma_m: NonNegativeFloat = 0.15
    """[m] σ of the centre's error across the ray (horizontal and vertical)."""
    size_sigma: NonNegativeFloat = 0.05
    """[-] σ of the relative error of length, width and height."""
    yaw_sigma_deg: NonNegativeFloat = 5.0
    """[deg] σ of the yaw error."""
    yaw_flip_probability: Fraction = 0.03
    """[-] probability that the estimate faces backwards (yaw + 180°)."""
    velocity_sigma_mps: NonNegativeFloat = 0.5
    """[m/s] σ of each velocity component's error."""
    distance_scale_m: PositiveFloat | None = None
    """[m] D in σ(d) = σ · (1 + d / D) for the lateral, size, yaw and velocity errors; omitted: no growth."""
    correlation_time_s: NonNegativeFloat = 0.0
    """[s] τ of the depth, lateral, yaw and velocity errors; 0: a fresh error every frame (white)."""
    size_correlation_time_s: NonNegativeFloat = 0.0
    """[s] τ of the size errors (a monocular detector's size guess persists); 0: white."""
    shared_fraction: Fraction = 0.0
    """[-] share of each error's variance common to every camera that sees the actor."""
    yaw_flip_duration_s: NonNegativeFloat = 0.0
    """[s] mean length of a yaw flip (a two-state Markov chain with stationary flip probability
    ``yaw_flip_probability``); 0: flips are drawn afresh every frame."""


class ScoreConfig(Strict):
    """Confidence: clip(base + gain · q − error_gain · (1 − exp(−e / error_scale_m)) − distance_gain ·
    min(1, d / distance_scale_m) + N(0, σ²), floor, 1) with q = (1 − occlusion) · (1 − truncation), e the
    bird's-eye-view centre error of the detection's 3D estimate [m] and d its true range from the camera [m]."""

    base: Fraction = 0.35
    """[-] score of an object seen with q = 0."""
    gain: Fraction = 0.6
    """[-] added at q = 1."""
    sigma: NonNegativeFloat = 0.05
    """[-] σ of the score noise."""
    floor: Fraction = 0.01
    """[-] lowest score reported."""
    error_gain: Fraction = 0.0
    """[-] score lost by a detection whose centre is far off (e ≫ error_scale_m)."""
    error_scale_m: PositiveFloat = 1.0
    """[m] centre error at which 63% of ``error_gain`` is lost."""
    distance_gain: Fraction = 0.0
    """[-] score lost at and beyond ``distance_scale_m``, linearly in the range."""
    distance_scale_m: PositiveFloat = 60.0
    """[m] range at which the whole ``distance_gain`` is lost."""


class ClutterConfig(Strict):
    """False positives: a Poisson number per camera and frame, anywhere in the image."""

    rate_per_frame: Annotated[float, Field(ge=0, le=50, allow_inf_nan=False)] = 0.2
    """[-] mean number of false positives per camera and frame (at most 50: every one is a row of every table)."""
    score_range: tuple[Fraction, Fraction] = (0.05, 0.45)
    """[-] their scores are uniform in this range."""
    height_range_px: tuple[PositiveFloat, PositiveFloat] = (20.0, 200.0)
    """[px] box heights are log-uniform in this range (at the image resolution)."""
    aspect_range: tuple[PositiveFloat, PositiveFloat] = (0.8, 2.5)
    """[-] width / height of the boxes, uniform."""
    depth_range_m: tuple[PositiveFloat, PositiveFloat] = (5.0, 80.0)
    """[m] their 3D estimates lie on the box centre's ray at a range uniform in this interval."""

    @model_validator(mode="after")
    def _check(self) -> ClutterConfig:
        for name in ("score_range", "height_range_px", "aspect_range", "depth_range_m"):
            low, high = getattr(self, name)
            if low > high:
                raise ValueError(f"{name}: lower bound {low} exceeds upper bound {high}")
        return self


class EmbeddingConfig(Strict):
    """Appearance embeddings (re-ID features): per identity a fixed unit vector, mixed with a vector shared
    by every vehicle of its class and colour (``lookalike_weight``) and with a view vector that turns smoothly
    with the direction it is seen from (``viewpoint_weight``, ``viewpoint_scale_deg``); plus two drifts with
    memory per actor, the same for every camera at one instant (Ornstein–Uhlenbeck processes: a fast one for pose
    and lighting, a slow one for lasting change of look), and white noise per observation, renormalised. The
    white noise vector has norm ≈ σ = (sigma + occlusion_sigma · occlusion + truncation_sigma · truncation) ·
    (1 + d / distance_scale_m); the drifts have norms ≈ ``drift_sigma`` and ``slow_drift_sigma`` (same growth
    factors). An actor seen again after g frames
    keeps a share exp(−g·Δt / τ) of each drift, so it looks less like itself the longer the gap.

    With ``target_auc`` set, ``sigma`` is not a setting but solved for: the ROC AUC of cosine distance
    separating same-identity pairs one frame apart from different-identity pairs, unoccluded, untruncated,
    from the same side at d → 0, is ``target_auc`` (traffic's class mix, ``colours`` colours).

    ``dimension`` is an effective dimension: different actors' unit vectors have cosine similarities spread by
    about 1/√D, so it sets how far apart strangers look as much as the vectors' length (``simrig detector fit
    --embeddings`` fits it from a real model's distances)."""

    dimension: Annotated[int, Field(ge=2, le=1024)] = 64
    """[-] embedding length (the effective dimension: see above)."""
    sigma: NonNegativeFloat = 0.2
    """[-] white noise norm for an unoccluded object (ignored when ``target_auc`` is set: then it is solved for)."""
    occlusion_sigma: NonNegativeFloat = 0.8
    """[-] white noise norm added at full occlusion."""
    truncation_sigma: NonNegativeFloat = 0.0
    """[-] white noise norm added at full truncation."""
    distance_scale_m: PositiveFloat | None = None
    """[m] D in the noise's growth factor 1 + d / D; omitted: no growth with range."""
    target_auc: Annotated[float, Field(gt=0.5, le=1, allow_inf_nan=False)] | None = None
    """[-] ROC AUC of same- (one frame apart) vs different-identity cosine distance at the reference condition;
    (0.5, 1]."""
    lookalike_weight: Annotated[float, Field(ge=0, lt=1, allow_inf_nan=False)] = 0.0
    """[-] share of an identity vector common to its class and colour (their cosine similarity)."""
    colours: Annotated[int, Field(ge=1, le=1000)] = 8
    """[-] number of paint colours, drawn uniformly per vehicle."""
    viewpoint_weight: Annotated[float, Field(ge=0, lt=1, allow_inf_nan=False)] = 0.0
    """[-] share of an embedding that depends on the direction the actor is seen from."""
    viewpoint_scale_deg: Annotated[float, Field(ge=5, le=180, allow_inf_nan=False)] = 30.0
    """[deg] how far the viewing direction turns before the view part changes: the width λ of its kernel (view
    vectors Δ apart have a cosine of about exp(−Δ²/4λ²): at 30°, 0.93 for 15°, 0.77 for 30°, 0.35 for 60°, 0.09
    for 90°; 1.00 for the 1.5° between a stereo pair's rays to a car 20 m away)."""
    drift_sigma: Annotated[float, Field(ge=0, le=10, allow_inf_nan=False)] = 0.0
    """[-] norm of the fast drift (0: none)."""
    drift_time_s: Annotated[float, Field(gt=0, le=3600, allow_inf_nan=False)] = 0.5
    """[s] correlation time of the fast drift."""
    slow_drift_sigma: Annotated[float, Field(ge=0, le=10, allow_inf_nan=False)] = 0.0
    """[-] norm of the slow drift (0: none)."""
    slow_drift_time_s: Annotated[float, Field(gt=0, le=3600, allow_inf_nan=False)] = 5.0
    """[s] correlation time of the slow drift."""


class GhostConfig(Strict):
    """False positives with a life: ghost objects born in the world (a Poisson process in time), each
    living an exponential time, either static (fixed position, zero velocity) or shadowing a real vehicle
    (a reflection, a split truck: a fixed offset from it, its velocity, dying with it). One 3D box per
    ghost, projected into every camera that sees it; each such camera reports it with ``probability``
    per frame; scores are Beta-distributed with the given mean and concentration."""

    birth_rate_hz: Annotated[float, Field(ge=0, le=100, allow_inf_nan=False)] = 0.0
    """[1/s] ghosts born per second (0: no ghosts; at most 100)."""
    mean_life_s: Annotated[float, Field(gt=0, le=3600, allow_inf_nan=False)] = 1.0
    """[s] mean life of a ghost."""
    shadow_fraction: Fraction = 0.5
    """[-] share of ghosts that shadow a real vehicle (the rest are static)."""
    range_m: tuple[NonNegativeFloat, PositiveFloat] = (5.0, 50.0)
    """[m] static ghosts are born uniformly on the ground in this ring around the ego; shadowed vehicles
    are chosen among those within it."""
    shadow_offset_m: tuple[FiniteFloat, FiniteFloat] = (1.0, 6.0)
    """[m] a shadow ghost sits behind (or ahead of) its vehicle by a distance uniform in this range."""
    probability: Fraction = 0.9
    """[-] per frame and camera that sees it, probability that the ghost is reported."""
    score_mean: Annotated[float, Field(gt=0, lt=1, allow_inf_nan=False)] = 0.5
    """[-] mean of the Beta score distribution."""
    score_concentration: PositiveFloat = 10.0
    """[-] α + β of the Beta score distribution."""

    @model_validator(mode="after")
    def _check(self) -> GhostConfig:
        for name in ("range_m", "shadow_offset_m"):
            low, high = getattr(self, name)
            if low > high:
                raise ValueError(f"{name}: lower bound {low} exceeds upper bound {high}")
        return self


class DuplicateConfig(Strict):
    """Failed non-maximum suppression: a detected object gets a second box in the same camera with the
    given probability, its pixel box shifted and scaled by N(0, relative_sigma²) of its size, its 3D centre
    moved by N(0, offset_sigma_m²), its score multiplied by ``score_factor``."""

    probability: Fraction = 0.0
    """[-] per detection, probability of a duplicate."""
    relative_sigma: NonNegativeFloat = 0.15
    """[-] σ of the duplicate's box edges as a fraction of the box size."""
    offset_sigma_m: NonNegativeFloat = 0.5
    """[m] σ of the duplicate's 3D centre offset per horizontal axis."""
    score_factor: Fraction = 0.6
    """[-] the duplicate's score relative to the detection's."""


class ConfusionConfig(Strict):
    """Class confusion: ``matrix[true][reported]`` is the probability that a detection of a ``true`` object
    is labelled ``reported``; each given row must sum to 1; classes without a row are never confused."""

    matrix: dict[Literal["car", "truck", "bus", "motorcycle"],
                 dict[Literal["car", "truck", "bus", "motorcycle"], Fraction]] = Field(default_factory=dict)
    """[-] row-stochastic confusion matrix over the classes."""

    @model_validator(mode="after")
    def _check(self) -> ConfusionConfig:
        for true, row in self.matrix.items():
            total = sum(row.values())
            if abs(total - 1.0) > 1e-6:
                raise ValueError(f"matrix: row {true!r} sums to {total:g}, not 1 (a row must be a distribution)")
        return self


class SensorConfig(Strict):
    """The detector model of every camera (one table per effect). ``preset`` names a calibrated detector
    (:mod:`.sensor_presets`); the scenario's own keys override the preset's key by key."""

    preset: str | None = None
    """Detector preset: perfect, ideal_noise (the defaults), monodis, centernet, km3d, bevformer_small."""
    detection: DetectionConfig = Field(default_factory=DetectionConfig)
    box2d: Box2DNoiseConfig = Field(default_factory=Box2DNoiseConfig)
    box3d: Box3DNoiseConfig = Field(default_factory=Box3DNoiseConfig)
    score: ScoreConfig = Field(default_factory=ScoreConfig)
    clutter: ClutterConfig = Field(default_factory=ClutterConfig)
    embedding: EmbeddingConfig = Field(default_factory=EmbeddingConfig)
    ghosts: GhostConfig = Field(default_factory=GhostConfig)
    duplicates: DuplicateConfig = Field(default_factory=DuplicateConfig)
    confusion: ConfusionConfig = Field(default_factory=ConfusionConfig)
    capture: CaptureConfig = Field(default_factory=CaptureConfig)
    """When each camera fires (:mod:`.timing_schema`)."""
    latency: LatencyConfig = Field(default_factory=LatencyConfig)
    """When detections reach the tracker (:mod:`.timing_schema`)."""
    ego_pose: EgoPoseConfig = Field(default_factory=EgoPoseConfig)
    """The error of the ego pose a tracker is given (:mod:`.timing_schema`)."""

    @model_serializer(mode="wrap")
    def _without_ideal_timing(self, handler):
        """The dump leaves out a timing table at its defaults (the ideal rig), so a scenario without timing
        settings stores what it stored before the tables existed (same manifest, same content keys)."""
        dumped = handler(self)
        if isinstance(dumped, dict):
            for name in set(TIMING_TABLES) - set(timing_tables_set(self)):
                dumped.pop(name, None)
        return dumped

    @field_validator("preset")
    @classmethod
    def _known_preset(cls, name: str | None) -> str | None:
        from .sensor_presets import PRESETS

        if name is not None and name not in PRESETS:
            raise ValueError(f"unknown detector preset {name!r}; known: {', '.join(PRESETS)}")
        return name


__all__ = ["FiniteFloat", "RenderConfig", "SensorConfig"]
