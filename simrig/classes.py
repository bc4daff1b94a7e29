"""Physical size of each actor class (numpy-free: the sensor and the renderer use it without highway-env)."""

from __future__ import annotations

from dataclasses import dataclass

from .types import ActorClass


@dataclass(frozen=True)
class ClassSpec:
    """Physical size of an actor class: length, width, height [m]."""

    length: float
    width: float
    height: float


CLASS_SPECS: dict[ActorClass, ClassSpec] = {
    ActorClass.CAR: ClassSpec(4.6, 1.9, 1.6),
    ActorClass.TRUCK: ClassSpec(10.0, 2.5, 3.6),
    ActorClass.BUS: ClassSpec(12.0, 2.55, 3.2),
    ActorClass.MOTORCYCLE: ClassSpec(2.2, 0.8, 1.5),
    ActorClass.PEDESTRIAN: ClassSpec(0.7, 0.7, 1.75),
    ActorClass.BICYCLE: ClassSpec(1.7, 0.6, 1.3),
}
"""Footprints and heights per class (typical European values; nuScenes' mean car is 4.6 × 1.9 × 1.7 m, its mean
pedestrian 0.73 × 0.67 × 1.77 m). Pedestrians and bicycles only come from imported ground truth."""
