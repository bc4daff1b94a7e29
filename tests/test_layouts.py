"""Road layouts: the long roads simrig builds keep their traffic alive, and each one's feature works — vehicles join
from the ramps, leave by the exits, cross at the crossings, and come the other way on two-way roads; their lines are
painted only where lanes are."""

import numpy as np
import pytest
from bench_engines import assert_same_bench_bytes
from highway_env.road.road import RoadNetwork
from simrig.scenarios import load_scenario
from simrig.scenarios.schema import TrafficConfig

from simrig.seeding import RandomStreams
from simrig.world import TrafficWorld
from simrig.world.layouts import LayoutNetwork, build_layout
from simrig.world.liveness import traffic_liveness

NEW_ROADS = ("merge_surround6", "intersection_surround6", "two_way_surround6", "exit_surround6")


@pytest.mark.slow  # 4 × 200 frames of traffic; CI's slow pass runs it
@pytest.mark.parametrize("name", NEW_ROADS)
def test_each_new_road_is_alive_for_200_frames(name):
    """At CI size (tests/perf/road_liveness.py runs 1,000 frames): vehicles in view in every
    frame, births and deaths in every 100 frames, speeds kept, no ego crash; crashes of others are events."""
    live = traffic_liveness(load_scenario(name), seed=0, frames=200)
    assert live.problems() == []
    assert live.progress_m > 150.0  # the ego drives through the layout (≥ 7.5 m/s on average)
    assert all(event.startswith(("vehicle_crashed id=", "ego_crashed")) for _, event in live.crashes)


def _world(name: str, seed: int = 0) -> TrafficWorld:
    scenario = load_scenario(name)
    streams = RandomStreams(seed)
    return TrafficWorld(scenario.traffic, scenario.frame_rate_hz, env_seed=streams.integer_seed("traffic"),
                        rng=streams.generator("population"))


def _lanes_over_time(world: TrafficWorld, frames: int) -> dict[int, list[tuple]]:
    """Each vehicle's lane index (highway-env's closest lane) per frame, by simrig id."""
    world.reset()
    seen: dict[int, list[tuple]] = {}
    for _ in range(frames):
        world.step()
        for vehicle in world.env.unwrapped.road.vehicles:
            if vehicle is not world.ego:
                seen.setdefault(vehicle.simrig_id, []).append(vehicle.lane_index)
    world.close()
    return seen


def test_ramp_vehicles_merge_onto_the_motorway_and_nobody_changes_into_an_acceleration_lane():
    lanes = _lanes_over_time(_world("merge_surround6"), 300)
    from_ramp = [path for path in lanes.values() if path[0][0].startswith(("ramp_", "converge_"))]
    assert from_ramp, "no vehicle was placed on a ramp"
    merged = [path for path in from_ramp if any(lane[0].startswith(("merge_", "merged_", "main_")) and
                                                lane[2] < 3 for lane in path)]
    assert merged, "no ramp vehicle reached a motorway lane"
    # a motorway vehicle never moves into an acceleration lane (the last lane of a merge section)
    for path in lanes.values():
        if not path[0][0].startswith(("ramp_", "converge_")):
            assert not any(lane[0].startswith("merge_") and lane[2] == 3 for lane in path)


def test_exiting_vehicles_leave_by_the_exit_ramps_and_the_ego_stays_on_the_motorway():
    world = _world("exit_surround6")
    lanes = _lanes_over_time(world, 250)
    left = [path for path in lanes.values() if any(lane[1].startswith("exit_") for lane in path)]
    assert len(left) >= 2
    assert not world.ego.lane_index[1].startswith("exit_")


def test_side_traffic_crosses_the_main_road_and_oncoming_traffic_comes_the_other_way():
    world = _world("intersection_surround6")
    world.reset()
    crossed, oncoming = set(), set()
    for _ in range(200):
        state = world.step()
        heading = (state.boxes[:, 6] - state.ego.yaw + np.pi) % (2 * np.pi) - np.pi
        relative = state.boxes[:, :2] - [state.ego.x, state.ego.y]
        side = np.abs(np.abs(heading) - np.pi / 2) < 0.3
        # a side vehicle on the main road: its lateral position (world y, left) within the two main lanes
        on_main = side & (np.abs(relative[:, 1] - 2.0) < 4.0)
        crossed |= set(state.actor_ids[on_main].tolist())
        oncoming |= set(state.actor_ids[np.abs(heading) > 3.0].tolist())
    world.close()
    assert len(crossed) >= 3 and len(oncoming) >= 3


def test_two_way_traffic_passes_at_the_sum_of_the_speeds():
    world = _world("two_way_surround6")
    state = world.reset()
    closing = []
    for _ in range(100):
        state = world.step()
        ego_velocity = np.array([state.ego.vx, state.ego.vy])
        towards = (state.boxes[:, 7:9] @ ego_velocity) < 0
        closing += list(np.linalg.norm(state.boxes[towards, 7:9] - ego_velocity, axis=1))
    world.close()
    assert closing and max(closing) > 1.8 * np.linalg.norm(ego_velocity)


@pytest.mark.parametrize("kind", ["two_way", "ramps", "exits", "crossings"])
def test_the_indexed_closest_lane_search_gives_highway_envs_answer(kind):
    """LayoutNetwork searches only nearby lanes; highway-env's own linear search over every lane is the oracle, at
    random positions and headings on and off the road."""
    layout = build_layout(TrafficConfig(layout={"kind": kind}).layout, 30.0, np.random.RandomState(0))
    network = layout.road.network
    assert isinstance(network, LayoutNetwork)
    rng = np.random.default_rng(1)
    points = np.column_stack([rng.uniform(-50.0, 3000.0, 400), rng.uniform(-60.0, 60.0, 400)])
    on_lanes = [network.get_lane(index).position(s, 0.0) for index in list(network.lanes_dict())[:40]
                for s in (0.0, 7.0, 30.0)]
    for position in [*points, *on_lanes]:
        heading = float(rng.uniform(-np.pi, np.pi))
        assert network.get_closest_lane_index(position, heading) == RoadNetwork.get_closest_lane_index(
            network, position, heading)


def test_same_seed_same_traffic_on_a_layout():
    a, b = (traffic_liveness(load_scenario("intersection_surround6"), seed=3, frames=60) for _ in range(2))
    np.testing.assert_array_equal(a.speed, b.speed)
    assert a.crashes == b.crashes


ROADS_SUITE = """
name = "roads_small"
scenarios = ["merge_surround6", "exit_surround6", "two_way_surround6", "intersection_surround6", "two_way_stereo"]
seeds = [7]
frames = 12

[[trackers]]
tracker = "global_hungarian"
rigs = ["surround6"]

[[trackers]]
tracker = "sort"
camera = "left"
rigs = ["stereo"]
"""


@pytest.mark.slow  # the default pass stays under 10 minutes; CI runs the slow pass too
def test_another_process_generates_the_same_bytes_for_each_new_road(tmp_path):
    """Across processes: each new scenario's dataset, manifest included, from a fresh process
    equals this process's."""
    import os
    import subprocess
    import sys

    from simrig.dataset import Dataset
    from simrig.pipeline.generate import generate

    env = {**os.environ, "PYOPENGL_PLATFORM": "egl"}
    for name in (*NEW_ROADS, "two_way_stereo"):
        here = Dataset.open(generate(load_scenario(name), seed=7, out=tmp_path / f"{name}-here", frames=8).path)
        subprocess.run([sys.executable, "-m", "simrig.cli", "generate", name, "--seed", "7", "--frames", "8", "--out",
                        str(tmp_path / f"{name}-there"), "--quiet"], check=True, env=env, capture_output=True)
        there = Dataset.open(tmp_path / f"{name}-there")
        assert there.manifest == here.manifest, name


@pytest.mark.slow
def test_the_new_roads_give_the_same_bench_bytes_on_the_local_pool_and_ray(tmp_path):
    """Across engines."""
    assert_same_bench_bytes(ROADS_SUITE, tmp_path)


def test_a_side_vehicle_waits_at_its_stop_line_while_a_main_road_vehicle_would_arrive_within_the_gap():
    """CrossingRoad's rule on a hand-made scene: one side vehicle 6 m before the junction at 5 m/s (its braking
    distance at 5 m/s² is 2.5 m, plus the 2 m margin: 4.5 m, so it can still stop, and 6 m is within the 3 m approach
    zone beyond that), one main-road car at 12 m/s. The junction spans x ∈ [c − 4, c + 4] m; the car's front reaches
    it after (distance − 4 − 2.3) / 12 s. Farther than the zone, or past its braking point, the side vehicle is left
    to its IDM."""
    from simrig.types import ActorClass
    from simrig.world.layouts import GAP_S, JUNCTION_Y, CrossingRoad
    from simrig.world.vehicles import VEHICLE_TYPES

    layout = build_layout(TrafficConfig(layout={"kind": "crossings"}).layout, 15.0, np.random.RandomState(0))
    road = layout.road
    assert isinstance(road, CrossingRoad)
    centre = float(road.crossings[0])
    car = VEHICLE_TYPES[ActorClass.CAR]
    front_at = JUNCTION_Y[0] - 6.0  # southbound (from the north end, towards +y): its front 6 m before the junction
    side = car(road, np.array([centre - 2.0, front_at - car.LENGTH / 2]), heading=np.pi / 2, speed=5.0,
               target_speed=12.0)
    assert side.lane_index[0] == "north_0"
    for seconds, held in ((GAP_S - 1.0, True), (GAP_S + 1.0, False)):
        distance = 4.0 + car.LENGTH / 2 + 12.0 * seconds  # the car's centre before the junction's near edge
        main = car(road, np.array([centre - distance, 0.0]), heading=0.0, speed=12.0, target_speed=12.0)
        road.vehicles = [side, main]
        road._give_way()
        assert side.holding is held and side.target_speed == (0.0 if held else road.side_speed), seconds
    near = car(road, np.array([centre - (4.0 + car.LENGTH / 2 + 12.0 * (GAP_S - 1.0)), 0.0]), heading=0.0,
               speed=12.0, target_speed=12.0)  # would hold a vehicle deciding now
    for front_at, speed in ((JUNCTION_Y[0] - 20.0, 5.0), (JUNCTION_Y[0] - 3.0, 5.0)):  # too far; committed
        side = car(road, np.array([centre - 2.0, front_at - car.LENGTH / 2]), heading=np.pi / 2, speed=speed,
                   target_speed=12.0)
        road.vehicles = [side, near]
        road._give_way()
        assert not getattr(side, "holding", False) and side.target_speed == 12.0


def _inside_a_lane(world: TrafficWorld, point: np.ndarray, margin: float) -> bool:
    """Whether a world point lies more than ``margin`` inside some lane, by highway-env's own lane coordinates."""
    position = np.array([point[0], -point[1]])  # world Y = −y
    for lane in world.env.unwrapped.road.network.lanes_list():
        along, across = lane.local_coordinates(position)
        if 0.0 < along < lane.length and abs(across) < lane.width_at(along) / 2.0 - margin:
            return True
    return False


@pytest.mark.parametrize("name", ["intersection_surround6", "exit_surround6", "roundabout_surround6"])
def test_no_painted_line_runs_through_a_lane(name):
    """Junction boxes and exit mouths are not painted across: every point of every painted line, 0.5 m apart,
    lies outside every lane's inside (0.3 m in from its borders: lines between lanes are on the border)."""
    from simrig.road import dash_segments

    world = _world(name)
    world.reset()
    markings = world.road_markings()
    ego = world.ego.position
    near = [line for line in markings.lines if np.hypot(*(line - [ego[0], -ego[1]]).T).min() < 250.0]
    assert near
    for line in near:
        for a, b in dash_segments(line, False):
            for t in np.linspace(0.0, 1.0, max(2, int(np.hypot(*(b - a)) / 0.5) + 1)):
                assert not _inside_a_lane(world, a + t * (b - a), 0.3), (name, a + t * (b - a))


def test_a_plain_highway_keeps_every_line_whole():
    """With no junction, clipping removes nothing: each lane's two lines (none on the far edges' outsides) span
    the lanes' whole length."""
    world = _world("highway_surround6")
    world.reset()
    lanes = world.env.unwrapped.road.network.lanes_list()
    painted = sum(np.hypot(*np.diff(line, axis=0).T).sum() for line in world.road_markings().lines)
    expected = sum(lane.length * sum(kind != 0 for kind in lane.line_types) for lane in lanes)  # LineType.NONE = 0
    assert painted == pytest.approx(expected, rel=1e-9)
