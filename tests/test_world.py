"""highway-env as the traffic source: frames, ids, sizes, density and determinism."""

import numpy as np
import pytest
from highway_env.vehicle.behavior import IDMVehicle
from simrig.scenarios.schema import TrafficConfig

from simrig.seeding import RandomStreams
from simrig.world import CLASS_SPECS, TrafficWorld
from simrig.world.vehicles import SimrigVehicle


def _world(seed=3, **overrides):
    streams = RandomStreams(seed)
    config = TrafficConfig(**{"vehicles": 30, "window_radius_m": 120.0, "spawn_min_distance_m": 80.0, **overrides})
    return TrafficWorld(config, 10.0, env_seed=streams.integer_seed("traffic"), rng=streams.generator("population"))


def _run(world, frames):
    states = [world.reset()]
    states += [world.step() for _ in range(frames - 1)]
    return states


def test_world_frame_has_y_to_the_left():
    world = _world()
    world.reset()
    for _ in range(5):
        state = world.step()
    ego = world.ego
    road_vehicles = {v.simrig_id: v for v in world.env.unwrapped.road.vehicles if v is not ego}
    ego_lane = ego.lane_index[2]
    checked = 0
    for actor_id, box in zip(state.actor_ids, state.boxes, strict=True):
        lane = road_vehicles[actor_id].lane_index[2]
        if lane < ego_lane:  # highway-env lane 0 is the leftmost
            assert box[1] > state.ego.y
            checked += 1
        elif lane > ego_lane:
            assert box[1] < state.ego.y
            checked += 1
        # Velocity is along the road (+x) and the heading matches it.
        assert box[7] > 0
        assert abs(box[6]) < 0.3
    assert checked > 5
    world.close()


def test_boxes_have_the_class_size_that_highway_env_simulates():
    world = _world()
    state = _run(world, 3)[-1]
    for vehicle in world.env.unwrapped.road.vehicles:
        assert isinstance(vehicle, SimrigVehicle)
    by_id = {v.simrig_id: v for v in world.env.unwrapped.road.vehicles}
    for actor_id, actor_class, box in zip(state.actor_ids, state.classes, state.boxes, strict=True):
        spec = CLASS_SPECS[actor_class]
        assert (box[3], box[4], box[5]) == (spec.length, spec.width, spec.height)
        assert by_id[actor_id].LENGTH == spec.length and by_id[actor_id].WIDTH == spec.width
        assert box[2] == spec.height / 2  # resting on the road
    world.close()


def test_density_is_held_and_ids_are_never_reused():
    world = _world()
    states = _run(world, 150)
    counts = [len(s.actor_ids) for s in states]
    assert min(counts[1:]) >= 27 and max(counts) <= 30
    seen_last = {}
    for state in states:
        assert len(set(state.actor_ids.tolist())) == len(state.actor_ids)
        distances = np.hypot(state.boxes[:, 0] - state.ego.x, state.boxes[:, 1] - state.ego.y)
        assert (distances <= 120.0 + 1e-9).all()
        for actor_id in state.actor_ids.tolist():
            if actor_id in seen_last:
                assert seen_last[actor_id] == state.frame - 1, f"id {actor_id} came back after a gap"
            seen_last[actor_id] = state.frame
    births = len(seen_last) - counts[0]
    assert births > 5  # traffic turns over: natural births and deaths
    assert [s.timestamp for s in states[:3]] == [0.0, 0.1, 0.2]
    world.close()


def test_ego_drives_itself_and_the_scenario_never_stops_early():
    world = _world(vehicles=0)
    states = _run(world, 60)
    xs = [s.ego.x for s in states]
    assert np.all(np.diff(xs) > 0)
    assert states[-1].ego.vx == pytest.approx(25.0, abs=0.5)  # IDM reaches the target speed on an empty road
    world.close()


def test_same_seed_same_traffic_different_seed_different_traffic():
    a = _run(_world(seed=11), 40)
    b = _run(_world(seed=11), 40)
    c = _run(_world(seed=12), 40)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x.boxes, y.boxes)
        np.testing.assert_array_equal(x.actor_ids, y.actor_ids)
    assert not np.array_equal(a[-1].boxes, c[-1].boxes)


def test_intersection_env_does_not_change_other_runs_in_the_process():
    # intersection-v0 rewrites IDMVehicle's class constants for the whole process; ours must not follow.
    before = _run(_world(seed=5), 60)
    intersection = _world(seed=5, env="intersection-v0", vehicles=8, window_radius_m=60.0, spawn_min_distance_m=30.0,
                          speed_range_mps=(6.0, 9.0), ego_speed_mps=8.0)
    _run(intersection, 5)
    assert IDMVehicle.DISTANCE_WANTED == 7  # the process-wide change did happen
    after = _run(_world(seed=5), 60)
    np.testing.assert_array_equal(before[-1].boxes, after[-1].boxes)


@pytest.mark.parametrize("env", ["merge-v0", "roundabout-v0", "intersection-v0"])
def test_other_maps_run_with_traffic(env):
    world = _world(env=env, vehicles=10, window_radius_m=80.0, spawn_min_distance_m=40.0,
                   speed_range_mps=(8.0, 14.0), ego_speed_mps=10.0)
    states = _run(world, 40)
    assert max(len(s.actor_ids) for s in states) >= 5
    assert all(np.isfinite(s.boxes).all() for s in states)
    world.close()


def _crash_two_vehicles(world):
    """Put one non-ego vehicle onto another (same lane, overlapping): highway-env flags both crashed."""
    a, b = [v for v in world.env.unwrapped.road.vehicles if v is not world.ego][:2]
    b.position = a.position + 1.0 * a.direction
    b.heading, b.speed = a.heading, a.speed + 5.0
    return a.simrig_id, b.simrig_id


def test_a_crash_of_other_vehicles_is_an_event_and_they_leave_the_road():
    world = _world(vehicles=10)
    world.reset()
    crashed = _crash_two_vehicles(world)
    state = world.step()
    assert sorted(e for e in state.events if e.startswith("vehicle_crashed")) == [
        f"vehicle_crashed id={i}" for i in sorted(crashed)
    ]
    later = [world.step() for _ in range(30)]
    for s in [state, *later]:
        assert not set(crashed) & set(s.actor_ids.tolist())  # removed in the frame of the crash, never back
    assert not any(v.crashed for v in world.env.unwrapped.road.vehicles)
    assert np.hypot(later[-1].boxes[:, 7], later[-1].boxes[:, 8]).mean() > 15.0  # nothing left blocking a lane
    assert len(later[-1].actor_ids) == 10  # the window refilled
    world.close()


def test_a_crash_reaches_the_dataset_manifest_as_a_world_event(tmp_path, monkeypatch):
    from simrig.scenarios import load_scenario
    from simrig.scenarios.sensor_schema import RenderConfig

    from simrig.pipeline.generate import generate
    from simrig.world.traffic import TrafficWorld as World

    crashed = []
    reset = World.reset

    def reset_then_crash(self):
        state = reset(self)
        crashed.extend(_crash_two_vehicles(self))
        return state

    monkeypatch.setattr(World, "reset", reset_then_crash)
    scenario = load_scenario("highway_surround6")
    scenario = scenario.model_copy(update={"render": RenderConfig(visibility=False)})
    result = generate(scenario, seed=0, out=tmp_path / "ds", frames=4)
    events = [e for e in result.manifest["events"] if e["event"].startswith("vehicle_crashed")]
    assert events == [{"frame": 1, "event": f"vehicle_crashed id={i}"} for i in sorted(crashed)]


def test_dense_traffic_does_not_crash_and_keeps_moving():
    # highway_surround6's traffic (40 vehicles in 150 m), seed 1: before new vehicles were placed at speeds
    # their gap allows, the first crash came at frame 37 and 21 vehicles had crashed by frame 200.
    from simrig.scenarios import load_scenario

    traffic = load_scenario("highway_surround6").traffic
    streams = RandomStreams(1)
    world = TrafficWorld(traffic, 10.0, env_seed=streams.integer_seed("traffic"), rng=streams.generator("population"))
    states, flagged = [world.reset()], set()
    for _ in range(199):
        states.append(world.step())
        flagged |= {v.simrig_id for v in world.env.unwrapped.road.vehicles if v.crashed}
    assert not flagged
    assert not [e for s in states for e in s.events if "crashed" in e]
    speeds = [np.hypot(s.boxes[:, 7], s.boxes[:, 8]).mean() for s in states]
    assert min(speeds) > 10.0  # IDM's equilibrium speed for this density is ~13 m/s; nothing stands still
    world.close()


@pytest.mark.parametrize("name", ["highway_surround6", "roundabout_surround6", "merge_surround6"])
def test_memoised_lane_coordinates_leave_every_table_as_highway_envs_own_give_them(name, tmp_path, monkeypatch):
    """Lane coordinates are memoised per position within a step (:mod:`simrig.world.lane_memo`): a dataset made
    with the memo has the same bytes as one made with highway-env's own method on every call."""
    import json

    from simrig.scenarios import load_scenario
    from simrig.scenarios.overrides import with_setting

    import simrig.world.traffic as traffic
    from simrig.pipeline.generate import generate

    scenario = with_setting(load_scenario(name), "render.visibility", False)
    generate(scenario, seed=2, out=tmp_path / "memo", frames=40)
    monkeypatch.setattr(traffic, "memoise_lanes", lambda network: [])
    generate(scenario, seed=2, out=tmp_path / "plain", frames=40)

    def hashes(folder):
        return {name: entry["sha256"] for name, entry in json.loads((folder / "manifest.json").read_text())[
            "files"].items()}

    assert hashes(tmp_path / "memo") == hashes(tmp_path / "plain")


@pytest.mark.parametrize("name", ["highway_surround6", "merge_surround6", "roundabout_surround6"])
def test_the_indexed_neighbour_search_answers_as_highway_envs_own_on_every_lane_of_every_step(name):
    """:mod:`simrig.world.neighbours` against highway-env's ``Road.neighbour_vehicles``: for every vehicle, on its
    own lane and on each lane beside it, at every step of real traffic (connected-lane search included)."""
    from highway_env.road.road import Road
    from simrig.scenarios import load_scenario

    from simrig.seeding import RandomStreams
    from simrig.world import TrafficWorld

    scenario = load_scenario(name)
    streams = RandomStreams(3)
    world = TrafficWorld(scenario.traffic, scenario.frame_rate_hz, env_seed=streams.integer_seed("traffic"),
                         rng=streams.generator("population"))
    world.reset()
    road = world.env.unwrapped.road
    asked = 0
    for _ in range(25):
        for connected in (False, True):
            road.neighbour_vehicles_connected_lanes = connected
            for vehicle in list(road.vehicles):
                for lane in [vehicle.lane_index, *road.network.side_lanes(vehicle.lane_index)]:
                    assert road.neighbour_vehicles(vehicle, lane) == Road.neighbour_vehicles(road, vehicle, lane)
                    asked += 1
        road.neighbour_vehicles_connected_lanes = False
        world.step()
    world.close()
    assert asked > 500


def test_the_road_step_collides_exactly_the_pairs_highway_envs_own_step_collides(monkeypatch):
    """:mod:`simrig.world.road_step` against highway-env's ``Road.step`` on one crowded road, deep-copied: highway-env's
    vehicles (whose spherical test reaches ``speed · dt`` further) and simrig's, an obstacle, pairs overlapping,
    pairs just inside and just outside the spherical test's reach, pairs placed at exactly that reach. Every pair
    that passes highway-env's spherical test (``norm(Δposition) ≤ (diagonal₁ + diagonal₂) / 2 + speed₁ · dt``,
    its own formula) gets the exact test on simrig's road too, and after every step each vehicle's position, crash
    flag and impact are the same on both roads, with crashes and impacts happening."""
    import copy

    from highway_env.road.lane import StraightLane
    from highway_env.road.road import Road, RoadNetwork
    from highway_env.vehicle.kinematics import Vehicle
    from highway_env.vehicle.objects import Obstacle, RoadObject

    from simrig.world.road_step import step_road

    network = RoadNetwork()
    for lane in range(3):
        network.add_lane("a", "b", StraightLane([0.0, 4.0 * lane], [1000.0, 4.0 * lane]))
    road = Road(network=network, np_random=np.random.default_rng(0))
    rng = np.random.default_rng(7)
    kinds = (IDMVehicle, SimrigVehicle)
    for index in range(36):
        lane = network.get_lane(("a", "b", index % 3))
        road.vehicles.append(kinds[index % 2](road, lane.position(float(rng.uniform(0.0, 120.0)), 0.0),
                                              speed=float(rng.uniform(5.0, 30.0))))
    anchor = Vehicle(road, np.array([500.0, 30.0]), speed=0.0)  # standing still: the edge pairs stay at the edge
    road.vehicles.append(anchor)
    for along in (0.0, -1e-9, 1e-9):  # at the sphere's edge, just inside it and just outside it
        other = Vehicle(road, anchor.position.copy(), speed=0.0)
        other.position = anchor.position + np.array([0.0, (anchor.diagonal + other.diagonal) / 2.0 + along])
        road.vehicles.append(other)
    road.objects.append(Obstacle(road, network.get_lane(("a", "b", 1)).position(60.0, 0.0)))
    theirs = copy.deepcopy(road)

    checked: list = []
    exact_test = RoadObject._is_colliding

    def recording(self, other, dt):
        checked.append((self, other, dt))
        return exact_test(self, other, dt)

    monkeypatch.setattr(RoadObject, "_is_colliding", recording)

    def pairs(on, within_sphere: bool) -> set:
        index = {id(thing): k for k, thing in enumerate(on.vehicles + on.objects)}
        return {(index[id(a)], index[id(b)]) for a, b, dt in checked if not within_sphere
                or np.linalg.norm(b.position - a.position) <= (a.diagonal + b.diagonal) / 2 + a.speed * dt}

    crashes = impacts = 0
    for _ in range(20):
        road.act()
        theirs.act()
        checked.clear()
        Road.step(theirs, 1 / 15)
        needed = pairs(theirs, within_sphere=True)
        checked.clear()
        step_road(road, 1 / 15)
        assert needed <= pairs(road, within_sphere=False)
        assert {(36, 37), (36, 38)} <= needed and (36, 39) not in needed  # the edge pairs, as placed
        for mine, their in zip(road.vehicles, theirs.vehicles, strict=True):
            assert np.array_equal(mine.position, their.position)
            assert (mine.crashed, mine.hit) == (their.crashed, their.hit)
            assert (mine.impact is None) == (their.impact is None)
            assert mine.impact is None or np.array_equal(mine.impact, their.impact)
        crashes += sum(v.crashed for v in road.vehicles)
        impacts += sum(v.impact is not None and np.any(v.impact) for v in road.vehicles)
    assert crashes > 0 and impacts > 0


@pytest.mark.parametrize("name", ["highway_surround6", "intersection_surround6"])
def test_a_dataset_stepped_by_the_road_step_has_the_bytes_of_one_stepped_by_highway_envs_own(name, tmp_path,
                                                                                         monkeypatch):
    """The same, end to end: a dataset (crossings and their give-way rule included) made with
    :func:`~simrig.world.road_step.step_road` has the same bytes as one made with highway-env's ``Road.step``."""
    import json

    from highway_env.road.road import Road
    from simrig.scenarios import load_scenario
    from simrig.scenarios.overrides import with_setting

    import simrig.world.layouts as layouts
    import simrig.world.traffic as traffic
    from simrig.pipeline.generate import generate

    scenario = with_setting(load_scenario(name), "render.visibility", False)
    generate(scenario, seed=4, out=tmp_path / "ours", frames=60)
    for module in (traffic, layouts):
        monkeypatch.setattr(module, "step_road", Road.step)
    generate(scenario, seed=4, out=tmp_path / "theirs", frames=60)

    def hashes(folder):
        return {name: entry["sha256"] for name, entry in json.loads((folder / "manifest.json").read_text())[
            "files"].items()}

    assert hashes(tmp_path / "ours") == hashes(tmp_path / "theirs")
