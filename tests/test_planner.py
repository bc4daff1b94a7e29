"""Planner-aware scores (open loop): the ego's own IDM/MOBIL asked on the ground truth and on the tracks.

Expected values come from IDM and MOBIL worked by hand on a one-vehicle road, from the real ego's own commands in a
simulated run, and from invariants of the planner (it reads only the leader and follower in its own and the side
lanes; it keeps no memory of identities)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from simrig.scenarios import load_scenario
from simrig.scenarios.schema import TrafficConfig

from simrig.classes import CLASS_SPECS
from simrig.dataset import Dataset
from simrig.dataset.ground_truth import load_ground_truth
from simrig.dataset.tracks_file import read_tracks, write_tracks
from simrig.scoring import score
from simrig.scoring.planner import LANE_SLIP, PlanningRoad, divergence
from simrig.seeding import RandomStreams
from simrig.types import ActorClass, Box3D, EgoPose, Track
from simrig.world import TrafficWorld
from simrig.world.vehicles import JAM_GAP_M

CAR = CLASS_SPECS[ActorClass.CAR]


def _car_box(x: float, y: float, speed: float) -> np.ndarray:
    """A car's world box (:data:`~simrig.types.BOX3D_FIELDS`) heading along +x."""
    return np.array([[x, y, CAR.height / 2, CAR.length, CAR.width, CAR.height, 0.0, speed, 0.0]])


def test_the_plan_is_idm_and_mobil_worked_by_hand():
    """Three lanes, the ego in the middle one at its target speed (IDM's free term 0), one car 60 m ahead at the
    same speed: IDM brakes with 3·(s*/60)², s* = 5 m + one car length + 25 m/s × 1.5 s (Δv = 0); both side lanes
    are empty, so MOBIL's gain is that braking (> 0.2 m/s²) on either side, and highway-env tries the right lane
    last, so it wins; during the change the command is the lower of both lanes' IDM commands."""
    road = PlanningRoad(TrafficConfig(env="highway-v0", lanes=3, ego_lane=1, vehicles=0), 10.0, seed=0)
    ego = road.ego(EgoPose(x=200.0, y=-4.0, z=0.0, yaw=0.0, vx=25.0, vy=0.0))  # lane 1: highway-env y = 4 m
    desired = JAM_GAP_M + CAR.length + 25.0 * 1.5
    expected = -3.0 * (desired / 60.0) ** 2
    plan = road.plan(ego, _car_box(260.0, -4.0, 25.0), np.array([7]))
    assert plan.acceleration == pytest.approx(expected, abs=1e-9)
    assert (plan.lane_change, plan.leader) == (1, 7)
    alone = road.plan(ego, np.zeros((0, 9)), np.zeros(0, np.int64))  # nothing ahead: free road, keep lane
    assert (alone.acceleration, alone.lane_change, alone.leader) == (pytest.approx(0.0, abs=1e-12), 0, -1)
    beside = road.plan(ego, _car_box(200.0 - 30.0, -8.0, 35.0), np.array([3]))  # fast car behind in the right lane
    assert beside.read == frozenset({3}) and beside.lane_change == 0


def test_a_query_leaves_the_world_unchanged_and_gives_the_egos_own_command():
    """A world queried at every frame (the ego's planner on the ground-truth boxes) steps exactly as one that is
    never queried, and each query's acceleration equals the command the real ego gave for that step, bit for bit,
    wherever neither changed lane (the query decides lane changes at every frame; the ego only when its 1 s timer
    is due)."""
    scenario = load_scenario("cut_in")
    streams = RandomStreams(3)

    def world():
        return TrafficWorld(scenario.traffic, scenario.frame_rate_hz, env_seed=streams.integer_seed("traffic"),
                            rng=RandomStreams(3).generator("population"),
                            scripted=tuple(enumerate(scenario.perturbations)))

    queried, plain = world(), world()
    state, reference = queried.reset(), plain.reset()
    road = PlanningRoad(scenario.traffic, scenario.frame_rate_hz, 3)
    compared = 0
    for _ in range(120):
        ego = road.ego(state.ego)
        plan = road.plan(ego, state.boxes, state.actor_ids)
        before = queried.ego.target_lane_index
        state, reference = queried.step(), plain.step()
        assert np.array_equal(state.boxes, reference.boxes) and state.ego == reference.ego
        if plan.lane_change == 0 and queried.ego.target_lane_index == before == queried.ego.lane_index:
            assert plan.acceleration == queried.ego.action["acceleration"]
            compared += 1
    assert compared > 100


def test_divergence_is_the_stated_action_noise_model():
    """Gaussian acceleration noise σ = 1 m/s²: KL = Δa²/2; a different lane decision adds
    (1 − ε)·ln((1 − ε)/(ε/2)) + (ε/2)·ln((ε/2)/(1 − ε)) with ε the slip probability."""
    eps = LANE_SLIP
    lane = (1 - eps) * math.log((1 - eps) / (eps / 2)) + (eps / 2) * math.log((eps / 2) / (1 - eps))
    values = divergence(np.array([2.0, 0.0, 1.0]), np.array([0, 1, -1]), np.array([0.0, 0.0, 0.0]),
                        np.array([0, 0, 1]))
    assert values == pytest.approx([2.0, lane, 0.5 + lane])


@pytest.fixture(scope="module")
def cut_in(tmp_path_factory):
    """``cut_in`` seed 4, 70 frames (the car starts its lane change at frame 40 and is the ego's leader from frame
    43 on; in seed 0 traffic holds it back and it merges behind the ego), visibility not rendered."""
    from simrig.pipeline.generate import generate

    scenario = load_scenario("cut_in")
    scenario = scenario.model_copy(update={"render": scenario.render.model_copy(update={"visibility": False})})
    out = tmp_path_factory.mktemp("planner") / "cut_in"
    generate(scenario, seed=4, out=out, frames=70)
    dataset = Dataset.open(out)
    return dataset, load_ground_truth(dataset)


def _tracks(truth, keep=None, ids=None) -> list[tuple[int, list[Track]]]:
    """The ground truth as tracks (track id = actor id + 1000 unless ``ids`` maps a (frame, actor) to another),
    leaving out the rows where ``keep(frame, actor, box)`` is false."""
    frames = []
    for frame in truth.frames.tolist():
        rows = np.flatnonzero(truth.frame == frame)
        tracks = []
        for r in rows:
            actor = int(truth.actor_id[r])
            if keep is not None and not keep(frame, actor, truth.boxes[r], truth.egos[frame]):
                continue
            ident = (ids or {}).get((frame, actor), actor + 1000)
            tracks.append(Track(ident, ActorClass(truth.label[r]), 0.9, Box3D(*truth.boxes[r].tolist())))
        frames.append((frame, tracks))
    return frames


def _cut_in_actor(dataset) -> int:
    event = next(e["event"] for e in dataset.manifest["events"] if e["event"].startswith("cut_in#0 spawned"))
    return int(event.split("id=")[1].split()[0])


def test_perfect_tracks_plan_exactly_as_the_ground_truth(cut_in, tmp_path):
    dataset, truth = cut_in
    write_tracks(tmp_path / "perfect", _tracks(truth))
    report = score(dataset, tmp_path / "perfect")
    overall = report.metrics3d["overall"]
    assert (overall["PKL"], overall["dACC"], overall["LANE"], overall["HZ_MISS"], overall["HZ_FAKE"]) == (0, 0, 0, 0, 0)
    plan = report.plan.to_pydict()
    assert plan["acceleration_truth"] == plan["acceleration_tracks"] and set(plan["divergence"]) == {0.0}
    assert min(plan["acceleration_truth"]) < -1.0  # the plan is not trivial: the ego brakes for the cut-in


def test_tracks_dropped_where_the_planner_never_looks_cost_nothing_while_hota_falls(cut_in, tmp_path):
    """(a) Every track more than 50 m from the ego dropped: the planner reads the 50 m class range, so the plan
    is the ground truth's at every frame, while HOTA falls (2D, scoring every vehicle in view: the evaluation's
    range rule, which would ignore the far ones as the devkit does, is off). Also every track
    two or more lanes from the ego's dropped (IDM and MOBIL read only the ego's lane and the side lanes): again the
    same plan at every frame, while AMOTA falls too."""
    dataset, truth = cut_in
    write_tracks(tmp_path / "perfect", _tracks(truth))
    perfect = score(dataset, tmp_path / "perfect", evaluation={"ignore": False})

    def near(frame, actor, box, ego):
        return math.hypot(box[0] - ego.x, box[1] - ego.y) <= 50.0

    def nearby_lanes(frame, actor, box, ego):
        return abs(box[1] - ego.y) < 6.0  # lanes are 4 m wide: the ego's lane and one each side

    for name, keep, falls in (("near", near, "HOTA"), ("lanes", nearby_lanes, "AMOTA")):
        write_tracks(tmp_path / name, _tracks(truth, keep))
        report = score(dataset, tmp_path / name, evaluation={"ignore": False})
        overall = report.metrics3d["overall"]
        assert (overall["PKL"], overall["LANE"], overall["HZ_MISS"], overall["HZ_FAKE"]) == (0, 0, 0, 0), name
        dimension = report.metrics2d if falls == "HOTA" else report.metrics3d
        assert dimension["overall"][falls] < (perfect.metrics2d if falls == "HOTA" else perfect.metrics3d)[
            "overall"][falls] - 0.01, name
        errors = report.errors.to_pandas()
        misses = errors[(errors.dimension == "3d") & (errors.kind == "FN")]
        assert set(misses.consequence) <= {0.0}, name  # weighed, and every weight 0


def test_losing_the_lead_vehicle_for_ten_frames_of_the_cut_in_is_a_large_consequence(cut_in, tmp_path):
    """(b) The cut-in car left out of otherwise perfect tracks for the first 10 frames in which it leads the ego:
    the plans differ only in those frames, the ground-truth plan brakes for it where the track-fed one does not
    (missed hazards), and each of those misses weighs exactly its frame's divergence (the tracks are the ground
    truth without that one car); its misses head the error table sorted by consequence. An identity swap of the
    same car with another vehicle, boxes exact, changes nothing: the planner keeps no memory of identities.
    (Scored without the devkit's gap filling, which would count the gap's boxes as found; the planner is always
    given the tracks as the tracker gave them at each frame — a car cannot fill a gap with later tracks.)"""
    dataset, truth = cut_in
    actor = _cut_in_actor(dataset)
    write_tracks(tmp_path / "perfect", _tracks(truth))
    truth_plan = score(dataset, tmp_path / "perfect").plan.to_pandas()
    first = int(truth_plan.frame[truth_plan.leader_truth == actor].min())
    lost = range(first, first + 10)
    write_tracks(tmp_path / "lost", _tracks(truth, lambda f, a, box, ego: not (a == actor and f in lost)))
    report = score(dataset, tmp_path / "lost", interpolation="none")  # the devkit would fill the 10-frame gap
    plan = report.plan.to_pandas()
    assert (plan.divergence[~plan.frame.isin(lost)] == 0).all()
    led = plan[plan.frame.isin(lost) & (plan.leader_truth == actor)]
    assert len(led) == 10 and (led.divergence > 0).all()
    assert (led.hazard == "missed").sum() >= 5 and led.divergence.max() > 5.0
    assert report.metrics3d["overall"]["HZ_MISS"] >= 5
    errors = report.errors.to_pandas()
    misses = errors[(errors.dimension == "3d") & (errors.kind == "FN")].set_index("frame")
    for frame, row in led.set_index("frame").iterrows():
        assert misses.loc[frame, "consequence"] == pytest.approx(row.divergence, abs=1e-12)
    ranked = errors[errors.dimension == "3d"].sort_values("consequence", ascending=False)
    assert set(ranked.head(len(led)).actor_id) == {actor}

    other = next(int(a) for a in truth.actor_id[truth.frame == 45] if a != actor)
    swapped = {(f, a): b + 1000 for f in range(40, 70) for a, b in ((actor, other), (other, actor))}
    write_tracks(tmp_path / "swapped", _tracks(truth, ids=swapped))
    swap = score(dataset, tmp_path / "swapped")
    assert swap.metrics3d["overall"]["IDS"] >= 1
    assert swap.metrics3d["overall"]["PKL"] == 0.0


def test_a_2d_tracker_is_not_planner_scored_and_the_report_says_so(small_dataset, sort_tracks):
    report = score(small_dataset, sort_tracks)
    assert report.metrics3d is None and report.plan is None
    assert "Planner-aware: not scored (2D tracks" in report.table()


def test_every_road_of_the_catalog_is_planned(tmp_path):
    """The planner scores datasets of the other maps too (a roundabout's ego follows a route through its
    segments): perfect tracks plan exactly as the ground truth there."""
    from simrig.scenarios.overrides import with_setting

    from simrig.pipeline.generate import generate

    scenario = with_setting(load_scenario("roundabout_surround6"), "render.visibility", False)
    generate(scenario, seed=100, out=tmp_path / "round", frames=40)
    dataset = Dataset.open(tmp_path / "round")
    truth = load_ground_truth(dataset)
    write_tracks(tmp_path / "perfect", _tracks(truth))
    report = score(dataset, tmp_path / "perfect")
    assert report.metrics3d["planner"] == {"scored": True} and report.metrics3d["overall"]["PKL"] == 0.0
    assert len(report.plan) == 40


def _plain_truth_plans(dataset, truth) -> tuple[list, dict]:
    """The plans on the ground truth and each read vehicle's consequence without the generation's shortcuts: one
    query per frame, and one more per read vehicle, each searching every lane afresh."""
    from simrig.scoring.planner import planner_road_of
    from simrig.scoring.truth_plans import in_range

    road, plans, consequence = planner_road_of(dataset), [], {}
    for position, frame in enumerate(truth.frames.tolist()):
        rows = truth.frame_rows(position)
        keep = in_range(truth.egos[position], truth.label[rows], truth.boxes[rows])
        ego = road.ego(truth.egos[position])
        seen = road.phantoms(truth.boxes[rows][keep], truth.actor_id[rows][keep])
        on_truth = road.plan_on(ego, seen)
        plans.append((on_truth.acceleration, on_truth.lane_change, on_truth.leader))
        for actor in on_truth.read:
            without = road.plan_on(ego, [phantom for phantom in seen if phantom.ident != actor])
            consequence[(frame, actor)] = float(divergence(on_truth.acceleration, on_truth.lane_change,
                                                           without.acceleration, without.lane_change))
    return plans, consequence


@pytest.fixture(scope="module")
def highway(tmp_path_factory):
    """``highway_surround6`` seed 3, 30 frames: 40 vehicles, side lanes full of leaders and followers."""
    from simrig.scenarios.overrides import with_setting

    from simrig.pipeline.generate import generate

    out = tmp_path_factory.mktemp("planner") / "highway"
    generate(with_setting(load_scenario("highway_surround6"), "render.visibility", False), seed=3, out=out, frames=30)
    dataset = Dataset.open(out)
    return dataset, load_ground_truth(dataset)


@pytest.mark.parametrize("scene", ["cut_in", "highway"])
def test_the_plans_a_generation_records_are_the_plain_computation_bit_for_bit(scene, request):
    """Generation records each frame's plan on the ground truth and what missing each vehicle it reads would
    change, with two shortcuts (neighbour searches reused; the ego lane's follower weighs 0 at politeness 0): the
    table equals the plain computation exactly, and the shortcut's zeros are really zeros."""
    from simrig.scoring.truth_plans import recorded_truth_side

    dataset, truth = request.getfixturevalue(scene)
    recorded = recorded_truth_side(dataset, truth)
    plans, consequence = _plain_truth_plans(dataset, truth)
    assert list(zip(recorded.acceleration.tolist(), recorded.lane_change.tolist(), recorded.leader.tolist(),
                    strict=True)) == plans
    assert recorded.consequence == consequence
    weights = np.array(list(consequence.values()))
    assert (weights > 0).any() and (weights == 0).any()  # both kinds of vehicle are read


def test_scores_on_recorded_plans_equal_scores_on_plans_computed_now(cut_in, tmp_path):
    """A dataset without the recorded table (generated before it existed) is scored on plans computed at once: the
    same scores, plan table and consequences."""
    from simrig.scoring.planner import planner_road_of, planner_scores
    from simrig.scoring.truth_plans import computed_truth_side, recorded_truth_side

    dataset, truth = cut_in
    lead = _cut_in_actor(dataset)
    write_tracks(tmp_path / "gappy", _tracks(truth, keep=lambda frame, actor, box, ego: actor != lead or frame % 3))
    report = score(dataset, tmp_path / "gappy", planner=False)
    errors = report.errors.to_pandas()
    misses = errors[(errors.dimension == "3d") & (errors.kind == "FN")][["frame", "actor_id"]].to_numpy()
    tracks3d = read_tracks(tmp_path / "gappy", frame_count=len(truth.frames), cameras=truth.rig.camera_names).tracks3d
    road = planner_road_of(dataset)
    on_recorded = planner_scores(road, truth, tracks3d, misses, recorded_truth_side(dataset, truth))
    on_computed = planner_scores(road, truth, tracks3d, misses, computed_truth_side(road, truth))
    assert on_recorded.metrics == on_computed.metrics and on_recorded.metrics["PKL"] > 0
    assert on_recorded.frames.equals(on_computed.frames)
    assert on_recorded.consequence == on_computed.consequence and max(on_recorded.consequence.values()) > 0
