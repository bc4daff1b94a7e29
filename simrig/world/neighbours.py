"""highway-env's neighbour search with each lane's answers computed once per arrangement of the vehicles.

``Road.neighbour_vehicles(vehicle, lane_index)`` walks every vehicle of the road and asks the lane (and, when the
road searches connected lanes, the lanes before and after it) where that vehicle is and whether it is on the lane;
every vehicle's IDM asks for its own lane and MOBIL for each lane beside it, so one simulation step asks every lane
about every vehicle dozens of times, though the answer depends on nothing but the lane and where the vehicles are.
:class:`NeighbourSearch` keeps, per lane, each vehicle's longitudinal coordinate on it (None when it is not on the
lane within highway-env's 1 m margin) for as long as no vehicle moved, was added or removed, and answers a search
with highway-env's own loop over those numbers — the same comparisons in the same order, so the same front and rear
vehicles, ties included, and datasets keep their bytes.
"""

from __future__ import annotations

import numpy as np
from highway_env.vehicle.objects import Landmark


class NeighbourSearch:
    """``road.neighbour_vehicles`` for one highway-env ``road`` (module docstring); install with :func:`install`."""

    def __init__(self, road):
        self.road = road
        self._things: list = []
        self._members: tuple = ()
        self._candidates: list = []
        self._positions = np.zeros(0)
        self._tables: dict[int, tuple[object, list]] = {}

    def _current(self) -> list:
        """The vehicles and objects searched (landmarks left out, as highway-env does), the lane tables emptied
        when any of them moved (an exact comparison of every position) or the lists changed."""
        things = self.road.vehicles + self.road.objects
        members = tuple(map(id, things))
        if members != self._members:  # ``_things`` keeps every member alive, so no id is reused while compared
            self._things, self._members, self._tables = things, members, {}
            self._candidates = [v for v in things if not isinstance(v, Landmark)]
        positions = np.concatenate([v.position for v in self._candidates]) if self._candidates else np.zeros(0)
        if not np.array_equal(positions, self._positions):
            self._positions, self._tables = positions, {}
        return self._candidates

    def _table(self, lane) -> list:
        """Each candidate's longitudinal coordinate on ``lane`` [m], None where it is not on the lane."""
        entry = self._tables.get(id(lane))
        if entry is None:
            table = []
            for candidate in self._candidates:
                s, lateral = lane.local_coordinates(candidate.position)
                table.append(s if lane.on_lane(candidate.position, s, lateral, margin=1) else None)
            entry = self._tables[id(lane)] = (lane, table)  # the lane kept with its table: its id stays its own
        return entry[1]

    def _lanes(self, lane_index, lane) -> list[tuple[object, float]]:
        """The lanes searched, each with the offset [m] that carries its coordinates onto ``lane``: the lane, then
        (when the road searches connected lanes) the lanes after it and before it, as highway-env orders them."""
        lanes = [(lane, 0)]
        if self.road.neighbour_vehicles_connected_lanes:
            graph = self.road.network.graph
            start, end, index = lane_index
            for following in graph.get(end, {}).values():
                if index < len(following):
                    lanes.append((following[index], lane.length))
                elif following:
                    lanes.append((following[0], lane.length))
            for ends in graph.values():
                if start in ends:
                    previous = ends[start]
                    if index < len(previous):
                        before = previous[index]
                    elif previous:
                        before = previous[0]
                    else:
                        continue
                    lanes.append((before, -before.length))
        return lanes

    def __call__(self, vehicle, lane_index=None) -> tuple:
        """The vehicle ahead of and behind ``vehicle`` on ``lane_index`` (default its own lane); None where none."""
        lane_index = lane_index or vehicle.lane_index
        if not lane_index:
            return None, None
        lane = self.road.network.get_lane(lane_index)
        s = lane.local_coordinates(vehicle.position)[0]
        candidates = self._current()
        searched = [(self._table(search_lane), offset) for search_lane, offset in self._lanes(lane_index, lane)]
        s_front = s_rear = v_front = v_rear = None
        for position, candidate in enumerate(candidates):
            if candidate is vehicle:
                continue
            for table, offset in searched:
                s_v = table[position]
                if s_v is None:
                    continue
                s_v += offset
                if s <= s_v and (s_front is None or s_v <= s_front):
                    s_front, v_front = s_v, candidate
                if s_v < s and (s_rear is None or s_v > s_rear):
                    s_rear, v_rear = s_v, candidate
                break  # matched on this lane: the lanes after it are not asked
        return v_front, v_rear


def install(road) -> NeighbourSearch:
    """Answer ``road``'s neighbour searches with a :class:`NeighbourSearch` (an instance attribute: highway-env's
    method stays on the class, where a planner's stand-in road still finds it)."""
    search = NeighbourSearch(road)
    road.neighbour_vehicles = search
    return search
