"""Scenario keys of the visibility render and of the detector model, each with its unit.

Each ``[sensor.*]`` table configures one sensor effect (:mod:`simrig.sensor.effects`).
"""

from __future__ import annotations

from typing import Annotated

from pydantic import Field, model_validator

from .base import FiniteFloat, NonNegativeFloat, PositiveFloat, Strict

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
    """The monocular 3D estimate in the world frame, built in the camera's frame from the true box."""

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


class ScoreConfig(Strict):
    """Confidence: clip(base + gain · q + N(0, σ²), floor, 1) with q = (1 − occlusion) · (1 − truncation)."""

    base: Fraction = 0.35
    """[-] score of an object seen with q = 0."""
    gain: Fraction = 0.6
    """[-] added at q = 1."""
    sigma: NonNegativeFloat = 0.05
    """[-] σ of the score noise."""
    floor: Fraction = 0.01
    """[-] lowest score reported."""


class ClutterConfig(Strict):
    """False positives: a Poisson number per camera and frame, anywhere in the image."""

    rate_per_frame: NonNegativeFloat = 0.2
    """[-] mean number of false positives per camera and frame."""
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
    """Appearance embeddings: a fixed random unit vector per identity, plus noise growing with occlusion,
    renormalised. The noise vector has norm ≈ σ = sigma + occlusion_sigma · occlusion."""

    dimension: Annotated[int, Field(ge=2, le=1024)] = 64
    """[-] embedding length."""
    sigma: NonNegativeFloat = 0.2
    """[-] noise norm for an unoccluded object."""
    occlusion_sigma: NonNegativeFloat = 0.8
    """[-] noise norm added at full occlusion."""


class SensorConfig(Strict):
    """The detector model of every camera (one table per effect)."""

    detection: DetectionConfig = Field(default_factory=DetectionConfig)
    box2d: Box2DNoiseConfig = Field(default_factory=Box2DNoiseConfig)
    box3d: Box3DNoiseConfig = Field(default_factory=Box3DNoiseConfig)
    score: ScoreConfig = Field(default_factory=ScoreConfig)
    clutter: ClutterConfig = Field(default_factory=ClutterConfig)
    embedding: EmbeddingConfig = Field(default_factory=EmbeddingConfig)


__all__ = ["FiniteFloat", "RenderConfig", "SensorConfig"]
