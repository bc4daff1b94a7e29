"""Collisions from geometry: footprints that touch, checked against highway-env's own polygon test, a scene
whose collision frame is worked out by hand, and closed-loop drives that must (and must not) collide."""

from __future__ import annotations

import numpy as np
import pytest
from highway_env.utils import are_polygons_intersecting
from simrig.scenarios import catalog, load_scenario
from simrig.scenarios.overrides import with_setting
from simrig.scenarios.schema import TrafficConfig

from simrig.dataset import Dataset
from simrig.pipeline.drive import drive
from simrig.scoring.drive_outcome import EGO_SPEC
from simrig.seeding import RandomStreams
from simrig.types import EGO_ID, ActorClass
from simrig.world import TrafficWorld
from simrig.world.collisions import touching_pairs
from simrig.world.vehicles import VEHICLE_TYPES


def _corners(x, y, yaw, length, width) -> np.ndarray:
    """A closed rectangle outline written out here, independently of simrig (highway-env's polygon layout)."""
    c, s = np.cos(yaw), np.sin(yaw)
    local = np.array([[-length / 2, -width / 2], [-length / 2, width / 2], [length / 2, width / 2],
                      [length / 2, -width / 2]])
    points = local @ np.array([[c, s], [-s, c]]) + np.array([x, y])
    return np.vstack([points, points[:1]])


def _highway_env_says(a, b) -> bool:
    """highway-env's separating-axis test on two ``(x, y, yaw, length, width)`` footprints, as they are."""
    return bool(are_polygons_intersecting(_corners(*a), _corners(*b), np.zeros(2), np.zeros(2))[0])


def test_touching_pairs_agree_with_highway_envs_polygon_test_on_random_rectangles():
    rng = np.random.default_rng(7)
    n = 60
    centres = rng.uniform(-12.0, 12.0, size=(n, 2))
    yaws = rng.uniform(-np.pi, np.pi, size=n)
    lengths, widths = rng.uniform(1.0, 12.0, size=n), rng.uniform(0.5, 2.6, size=n)
    found = {tuple(p) for p in touching_pairs(centres, yaws, lengths, widths).tolist()}
    expected = {(i, j) for i in range(n) for j in range(i + 1, n)
                if _highway_env_says((*centres[i], yaws[i], lengths[i], widths[i]),
                                     (*centres[j], yaws[j], lengths[j], widths[j]))}
    assert found == expected
    assert 30 < len(expected) < n * (n - 1) / 2  # both answers occur often


def _two_car_world(gap_m: float, ego_speed: float, lead_speed: float) -> tuple[TrafficWorld, int]:
    """One lane, no traffic: the ego (driving blind: it perceives nothing, so it keeps its speed) behind one car at
    ``gap_m`` between bumpers that also keeps its speed. Returns the world (reset) and the car's id."""
    streams = RandomStreams(0)
    config = TrafficConfig(lanes=1, ego_lane=0, vehicles=0, ego_speed_mps=ego_speed)
    world = TrafficWorld(config, 10.0, env_seed=streams.integer_seed("traffic"), rng=streams.generator("population"),
                         ego_on_perception=True)
    world.reset()
    world.perceive(np.zeros((0, 9)), np.zeros(0, np.int64))
    ego, car_type = world.ego, VEHICLE_TYPES[ActorClass.CAR]
    ahead = ego.position + (gap_m + (ego.LENGTH + car_type.LENGTH) / 2.0) * ego.direction
    car = car_type(world.env.unwrapped.road, ahead, heading=ego.heading, speed=lead_speed, target_speed=lead_speed,
                   target_lane_index=ego.lane_index)
    car.enable_lane_change = False
    car.simrig_id = 0
    world.env.unwrapped.road.vehicles.append(car)
    return world, car.simrig_id


def test_a_collision_is_recorded_at_the_frame_worked_out_by_hand_and_the_pair_stands_still():
    """Gap 7.45 m closing at 10 m/s and 10 frames/s: the gap is 0.45 m after 7 frames and −0.55 m after 8, so the
    footprints first overlap at frame 8, closing at 10 m/s; from then on both stand where they met."""
    world, car = _two_car_world(gap_m=7.45, ego_speed=20.0, lead_speed=10.0)
    states = [world.step() for _ in range(12)]
    hit = [(s.frame, c) for s in states for c in s.collisions]
    assert [frame for frame, _ in hit] == [8]
    collision = hit[0][1]
    assert (collision.first, collision.second) == (EGO_ID, car)
    assert collision.closing_speed == pytest.approx(10.0, abs=1e-6)
    assert collision.geometry and collision.highway_env
    assert "ego_crashed" in states[7].events
    at_hit, last = states[7], states[-1]
    assert (last.ego.x, last.ego.y) == (at_hit.ego.x, at_hit.ego.y) and (last.ego.vx, last.ego.vy) == (0.0, 0.0)
    assert last.actor_ids.tolist() == [car] and np.array_equal(last.boxes[0, :2], at_hit.boxes[0, :2])
    assert np.all(last.boxes[0, 7:9] == 0.0)
    world.close()


def test_two_other_vehicles_that_collide_are_rows_of_the_dataset_not_only_manifest_events(tmp_path, monkeypatch):
    from simrig.pipeline.generate import generate

    crashed = _plant_a_crash_at_frame_1(monkeypatch)
    scenario = with_setting(load_scenario("highway_surround6"), "render.visibility", False)
    generate(scenario, seed=0, out=tmp_path / "ds", frames=4)
    rows = Dataset.open(tmp_path / "ds").table("collisions").to_pylist()
    assert [(r["frame"], r["first"], r["second"], r["geometry"], r["highway_env"]) for r in rows] == [
        (1, *crashed, True, True)]
    assert 4.0 < rows[0]["closing_speed"] <= 5.0 + 1e-9  # 5 m/s less what IDM braking took off in one step


def test_a_scenario_that_refuses_crashes_stops_at_the_first_one_and_leaves_no_dataset(tmp_path, monkeypatch):
    from simrig.errors import TrafficCrashError
    from simrig.pipeline.generate import generate

    crashed = _plant_a_crash_at_frame_1(monkeypatch)
    scenario = with_setting(with_setting(load_scenario("highway_surround6"), "render.visibility", False),
                            "traffic.crashes", "refused")
    with pytest.raises(TrafficCrashError) as refused:
        generate(scenario, seed=0, out=tmp_path / "ds", frames=4)
    assert str(refused.value).startswith(f"highway_surround6: seed 0: vehicles {crashed[0]} and {crashed[1]} "
                                         "collide at frame 1, and the scenario refuses crashes")
    assert not (tmp_path / "ds").exists() and list(tmp_path.iterdir()) == []


def _plant_a_crash_at_frame_1(monkeypatch) -> list[int]:
    """Two other vehicles placed 0.3 m apart, the one behind 5 m/s faster: they collide in the first step.
    Returns their ids, sorted (filled in when the world is reset)."""
    reset = TrafficWorld.reset
    crashed: list[int] = []

    def reset_then_crash(self):
        state = reset(self)
        a, b = [v for v in self.env.unwrapped.road.vehicles if v is not self.ego][:2]
        gap = 0.3  # [m] between b's front and a's rear; b is 5 m/s faster: it closes ≥ 0.44 m in the step
        b.position = a.position - ((a.LENGTH + b.LENGTH) / 2.0 + gap) * a.direction
        b.heading, b.speed = a.heading, a.speed + 5.0
        crashed.extend(sorted((a.simrig_id, b.simrig_id)))
        return state

    monkeypatch.setattr(TrafficWorld, "reset", reset_then_crash)
    return crashed


def test_a_run_refused_for_a_crash_leaves_no_run_folder(tmp_path, capsys):
    """``simrig run`` of a scenario that refuses crashes, on a seed whose traffic crashes: one line, and the run
    folder it would have made is not left behind (empty)."""
    from simrig.cli import main

    (tmp_path / "no_crash.toml").write_text('extends = "intersection_surround6"\nname = "no_crash"\n'
                                            '[render]\nvisibility = false\n[traffic]\ncrashes = "refused"\n')
    out = tmp_path / "run"
    assert main(["run", str(tmp_path / "no_crash.toml"), "--seed", "0", "--frames", "20", "--out", str(out),
                 "--quiet"]) == 2
    assert "collide at frame 18, and the scenario refuses crashes" in capsys.readouterr().err
    assert not out.exists()


CRASHING_SUITE = """
name = "crashes"
scenarios = ["no_crash.toml"]
seeds = [0, 1]
frames = 20

[[trackers]]
tracker = "global_hungarian"
"""


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
@pytest.mark.parametrize("crashes", ["refused", "allowed"])
def test_a_bench_records_a_refused_crash_as_that_cells_failure_and_counts_allowed_ones(crashes, tmp_path):
    """intersection_surround6 seed 0: two other vehicles collide at frame 18 (seed 1: none in 20 frames)."""
    import pyarrow.parquet as pq

    from simrig.benchmark import run_bench

    (tmp_path / "no_crash.toml").write_text(f'extends = "intersection_surround6"\nname = "no_crash"\n'
                                            f'[render]\nvisibility = false\n[traffic]\ncrashes = "{crashes}"\n')
    (tmp_path / "suite.toml").write_text(CRASHING_SUITE)
    rows = {row["seed"]: row for row in pq.read_table(run_bench(tmp_path / "suite.toml", out=tmp_path / "bench",
                                                                workers=1).results).to_pylist()}
    assert rows[1]["failure"] is None and rows[1]["traffic_crashes"] == 0 and rows[1]["3d_AMOTA"] >= 0
    if crashes == "refused":
        assert rows[0]["failure"].startswith("traffic crash: no_crash: seed 0: vehicles ")
        assert "collide at frame 18" in rows[0]["failure"] and rows[0]["3d_AMOTA"] is None  # NaN: null
        from simrig.report import write_report

        text = write_report(tmp_path / "bench").read_text()
        assert "## Rows without metrics" in text and "| global_hungarian | no_crash | 0 | - | traffic crash: " in text
    else:
        assert rows[0]["failure"] is None and rows[0]["traffic_crashes"] == 1


class Blind:
    """A tracker that reports nothing: the ego drives as if the road were empty."""

    def reset(self, *, rig, seed=None):
        pass

    def step(self, frame):
        return []


def _first_overlap_frame(dataset: Dataset) -> int | None:
    """The first frame where the ego's footprint and any ground-truth box's touch, by highway-env's polygon test on
    the recorded boxes (the ego's box: the car class size at the ego pose)."""
    truth = dataset.ground_truth
    for position, frame in enumerate(truth.frames):
        ego = truth.egos[position]
        mine = (ego.x, ego.y, ego.yaw, EGO_SPEC.length, EGO_SPEC.width)
        for box in truth.boxes[truth.frame == frame]:
            if _highway_env_says(mine, (box[0], box[1], box[6], box[3], box[4])):
                return int(frame)
    return None


@pytest.fixture(scope="module")
def lead_brake():
    return with_setting(load_scenario("lead_brake"), "render.visibility", False)


def test_a_tracker_that_sees_nothing_collides_on_lead_brake_and_the_ground_truth_does_not(lead_brake, tmp_path):
    blind = drive(lead_brake, seed=200, out=tmp_path / "blind", frames=100, tracker=Blind())
    truth = drive(lead_brake, seed=200, out=tmp_path / "truth", frames=100)
    assert blind.outcome.collisions >= 1 and truth.outcome.collisions == 0
    assert blind.outcome.collision_frame == _first_overlap_frame(Dataset.open(blind.dataset))
    assert _first_overlap_frame(Dataset.open(truth.dataset)) is None
    assert blind.outcome.collision_speed_mps > 1.0 and blind.outcome.collision_actor >= 0
    moved = np.hypot(*np.diff(np.array([(e.x, e.y) for e in Dataset.open(blind.dataset).ground_truth.egos]),
                              axis=0).T)
    assert np.all(moved[blind.outcome.collision_frame:] == 0.0)  # no progress after the collision
    assert blind.outcome.progress_m < truth.outcome.progress_m


@pytest.mark.slow
def test_saga_on_lead_brake_seed_200_reports_the_frame_its_footprints_first_overlap(lead_brake, tmp_path):
    result = drive(lead_brake, seed=200, out=tmp_path / "saga", frames=100, tracker="saga")
    assert result.outcome.collision_frame == _first_overlap_frame(Dataset.open(result.dataset))


def _traffic_collisions(name: str, seed: int, blind: bool) -> list:
    scenario = load_scenario(name)
    streams = RandomStreams(seed)
    from simrig.pipeline.generate import _SimulatedWorld  # the generator's own world, as a dataset is made

    world = _SimulatedWorld(with_setting(scenario, "render.visibility", False), None, streams, False,
                            ego_on_perception=blind).traffic
    found = []
    state = world.reset()
    for _ in range(scenario.frames - 1):
        if blind:
            world.perceive(np.zeros((0, 9)), np.zeros(0, np.int64))
        state = world.step()
        found += state.collisions
    world.close()
    return found


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(catalog()))
def test_geometry_and_highway_envs_flag_agree_on_every_catalog_scenario(name):
    """Seeds 100-104 as the catalog drives them, and again with a blind ego (so that collisions happen)."""
    found = [c for seed in range(100, 105) for blind in (False, True) for c in _traffic_collisions(name, seed, blind)]
    assert all(c.geometry and c.highway_env for c in found), [c for c in found if not (c.geometry and c.highway_env)]


def test_closing_speed_is_along_the_contact_normal_worked_out_by_hand():
    """Side by side, b 1.8 m to a's left (0.1 m of overlap across, 3.6 m along): the contact normal is across, and
    b drifting right at 1.5 m/s closes at 1.5 m/s whatever both do along the road."""
    from simrig.world.collisions import closing_speeds

    centres = np.array([[0.0, 0.0], [1.0, 1.8]])
    size = (np.zeros(2), np.full(2, 4.6), np.full(2, 1.9))
    assert touching_pairs(centres, *size).tolist() == [[0, 1]]
    speed = closing_speeds(centres, *size, np.array([[20.0, 0.0], [25.0, -1.5]]), np.array([[0, 1]]))
    assert speed.tolist() == pytest.approx([1.5])
