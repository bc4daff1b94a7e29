"""Vehicle classes for highway-env with simrig's sizes and a size-aware IDM gap.

Each actor class is an ``IDMVehicle`` subclass whose ``LENGTH``/``WIDTH`` are the class's real footprint, so
highway-env's collision checks, lane-change decisions and our 3D boxes describe the same vehicle. The IDM
constants are set on every subclass explicitly: ``intersection-v0`` rewrites ``IDMVehicle.DISTANCE_WANTED``
and friends at class level for the whole process, and our vehicles must not inherit that change.

highway-env's IDM uses a jam distance of ``5 m + LENGTH`` between centres, which is right only for two 5 m
cars. Here the desired gap is ``JAM_GAP_M`` between bumpers: ``s* = s0 + (L_self + L_front)/2 + v·T +
v·Δv / (2·sqrt(a·b))``, so a car behind a 12 m bus keeps the same bumper gap as behind a car.
"""

from __future__ import annotations

import numpy as np
from highway_env.vehicle.behavior import IDMVehicle

from ..classes import CLASS_SPECS
from ..types import ActorClass

JAM_GAP_M = 5.0
"""[m] IDM jam distance between bumpers (highway-env's default for its 5 m cars)."""


_IDM_CONSTANTS = {
    "ACC_MAX": 6.0,  # [m/s²]
    "COMFORT_ACC_MAX": 3.0,  # [m/s²]
    "COMFORT_ACC_MIN": -5.0,  # [m/s²]
    "TIME_WANTED": 1.5,  # [s]
    "DELTA": 4.0,  # [-]
    "POLITENESS": 0.0,  # [-]
    "LANE_CHANGE_MIN_ACC_GAIN": 0.2,  # [m/s²]
    "LANE_CHANGE_MAX_BRAKING_IMPOSED": 2.0,  # [m/s²]
}
"""highway-env 1.x's IDM/MOBIL defaults, pinned here so no other env can change them under us."""


class SimrigVehicle(IDMVehicle):
    """An IDM/MOBIL-driven vehicle of one simrig actor class (see the subclasses in :data:`VEHICLE_TYPES`)."""

    ACTOR_CLASS: ActorClass = ActorClass.CAR
    HEIGHT: float = CLASS_SPECS[ActorClass.CAR].height
    DISTANCE_WANTED = JAM_GAP_M + CLASS_SPECS[ActorClass.CAR].length
    simrig_id: int = -1
    """The actor id simrig gave this vehicle (highway-env has none)."""
    frozen: bool = False
    """True once the vehicle stands where it collided (:meth:`freeze`)."""

    def handle_collisions(self, other, dt: float = 0) -> None:
        """highway-env's crash check on the footprints as they are now (``dt = 0``), not as they would be after
        another step at constant velocity: its flag then means what the geometric check means — the footprints
        touch or overlap at the end of a simulation step (:mod:`simrig.world.collisions`)."""
        super().handle_collisions(other, 0.0)

    def freeze(self) -> None:
        """Stand still from now on where the vehicle is (after a collision): speed 0, no acceleration, no steering,
        and no push apart from highway-env (its ``impact``)."""
        self.frozen = True
        self.speed = 0.0
        self.target_speed = 0.0
        self.impact = None

    def step(self, dt: float) -> None:
        if self.frozen:
            self.speed, self.impact = 0.0, None
            return
        super().step(dt)

    def desired_gap(self, ego_vehicle, front_vehicle=None, projected: bool = True) -> float:
        """Desired centre-to-centre distance [m] from ``ego_vehicle`` to ``front_vehicle`` (module docstring)."""
        bumpers = (ego_vehicle.LENGTH + front_vehicle.LENGTH) / 2.0
        ab = -self.COMFORT_ACC_MAX * self.COMFORT_ACC_MIN
        if projected:
            dv = np.dot(ego_vehicle.velocity - front_vehicle.velocity, ego_vehicle.direction)
        else:
            dv = ego_vehicle.speed - front_vehicle.speed
        return JAM_GAP_M + bumpers + ego_vehicle.speed * self.TIME_WANTED + ego_vehicle.speed * dv / (2 * np.sqrt(ab))


def _vehicle_type(actor_class: ActorClass) -> type[SimrigVehicle]:
    spec = CLASS_SPECS[actor_class]
    attributes = {
        **_IDM_CONSTANTS,
        "ACTOR_CLASS": actor_class,
        "LENGTH": spec.length,
        "WIDTH": spec.width,
        "HEIGHT": spec.height,
        "DISTANCE_WANTED": JAM_GAP_M + spec.length,
        "__doc__": f"A {actor_class.value}: {spec.length} × {spec.width} × {spec.height} m.",
    }
    return type(f"Simrig{actor_class.value.capitalize()}", (SimrigVehicle,), attributes)


VEHICLE_TYPES: dict[ActorClass, type[SimrigVehicle]] = {cls: _vehicle_type(cls) for cls in ActorClass}
"""The highway-env vehicle type of each actor class."""
