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
from highway_env import utils
from highway_env.road.lane import StraightLane
from highway_env.vehicle.behavior import IDMVehicle
from highway_env.vehicle.objects import Obstacle

from ..classes import CLASS_SPECS
from ..types import ActorClass

JAM_GAP_M = 5.0
"""[m] IDM jam distance between bumpers (highway-env's default for its 5 m cars)."""
STEERING_LATERAL_ACCELERATION_MPS2 = 2.0
"""[m/s²] the most lateral acceleration a vehicle's steering adds to what its lane's own curve asks for: lane
changes and merges stay at or under it (drivers change lanes at 1–2 m/s²; naturalistic highway data such as highD,
Krajewski et al., ITSC 2018). highway-env's controller (heading time constant 0.2 s, lateral 0.6 s) changed lanes
in about 2 s, at up to 134 °/s of yaw for the ego and 225 °/s for other vehicles, and up to 72 m/s² lateral
(``reports/motion/index.md``)."""
LATERAL_SPEED_MPS = 1.2
"""[m/s] the fastest a lane change moves sideways (a 4 m lane change then lasts about 5 s, the mean of 4.6 s that
Toledo and Zohar measured on NGSIM highways, TRR 1999, 2007)."""
TAU_LATERAL_S = 1.0
"""[s] time constant of the lateral position loop (how a lane change settles on the new lane's centre)."""
TAU_HEADING_S = 0.3
"""[s] time constant of the heading loop."""
YAW_RATE_MAX = np.deg2rad(30.0)
"""[rad/s] the most yaw rate steering adds at walking speeds, where the lateral-acceleration bound allows more."""
CURVATURE_STEP_M = 1.0
"""[m] the step along the lane over which its curvature is taken (heading change / distance)."""
LANE_END_M = 30.0
"""[m] a vehicle whose lane ends closer than this ahead of it (a fixed obstacle) may merge from a standstill."""
CURVE_LATERAL_ACCELERATION_MPS2 = 3.0
"""[m/s²] the lateral acceleration a vehicle takes a curve at, at most: it slows to √(a / κ) for the sharpest
curvature κ ahead. About the side friction AASHTO's Green Book designs low-speed urban curves for (f ≈ 0.27–0.32
at 25–32 km/h); highway-env's vehicles took its roundabout at its 10 m/s limit, 5–7 m/s²."""
CURVE_LOOKAHEAD_S = 3.0
"""[s] how far ahead, at the current speed, a vehicle looks for curves (at least :data:`CURVE_LOOKAHEAD_MIN_M`)."""
CURVE_LOOKAHEAD_MIN_M = 15.0
"""[m] the shortest look-ahead for curves."""
CURVE_SAMPLES = 8
"""[-] points along the look-ahead where the curvature is taken."""


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

    def change_lane_policy(self) -> None:
        """highway-env's MOBIL, and also from a standstill in a lane that ends: highway-env asks MOBIL only above
        1 m/s, so a ramp vehicle stopped at the end of its acceleration lane waited there for good. Stopped behind
        the end of its lane (:meth:`blocked_by_lane_end`), it asks MOBIL for a side lane every
        ``LANE_CHANGE_DELAY``, and takes the first that is safe (MOBIL's braking imposed on the new follower) —
        merging from a standstill into a gap, as a driver at the end of a ramp does."""
        if self.lane_index != self.target_lane_index or abs(self.speed) >= 1.0 or not self.blocked_by_lane_end():
            super().change_lane_policy()
            return
        if not utils.do_every(self.LANE_CHANGE_DELAY, self.timer):
            return
        self.timer = 0
        network = self.road.network
        for lane_index in network.side_lanes(self.lane_index):
            if network.get_lane(lane_index).is_reachable_from(self.position) and self.mobil(lane_index):
                self.target_lane_index = lane_index
                return

    def blocked_by_lane_end(self) -> bool:
        """Whether the nearest thing ahead in the vehicle's own lane is a fixed obstacle (the end of a ramp's
        acceleration lane) within :data:`LANE_END_M`."""
        front, _ = self.road.neighbour_vehicles(self, self.lane_index)
        return isinstance(front, Obstacle) and self.lane_distance_to(front) < LANE_END_M

    def act(self, action=None) -> None:
        """highway-env's IDM + MOBIL; while merging away from the end of its lane, the acceleration is IDM's in the
        lane it merges into alone (highway-env also brakes for the current lane's front, which holds a vehicle
        merging from behind a lane end still)."""
        super().act(action)
        if self.lane_index == self.target_lane_index or self.crashed or not self.blocked_by_lane_end():
            return
        front, rear = self.road.neighbour_vehicles(self, self.target_lane_index)
        target = self.acceleration(ego_vehicle=self, front_vehicle=front, rear_vehicle=rear)
        self.action["acceleration"] = float(np.clip(target, -self.ACC_MAX, self.ACC_MAX))

    def acceleration(self, ego_vehicle, front_vehicle=None, rear_vehicle=None) -> float:
        """highway-env's IDM acceleration [m/s²], and for one of simrig's vehicles no more than what reaches each
        curve ahead at its curve speed (:meth:`curve_braking`)."""
        acceleration = super().acceleration(ego_vehicle, front_vehicle, rear_vehicle)
        if not isinstance(ego_vehicle, SimrigVehicle):
            return acceleration
        return min(acceleration, ego_vehicle.curve_braking())

    def curve_braking(self) -> float:
        """[m/s²] the acceleration that brings the vehicle to √(:data:`CURVE_LATERAL_ACCELERATION_MPS2` / κ) by
        each point ahead of curvature κ [1/m] (within :data:`CURVE_LOOKAHEAD_S`, on the lane it is on and the lane it
        steers to, then the next one on its route): −(v² − v_κ²) / 2d at distance d, the least over the points; in a
        curve taken too fast, IDM's free-road term towards v_κ. +inf when nothing ahead asks for less speed."""
        network = self.road.network
        speed = max(self.speed, 0.0)
        ahead = max(speed * CURVE_LOOKAHEAD_S, CURVE_LOOKAHEAD_MIN_M)
        pieces = []  # (lane, start, stop, distance from the vehicle to start) [m]
        for current in {self.lane_index, self.target_lane_index}:  # the lane it is on and the one it steers to
            lane = network.get_lane(current)
            along = lane.local_coordinates(self.position)[0]
            pieces.append((lane, along, min(along + ahead, lane.length), 0.0))
            following = self._next_lane_on_route(current)
            if following is not None and along + ahead > lane.length:
                pieces.append((network.get_lane(following), 0.0, along + ahead - lane.length, lane.length - along))
        best = np.inf
        for lane, start, stop, offset in pieces:
            if isinstance(lane, StraightLane) or stop <= start:
                continue
            points = np.linspace(start, stop, CURVE_SAMPLES)
            turns = np.abs([utils.wrap_to_pi(lane.heading_at(x + CURVATURE_STEP_M) - lane.heading_at(x))
                            for x in points]) / CURVATURE_STEP_M
            allowed = np.sqrt(CURVE_LATERAL_ACCELERATION_MPS2 / np.maximum(turns, 1e-9))
            distance = offset + points - start
            if allowed[0] < speed and distance[0] <= 0.0:  # in the curve already
                best = min(best, self.COMFORT_ACC_MAX * (1 - (speed / allowed[0]) ** self.DELTA))
            faster = (allowed < speed) & (distance > 0.0)
            if faster.any():
                best = min(best, float(np.min(-(speed**2 - allowed[faster] ** 2) / (2 * distance[faster]))))
        return best

    def _next_lane_on_route(self, current) -> tuple | None:
        """The lane index after ``current`` on the vehicle's route (the same lane id, or the nearest that exists);
        None without one. Reads the route; never draws a random next road as highway-env's ``next_lane`` does."""
        route = self.route or []
        for index, step in enumerate(route[:-1]):
            if tuple(step[:2]) == tuple(current[:2]):
                start, end, lane_id = route[index + 1]
                count = len(self.road.network.graph[start][end])
                return start, end, min(current[2] if lane_id is None else lane_id, count - 1)
        return None

    def steering_control(self, target_lane_index) -> float:
        """Steering [rad] to follow the centre of lane ``target_lane_index`` with bounded lateral acceleration.

        The yaw rate commanded is the lane's own, v·κ (its curve: κ from its heading 1 m on), plus a correction
        towards the heading that would close the lateral offset y at the lateral speed −y / :data:`TAU_LATERAL_S`
        (at most :data:`LATERAL_SPEED_MPS`), reached with the heading time constant :data:`TAU_HEADING_S` — that
        correction bounded so the lateral acceleration it adds, v·ω, is at most
        :data:`STEERING_LATERAL_ACCELERATION_MPS2` (and ω at most :data:`YAW_RATE_MAX`). The yaw rate becomes a
        steering angle through highway-env's kinematic bicycle (ψ̇ = v·sin β / (L/2), δ = atan(2·tan β)). Frames as
        highway-env's (y right)."""
        lane = self.road.network.get_lane(target_lane_index)
        along, lateral = lane.local_coordinates(self.position)
        lane_heading = lane.heading_at(along)
        curvature = utils.wrap_to_pi(lane.heading_at(along + CURVATURE_STEP_M) - lane_heading) / CURVATURE_STEP_M
        speed = max(abs(self.speed), 0.1)
        lateral_speed = _clip(-lateral / TAU_LATERAL_S, -LATERAL_SPEED_MPS, LATERAL_SPEED_MPS)
        heading_ref = lane_heading + np.arcsin(_clip(lateral_speed / speed, -_SIN_45, _SIN_45))
        bound = min(STEERING_LATERAL_ACCELERATION_MPS2 / speed, YAW_RATE_MAX)
        correction = _clip(utils.wrap_to_pi(heading_ref - self.heading) / TAU_HEADING_S, -bound, bound)
        yaw_rate = self.speed * curvature + correction
        slip = np.arcsin(_clip(self.LENGTH / 2 / utils.not_zero(self.speed) * yaw_rate, -1, 1))
        return float(_clip(np.arctan(2 * np.tan(slip)), -self.MAX_STEERING_ANGLE, self.MAX_STEERING_ANGLE))

    def freeze(self) -> None:
        """Stand still from now on where the vehicle is (after a collision): speed 0, no acceleration, no steering,
        and no push apart from highway-env (its ``impact``)."""
        self.frozen = True
        self.speed = 0.0
        self.target_speed = 0.0
        self.impact = None

    def step(self, dt: float) -> None:
        """highway-env's kinematic step, except that a frozen vehicle stays put and braking stops at standstill
        (highway-env's IDM would drive a stopped vehicle backwards)."""
        if self.frozen:
            self.speed, self.impact = 0.0, None
            return
        if self.action and self.speed >= 0.0 and self.speed + self.action["acceleration"] * dt < 0.0:
            self.action["acceleration"] = -self.speed / dt
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


_SIN_45 = float(np.sin(np.pi / 4))


def _clip(value: float, low: float, high: float) -> float:
    """``np.clip`` of one number, the same value (NaN stays NaN) without numpy's per-call cost: the steering law
    runs for every vehicle at every simulation step."""
    return min(max(value, low), high)


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
