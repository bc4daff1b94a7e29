"""The detector model: configured rates and noise levels are what comes out, effect by effect."""

import numpy as np
import pytest
from simrig.scenarios import ScenarioError
from simrig.scenarios.schema import RigConfig, Scenario
from simrig.scenarios.sensor_schema import Box3DNoiseConfig, DetectionConfig

from simrig.causes import Cause
from simrig.classes import CLASS_SPECS
from simrig.geometry import camera_from_world, project_boxes
from simrig.render.visibility import Visibility
from simrig.rig import build_rig
from simrig.seeding import RandomStreams
from simrig.sensor.batch import FrameContext, SensorBatch
from simrig.sensor.effects import DetectionDraw, DetectionProbability, Monocular3D
from simrig.sensor.model import SensorModel
from simrig.sensor.processes import GaussMarkov, TwoStateMarkov
from simrig.types import ActorClass, EgoPose, GroundTruthFrame

RIG = build_rig(RigConfig())
EGO = EgoPose(0.0, 0.0, 0.0, 0.0)


def _cars_ahead(distances):
    """Cars straight ahead of the front camera at the given ranges [m] (they overlap: no renderer here)."""
    spec = CLASS_SPECS[ActorClass.CAR]
    front = RIG.cameras[0]
    boxes = np.zeros((len(distances), 9))
    boxes[:, 0] = front.position[0] + np.asarray(distances)
    boxes[:, 2] = front.position[2]  # centre at the camera's height: the range is the x offset
    boxes[:, 3:6] = spec.length, spec.width, spec.height
    return boxes


def _batch(boxes, visible_fraction=1.0):
    """The front camera's batch alone (a rig of one camera: every array has a camera axis of length 1)."""
    n = len(boxes)
    projection = project_boxes(boxes, RIG, EGO)
    world_from_camera = np.linalg.inv(camera_from_world(RIG, EGO))[:1]
    context = FrameContext(0, 0.0, 0.0, np.arange(n, dtype=np.int64), np.hypot(boxes[:, 0], boxes[:, 1]))
    return SensorBatch(
        context=context, cameras=RIG.cameras[:1], world_from_camera=world_from_camera,
        classes=np.full(n, "car", dtype=object), boxes3d=boxes, boxes2d=projection.boxes[:1],
        truncation=projection.truncation[:1], visible_fraction=np.full((1, n), visible_fraction),
        distance=np.linalg.norm(boxes[:, :3] - world_from_camera[:, None, :3, 3], axis=-1),
        in_view=projection.in_view[:1],
    )


@pytest.mark.parametrize("distance", [10.0, 30.0, 50.0])
def test_depth_error_standard_deviation_follows_sigma_of_d(distance):
    config = Box3DNoiseConfig(depth_sigma_m=0.2, depth_sigma_per_m=0.03)
    batch = _batch(_cars_ahead(np.full(20000, distance)))
    batch.detected = np.ones((1, len(batch)), dtype=bool)
    Monocular3D(RandomStreams(3), config).apply(batch)
    camera_centre = batch.world_from_camera[0, :3, 3]
    ray = batch.boxes3d[:, :3] - camera_centre
    unit = ray / np.linalg.norm(ray, axis=1, keepdims=True)
    error = np.einsum("ij,ij->i", batch.det_boxes3d[0, :, :3] - camera_centre, unit) - np.linalg.norm(ray, axis=1)
    expected = 0.2 + 0.03 * distance
    assert abs(error.std() / expected - 1.0) < 0.10, (error.std(), expected)
    assert abs(error.mean()) < 0.05 * expected


def test_miss_rate_equals_the_configured_probability():
    config = DetectionConfig(probability=0.85)
    batch = _batch(_cars_ahead(np.full(20000, 20.0)))
    DetectionProbability(config).apply(batch)
    np.testing.assert_allclose(batch.probability, 0.85)
    DetectionDraw(RandomStreams(5)).apply(batch)
    assert abs((1.0 - batch.detected.mean()) - 0.15) < 0.02
    assert not batch.causes.any()  # near, unoccluded, untruncated: a miss here has no cause but chance


def test_probability_ramps_and_causes():
    config = DetectionConfig(probability=1.0, min_visible_fraction=0.1, full_visible_fraction=0.5,
                             full_range_m=60.0, max_range_m=100.0)
    batch = _batch(_cars_ahead([20.0, 20.0, 80.0]), visible_fraction=1.0)
    batch.visible_fraction = np.array([[1.0, 0.3, 1.0]])
    DetectionProbability(config).apply(batch)
    np.testing.assert_allclose(batch.probability, [[1.0, 0.5, 0.5]])
    assert batch.causes.tolist() == [[0, int(Cause.OCCLUDED), int(Cause.FAR)]]


def _frame(boxes, frame=0):
    n = len(boxes)
    return GroundTruthFrame(frame=frame, timestamp=frame / 10, ego=EGO, actor_ids=np.arange(n),
                            classes=np.full(n, "car", dtype=object), boxes=boxes)


def _scenario(**changes):
    base = {"name": "t", "render": {"visibility": False}, "sensor": {"clutter": {"rate_per_frame": 0.0}}}
    base.update(changes)
    return Scenario.model_validate(base)


def test_an_object_in_two_overlapping_cameras_gives_two_detections_with_independent_noise():
    bearing = np.radians(27.5)  # inside the 22.5°–32.5° overlap of CAM_FRONT and CAM_FRONT_LEFT
    boxes = np.array([[20 * np.cos(bearing), 20 * np.sin(bearing), 0.8, 2.2, 0.8, 1.5, 0.0, 0.0, 0.0]])
    state = _frame(boxes)
    projection = project_boxes(boxes, RIG, EGO)
    model = SensorModel(_scenario(sensor={"detection": {"probability": 1.0}, "clutter": {"rate_per_frame": 0.0}}),
                        RIG, RandomStreams(0))
    output = model.observe(state, projection, Visibility.unmeasured(projection))
    batch = output.batch
    seen = {camera.name: index for index, camera in enumerate(batch.cameras) if batch.detected[index].any()}
    assert set(seen) == {"CAM_FRONT", "CAM_FRONT_LEFT"}
    a, b = batch.det_boxes3d[seen["CAM_FRONT"], 0], batch.det_boxes3d[seen["CAM_FRONT_LEFT"], 0]
    assert np.all(np.isfinite(a)) and not np.allclose(a[:3], b[:3])


def test_calibration_error_rotates_the_estimate_about_the_camera():
    boxes = _cars_ahead([30.0])
    scenario = _scenario(
        sensor={"detection": {"probability": 1.0}, "clutter": {"rate_per_frame": 0.0},
                "box3d": {"depth_sigma_m": 0, "depth_sigma_per_m": 0, "lateral_sigma_m": 0, "size_sigma": 0,
                          "yaw_sigma_deg": 0, "yaw_flip_probability": 0, "velocity_sigma_mps": 0}},
        perturbations=[{"kind": "calibration", "frames": [0, 5], "cameras": ["CAM_FRONT"], "yaw_offset_deg": 2.0}],
    )
    projection = project_boxes(boxes, RIG, EGO)
    output = SensorModel(scenario, RIG, RandomStreams(0)).observe(_frame(boxes), projection,
                                                                  Visibility.unmeasured(projection))
    estimate = output.batch.det_boxes3d[0, 0]  # the front camera's estimate of the car
    camera = np.array(RIG.cameras[0].position[:2])
    assert np.degrees(np.arctan2(estimate[1] - camera[1], estimate[0] - camera[0])) == pytest.approx(2.0)
    assert np.degrees(estimate[6]) == pytest.approx(2.0)
    assert output.batch.causes[0, 0] & Cause.CALIBRATION


def test_blackout_silences_a_camera_and_says_why():
    boxes = _cars_ahead([15.0])
    scenario = _scenario(
        sensor={"clutter": {"rate_per_frame": 5.0}},
        perturbations=[{"kind": "blackout", "seconds": [0.0, 1.0], "cameras": ["CAM_FRONT"]}],
    )
    projection = project_boxes(boxes, RIG, EGO)
    model = SensorModel(scenario, RIG, RandomStreams(0))
    output = model.observe(_frame(boxes), projection, Visibility.unmeasured(projection))
    batch = output.batch  # camera 0 is CAM_FRONT
    assert not batch.detected[0].any() and len(batch.false_positives(0)["scores"]) == 0
    assert batch.causes[0, 0] & Cause.BLACKOUT
    assert len(batch.false_positives(1)["scores"]) > 0  # other cameras still report clutter
    assert output.events == ("blackout#0 cameras=CAM_FRONT",)


def test_a_perturbation_naming_an_unknown_camera_is_a_clear_error():
    scenario = _scenario(perturbations=[{"kind": "blackout", "frames": [0, 1], "cameras": ["CAM_TOP"]}])
    with pytest.raises(ScenarioError, match=r"perturbations\.0\.cameras: rig 'surround6' has no camera 'CAM_TOP'"):
        SensorModel(scenario, RIG, RandomStreams(0))


def test_embeddings_are_unit_vectors_closer_to_their_identity_when_unoccluded():
    boxes = _cars_ahead(np.full(500, 20.0))
    scenario = _scenario(sensor={"detection": {"probability": 1.0, "min_visible_fraction": 0.0,
                                               "full_visible_fraction": 0.01}, "clutter": {"rate_per_frame": 0.0}})
    projection = project_boxes(boxes, RIG, EGO)
    model = SensorModel(scenario, RIG, RandomStreams(0))
    similarity = {}
    for occlusion in (0.0, 0.8):
        visibility = Visibility.unmeasured(projection)
        visibility = Visibility(visibility.visible_px, visibility.silhouette_px,
                                np.where(projection.in_view, occlusion, np.nan))
        embeddings = model.observe(_frame(boxes), projection, visibility).batch.embeddings[0]  # CAM_FRONT
        identity = np.array([model.embeddings.identity(i) for i in range(len(boxes))])
        np.testing.assert_allclose(np.linalg.norm(embeddings, axis=1), 1.0, atol=1e-5)
        similarity[occlusion] = float(np.mean(np.sum(embeddings * identity, axis=1)))
    assert similarity[0.0] > 0.95 > similarity[0.8]


def test_processes_kept_for_every_camera_at_once_equal_one_process_per_camera():
    """The sensor keeps its (actor, camera) processes in one array per effect; each camera's column must
    evolve exactly as a process of its own would, actors entering and leaving included."""
    rng = np.random.default_rng(0)
    phi = np.array([0.9, 0.5, 0.0])
    frames = [np.array([1, 2, 3]), np.array([3, 1, 7]), np.array([7, 9]), np.array([9, 7, 1, 2])]
    cameras = 4
    joint_gauss, joint_chain = GaussMarkov(phi), TwoStateMarkov(0.3, 0.5, 0.1)
    own_gauss = [GaussMarkov(phi) for _ in range(cameras)]
    own_chain = [TwoStateMarkov(0.3, 0.5, 0.1) for _ in range(cameras)]
    for ids in frames:
        z = rng.standard_normal((len(ids), cameras, len(phi)))
        u = rng.random((len(ids), cameras))
        joint_z, joint_u = joint_gauss.step(ids, z), joint_chain.step(ids, u)
        for camera in range(cameras):
            np.testing.assert_array_equal(joint_z[:, camera], own_gauss[camera].step(ids, z[:, camera]))
            np.testing.assert_array_equal(joint_u[:, camera], own_chain[camera].step(ids, u[:, camera]))
