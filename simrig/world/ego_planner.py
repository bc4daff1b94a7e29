"""The ego's own planner (highway-env's IDM + MOBIL, :mod:`simrig.world.vehicles`) asked what it would do given a
perception of the road — ground truth or a tracker's tracks as :mod:`~simrig.world.phantoms` — in two ways:

* **A query** (:func:`plan`, open loop): a shallow copy of the ego (its route list copied, since highway-env's
  ``next_lane`` pops it in place) runs highway-env's unmodified ``IDMVehicle.act`` on a
  :class:`~simrig.world.phantoms.PhantomRoad` holding only itself and the phantoms. Nothing of the simulated world
  changes (the research notes checked the whole state bit for bit over 200-frame runs on four maps). MOBIL is
  evaluated at every query, whatever the ego's 1 s lane-change timer says, so that every frame has a lane decision
  to compare; a query on the ground truth gives the command the real ego would give at a frame where its timer is
  due.
* **Driving** (:func:`drive_on_perception`, closed loop): the real ego's ``act`` runs with the road's vehicle list
  swapped for ``[ego, *phantoms]`` for the ego's decision only; every other vehicle, the collision check and the
  physics see the real world.

Accelerations are the commands ``act`` stores (clipped to ±``ACC_MAX`` = 6 m/s²); lane changes count in
highway-env's lane numbers (from the left in the driving direction): −1 a change to the left, +1 to the right.
"""

from __future__ import annotations

import copy
import types
from dataclasses import dataclass, field

import numpy as np
from highway_env.road.road import Road
from highway_env.vehicle.behavior import IDMVehicle

from ..types import EgoPose
from .phantoms import PhantomRoad


@dataclass(frozen=True)
class EgoPlan:
    """What the ego's planner commands for the next step.

    acceleration [m/s²]; lane_change: −1 left, 0 keep, +1 right; leader: the ident of the
    vehicle ahead in the ego's lane (−1: free road); read: the idents of every vehicle a neighbour search returned —
    the vehicles the plan depends on (removing any other leaves the plan unchanged); lane: the ego's lane index;
    searches: each neighbour search's answer by lane index, (front, rear) phantoms or None (for a further query on
    a subset of the same phantoms, :class:`~simrig.world.phantoms.PhantomRoad`'s ``known``)."""

    acceleration: float
    lane_change: int
    leader: int
    read: frozenset[int]
    lane: tuple | None = field(default=None, compare=False)
    searches: dict = field(default_factory=dict, compare=False, repr=False)


def plan(ego: IDMVehicle, phantoms: list, real_road: Road, known: dict | None = None) -> EgoPlan:
    """The command ``ego``'s IDM/MOBIL would give if ``real_road`` held only ``phantoms`` (module docstring).

    ``ego`` is left exactly as it was (a shallow copy decides); MOBIL is evaluated now whatever its timer says.
    ``known``: neighbour-search answers still true of ``phantoms`` (:class:`~simrig.world.phantoms.PhantomRoad`)."""
    probe = copy.copy(ego)
    if ego.route:
        probe.route = list(ego.route)
    if probe.lane_index == probe.target_lane_index:
        probe.timer = np.inf  # utils.do_every(LANE_CHANGE_DELAY, inf): MOBIL decides now
    road = PhantomRoad(real_road, [probe, *phantoms], known)
    if real_road.network.get_lane(probe.target_lane_index).after_end(probe.position):
        road.np_random = copy.deepcopy(real_road.np_random)  # next_lane may be handed the generator: never draw from it
    probe.road = road
    lane = probe.lane_index
    leader, _ = road.neighbour_vehicles(probe, lane)
    IDMVehicle.act(probe)
    target = probe.target_lane_index
    return EgoPlan(
        acceleration=float(probe.action["acceleration"]),
        lane_change=int(target[2] - lane[2]) if target[:2] == lane[:2] else 0,
        leader=-1 if leader is None else int(getattr(leader, "ident", -1)),
        read=frozenset(int(getattr(v, "ident", -1)) for v in road.read if v is not probe),
        lane=lane,
        searches=road.searches,
    )


def planning_ego(road: Road, ego_type: type[IDMVehicle], pose: EgoPose, target_speed: float,
                 route: list | None) -> IDMVehicle:
    """An ego of ``ego_type`` on ``road`` where ``pose`` (world frame) puts it, for queries: its lane is the closest
    one to its heading, it is not changing lane, and its ``route`` (highway-env lane indices, or None) starts at
    the segment it is on (:func:`route_from`)."""
    heading = -pose.yaw
    velocity = np.array([pose.vx, -pose.vy])
    speed = float(velocity[0] * np.cos(heading) + velocity[1] * np.sin(heading))
    position = np.array([pose.x, -pose.y])
    lane = road.network.get_closest_lane_index(position, heading)
    return ego_type(road, position, heading=heading, speed=speed, target_lane_index=lane, target_speed=target_speed,
                    route=route_from(route, lane))


def route_from(route: list | None, lane_index: tuple) -> list | None:
    """The part of ``route`` from the segment of ``lane_index`` on; when that segment is not on it (where lanes
    overlap, as at a roundabout's entries, the closest lane can be a neighbour of the ego's), from the first step
    that starts where the segment ends; None when neither is on it (highway-env then picks the next segment).

    >>> route = [("a", "b", 0), ("b", "c", None), ("c", "d", None)]
    >>> route_from(route, ("b", "c", 1)), route_from(route, ("x", "c", 0)), route_from(route, ("x", "y", 0))
    ([('b', 'c', None), ('c', 'd', None)], [('c', 'd', None)], None)
    """
    if not route:
        return None
    for position, step in enumerate(route):
        if tuple(step[:2]) == tuple(lane_index[:2]):
            return list(route[position:])
    for position, step in enumerate(route):
        if step[0] == lane_index[1]:
            return list(route[position:])
    return None


def drive_on_perception(ego: IDMVehicle) -> None:
    """From now on ``ego`` decides on ``ego.perceived`` (a list of phantoms set before every step; None: on the
    real road) instead of the road's vehicles (module docstring). The physics, the collision check and every other
    vehicle still see the real road."""
    ego.perceived = None
    ego.act = types.MethodType(_act_on_perceived, ego)


def _act_on_perceived(self: IDMVehicle, action=None) -> None:
    phantoms = self.perceived
    if phantoms is None:
        IDMVehicle.act(self, action)
        return
    road = self.road
    real = road.vehicles  # Road.act() is iterating over this very list: rebinding the attribute leaves it intact
    road.vehicles = [self, *phantoms]
    try:
        IDMVehicle.act(self, action)
    finally:
        road.vehicles = real
