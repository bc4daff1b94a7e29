"""highway-env as simrig's traffic source: an IDM-driven ego inside steady traffic, exact 3D ground truth.

What this module adds to highway-env (the README's "What simrig does with highway-env, and why" has the measured facts):

* The ego drives itself (IDM + MOBIL, like every other vehicle), so no agent action ends an episode. The
  scenario always runs all its frames: a crash of the ego or the end of highway-env's episode is recorded
  as an event (``ego_crashed``, ``env_terminated``) and stepping goes on.
* Collisions are found from geometry, after every simulation step: footprints that touch or overlap
  (:mod:`simrig.world.collisions`, with highway-env's own crash flag recorded beside each one). Each frame's
  ground truth lists the collisions of its step (``GroundTruthFrame.collisions``). The ego and whatever it
  touched freeze: they stand where they met for the rest of the sequence (a drive's progress ends there; no car
  it hit vanishes).
* All traffic is simrig's: highway-env's own vehicles are removed at reset and intersection-v0's spawning
  is switched off. ``vehicles`` others are kept in a disc of ``window_radius_m`` around the ego: a vehicle
  leaving the disc is removed (a death), a new one appears on a random lane between
  ``spawn_min_distance_m`` and the radius (a birth), at least ``SPAWN_CLEARANCE_M`` from every bumper.
* A new vehicle is placed only where highway-env's own IDM would not make it, or the vehicle behind it,
  brake harder than the vehicles can (``SPAWN_MAX_BRAKING_MPS2``), starting at the highest speed (up to its
  drawn one, or the speed of the vehicle behind it if higher) that its gap ahead allows. Placing vehicles at
  their drawn speed 10 m behind slower ones was what made non-ego vehicles crash (~90 crashes in 1,000
  frames of ``highway_surround6``, seed 1). Dense traffic therefore flows at the speed its density allows
  under IDM (~15 m/s for 40 vehicles in 150 m around the ego on 4 lanes). At reset the window is first
  filled by bumper clearance alone (the requested density from frame 0, as far as it fits), then initial
  speeds are lowered until every vehicle, the ego included, can keep its gap (``_settle_initial_speeds``).
* Crashes of other vehicles: highway-env brakes a crashed vehicle to a standstill and leaves it on the road
  for good, so its lane jams behind it and, after a few crashes, all traffic (the ego too) stands still.
  Rule: two non-ego vehicles that collide are recorded as a collision of the frame (in the dataset's
  ``collisions`` table) and as ``vehicle_crashed id=N`` events, and are removed from the road in that same
  frame (they are absent from that frame's ground truth: their last boxes are the frame before). A crashed
  scripted vehicle (occluder, cut-in) follows the same rule; its script ends.
* On highway-v0 the ego is moved ``window_radius_m`` down the road so that the window behind it lies on
  the road (highway-env places it at the start, behind all traffic).
* Ids come from a counter (highway-env has none; ``id()`` is reused after removal).
* highway-env's y axis points right: it is converted here, once, to the world frame
  (X = x, Y = −y, yaw = −heading, vY = −vy), and nowhere else.
"""

from __future__ import annotations

import types

import gymnasium as gym
import highway_env  # noqa: F401  (registers the environments)
import numpy as np

from simrig.scenarios.perturbation_schema import CutIn, LeadBrake, Occluder, Stalled
from simrig.scenarios.schema import TrafficConfig

from ..road import RoadMarkings
from ..types import EGO_ID, ActorClass, Collision, EgoPose, GroundTruthFrame
from .collisions import CollisionWatch
from .ego_planner import drive_on_perception
from .lane_memo import forget, memoise_lanes
from .layouts import LIMIT_MARGIN_MPS, CrossingRoad, build_layout, lane_samples
from .markings import road_markings
from .neighbours import install as index_neighbours
from .phantoms import phantoms_from_boxes
from .road_step import step_road
from .vehicles import VEHICLE_TYPES, SimrigVehicle

SPAWN_CLEARANCE_M = 10.0
"""[m] minimum bumper-to-bumper distance between a spawned vehicle and any other vehicle."""
SPAWN_ATTEMPTS = 30
"""[-] random placements tried per missing vehicle and frame before giving up until the next frame."""
SPAWN_MAX_BRAKING_MPS2 = VEHICLE_TYPES[ActorClass.CAR].ACC_MAX
"""[m/s²] the IDM braking a new vehicle may need, or impose on the vehicle behind it: the hardest braking
highway-env lets our vehicles do (``ACC_MAX``, 6 m/s²), so IDM can always keep the gaps it starts with.
(A lane change's limit, 2 m/s², would hold dense scenarios to IDM's free-flow spacing: 21 of 40 vehicles.)"""
SPAWN_MIN_SPEED_FRACTION = 0.05
"""[-] a new vehicle starts at no less than this fraction of its drawn speed (:func:`_safe_to_join`)."""
SPAWN_SPEED_BISECTIONS = 6
"""[-] bisection steps for the speed a new vehicle's gap allows (to ~1.5% of its drawn speed)."""
EGO_CLASS = ActorClass.CAR
Scripted = Occluder | CutIn | LeadBrake | Stalled
"""The world perturbations: vehicles simrig places and steers (``WORLD_KINDS``)."""

_ENV_CONFIG = {
    "highway-v0": lambda cfg: {
        "lanes_count": cfg.lanes, "vehicles_count": 0, "controlled_vehicles": 1, "initial_lane_id": cfg.ego_lane,
    },
    "merge-v0": lambda cfg: {},
    "roundabout-v0": lambda cfg: {},
    "intersection-v0": lambda cfg: {"spawn_probability": 0.0, "initial_vehicle_count": 0},
}


def _integral_as_int(value: float) -> int | float:
    """An int where the value is integral (intersection-v0 uses the frequencies as loop counts)."""
    return int(value) if float(value).is_integer() else value


class TrafficWorld:
    """Steps highway-env at the scenario's frame rate and reports exact ground truth per frame.

    Each frame is a :class:`~simrig.types.GroundTruthFrame` without camera projections (the rig adds them);
    its ``events`` are what happened in the simulator at that frame (``ego_crashed``, ``vehicle_crashed id=N``,
    ``env_terminated``, and the scripted vehicles' events).

    ``env_seed`` seeds highway-env (its road and vehicle randomness); ``rng`` drives simrig's own choices
    (where and which vehicles appear). Both come from the scenario seed (:mod:`simrig.seeding`).

    ``ego_on_perception`` (closed loop): the ego's planner decides on what :meth:`perceive` last gave it instead of
    the real vehicles (:func:`~simrig.world.ego_planner.drive_on_perception`); everything else sees the real road.
    """

    def __init__(
        self,
        config: TrafficConfig,
        frame_rate_hz: float,
        *,
        env_seed: int,
        rng: np.random.Generator,
        scripted: tuple[tuple[int, Scripted], ...] = (),
        ego_on_perception: bool = False,
    ):
        self.config = config
        self._ego_on_perception = ego_on_perception
        self._scripted = [(index, script, script.frame_window(frame_rate_hz)) for index, script in scripted]
        self._script_vehicles: dict[int, SimrigVehicle] = {}
        self.frame_rate_hz = frame_rate_hz
        self._env_seed = env_seed
        self._rng = rng
        env_config = {
            "observation": {"type": "AttributesObservation", "attributes": ["time"]},
            "duration": 1e9,
            "policy_frequency": _integral_as_int(frame_rate_hz),
            "simulation_frequency": _integral_as_int(frame_rate_hz * config.simulation_substeps),
            **_ENV_CONFIG[config.env](config),
        }
        self.env = gym.make(config.env, config=env_config, render_mode=None, disable_env_checker=True)
        self._classes = [ActorClass(name) for name in config.class_mix]
        weights = np.array([config.class_mix[name] for name in config.class_mix], dtype=float)
        self._class_weights = weights / weights.sum()
        self._next_id = 0
        self._frame = -1
        self._terminated_reported = False
        self.ego: SimrigVehicle | None = None
        self._layout = None

    # ------------------------------------------------------------------ life cycle
    def reset(self) -> GroundTruthFrame:
        """Start the scenario: a fresh road, the IDM ego placed inside the traffic, the window populated."""
        road, lane_index, position, heading, route = self._start()
        env = self.env.unwrapped
        ego_type = VEHICLE_TYPES[EGO_CLASS]
        speed = self.config.ego_speed_mps
        self.ego = ego_type(
            road, position, heading=heading, speed=speed, target_lane_index=lane_index, target_speed=speed,
            route=route,
        )
        road.vehicles = [self.ego]
        env.controlled_vehicles = [self.ego]
        self._watch = CollisionWatch(self.ego)
        self._lane_memos = memoise_lanes(road.network)
        index_neighbours(road)
        self._watch_steps(road)
        if self._ego_on_perception:
            drive_on_perception(self.ego)
        if self._layout is None:
            self._lanes = road.network.lanes_list()
            self._lane_indices = [
                (start, end, index)
                for start, ends in road.network.graph.items()
                for end, lanes in ends.items()
                for index in range(len(lanes))
            ]
        else:
            self._lane_indices = sorted({lane for group in self._layout.groups for lane in group.lanes})
            self._lanes = [road.network.get_lane(index) for index in self._lane_indices]
            self._lane_points, self._lane_owner = lane_samples(road.network, tuple(self._lane_indices))
            position_of = {lane: position for position, lane in enumerate(self._lane_indices)}
            self._pairs = np.array([(position_of[lane], g) for g, group in enumerate(self._layout.groups)
                                    for lane in group.lanes], dtype=np.int64).reshape(-1, 2)
        self._nodes = list(road.network.graph)
        self._next_id = 0
        self._frame = 0
        self._terminated_reported = False
        self._script_vehicles = {}
        events = self._run_scripts()
        self._fill(self.config.initial_clearance_m)
        self._settle_initial_speeds()
        return self._state(tuple(events))

    def _start(self) -> tuple:
        """Reset highway-env and give the road, and the ego's start: lane index, position, heading [rad] and route
        (highway-env frame). With a layout its road replaces the environment's (:mod:`~simrig.world.layouts`)."""
        self.env.reset(seed=self._env_seed)
        env = self.env.unwrapped
        self._layout = None
        if self.config.layout is None:
            road, old = env.road, env.vehicle
            lane_index = old.lane_index
            lane = road.network.get_lane(lane_index)
            position, heading = old.position.copy(), old.heading
            if self.config.env == "highway-v0":
                s = self.config.window_radius_m + 10.0
                position, heading = lane.position(s, 0.0), lane.heading_at(s)
            return road, lane_index, position, heading, old.route
        limit = max(self.config.speed_range_mps[1], self.config.ego_speed_mps) + LIMIT_MARGIN_MPS
        self._layout = build_layout(self.config.layout, limit, env.np_random)
        road = env.road = self._layout.road
        first = road.network.get_lane(self._layout.ego_lane)
        position = first.position(self.config.window_radius_m + 10.0, 0.0)  # the window behind the ego on the road
        lane_index = road.network.get_closest_lane_index(position, first.heading_at(0.0))
        lane = road.network.get_lane(lane_index)
        heading = lane.heading_at(lane.local_coordinates(position)[0])
        path = road.network.shortest_path(lane_index[1], self._layout.ego_destination)
        route = [(*lane_index[:2], None)] + [(a, b, None) for a, b in zip(path[:-1], path[1:], strict=True)]
        return road, lane_index, position, heading, route

    def step(self) -> GroundTruthFrame:
        """Advance one frame (1 / frame rate seconds) and keep the traffic window at its density."""
        if self.ego is None:
            raise RuntimeError("TrafficWorld.step() called before reset()")
        was_frozen = self.ego.frozen
        _, _, terminated, _, _ = self.env.step(None)
        self._frame += 1
        collisions = self._watch.take_frame()
        events = []
        if self.ego.frozen and not was_frozen:
            events.append("ego_crashed")
        if terminated and not self._terminated_reported:
            self._terminated_reported = True
            events.append("env_terminated")
        events.extend(self._remove_crashed(collisions))
        self._remove_far()
        events.extend(self._run_scripts())
        self._fill(self.config.spawn_min_distance_m)
        return self._state(tuple(events), collisions)

    def close(self) -> None:
        self.env.close()

    # ------------------------------------------------------------------ the ego's planner
    def perceive(self, boxes: np.ndarray, idents: np.ndarray) -> None:
        """What the ego's planner decides on at the next :meth:`step` (closed loop, ``ego_on_perception``): world
        boxes ``(N, 9)`` (:data:`~simrig.types.BOX3D_FIELDS`) with their ``idents`` ``(N,)``."""
        if not self._ego_on_perception:
            raise RuntimeError("TrafficWorld.perceive(): the world was not built with ego_on_perception")
        self.ego.perceived = phantoms_from_boxes(self.env.unwrapped.road, boxes, idents)

    def planning_road(self):
        """The scenario's road with no vehicle on it, and the ego's planned route at the start (highway-env lane
        indices; None on a road without routes): what a planner query on recorded frames needs
        (:func:`~simrig.world.ego_planner.planning_ego`). Call instead of :meth:`reset`."""
        road, _, _, _, route = self._start()
        road.vehicles = []
        return road, (list(route) if route else None)

    # ------------------------------------------------------------------ traffic window
    def _others(self) -> list:
        return [vehicle for vehicle in self.env.unwrapped.road.vehicles if vehicle is not self.ego]

    def _watch_steps(self, road) -> None:
        """Check for collisions after every simulation step of ``road`` (highway-env steps it
        ``simulation_substeps`` times a frame): the ego and what it touched freeze at that step."""
        step = road.step if isinstance(road, CrossingRoad) else (lambda dt: step_road(road, dt))
        watch = self._watch

        def watched_step(dt: float) -> None:
            watch.before_step(road)
            step(dt)
            forget(self._lane_memos)  # every vehicle moved
            for collision in watch.after_step(road):
                if collision.geometry and EGO_ID in (collision.first, collision.second):
                    self._freeze_with_ego(road, collision)

        road.step = watched_step

    def _freeze_with_ego(self, road, collision: Collision) -> None:
        other = collision.second if collision.first == EGO_ID else collision.first
        self.ego.freeze()
        for vehicle in road.vehicles:
            if vehicle is not self.ego and vehicle.simrig_id == other:
                vehicle.freeze()

    def _remove_crashed(self, collisions: tuple[Collision, ...]) -> list[str]:
        """Remove the non-ego vehicles that collided during this frame and did not touch the ego (those freeze with
        it); one ``vehicle_crashed`` event each."""
        road = self.env.unwrapped.road
        ids = {c.first for c in collisions if c.geometry} | {c.second for c in collisions if c.geometry}
        crashed = [v for v in road.vehicles if v is not self.ego and not v.frozen and v.simrig_id in ids]
        if crashed:
            road.vehicles = [v for v in road.vehicles if all(v is not c for c in crashed)]
        return [f"vehicle_crashed id={v.simrig_id}" for v in sorted(crashed, key=lambda v: v.simrig_id)]

    def _remove_far(self) -> None:
        road = self.env.unwrapped.road
        positions = np.array([v.position for v in road.vehicles])
        distance = np.hypot(*(positions - self.ego.position).T)
        road.vehicles = [
            v for v, d in zip(road.vehicles, distance, strict=True) if v is self.ego or d <= self.config.window_radius_m
        ]

    def _fill(self, min_distance: float) -> None:
        """Spawn vehicles until the window holds ``vehicles`` others or a vehicle finds no room this frame.

        The road's positions and sizes are gathered once per frame and extended with each new vehicle, so
        the cost is linear in the vehicle count (one O(N) numpy check per attempt)."""
        missing = self.config.vehicles - (len(self.env.unwrapped.road.vehicles) - 1)
        if missing <= 0:
            return
        snapshot = _RoadSnapshot(self.env.unwrapped.road.vehicles)
        for _ in range(missing):
            if not self._spawn(min_distance, self.config.window_radius_m, snapshot, join_safely=self._frame > 0):
                break  # the window is full for now; try again next frame

    def _spawn(self, min_distance: float, max_distance: float, snapshot: _RoadSnapshot, join_safely: bool) -> bool:
        """Place one vehicle on a random lane at a distance from the ego in [min, max]; False if no room.

        Room means: :data:`SPAWN_CLEARANCE_M` from every bumper in the lane, and no IDM braking harder than
        :data:`SPAWN_MAX_BRAKING_MPS2` for the new vehicle or the one behind it (module docstring; at reset,
        ``join_safely`` is false: speeds are settled afterwards, :meth:`_settle_initial_speeds`). The
        :data:`SPAWN_ATTEMPTS` random placements are drawn at once and their clearance checked in one numpy
        pass (``(attempts, N)``); the first that has room is taken."""
        attempts = SPAWN_ATTEMPTS
        road = self.env.unwrapped.road
        rng = self._rng
        ego_position = self.ego.position
        if self._layout is None:
            picks = rng.integers(len(self._lanes), size=attempts)
        else:
            picks, groups = self._layout_picks(attempts, max_distance)
            if picks is None:
                return False
        sides = rng.uniform(-1.0, 1.0, size=attempts)  # ahead or behind, anywhere in [min, max] along the lane
        class_rows = rng.choice(len(self._classes), size=attempts, p=self._class_weights)
        speeds = rng.uniform(*self.config.speed_range_mps, size=attempts)
        if self._layout is None:
            destinations = rng.integers(len(self._nodes), size=attempts)
        offsets = np.copysign(min_distance + np.abs(sides) * (max_distance - min_distance), sides)
        candidates = []  # (attempt, position, heading) of the placements on the road and in the ring
        for attempt, (pick, offset) in enumerate(zip(picks, offsets, strict=True)):
            lane = self._lanes[pick]
            s = snapshot.ego_along(int(pick), lane, ego_position) + float(offset)
            if not 0.0 <= s <= lane.length:
                continue
            position = lane.position(s, 0.0)
            if min_distance <= float(np.hypot(*(position - ego_position))) <= max_distance:
                candidates.append((attempt, position, lane.heading_at(s)))
        if not candidates:
            return False
        attempt_of = np.array([c[0] for c in candidates])
        types = [VEHICLE_TYPES[self._classes[class_rows[attempt]]] for attempt in attempt_of]
        sizes = np.array([(t.LENGTH, t.WIDTH) for t in types])
        along, same_lane = _lane_offsets(
            np.array([c[1] for c in candidates]), np.array([c[2] for c in candidates]), sizes[:, 1],
            snapshot.positions, snapshot.half_sizes,
        )
        blocked = _blocking(along, same_lane, sizes[:, 0], snapshot.half_sizes).any(axis=1)
        for index in np.flatnonzero(~blocked):
            attempt, position, heading = candidates[index]
            speed = float(speeds[attempt])
            vehicle = types[index](
                road, position, heading=heading, speed=speed, target_lane_index=self._lane_indices[picks[attempt]],
                target_speed=speed,
            )
            if join_safely and not _safe_to_join(vehicle, *snapshot.neighbours(along[index], same_lane[index])):
                continue
            if self._layout is None:
                vehicle.plan_route_to(self._nodes[destinations[attempt]])
            else:
                group = self._layout.groups[groups[attempt]]
                vehicle.plan_route_to(group.destination(self._lane_indices[picks[attempt]], float(position[0])))
            vehicle.simrig_id = self._next_id
            self._next_id += 1
            road.vehicles.append(vehicle)
            snapshot.append(vehicle)
            return True
        return False

    def _layout_picks(self, attempts: int, max_distance: float) -> tuple:
        """``attempts`` lanes (positions in the layout's lanes) and the spawn group of each, drawn among the lanes
        that come within ``max_distance`` of the ego: each group gets its share of new vehicles, spread evenly over
        its lanes near the ego. (None, None) when no group has a lane there."""
        near = np.zeros(len(self._lanes), dtype=bool)
        distance = np.hypot(*(self._lane_points - self.ego.position).T)
        near[self._lane_owner[distance <= max_distance]] = True
        pairs = self._pairs[near[self._pairs[:, 0]]]
        shares = np.array([group.share for group in self._layout.groups])
        counts = np.bincount(pairs[:, 1], minlength=len(shares))
        weights = shares[pairs[:, 1]] / np.maximum(counts[pairs[:, 1]], 1)
        if not len(pairs) or weights.sum() <= 0.0:
            return None, None
        rows = self._rng.choice(len(pairs), size=attempts, p=weights / weights.sum())
        return pairs[rows, 0], pairs[rows, 1]

    def _settle_initial_speeds(self) -> None:
        """At reset, after the window is populated (bumper clearance only, as many as fit): lower initial
        speeds — never target speeds — until no vehicle, the ego included, needs IDM braking harder than
        :data:`SPAWN_MAX_BRAKING_MPS2` behind the vehicle ahead of it in its lane. Lowering a speed can only
        make the vehicle behind brake harder, so this repeats until nothing changes (speeds only go down).
        A non-ego vehicle that would need less than :data:`SPAWN_MIN_SPEED_FRACTION` of its speed is removed."""
        road = self.env.unwrapped.road
        for _ in range(len(road.vehicles) + 1):
            snapshot = _RoadSnapshot(road.vehicles)
            vehicles = snapshot.vehicles
            along, same_lane = _lane_offsets(
                snapshot.positions, np.array([v.heading for v in vehicles]), np.array([v.WIDTH for v in vehicles]),
                snapshot.positions, snapshot.half_sizes,
            )
            changed, removed = False, []
            for index, vehicle in enumerate(vehicles):
                front, _ = snapshot.neighbours(along[index], same_lane[index])
                if front is None or vehicle.acceleration(vehicle, front) >= -SPAWN_MAX_BRAKING_MPS2:
                    continue
                changed = True
                speed = _highest_speed_behind(vehicle, front, vehicle.speed)
                if speed is None and vehicle is not self.ego:
                    removed.append(vehicle)
                vehicle.speed = speed if speed is not None else vehicle.speed * SPAWN_MIN_SPEED_FRACTION
            if removed:
                road.vehicles = [v for v in road.vehicles if all(v is not r for r in removed)]
            if not changed:
                return

    # ------------------------------------------------------------------ scripted vehicles
    def _run_scripts(self) -> list[str]:
        """Spawn, steer and remove the vehicles of ``occluder`` and ``cut_in`` perturbations at this frame."""
        events = []
        road = self.env.unwrapped.road
        for index, script, (first, last) in self._scripted:
            name = f"{script.kind}#{index}"
            vehicle = self._script_vehicles.get(index)
            if self._frame == first:
                vehicle, event = self._spawn_scripted(script, name)
                self._script_vehicles[index] = vehicle
                events.append(event)
            if vehicle is None or vehicle not in road.vehicles:
                continue
            if isinstance(script, CutIn) and self._frame == last:
                vehicle.target_lane_index = (*vehicle.lane_index[:2], self.ego.lane_index[2])
                events.append(f"{name} changes into the ego's lane id={vehicle.simrig_id}")
            if isinstance(script, LeadBrake) and self._frame == last:
                vehicle.target_speed = 0.0  # IDM's free term then brakes at its limit, set to the script's
                vehicle.ACC_MAX = script.deceleration_mps2
                events.append(f"{name} brakes at {script.deceleration_mps2:g} m/s² id={vehicle.simrig_id}")
            if (isinstance(script, LeadBrake) and self._frame >= last
                    and vehicle.speed <= script.deceleration_mps2 / self.frame_rate_hz):
                _hold_still(vehicle)  # the next step would overshoot zero: stopped
            if isinstance(script, (Occluder, Stalled)) and self._frame == last + 1:
                road.vehicles.remove(vehicle)
                events.append(f"{name} removed id={vehicle.simrig_id}")
        return events

    def _spawn_scripted(self, script: Scripted, name: str) -> tuple[SimrigVehicle, str]:
        """Place a scripted vehicle ``lane_offset`` lanes beside the ego (mirrored to the other side if the
        road has no lane there) and ``offset_m`` along the road; vehicles in its way are removed. A stalled one
        stands still (:func:`_hold_still`)."""
        road = self.env.unwrapped.road
        start, end, ego_lane = self.ego.lane_index
        lanes = road.network.graph[start][end]
        note = ""
        lane_id = ego_lane - script.lane_offset  # highway-env numbers lanes from the left
        if not 0 <= lane_id < len(lanes):
            lane_id = ego_lane + script.lane_offset
            note = " (mirrored: no lane on the requested side)"
            if not 0 <= lane_id < len(lanes):
                raise ValueError(f"{name}: the road has no lane {script.lane_offset:+d} from the ego's on either side")
        lane = lanes[lane_id]
        s = lane.local_coordinates(self.ego.position)[0] + script.offset_m
        position, heading = lane.position(s, 0.0), lane.heading_at(s)
        vehicle_type = VEHICLE_TYPES[ActorClass(script.actor_class)]
        others = self._others()
        snapshot = _RoadSnapshot(others)
        along, same_lane = _lane_offsets(
            position[None, :], np.array([heading]), np.array([vehicle_type.WIDTH]), snapshot.positions,
            snapshot.half_sizes,
        )
        hits = _blocking(along, same_lane, np.array([vehicle_type.LENGTH]), snapshot.half_sizes)[0]
        in_way = [v for v, hit in zip(others, hits, strict=True) if hit]
        road.vehicles = [v for v in road.vehicles if v not in in_way]
        speed = 0.0 if isinstance(script, Stalled) else self.ego.target_speed + script.relative_speed_mps
        vehicle = vehicle_type(
            road, position, heading=heading, speed=speed, target_lane_index=(start, end, lane_id), target_speed=speed
        )
        vehicle.enable_lane_change = False
        if isinstance(script, Stalled):
            _hold_still(vehicle)
        vehicle.simrig_id = self._next_id
        self._next_id += 1
        road.vehicles.append(vehicle)
        removed = f", removed {len(in_way)} in its way" if in_way else ""
        return vehicle, f"{name} spawned id={vehicle.simrig_id} lane {lane_id}{note}{removed}"

    def road_markings(self) -> RoadMarkings:
        """The painted lines of the road network in the world frame, where lanes are (for colour renders and
        plots; :mod:`simrig.world.markings`). Call after :meth:`reset`."""
        ego = self.ego.position
        return road_markings(self.env.unwrapped.road.network, centre=(float(ego[0]), float(-ego[1])))

    # ------------------------------------------------------------------ ground truth
    def _state(self, events: tuple[str, ...], collisions: tuple[Collision, ...] = ()) -> GroundTruthFrame:
        """Ground truth now, converted from highway-env's frame (y right) to the world frame (y left)."""
        others = self._others()
        for vehicle in others:
            if getattr(vehicle, "simrig_id", -1) < 0:
                raise RuntimeError(f"a vehicle not spawned by simrig appeared in {self.config.env}: {vehicle!r}")
        n = len(others)
        boxes = np.empty((n, 9))
        if n:
            positions = np.array([v.position for v in others])
            velocities = np.array([v.velocity for v in others])
            boxes[:, 0] = positions[:, 0]
            boxes[:, 1] = -positions[:, 1]
            boxes[:, 3] = [v.LENGTH for v in others]
            boxes[:, 4] = [v.WIDTH for v in others]
            boxes[:, 5] = [v.HEIGHT for v in others]
            boxes[:, 2] = boxes[:, 5] / 2.0
            boxes[:, 6] = [-v.heading for v in others]
            boxes[:, 7] = velocities[:, 0]
            boxes[:, 8] = -velocities[:, 1]
        ego = self.ego
        ego_pose = EgoPose(
            x=float(ego.position[0]),
            y=float(-ego.position[1]),
            z=0.0,
            yaw=float(-ego.heading),
            vx=float(ego.velocity[0]),
            vy=float(-ego.velocity[1]),
        )
        return GroundTruthFrame(
            frame=self._frame,
            timestamp=self._frame / self.frame_rate_hz,
            ego=ego_pose,
            actor_ids=np.array([v.simrig_id for v in others], dtype=np.int64),
            classes=np.array([v.ACTOR_CLASS.value for v in others], dtype=object),
            boxes=boxes,
            events=events,
            collisions=collisions,
        )


def _hold_still(vehicle: SimrigVehicle) -> None:
    """Stop ``vehicle`` for good: speed 0, and from now on it commands no acceleration and no steering (IDM with a
    target speed of 0 would otherwise rock about zero at its braking limit)."""
    vehicle.speed = 0.0
    vehicle.target_speed = 0.0
    vehicle.act = types.MethodType(_stand, vehicle)


def _stand(self, action=None) -> None:
    self.action = {"steering": 0.0, "acceleration": 0.0}


class _RoadSnapshot:
    """The road's vehicles with their positions ``(M, 2)``, half lengths and widths ``(M, 2)`` [m] and speeds
    [m/s] as arrays (highway-env frame), gathered once per frame and extended as vehicles are added."""

    def __init__(self, vehicles: list):
        self._ego_along: dict[int, float] = {}
        self.vehicles = list(vehicles)
        self.positions = np.array([v.position for v in self.vehicles]).reshape(-1, 2)
        self.half_sizes = np.array([(v.LENGTH / 2.0, v.WIDTH / 2.0) for v in self.vehicles]).reshape(-1, 2)

    def ego_along(self, index: int, lane, ego_position: np.ndarray) -> float:
        """[m] the ego's longitudinal coordinate on lane ``index`` (computed once per lane and frame)."""
        if index not in self._ego_along:
            self._ego_along[index] = float(lane.local_coordinates(ego_position)[0])
        return self._ego_along[index]

    def append(self, vehicle) -> None:
        self.vehicles.append(vehicle)
        self.positions = np.vstack([self.positions, vehicle.position])
        self.half_sizes = np.vstack([self.half_sizes, (vehicle.LENGTH / 2.0, vehicle.WIDTH / 2.0)])

    def neighbours(self, along: np.ndarray, same_lane: np.ndarray) -> tuple:
        """The nearest vehicle ahead of and behind a new vehicle in its lane (None where there is none), from
        :func:`_lane_offsets`."""
        ahead = np.where(same_lane & (along > 0.0), along, np.inf)
        behind = np.where(same_lane & (along <= 0.0), -along, np.inf)
        front = self.vehicles[int(np.argmin(ahead))] if np.isfinite(ahead).any() else None
        rear = self.vehicles[int(np.argmin(behind))] if np.isfinite(behind).any() else None
        return front, rear


def _lane_offsets(points: np.ndarray, headings: np.ndarray, widths: np.ndarray, positions: np.ndarray,
                  half_sizes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For new vehicles at ``points`` ``(K, 2)`` (highway-env frame) with ``headings`` [rad] and ``widths`` [m]
    ``(K,)``: the signed distance [m] along each one's heading to each vehicle at ``positions`` ``(M, 2)``
    (half lengths and widths ``half_sizes`` ``(M, 2)``), and whether that vehicle overlaps its lane (lateral
    distance under the two half widths + 0.5 m, so neighbours in the next lane do not count); both ``(K, M)``."""
    direction = np.stack([np.cos(headings), np.sin(headings)], axis=1)[:, None, :]
    offset = positions[None, :, :] - points[:, None, :]
    along = (offset * direction).sum(axis=2)
    across = np.abs(offset[..., 0] * direction[..., 1] - offset[..., 1] * direction[..., 0])
    return along, across < half_sizes[None, :, 1] + widths[:, None] / 2.0 + 0.5


def _blocking(along: np.ndarray, same_lane: np.ndarray, lengths: np.ndarray, half_sizes: np.ndarray) -> np.ndarray:
    """``(K, M)``: which vehicles (from :func:`_lane_offsets`) new vehicles of ``lengths`` [m] ``(K,)`` would
    overlap in lane or come within :data:`SPAWN_CLEARANCE_M` of, bumper to bumper."""
    return same_lane & (np.abs(along) < half_sizes[None, :, 0] + lengths[:, None] / 2.0 + SPAWN_CLEARANCE_M)


def _highest_speed_behind(vehicle, front, top: float) -> float | None:
    """[m/s] the highest speed in [:data:`SPAWN_MIN_SPEED_FRACTION` · ``top``, ``top``] at which ``vehicle``'s
    IDM braking behind ``front`` (None: no vehicle ahead) stays within :data:`SPAWN_MAX_BRAKING_MPS2`, found by
    bisection (IDM brakes harder the faster it goes); None if even the lowest is too fast. Leaves
    ``vehicle.speed`` at the last speed tried."""

    def allows(speed: float) -> bool:
        vehicle.speed = speed
        return front is None or vehicle.acceleration(vehicle, front) >= -SPAWN_MAX_BRAKING_MPS2

    if allows(top):
        return top
    allowed, too_fast = top * SPAWN_MIN_SPEED_FRACTION, top
    if not allows(allowed):
        return None
    for _ in range(SPAWN_SPEED_BISECTIONS):
        middle = (allowed + too_fast) / 2.0
        allowed, too_fast = (middle, too_fast) if allows(middle) else (allowed, middle)
    return allowed


def _safe_to_join(vehicle, front, rear) -> bool:
    """Whether ``vehicle`` can join its lane between ``front`` and ``rear`` (either None) without IDM braking
    harder than :data:`SPAWN_MAX_BRAKING_MPS2`, for itself or for ``rear``, and at which speed (set on
    ``vehicle``): the highest speed, from its drawn speed or the speed of ``rear`` if that is higher (merging
    at the lane's speed) down to :data:`SPAWN_MIN_SPEED_FRACTION` of that, at which its own IDM braking stays
    within the limit (:func:`_highest_speed_behind`), provided ``rear`` then does too (the slower the new
    vehicle, the harder ``rear`` brakes). Its target speed stays the drawn one."""
    drawn = vehicle.speed
    top = drawn if rear is None else max(drawn, rear.speed)

    def rear_allows(speed: float) -> bool:
        vehicle.speed = speed
        return rear is None or rear.acceleration(rear, vehicle) >= -SPAWN_MAX_BRAKING_MPS2

    speed = _highest_speed_behind(vehicle, front, top) if rear_allows(top) else None  # rear: fail fast at top
    if speed is None or not rear_allows(speed):
        vehicle.speed = drawn
        return False
    return True
