"""Long road layouts built from highway-env's road parts (``[traffic.layout]``,
:mod:`~simrig.scenarios.layout_schema`): oncoming lanes, on-ramps, exits and crossings, repeated along a road of
``length_m`` so that the ego never runs out of road in a long run.

Each builder returns a :class:`Layout`: the road (a highway-env ``Road``, or a :class:`CrossingRoad` where side
streets give way), where the ego starts and where it is going, and the **spawn groups**: the lanes new vehicles are
placed on, the share of new vehicles each group gets, and where a vehicle of the group is going (a node of the
network, given the lane and the position it starts at). Geometry follows highway-env: x along the road, y to the
right, lanes of a segment numbered from the left, ``StraightLane.DEFAULT_WIDTH`` (4 m) wide; a ramp converges
like ``merge-v0``'s (a 6.5 m sine over 80 m into an 80 m acceleration lane ending at an obstacle), an exit leaves
like ``exit-v0``'s (a 150 m-radius quarter circle to the right).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from highway_env.road.lane import AbstractLane, CircularLane, LineType, SineLane, StraightLane
from highway_env.road.road import Road, RoadNetwork
from highway_env.vehicle.objects import Obstacle

from simrig.scenarios.layout_schema import CrossingsLayout, ExitsLayout, RampsLayout, TwoWayLayout

from .road_step import step_road

LANE_WIDTH_M = StraightLane.DEFAULT_WIDTH
RAMP_APPROACH_M = 100.0
"""[m] straight part of an on-ramp, beside the road."""
RAMP_CONVERGE_M = 80.0
"""[m] the sine part of an on-ramp (``merge-v0``'s)."""
RAMP_ACCELERATION_M = 200.0
"""[m] the acceleration lane at the end of an on-ramp (``merge-v0``'s is 80 m: too short for its IDM vehicles to
find a gap in dense traffic, and a vehicle that stops at its end never changes lane)."""
RAMP_OFFSET_M = 6.5
"""[m] lateral distance the ramp converges over (``merge-v0``'s: twice its 3.25 m amplitude)."""
EXIT_RADIUS_M = 150.0
"""[m] radius of an exit ramp's curve (``exit-v0``'s)."""
EXIT_SPEED_MPS = 15.0
"""[m/s] speed limit on an exit ramp."""
SIDE_ROAD_HALF_M = 150.0
"""[m] how far a side road of a crossing reaches on each side of the main road."""
JUNCTION_Y = (-1.5 * StraightLane.DEFAULT_WIDTH, 0.5 * StraightLane.DEFAULT_WIDTH)
"""[m] the main road of a crossings layout across (highway-env frame: the oncoming lane's far edge to the forward
lane's near edge)."""
JUNCTION_HALF_M = StraightLane.DEFAULT_WIDTH
"""[m] half the width of a side street (one lane each way)."""
GAP_S = 4.0
"""[s] a side vehicle waits while a main-road vehicle would reach the junction within this (crossing 8 m of main
road plus its length from a stop takes about 3 s at highway-env's 3 m/s² comfortable acceleration)."""
STOP_DECELERATION_MPS2 = 5.0
"""[m/s²] the braking a side vehicle may still use to stop at the line (IDM's own braking limit is 6)."""
STOP_MARGIN_M = 2.0
"""[m] a side vehicle stops this far before the junction."""
APPROACH_M = 3.0
"""[m] a side vehicle decides whether to give way once it is within its braking distance plus this of the
junction, so that it stops near the line; farther away it follows the street (and the queue) by its IDM."""
NEAR_M = 20.0
"""[m] lanes farther than this from a position are left out of its closest-lane search (:class:`LayoutNetwork`)."""
LIMIT_MARGIN_MPS = 5.0
"""[m/s] the main road's speed limit is the fastest drawn target speed plus this (highway-env's IDM never drives
faster than its lane's limit, 20 m/s unless set)."""

_C, _S, _N = LineType.CONTINUOUS_LINE, LineType.STRIPED, LineType.NONE
LaneIndex = tuple[str, str, int]


class LayoutNetwork(RoadNetwork):
    """highway-env's road network with two changes for long layouts:

    * MOBIL never offers a ``forbidden`` lane (an on-ramp's acceleration lane) to a vehicle on an ordinary lane as a
      lane to change into: highway-env marks such lanes forbidden but lets its IDM vehicles change into them, where
      they then stand at the obstacle that ends the lane. A vehicle on a forbidden lane may change out of it.
    * The closest lane to a position (asked for every vehicle at every simulation step) is searched among the lanes
      that pass within :data:`NEAR_M` of it, not all of them: highway-env's search is linear in the lanes, and a
      6 km layout has a hundred. Same answer: the lanes left out are more than :data:`NEAR_M` away, and the answer
      is taken only when it lies within half that (a lane's distance counts at most π for heading); otherwise, and
      before :meth:`freeze`, every lane is searched as highway-env does.
    """

    _boxes: np.ndarray | None = None

    def freeze(self) -> None:
        """Index the lanes for the closest-lane search (call once every lane is added)."""
        indices = [(start, end, lane_id) for start, ends in self.graph.items() for end, lanes in ends.items()
                   for lane_id in range(len(lanes))]
        points, owners = lane_samples(self, tuple(indices), step_m=5.0)
        starts = np.flatnonzero(np.r_[True, owners[1:] != owners[:-1]])  # each lane's points are contiguous
        lows = np.minimum.reduceat(points, starts, axis=0) - NEAR_M
        highs = np.maximum.reduceat(points, starts, axis=0) + NEAR_M
        self._indices, self._boxes = indices, np.stack([lows, highs], axis=1)

    def get_closest_lane_index(self, position: np.ndarray, heading: float | None = None) -> LaneIndex:
        if self._boxes is not None:
            inside = np.flatnonzero(((position >= self._boxes[:, 0]) & (position <= self._boxes[:, 1])).all(axis=1))
            if len(inside):
                distances = [self.get_lane(self._indices[i]).distance_with_heading(position, heading) for i in inside]
                best = int(np.argmin(distances))
                if distances[best] <= NEAR_M / 2.0:
                    return self._indices[inside[best]]
        return super().get_closest_lane_index(position, heading)

    def side_lanes(self, lane_index: LaneIndex) -> list[LaneIndex]:
        lanes = super().side_lanes(lane_index)
        if self.get_lane(lane_index).forbidden:
            return lanes
        return [index for index in lanes if not self.get_lane(index).forbidden]


@dataclass(frozen=True)
class SpawnGroup:
    """Where new vehicles go: ``lanes`` (lane indices), the ``share`` of new vehicles placed there, and
    ``destination(lane_index, x)``: the node a vehicle starting on that lane at longitudinal road position ``x``
    [m] (highway-env frame) drives to."""

    name: str
    lanes: tuple[LaneIndex, ...]
    share: float
    destination: Callable[[LaneIndex, float], str]


@dataclass(frozen=True)
class Layout:
    """A built layout: its ``road``, the ego's start lane and the ``ego_destination`` node it drives to, and the
    spawn groups (module docstring)."""

    road: Road
    ego_lane: LaneIndex
    ego_destination: str
    groups: tuple[SpawnGroup, ...]


def build_layout(config, speed_limit: float, np_random) -> Layout:
    """The :class:`Layout` of ``config`` (one of :mod:`~simrig.scenarios.layout_schema`'s kinds); ``speed_limit``
    [m/s] of the main road; ``np_random``: highway-env's generator for the road (the environment's)."""
    builders = {TwoWayLayout: _two_way, RampsLayout: _ramps, ExitsLayout: _exits, CrossingsLayout: _crossings}
    layout = builders[type(config)](config, speed_limit, np_random)
    layout.road.network.freeze()
    for obstacle in layout.road.objects:  # placed before the index existed
        obstacle.lane_index = layout.road.network.get_closest_lane_index(obstacle.position, obstacle.heading)
        obstacle.lane = layout.road.network.get_lane(obstacle.lane_index)
    return layout


def _carriageway(net: RoadNetwork, start: str, end: str, x0: float, x1: float, lanes: int, y0: float,
                 limit: float, priority: int = 0, outer_right: bool = True) -> None:
    """``lanes`` straight lanes from ``x0`` to ``x1`` (x1 < x0: driving towards −x), the leftmost at lateral
    offset ``y0`` and the others further to the driving direction's right."""
    sign = 1.0 if x1 > x0 else -1.0
    for lane in range(lanes):
        y = y0 + sign * lane * LANE_WIDTH_M
        left = _C if lane == 0 else _S
        right = _C if lane == lanes - 1 and outer_right else _N
        net.add_lane(start, end, StraightLane([x0, y], [x1, y], line_types=(left, right), speed_limit=limit,
                                              priority=priority))


def _two_way(config: TwoWayLayout, limit: float, np_random) -> Layout:
    net = LayoutNetwork()
    n, length = config.lanes_per_direction, config.length_m
    _carriageway(net, "forward_start", "forward_end", 0.0, length, n, 0.0, limit)
    for lane in range(n):  # oncoming, to the left (−y); its lane 0 next to the centre line, which is painted once
        y = -(lane + 1) * LANE_WIDTH_M
        line_types = (_N if lane == 0 else _S, _C if lane == n - 1 else _N)
        net.add_lane("oncoming_start", "oncoming_end",
                     StraightLane([length, y], [0.0, y], line_types=line_types, speed_limit=limit))
    forward = tuple(("forward_start", "forward_end", lane) for lane in range(n))
    oncoming = tuple(("oncoming_start", "oncoming_end", lane) for lane in range(n))
    return Layout(
        road=Road(network=net, np_random=np_random),
        ego_lane=forward[-1], ego_destination="forward_end",
        groups=(SpawnGroup("forward", forward, 1.0 - config.oncoming_share, lambda lane, x: "forward_end"),
                SpawnGroup("oncoming", oncoming, config.oncoming_share, lambda lane, x: "oncoming_end")),
    )


def _feature_positions(length: float, spacing: float) -> np.ndarray:
    """[m] where a layout's repeated feature starts: every ``spacing`` from ``spacing`` on, leaving one spacing of
    plain road at the end."""
    return np.arange(spacing, length - spacing + 1e-9, spacing)


def _ramps(config: RampsLayout, limit: float, np_random) -> Layout:
    net = LayoutNetwork()
    n, length = config.lanes, config.length_m
    y_acceleration = n * LANE_WIDTH_M
    y_ramp = y_acceleration + RAMP_OFFSET_M
    node, x = "main_0", 0.0
    main, ramp_lanes, objects = [], [], []
    for k, start in enumerate(_feature_positions(length, config.ramp_spacing_m)):
        merge_start, merge_end = f"merge_{k}", f"merged_{k}"
        _carriageway(net, node, merge_start, x, start, n, 0.0, limit)
        main += [(node, merge_start, lane) for lane in range(n)]
        _carriageway(net, merge_start, merge_end, start, start + RAMP_ACCELERATION_M, n, 0.0, limit,
                     outer_right=False)
        main += [(merge_start, merge_end, lane) for lane in range(n)]
        approach = StraightLane([start - RAMP_CONVERGE_M - RAMP_APPROACH_M, y_ramp], [start - RAMP_CONVERGE_M, y_ramp],
                                line_types=(_C, _C), forbidden=True, speed_limit=limit)
        converge = SineLane([start - RAMP_CONVERGE_M, y_ramp - RAMP_OFFSET_M / 2],
                            [start, y_ramp - RAMP_OFFSET_M / 2], RAMP_OFFSET_M / 2, np.pi / RAMP_CONVERGE_M,
                            np.pi / 2, line_types=(_C, _C), forbidden=True, speed_limit=limit)
        acceleration = StraightLane([start, y_acceleration], [start + RAMP_ACCELERATION_M, y_acceleration],
                                    line_types=(_S, _C), forbidden=True, speed_limit=limit)
        net.add_lane(f"ramp_{k}", f"converge_{k}", approach)
        net.add_lane(f"converge_{k}", merge_start, converge)
        net.add_lane(merge_start, merge_end, acceleration)  # lane n of the merge section: MOBIL merges from it
        ramp_lanes += [(f"ramp_{k}", f"converge_{k}", 0), (f"converge_{k}", merge_start, 0)]
        objects.append(acceleration.position(RAMP_ACCELERATION_M, 0.0))
        node, x = merge_end, start + RAMP_ACCELERATION_M
    _carriageway(net, node, "main_end", x, length, n, 0.0, limit)
    main += [(node, "main_end", lane) for lane in range(n)]
    road = Road(network=net, np_random=np_random)
    for position in objects:
        road.objects.append(Obstacle(road, position))
    ego_lane = main[n - 1]
    return Layout(
        road=road, ego_lane=ego_lane, ego_destination="main_end",
        groups=(SpawnGroup("motorway", tuple(main), 1.0 - config.ramp_share, lambda lane, x: "main_end"),
                SpawnGroup("ramps", tuple(ramp_lanes), config.ramp_share, lambda lane, x: "main_end")),
    )


def _exits(config: ExitsLayout, limit: float, np_random) -> Layout:
    net = LayoutNetwork()
    n, length = config.lanes, config.length_m
    node, x = "main_0", 0.0
    main, rightmost, exits_at = [], [], []
    for k, fork in enumerate(_feature_positions(length, config.exit_spacing_m)):
        fork_node = f"fork_{k}"
        _carriageway(net, node, fork_node, x, fork, n, 0.0, limit)
        main += [(node, fork_node, lane) for lane in range(n)]
        rightmost.append((node, fork_node, n - 1))
        exits_at.append((fork, f"exit_{k}"))
        centre = np.array([fork, (n - 1) * LANE_WIDTH_M + EXIT_RADIUS_M])
        net.add_lane(fork_node, f"exit_{k}", CircularLane(
            centre, EXIT_RADIUS_M, 3 * np.pi / 2, 3 * np.pi / 2 + np.pi / 2, clockwise=True,
            line_types=(_N, _C), forbidden=True, speed_limit=EXIT_SPEED_MPS))
        node, x = fork_node, fork
    _carriageway(net, node, "main_end", x, length, n, 0.0, limit)
    main += [(node, "main_end", lane) for lane in range(n)]
    forks = np.array([position for position, _ in exits_at])

    def next_exit(lane: LaneIndex, position: float) -> str:
        later = np.flatnonzero(forks > position + 1.0)
        return exits_at[int(later[0])][1] if len(later) else "main_end"

    return Layout(
        road=Road(network=net, np_random=np_random), ego_lane=main[n - 2], ego_destination="main_end",
        groups=(SpawnGroup("through", tuple(main), 1.0 - config.exit_share, lambda lane, x: "main_end"),
                SpawnGroup("exiting", tuple(rightmost), config.exit_share, next_exit)),
    )


def _crossings(config: CrossingsLayout, limit: float, np_random) -> Layout:
    net = LayoutNetwork()
    length, half = config.length_m, SIDE_ROAD_HALF_M
    main_priority, side_priority = 3, 1
    forward, oncoming, side = [], [], []
    positions = np.arange(config.crossing_spacing_m, length - config.crossing_spacing_m + 1e-9,
                          config.crossing_spacing_m)
    nodes = ["main_0", *(f"cross_{k}" for k in range(len(positions))), "main_end"]
    xs = [0.0, *positions.tolist(), length]
    for a, b, x0, x1 in zip(nodes[:-1], nodes[1:], xs[:-1], xs[1:], strict=True):
        net.add_lane(a, b, StraightLane([x0, 0.0], [x1, 0.0], line_types=(_C, _C), speed_limit=limit,
                                        priority=main_priority))
        net.add_lane(f"back_{b}", f"back_{a}", StraightLane([x1, -LANE_WIDTH_M], [x0, -LANE_WIDTH_M],
                                                            line_types=(_N, _C), speed_limit=limit,
                                                            priority=main_priority))
        forward.append((a, b, 0))
        oncoming.append((f"back_{b}", f"back_{a}", 0))
    for k, x in enumerate(positions.tolist()):
        centre = -LANE_WIDTH_M / 2.0  # between the two main lanes; highway-env's −y is to the main road's left
        y_north, y_south = centre - half, centre + half
        # southbound (towards +y) on the right of its direction (x − 2 m); northbound on x + 2 m
        net.add_lane(f"north_{k}", f"south_end_{k}", StraightLane(
            [x - LANE_WIDTH_M / 2, y_north], [x - LANE_WIDTH_M / 2, y_south], line_types=(_N, _C),
            speed_limit=config.side_speed_mps, priority=side_priority))
        net.add_lane(f"south_{k}", f"north_end_{k}", StraightLane(
            [x + LANE_WIDTH_M / 2, y_south], [x + LANE_WIDTH_M / 2, y_north], line_types=(_N, _C),
            speed_limit=config.side_speed_mps, priority=side_priority))
        side += [(f"north_{k}", f"south_end_{k}", 0), (f"south_{k}", f"north_end_{k}", 0)]
    road = CrossingRoad(network=net, np_random=np_random)
    road.crossings = positions
    road.side_speed = config.side_speed_mps
    return Layout(
        road=road, ego_lane=forward[0], ego_destination="main_end",
        groups=(SpawnGroup("forward", tuple(forward), 1.0 - config.side_share - config.oncoming_share,
                           lambda lane, x: "main_end"),
                SpawnGroup("oncoming", tuple(oncoming), config.oncoming_share, lambda lane, x: "back_main_0"),
                SpawnGroup("side", tuple(side), config.side_share, lambda lane, x: lane[1])),
    )


class CrossingRoad(Road):
    """The road of a ``crossings`` layout: side-street vehicles give way at a stop line.

    highway-env's ``RegulatedRoad`` (``intersection-v0``'s rule) looks for conflicts every 0.5 s, 3 s ahead at
    constant speeds, and stops the lower-priority vehicle when it finds one; on straight crossings it found some too
    late, told a side vehicle already at the main road to stop there, and the ego drove into it (seed 102 of
    ``intersection_surround6``, frame 323). Here, at every simulation step, a side vehicle that can still stop before
    the main road (its front is more than its braking distance at :data:`STOP_DECELERATION_MPS2`, plus
    :data:`STOP_MARGIN_M`, from the junction, and at most :data:`APPROACH_M` more) is held (target speed 0) while a
    main-road vehicle is in the junction or would reach it within :data:`GAP_S` at its speed, and released (target
    speed: the side street's limit) otherwise. A side vehicle past that point goes on: it is committed. Main-road
    vehicles, the ego among them, keep their priority and brake, by their IDM, only for what is in their lane. A
    busy main road holds the side streets for long: gap acceptance, not signals."""

    crossings: np.ndarray = np.zeros(0)
    """[m] x of each crossing's centre line (highway-env frame)."""
    side_speed: float = 12.0

    def step(self, dt: float) -> None:
        self._give_way()
        step_road(self, dt)

    def _give_way(self) -> None:
        main = [v for v in self.vehicles if not str(v.lane_index[0]).startswith(("north_", "south_"))]
        if len(main):
            x = np.array([v.position[0] for v in main])
            velocity = np.array([v.velocity[0] for v in main])
            half = np.array([v.LENGTH / 2.0 for v in main])
        for vehicle in self.vehicles:
            lane_from = str(vehicle.lane_index[0])
            if not lane_from.startswith(("north_", "south_")):
                continue
            centre = float(self.crossings[int(lane_from.split("_")[-1])])
            southbound = lane_from.startswith("north_")  # from the north end, driving towards +y
            front = vehicle.position[1] + (vehicle.LENGTH / 2.0 if southbound else -vehicle.LENGTH / 2.0)
            edge = JUNCTION_Y[0] if southbound else JUNCTION_Y[1]
            ahead = (edge - front) if southbound else (front - edge)  # [m] to the junction; < 0: in or past it
            stopping = max(vehicle.speed, 0.0) ** 2 / (2.0 * STOP_DECELERATION_MPS2) + STOP_MARGIN_M
            if ahead <= stopping or ahead > stopping + APPROACH_M:  # committed, or not yet at the line
                if getattr(vehicle, "holding", False):
                    vehicle.holding, vehicle.target_speed = False, self.side_speed
                continue
            blocked = False
            if len(main):
                near, far = centre - JUNCTION_HALF_M - half, centre + JUNCTION_HALF_M + half  # footprint reaches it
                moving = np.abs(velocity) > 0.1
                enter = np.where(velocity > 0, near - x, x - far) / np.where(moving, np.abs(velocity), 1.0)
                leave = np.where(velocity > 0, far - x, x - near) / np.where(moving, np.abs(velocity), 1.0)
                inside = (x >= near) & (x <= far)
                blocked = bool((inside | (moving & (leave > 0.0) & (enter < GAP_S))).any())
            vehicle.holding = blocked
            vehicle.target_speed = 0.0 if blocked else self.side_speed


def lane_samples(network: RoadNetwork, lanes: tuple[LaneIndex, ...],
                 step_m: float = 10.0) -> tuple[np.ndarray, np.ndarray]:
    """Points every ``step_m`` along each of ``lanes`` ``(P, 2)`` (highway-env frame) and the position in ``lanes``
    of the lane each belongs to ``(P,)``, each lane's points together: to find the lanes near a position in one numpy
    pass (the spawn window, :class:`LayoutNetwork`'s index)."""
    points, owners = [], []
    for position, index in enumerate(lanes):
        lane: AbstractLane = network.get_lane(index)
        s = np.linspace(0.0, lane.length, max(2, int(np.ceil(lane.length / step_m)) + 1))
        points.extend(lane.position(value, 0.0) for value in s)
        owners.extend([position] * len(s))
    return np.array(points), np.array(owners)
