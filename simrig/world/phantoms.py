"""Phantom vehicles: what a perception output (a tracker's tracks, or the ground truth) looks like to highway-env's
IDM/MOBIL planner, without being part of the simulated world.

A :class:`Phantom` is a highway-env ``ControlledVehicle`` made from a world-frame 3D box: the planner finds it,
follows it and checks lane changes against it exactly as it would a real vehicle, but it is never stepped, never
collides and is never put on the road for good. What IDM/MOBIL read from a vehicle (highway-env 1.12
``behavior.py``, ``road.py``; measured in the issue-31 research notes): the position (neighbour search), the
velocity and heading (the projected speed difference of the desired gap), ``LENGTH`` (simrig's bumper-to-bumper gap,
:mod:`simrig.world.vehicles`), and, when the phantom is the follower in MOBIL's safety check, ``target_speed`` and
its lane. A phantom's own target speed cannot be known from a box: it is taken as its current speed (the follower
neither speeds up nor slows down of its own accord), which with simrig's politeness 0 enters only that safety check.
A phantom has no lane-change intent (its target lane is its lane).

Frames: boxes come in simrig's world frame (:data:`~simrig.types.BOX3D_FIELDS`: x, y [m], yaw [rad] counter-clockwise,
vx, vy [m/s], y to the left); highway-env's y points right, so a phantom sits at (x, −y) with heading −yaw and
velocity (vx, −vy) — the inverse of :mod:`simrig.world.traffic`'s conversion, done here and nowhere else.
"""

from __future__ import annotations

import numpy as np
from highway_env.road.road import Road
from highway_env.vehicle.controller import ControlledVehicle
from highway_env.vehicle.objects import Landmark


class Phantom(ControlledVehicle):
    """A vehicle made from one box, for planner queries only (module docstring).

    ``Vehicle.__init__`` is not called: its closest-lane search (≈ 20 µs a vehicle) is needed only for the few
    phantoms MOBIL asks for their lane, so ``lane_index`` is found on first use. ``ident``: the track id or
    actor id the phantom stands for (−1 when none)."""

    def __init__(self, road: Road, position: np.ndarray, heading: float, velocity: np.ndarray, length: float,
                 width: float, ident: int = -1):
        self.road = road
        self.position = position
        self.heading = heading
        self._velocity = velocity
        self.speed = float(velocity[0] * np.cos(heading) + velocity[1] * np.sin(heading))  # [m/s] along the heading
        self.LENGTH = length
        self.WIDTH = width
        self.target_speed = self.speed
        self._lane_index = None
        self.route = None
        self.crashed = False
        self.ident = ident

    @property
    def velocity(self) -> np.ndarray:
        """[m/s] highway-env frame (not speed × direction: a track's velocity need not follow its yaw)."""
        return self._velocity

    @property
    def lane_index(self):
        if self._lane_index is None:
            self._lane_index = self.road.network.get_closest_lane_index(self.position, self.heading)
            self._lane = self.road.network.get_lane(self._lane_index)
        return self._lane_index

    @property
    def lane(self):
        return self._lane if self._lane_index is not None else self.road.network.get_lane(self.lane_index)

    @property
    def target_lane_index(self):
        return self.lane_index  # no lane-change intent

    def __repr__(self) -> str:
        return f"Phantom#{self.ident}({self.position[0]:.1f}, {self.position[1]:.1f})"


def phantoms_from_boxes(road: Road, boxes: np.ndarray, idents: np.ndarray) -> list[Phantom]:
    """Phantoms of world-frame boxes ``(N, 9)`` (:data:`~simrig.types.BOX3D_FIELDS`) with their ``idents``
    ``(N,)`` on ``road``, in highway-env's frame."""
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 9)
    positions = np.column_stack([boxes[:, 0], -boxes[:, 1]])
    velocities = np.column_stack([boxes[:, 7], -boxes[:, 8]])
    headings = (-boxes[:, 6]).tolist()
    lengths, widths = boxes[:, 3].tolist(), boxes[:, 4].tolist()
    return [Phantom(road, positions[i], headings[i], velocities[i], lengths[i], widths[i], int(ident))
            for i, ident in enumerate(np.asarray(idents).tolist())]


class PhantomRoad(Road):
    """A stand-in road for one planner query: the real road's network and a given vehicle list (the planning ego and
    phantoms). Neighbours are found by highway-env's own search (``Road.neighbour_vehicles``: a vehicle is in a lane
    when its centre is within half the lane width + 1 m of the centre line; the front vehicle is the nearest at or
    ahead of the ego, the rear the nearest behind); ``read`` collects every vehicle a search returned: the vehicles
    the plan depended on. Within one query nothing moves, so each (vehicle, lane) search is done once and its answer
    reused: MOBIL searches the ego's own lane again for every side lane, and IDM once more. (A numpy search gave the
    same answers but was no faster at the ≤ 50 m of vehicles a plan sees: ``reports/perf/planner.md``.)

    ``searches`` records the planning ego's (``vehicles[0]``) answers by lane index: (front, rear). ``known`` gives
    such answers up front, from a query on a list these vehicles are a subset of: an answer that does not hold a
    vehicle removed since is still the nearest front and rear (highway-env's ties go to the same one), so it is not
    searched again."""

    def __init__(self, real: Road, vehicles: list, known: dict | None = None):
        self.network = real.network
        self.vehicles = vehicles
        self.objects = [o for o in real.objects if not isinstance(o, Landmark)]
        self.np_random = real.np_random
        self.record_history = False
        self.neighbour_vehicles_connected_lanes = real.neighbour_vehicles_connected_lanes
        self.read: list = []
        self.searches: dict = {}
        self._known = known or {}
        self._searched: dict = {}

    def neighbour_vehicles(self, vehicle, lane_index=None) -> tuple:
        lane = lane_index or vehicle.lane_index
        key = (id(vehicle), lane)
        found = self._searched.get(key)
        if found is None:
            planning_ego = vehicle is self.vehicles[0]
            found = self._known.get(lane) if planning_ego else None
            if found is None:
                found = Road.neighbour_vehicles(self, vehicle, lane_index)
            self._searched[key] = found
            if planning_ego:
                self.searches[lane] = found
            self.read.extend(v for v in found if v is not None)
        return found
