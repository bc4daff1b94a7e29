"""Capture timing: cameras that fire at their own times, detections that arrive late, an estimated ego pose.

Expected values come from arithmetic on hand-built scenes (a car at constant velocity: where it is at each
camera's capture time) and from invariants (a detection's position relative to the pose the tracker is given
equals the true position relative to the true pose)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from simrig.scenarios import ScenarioError, load_scenario
from simrig.scenarios.schema import Scenario

from simrig.dataset import Dataset
from simrig.geometry import project_boxes
from simrig.pipeline.generate import generate
from simrig.render.visibility import Visibility
from simrig.rig import build_rig
from simrig.seeding import RandomStreams
from simrig.sensor.capture import as_estimated, sweep_order
from simrig.sensor.model import SensorModel
from simrig.types import EgoPose, GroundTruthFrame

TWO_CAMERAS = {"preset": "custom", "cameras": [
    {"name": "A", "yaw_deg": 10.0, "hfov_deg": 60.0, "x_m": 1.5},
    {"name": "B", "yaw_deg": -10.0, "hfov_deg": 60.0, "x_m": 1.5},
]}
CAR = np.array([[30.0, 1.0, 0.8, 4.5, 1.9, 1.6, 0.1, 25.0, 3.0]])  # ahead of both cameras, moving at (25, 3) m/s
EGO = EgoPose(0.0, 0.0, 0.0, 0.0, vx=20.0, vy=0.0)


def _two_camera_scenario(**sensor) -> Scenario:
    return Scenario.model_validate({
        "name": "t", "rig": TWO_CAMERAS, "render": {"visibility": False},
        "sensor": {"preset": "perfect", "capture": {"trigger": "given", "offsets_s": {"A": 0.0, "B": 0.04}},
                   **sensor}})


def _observe(scenario: Scenario, boxes=CAR, ego=EGO, frame=0):
    rig = build_rig(scenario.rig)
    state = GroundTruthFrame(frame=frame, timestamp=frame / 10, ego=ego, actor_ids=np.arange(len(boxes)),
                             classes=np.full(len(boxes), "car", dtype=object), boxes=boxes)
    projection = project_boxes(boxes, rig, ego)
    return rig, SensorModel(scenario, rig, RandomStreams(0)).observe(state, projection,
                                                                     Visibility.unmeasured(projection))


def test_two_cameras_40_ms_apart_see_one_car_velocity_times_40_ms_apart():
    rig, output = _observe(_two_camera_scenario())
    batch = output.batch
    assert batch.detected.all()  # the car is in both cameras and the sensor is perfect
    a, b = batch.det_boxes3d[0, 0], batch.det_boxes3d[1, 0]
    np.testing.assert_allclose(b[:2] - a[:2], CAR[0, 7:9] * 0.04, atol=1e-6)  # (1.0, 0.12) m
    np.testing.assert_allclose(a[:3], CAR[0, :3], atol=1e-6)  # camera A fires at the tick
    # each camera's ground truth is the car where it is at that camera's time, seen from where the ego is then
    for index, offset in enumerate((0.0, 0.04)):
        car = CAR.copy()
        car[0, :2] += CAR[0, 7:9] * offset
        ego = EgoPose(EGO.x + EGO.vx * offset, EGO.y, EGO.z, EGO.yaw, EGO.vx, EGO.vy)  # by hand, not .moved()
        np.testing.assert_allclose(output.projection.boxes[index], project_boxes(car, rig, ego).boxes[index],
                                   atol=1e-6)
    assert not np.allclose(output.projection.boxes[1], project_boxes(CAR, rig, EGO).boxes[1], atol=1.0)
    np.testing.assert_allclose(output.captures.offsets, [0.0, 0.04])


def test_a_synchronous_rig_sees_every_camera_at_the_tick():
    scenario = Scenario.model_validate({"name": "t", "rig": TWO_CAMERAS, "render": {"visibility": False},
                                        "sensor": {"preset": "perfect"}})
    _, output = _observe(scenario)
    np.testing.assert_allclose(output.batch.det_boxes3d[:, 0, :3], np.repeat(CAR[:, :3], 2, axis=0), atol=1e-6)
    assert output.captures is None and output.ego_estimate is None


def test_a_sweep_fires_clockwise_from_the_front_evenly_over_its_spread():
    rig = build_rig(load_scenario("highway_surround6").rig)
    assert sweep_order(rig) == ("CAM_FRONT", "CAM_FRONT_RIGHT", "CAM_BACK_RIGHT", "CAM_BACK", "CAM_BACK_LEFT",
                                "CAM_FRONT_LEFT")
    scenario = Scenario.model_validate({"name": "t", "render": {"visibility": False},
                                        "sensor": {"capture": {"trigger": "sweep", "spread_s": 0.05}}})
    _, output = _observe(scenario, ego=EgoPose(0, 0, 0, 0))
    offsets = dict(zip(rig.camera_names, output.captures.offsets, strict=True))
    assert offsets == pytest.approx({"CAM_FRONT": 0.0, "CAM_FRONT_RIGHT": 0.01, "CAM_BACK_RIGHT": 0.02,
                                     "CAM_BACK": 0.03, "CAM_BACK_LEFT": 0.04, "CAM_FRONT_LEFT": 0.05})


def test_clock_skew_changes_the_reported_time_not_where_the_camera_saw_the_car():
    skewed = _two_camera_scenario(capture={"trigger": "given", "offsets_s": {"B": 0.04}, "clock_skew_s": {"B": 0.01}})
    _, output = _observe(skewed)
    np.testing.assert_allclose(output.captures.reported, [0.0, 0.05])
    np.testing.assert_allclose(output.batch.det_boxes3d[1, 0, :2], CAR[0, :2] + CAR[0, 7:9] * 0.04, atol=1e-6)


def test_detections_are_placed_with_the_estimated_ego_pose():
    scenario = _two_camera_scenario(ego_pose={"noise_m": 0.5, "noise_yaw_deg": 2.0})
    _, output = _observe(scenario, ego=EgoPose(5.0, -2.0, 0.0, 0.3, 20.0, 0.0))
    true, estimate = EgoPose(5.0, -2.0, 0.0, 0.3, 20.0, 0.0), output.ego_estimate
    assert estimate != true
    # invariant: relative to the pose the tracker is given, a detection is where the car truly is relative to the ego
    for camera, offset in enumerate((0.0, 0.04)):
        detection = output.batch.det_boxes3d[camera, 0]
        car = CAR[0, :2] + CAR[0, 7:9] * offset
        seen = _in_ego(detection[:2], estimate)
        np.testing.assert_allclose(seen, _in_ego(car, true), atol=1e-6)
        assert detection[6] == pytest.approx(CAR[0, 6] + estimate.yaw - true.yaw)


def _in_ego(point, ego: EgoPose) -> np.ndarray:
    c, s = math.cos(ego.yaw), math.sin(ego.yaw)
    dx, dy = point[0] - ego.x, point[1] - ego.y
    return np.array([c * dx + s * dy, -s * dx + c * dy])


def test_as_estimated_with_the_true_pose_is_the_identity():
    ego = EgoPose(3.0, 4.0, 0.0, 1.0, 2.0, 1.0)
    np.testing.assert_allclose(as_estimated(CAR, ego, ego), CAR, atol=1e-12)


# ---------------------------------------------------------------------------------------------- the pipeline
SMALL = """extends = "highway_surround6"
frames = 24
[traffic]
vehicles = 12
window_radius_m = 90.0
spawn_min_distance_m = 60.0
[render]
visibility = false
[sensor.capture]
trigger = "sweep"
spread_s = 0.05
jitter_s = 0.002
clock_skew_s = { CAM_BACK = 0.004 }
[sensor.latency]
fixed_s = 0.07
random_s = 0.03
by_camera_s = { CAM_FRONT_LEFT = 0.1 }
[sensor.ego_pose]
noise_m = 0.05
drift_m_per_sqrt_s = 0.3
drift_yaw_deg_per_sqrt_s = 0.2
"""


@pytest.fixture(scope="module")
def timed(tmp_path_factory):
    folder = tmp_path_factory.mktemp("timed")
    (folder / "timed.toml").write_text(SMALL)
    scenario = load_scenario(folder / "timed.toml")
    dataset = Dataset.open(generate(scenario, seed=5, out=folder / "all").path)
    return scenario, dataset, folder


def _table(dataset: Dataset, name: str):
    return dataset.table(name).to_pandas()


def test_each_detection_reaches_the_tracker_at_its_arrival_frame_with_its_capture_time(timed):
    _, dataset, _ = timed
    captures = _table(dataset, "captures")
    detections = _table(dataset, "detections")
    assert (captures["arrival_frame"] > captures["frame"]).any()  # the latency makes some late
    arrival = captures.set_index(["frame", "camera"])["arrival_frame"]
    reported = captures.set_index(["frame", "camera"])["reported_time"]
    expected: dict[int, list] = {}
    for row in detections.itertuples():
        expected.setdefault(int(arrival[(row.frame, row.camera)]), []).append(
            (row.camera, float(reported[(row.frame, row.camera)]), row.frame < arrival[(row.frame, row.camera)],
             round(row.x1, 9)))
    names = dataset.rig.camera_names
    seen = 0
    for frame in dataset.sensor_frames():
        arrays = frame.arrays
        got = sorted((names[c], float(t), bool(late), round(float(x1), 9)) for c, t, late, x1 in zip(
            arrays.cameras, arrays.capture_times, arrays.late, arrays.boxes2d[:, 0], strict=True))
        assert got == sorted(expected.get(frame.frame, [])), frame.frame
        assert np.all(np.diff(arrays.cameras) >= 0)  # rig order, as for a synchronous rig
        seen += len(arrays)
    assert seen == sum(len(v) for k, v in expected.items() if k < dataset.frame_count)
    # CAM_FRONT_LEFT's 0.1 s extra delay: never on time
    assert (captures.loc[captures.camera == "CAM_FRONT_LEFT", "arrival_frame"] > captures.loc[
        captures.camera == "CAM_FRONT_LEFT", "frame"]).all()


def test_the_tracker_is_given_the_estimated_pose_and_ground_truth_keeps_the_true_one(timed):
    _, dataset, _ = timed
    estimates = _table(dataset, "ego_estimates")
    true = _table(dataset, "ego_poses")
    given = [frame.ego for frame in dataset.sensor_frames()]
    assert [ego.x for ego in given] == estimates["x"].tolist()
    assert [ego.x for ego in dataset.ground_truth.egos] == true["x"].tolist()
    assert (estimates["x"] - true["x"]).abs().max() > 0.01


def test_captures_follow_the_schedule(timed):
    scenario, dataset, _ = timed
    captures = _table(dataset, "captures")
    tick = captures["frame"] / scenario.frame_rate_hz
    offset = (captures["capture_time"] - tick).to_numpy().reshape(-1, 6)
    base = np.array([0.0, 0.05, 0.04, 0.03, 0.02, 0.01])  # rig order: FRONT, FRONT_LEFT, BACK_LEFT, BACK, ...
    assert np.abs(offset - base).max() <= 3 * 0.002 + 1e-12 and np.abs(offset - base).max() > 0
    skew = (captures["reported_time"] - captures["capture_time"]).to_numpy().reshape(-1, 6)
    np.testing.assert_allclose(skew, np.tile([0, 0, 0, 0.004, 0, 0], (len(skew), 1)), atol=1e-12)


def test_the_ground_truth_of_each_camera_is_at_its_capture_time(timed):
    _, dataset, _ = timed
    truth = dataset.ground_truth
    offsets = truth.capture_offsets
    for frame in list(dataset.ground_truth_frames())[::7]:
        position = int(np.searchsorted(truth.frames, frame.frame))
        for index, name in enumerate(dataset.rig.camera_names):
            delta = offsets[position, index]
            moved = np.array(frame.boxes, copy=True)
            moved[:, :2] += moved[:, 7:9] * delta
            ego = frame.ego
            at = EgoPose(ego.x + ego.vx * delta, ego.y + ego.vy * delta, ego.z, ego.yaw, ego.vx, ego.vy)
            np.testing.assert_allclose(frame.cameras[name].boxes, project_boxes(moved, dataset.rig, at).boxes[index],
                                       atol=1e-6)


def test_same_seed_same_bytes_and_the_timing_draws_follow_the_seed(timed, tmp_path):
    scenario, dataset, _ = timed
    again = Dataset.open(generate(scenario, seed=5, out=tmp_path / "again").path)
    other = Dataset.open(generate(scenario, seed=6, out=tmp_path / "other").path)
    assert again.manifest["files"] == dataset.manifest["files"]
    for table in ("captures", "ego_estimates"):
        assert other.manifest["files"][table]["sha256"] != dataset.manifest["files"][table]["sha256"]


def test_each_timing_cause_is_a_cause_group(timed):
    from simrig.sensor.groups import present_groups

    scenario, _, _ = timed
    assert {"trigger", "latency", "ego_pose"} <= set(present_groups(scenario, 6))
    assert not {"trigger", "latency", "ego_pose"} & set(present_groups(load_scenario("highway_surround6"), 6))


def test_another_process_makes_the_same_bytes(timed):
    import os
    import subprocess
    import sys

    _, dataset, folder = timed
    env = {**os.environ, "PYOPENGL_PLATFORM": "egl"}
    subprocess.run([sys.executable, "-m", "simrig.cli", "generate", str(folder / "timed.toml"), "--seed", "5", "--out",
                    str(folder / "other-process"), "--quiet"], check=True, env=env, capture_output=True)
    other = Dataset.open(folder / "other-process")
    assert other.manifest["files"] == dataset.manifest["files"]


def _removed(timed, group) -> Dataset:
    scenario, dataset, folder = timed
    return Dataset.open(generate(scenario, seed=5, out=folder / group, world_from=dataset,
                                 removed=frozenset({group})).path)


def test_removing_the_latency_changes_only_when_detections_arrive(timed):
    _, dataset, _ = timed
    removed = _removed(timed, "latency")
    for table in ("detections", "sensor_truth", "projections", "ego_estimates", "ground_truth"):
        assert removed.manifest["files"][table]["sha256"] == dataset.manifest["files"][table]["sha256"], table
    before, after = _table(dataset, "captures"), _table(removed, "captures")
    assert before.drop(columns="arrival_frame").equals(after.drop(columns="arrival_frame"))
    assert (after["arrival_frame"] == after["frame"]).all()


def test_removing_the_ego_pose_error_moves_detections_back_by_exactly_the_pose_error(timed):
    _, dataset, _ = timed
    removed = _removed(timed, "ego_pose")
    for table in ("captures", "sensor_truth", "projections"):
        assert removed.manifest["files"][table]["sha256"] == dataset.manifest["files"][table]["sha256"], table
    poses, estimates = _table(dataset, "ego_poses"), _table(dataset, "ego_estimates")
    np.testing.assert_allclose(_table(removed, "ego_estimates")[["x", "y", "yaw"]], poses[["x", "y", "yaw"]])
    before, after = _table(dataset, "detections"), _table(removed, "detections")
    fields = ["x", "y", "z", "length", "width", "height", "yaw", "vx", "vy"]
    for frame in range(0, dataset.frame_count, 5):
        rows = before.frame == frame
        true = EgoPose(*poses.loc[frame, ["x", "y", "z", "yaw", "vx", "vy"]])
        estimate = EgoPose(*estimates.loc[frame, ["x", "y", "z", "yaw", "vx", "vy"]])
        np.testing.assert_allclose(as_estimated(after.loc[rows, fields].to_numpy(), true, estimate),
                                   before.loc[rows, fields].to_numpy(), atol=1e-9)
    assert before.drop(columns=fields).equals(after.drop(columns=fields))


def test_removing_the_trigger_offsets_leaves_the_other_draws(timed):
    _, dataset, _ = timed
    removed = _removed(timed, "trigger")
    assert removed.manifest["files"]["ego_estimates"]["sha256"] == dataset.manifest["files"]["ego_estimates"]["sha256"]
    captures = _table(removed, "captures")
    tick = captures["frame"] / 10.0
    np.testing.assert_allclose(captures["capture_time"], tick, atol=1e-12)
    np.testing.assert_allclose(captures["reported_time"], tick, atol=1e-12)
    # the random latency draws are the same: a capture at the tick arrives no later than one taken after it
    assert (captures["arrival_frame"] <= _table(dataset, "captures")["arrival_frame"]).all()
    # the detector's own draws do not depend on the timing: a detection decided with the same probability is
    # decided the same way
    key = ["frame", "camera", "actor_id"]
    before = _table(dataset, "sensor_truth").set_index(key)
    after = _table(removed, "sensor_truth").set_index(key)
    real = before.index.get_level_values("actor_id") >= 0
    same_p = (before.loc[real, "probability"] == after.loc[before.index[real], "probability"]).to_numpy()
    decided = before.loc[real, "detection"].to_numpy() >= 0
    assert same_p.sum() > 100
    assert np.array_equal(decided[same_p], after.loc[before.index[real], "detection"].to_numpy()[same_p] >= 0)


def test_a_scenario_without_timing_stores_no_trace_of_it(tmp_path):
    scenario = load_scenario("highway_surround6")
    assert "capture" not in scenario.model_dump(mode="json")["sensor"]
    dataset = Dataset.open(generate(scenario, seed=1, out=tmp_path / "d", frames=3).path)
    assert not dataset.has_table("captures") and not dataset.has_table("ego_estimates")
    assert dataset.ground_truth.capture_offsets is None
    frames = list(dataset.sensor_frames())
    assert all(np.isnan(f.arrays.capture_times).all() and not f.arrays.late.any() for f in frames)


@pytest.mark.parametrize(("text", "expected"), [
    ("[sensor.latency]\nfixed_s = -0.1", "sensor.latency.fixed_s: Input should be greater than or equal to 0"),
    ('[sensor.capture]\ntrigger = "sweep"\norder = ["CAM_FRONT", "CAM_BACK", "CAM_FRONT"]',
     "sensor.capture.order: camera 'CAM_FRONT' named twice"),
    ("frames = 20\n[sensor.latency]\nfixed_s = 2.5",
     "sensor.latency.fixed_s: a latency of 2.5 s is longer than the run (20 frames, 2 s)"),
    ("frames = 20\n[sensor.latency]\nfixed_s = 1.0\nby_camera_s = { CAM_BACK = 1.0 }",
     "sensor.latency.by_camera_s.CAM_BACK: a latency of 2 s is longer than the run"),
    ('[sensor.capture]\ntrigger = "sweep"\nspread_s = 0.12', "sensor.capture.spread_s: the last capture of a frame"),
    ("[sensor.capture]\njitter_s = 0.05", "sensor.capture.jitter_s: the last capture of a frame"),
    ("[sensor.capture]\nspread_s = 0.04", "sensor.capture.spread_s: only a 'sweep' trigger takes it"),
    ("[sensor.ego_pose]\nnoise_m = -1", "sensor.ego_pose.noise_m: Input should be greater than or equal to 0"),
    ('[sensor.capture]\ntrigger = "given"\noffsets_s = { CAM_FRONT = -0.01 }',
     "sensor.capture.offsets_s.CAM_FRONT: Input should be greater than or equal to 0"),
    ("[sensor.latency]\nrandom_s = nan", "sensor.latency.random_s"),
    ("[sensor.capture]\nrate_hz = { CAM_BACK = -5.0 }",
     "sensor.capture.rate_hz.CAM_BACK: Input should be greater than 0"),
    ("[sensor.capture]\nrate_hz = { CAM_BACK = 3.0 }",
     "sensor.capture.rate_hz.CAM_BACK: 3 Hz does not divide the frame rate (10 Hz)"),
    ("[sensor.capture]\nrate_hz = { CAM_BACK = 20.0 }", "sensor.capture.rate_hz.CAM_BACK: 20 Hz does not divide"),
    ('[sensor.capture]\ntrigger = "given"', "sensor.capture.offsets_s: a 'given' trigger needs the offset of at least"),
])
def test_bad_timing_settings_get_one_line_naming_the_key(tmp_path, text, expected):
    (tmp_path / "bad.toml").write_text(f'name = "bad"\n{text}\n')
    with pytest.raises(ScenarioError) as caught:
        load_scenario(tmp_path / "bad.toml")
    message = str(caught.value)
    assert expected in message and "\n" not in message and "(top level)" not in message, message


def test_a_camera_slower_than_the_frame_rate_takes_an_image_every_n_th_frame(tmp_path):
    from simrig.dataset.ground_truth import project_tracks
    from simrig.dataset.tracks_file import TrackRows

    (tmp_path / "slow.toml").write_text(SMALL.split("[sensor.capture]")[0]
                                        + "[sensor.capture]\nrate_hz = { CAM_BACK = 5.0, CAM_FRONT = 2.5 }\n")
    dataset = Dataset.open(generate(load_scenario(tmp_path / "slow.toml"), seed=2, out=tmp_path / "d").path)
    captures = _table(dataset, "captures")
    every = {"CAM_BACK": 2, "CAM_FRONT": 4}
    expected = [frame % every.get(camera, 1) == 0 for frame, camera in zip(captures.frame, captures.camera,
                                                                            strict=True)]
    assert captures["fired"].tolist() == expected
    detections = _table(dataset, "detections")
    shot = {(f, c) for f, c, fired in zip(captures.frame, captures.camera, captures.fired, strict=True) if fired}
    assert set(zip(detections.frame, detections.camera, strict=True)) <= shot
    assert {c for f, c in zip(detections.frame, detections.camera, strict=True)} >= {"CAM_BACK", "CAM_FRONT"}
    projections = _table(dataset, "projections")
    seen = {(f, c) for f, c, v in zip(projections.frame, projections.camera, projections.in_view, strict=True) if v}
    assert seen <= shot and {c for _, c in seen} >= {"CAM_BACK", "CAM_FRONT"}  # no image, no ground truth in view
    truth = dataset.ground_truth  # a 3D tracker reporting the ground truth is projected only where an image was
    rows = TrackRows(truth.frame, truth.actor_id, truth.label, np.ones(len(truth.frame)), truth.boxes)
    projected = project_tracks(truth, rows)
    assert set(zip(projected.frame, projected.camera, strict=True)) == seen


@pytest.mark.parametrize(("sensor", "frames", "expected"), [
    ({"latency": {"by_camera_s": {"CAM_MIDDLE": 0.1}}}, 2,
     "sensor.latency.by_camera_s: rig 'surround6' has no camera 'CAM_MIDDLE'"),
    ({"capture": {"trigger": "sweep", "order": ["CAM_FRONT", "CAM_BACK"]}}, 2,
     "sensor.capture.order: names 2 of the rig's 6 cameras (not CAM_FRONT_LEFT, CAM_BACK_LEFT, CAM_BACK_RIGHT, "
     "CAM_FRONT_RIGHT); name every camera"),
    ({"latency": {"fixed_s": 5.0}}, 10,  # the scenario's 200 frames would do; the 10 asked for would not
     "sensor.latency.fixed_s: a latency of 5 s is longer than the run (10 frames, 1 s)"),
])
def test_settings_that_depend_on_the_rig_or_the_run_are_checked_before_any_work(tmp_path, sensor, frames, expected):
    scenario = Scenario.model_validate({"name": "t", "render": {"visibility": False}, "sensor": sensor})
    with pytest.raises(ScenarioError) as caught:
        generate(scenario, seed=0, out=tmp_path / "x", frames=frames)
    assert expected in str(caught.value), caught.value
    assert not (tmp_path / "x").exists()


# ---------------------------------------------------------------------------------------------- the trackers
def _moving_car_frames(*, late: bool):
    """A car at a constant (30, 0) m/s, 20 m ahead of a still ego, seen by cameras A (at the tick) and B (40 ms
    after it, with the higher score: the one an NMS keeps), exactly; ``late``: every detection is delivered one
    frame after its capture."""
    from simrig.types import DetectionArrays, SensorFrame

    rig = build_rig(Scenario.model_validate({"name": "t", "rig": TWO_CAMERAS}).rig)
    ego = EgoPose(0.0, 0.0, 0.0, 0.0)

    def car_at(t):
        return np.array([20.0 + 30.0 * t, 0.0, 0.8, 4.5, 1.9, 1.6, 0.0, 30.0, 0.0])

    frames = []
    for k in range(30):
        captured = k - 1 if late else k
        if captured < 0:
            arrays = DetectionArrays.empty()
        else:
            times = np.array([captured / 10, captured / 10 + 0.04])
            arrays = DetectionArrays(np.stack([car_at(t) for t in times]), np.array([[0, 0, 10, 10.0]] * 2),
                                     np.array([0.8, 0.95]), np.zeros(2, dtype=np.int64), np.array([0, 1]),
                                     capture_times=times, late=np.full(2, late))
        frames.append((SensorFrame(k, k / 10, ego, rig, arrays=arrays), car_at(k / 10)))
    return rig, frames


@pytest.mark.parametrize("name", ["saga", "polymot", "global_hungarian", "mutr3d", "simpletrack"])
@pytest.mark.parametrize("late", [False, True])
def test_reference_trackers_predict_tracks_to_each_capture_time(name, late):
    from simrig.trackers import registry

    rig, frames = _moving_car_frames(late=late)
    errors = {}
    for compensation in (True, False):
        tracker = registry.create(name, motion_compensation=compensation)
        tracker.reset(rig=rig, seed=0)
        ids, error = set(), []
        for frame, truth in frames:
            tracks = tracker.step(frame)
            ids |= {track.track_id for track in tracks}
            if frame.frame >= 15 and tracks:
                error.append(max(abs(track.box3d.x - truth[0]) for track in tracks))
        errors[compensation] = (len(ids), max(error) if error else np.inf)
    ids, error = errors[True]
    # every track where the car is at the frame's time (global_hungarian, one-to-one, also starts a second
    # track from the second camera's detection: that is its own rule, not the timing's)
    assert ids == (2 if name == "global_hungarian" else 1) and error < 0.1, errors
    # taken at the frame's time, B's detections (1.2 m ahead) pull the track forward; late ones (3 m behind) back
    assert errors[False][1] > (1.0 if late else 0.3), errors


def test_tracks_made_with_the_estimated_pose_are_scored_relative_to_the_ego(timed):
    from simrig.dataset.ground_truth import relative_to_true_ego
    from simrig.dataset.tracks_file import TrackRows

    _, dataset, _ = timed
    truth = dataset.ground_truth
    assert truth.given_egos is not None
    # a tracker that reports every car exactly where the estimated pose puts it
    position = np.searchsorted(truth.frames, truth.frame)
    reported = np.concatenate([as_estimated(truth.boxes[position == i], truth.egos[i], truth.given_egos[i])
                               for i in range(len(truth.frames))])
    assert np.abs(reported[:, :2] - truth.boxes[:, :2]).max() > 0.1
    rows = TrackRows(truth.frame, truth.actor_id, truth.label, np.ones(len(truth.frame)), reported)
    np.testing.assert_allclose(relative_to_true_ego(truth, rows).boxes, truth.boxes, atol=1e-9)


def test_a_search_space_can_vary_the_timing(tmp_path):
    from simrig.search import load_space

    (tmp_path / "space.toml").write_text("""
name = "timing"
base = "sweep_surround6"
frames = 20
tracker = "saga"
budget = 3
seeds = 1

[base_settings]
"render.visibility" = false

[objective]
metric = "3d_AMOTA"
direction = "minimize"
failure = { metric = "3d_IDS", at_least = 1 }

[[dimensions]]
path = "sensor.capture.spread_s"
low = 0.0
high = 0.08

[[dimensions]]
path = "sensor.latency.fixed_s"
low = 0.0
high = 0.3

[[dimensions]]
path = "sensor.ego_pose.drift_m_per_sqrt_s"
low = 0.0
high = 1.0
""")
    space = load_space(tmp_path / "space.toml")
    scenario = space.scenario_for({"sensor.capture.spread_s": 0.07, "sensor.latency.fixed_s": 0.25,
                                   "sensor.ego_pose.drift_m_per_sqrt_s": 0.5})
    assert (scenario.sensor.capture.spread_s, scenario.sensor.latency.fixed_s,
            scenario.sensor.ego_pose.drift_m_per_sqrt_s) == (0.07, 0.25, 0.5)
    assert scenario.sensor.capture.trigger == "sweep"  # the base scenario's own settings kept


def test_the_dataset_summary_says_how_late_the_detections_are(timed):
    _, dataset, _ = timed
    captures = _table(dataset, "captures").set_index(["frame", "camera"])["arrival_frame"]
    detections = _table(dataset, "detections")
    arrival = captures.loc[list(zip(detections.frame, detections.camera, strict=True))].to_numpy()
    late, never = int((arrival > detections.frame.to_numpy()).sum()), int((arrival >= dataset.frame_count).sum())
    line = next(line for line in dataset.summary().splitlines() if line.startswith("timing"))
    assert f"{late} of {len(detections)} detections late, {never} after the last frame" in line
    assert "ego pose estimated" in line and late > 0
    assert not any(line.startswith("timing") for line in load_summary_of_synchronous(timed).splitlines())


def load_summary_of_synchronous(timed) -> str:
    _, _, folder = timed
    scenario = load_scenario("highway_surround6")
    return Dataset.open(generate(scenario, seed=1, out=folder / "sync-summary", frames=2).path).summary()
