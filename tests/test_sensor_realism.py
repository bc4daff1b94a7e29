"""The realistic detector model: correlated errors, miss bursts, ghosts, re-ID separability, independence of
the random streams, and one-line errors for bad settings. Expected values come from the process
definitions (φ = exp(−Δt/τ), geometric stays), not from the code under test."""

import numpy as np
import pytest
from scipy import stats
from simrig.scenarios import ScenarioError, load_scenario
from simrig.scenarios.schema import RigConfig, Scenario

from simrig.causes import Cause
from simrig.classes import CLASS_SPECS
from simrig.detector.measure import consecutive_pairs, lag1, miss_runs
from simrig.geometry import project_boxes
from simrig.render.visibility import Visibility
from simrig.rig import build_rig
from simrig.seeding import RandomStreams
from simrig.sensor.appearance import roc_auc
from simrig.sensor.model import SensorModel
from simrig.types import ActorClass, EgoPose, GroundTruthFrame

RIG = build_rig(RigConfig())
EGO = EgoPose(0.0, 0.0, 0.0, 0.0)


def _cars_ahead(count: int, distance: float = 20.0) -> np.ndarray:
    """``count`` cars straight ahead of the front camera at ``distance`` [m] (they overlap: no renderer)."""
    spec = CLASS_SPECS[ActorClass.CAR]
    boxes = np.zeros((count, 9))
    boxes[:, 0] = RIG.cameras[0].position[0] + distance
    boxes[:, 2] = RIG.cameras[0].position[2]
    boxes[:, 3:6] = spec.length, spec.width, spec.height
    return boxes


def _scenario(rate_hz: float = 10.0, **sensor) -> Scenario:
    sensor.setdefault("clutter", {"rate_per_frame": 0.0})
    return Scenario.model_validate({"name": "t", "frame_rate_hz": rate_hz, "render": {"visibility": False},
                                    "traffic": {"class_mix": {"car": 1.0}}, "sensor": sensor})


def _run(scenario: Scenario, boxes: np.ndarray, frames: int, seed: int = 0):
    """Observe the same static scene for ``frames`` frames; yields (frame, output)."""
    model = SensorModel(scenario, RIG, RandomStreams(seed))
    projection = project_boxes(boxes, RIG, EGO)
    visibility = Visibility.unmeasured(projection)
    n = len(boxes)
    for frame in range(frames):
        state = GroundTruthFrame(frame=frame, timestamp=frame / scenario.frame_rate_hz, ego=EGO,
                                 actor_ids=np.arange(n), classes=np.full(n, "car", dtype=object), boxes=boxes)
        yield frame, model.observe(state, projection, visibility), model


@pytest.mark.parametrize("rate_hz", [10.0, 20.0])
def test_depth_error_lag1_correlation_is_exp_minus_dt_over_tau_at_any_frame_rate(rate_hz):
    tau = 0.8
    scenario = _scenario(rate_hz, detection={"probability": 1.0},
                         box3d={"correlation_time_s": tau, "depth_sigma_m": 0.5, "depth_sigma_per_m": 0.0})
    boxes = _cars_ahead(40)
    centre = None
    errors, frames, actors = [], [], []
    for frame, output, _ in _run(scenario, boxes, int(30 * rate_hz)):
        batch = output.batch  # camera 0: CAM_FRONT
        centre = batch.world_from_camera[0, :3, 3]
        errors.append(np.linalg.norm(batch.det_boxes3d[0, :, :3] - centre, axis=1)
                      - np.linalg.norm(boxes[:, :3] - centre, axis=1))
        frames.append(np.full(len(boxes), frame))
        actors.append(np.arange(len(boxes)))
    errors, frames, actors = map(np.concatenate, (errors, frames, actors))
    a, b = consecutive_pairs(frames, np.zeros_like(frames), actors)
    expected = np.exp(-1.0 / (rate_hz * tau))
    assert lag1(errors, a, b) == pytest.approx(expected, abs=0.05)
    assert errors.std() == pytest.approx(0.5, rel=0.1)  # σ is the stationary σ


@pytest.mark.parametrize("rate_hz", [10.0, 20.0])
def test_mean_miss_burst_length_in_seconds_is_the_configured_one_at_any_frame_rate(rate_hz):
    scenario = _scenario(rate_hz, detection={"probability": 1.0, "burst_fraction": 0.2, "burst_mean_s": 0.5})
    boxes = _cars_ahead(60)
    detected, frames, actors = [], [], []
    for frame, output, _ in _run(scenario, boxes, int(30 * rate_hz)):
        detected.append(output.batch.detected[0])
        frames.append(np.full(len(boxes), frame))
        actors.append(np.arange(len(boxes)))
    detected, frames, actors = map(np.concatenate, (detected, frames, actors))
    runs = miss_runs(frames, actors, np.ones_like(detected), detected)
    assert runs.mean() / rate_hz == pytest.approx(0.5, rel=0.10)
    assert 1.0 - detected.mean() == pytest.approx(0.2, abs=0.03)


def test_switching_one_cause_off_leaves_every_other_draw_bit_identical():
    on = {"detection": {"probability": 0.9}, "box3d": {"correlation_time_s": 0.5},
          "ghosts": {"birth_rate_hz": 5.0}, "duplicates": {"probability": 0.3},
          "confusion": {"matrix": {"car": {"car": 0.8, "truck": 0.2}}}}
    boxes = _cars_ahead(20)
    for switch in ("ghosts", "duplicates", "confusion"):
        off = {**on, switch: {}}
        for (_, a, _), (_, b, _) in zip(_run(_scenario(**on), boxes, 5), _run(_scenario(**off), boxes, 5),
                                        strict=True):
            x, y = a.batch, b.batch  # every camera at once
            assert np.array_equal(x.detected, y.detected)
            np.testing.assert_array_equal(x.det_boxes3d, y.det_boxes3d)
            np.testing.assert_array_equal(x.scores, y.scores)
            np.testing.assert_array_equal(x.embeddings, y.embeddings)


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_a_ghost_is_one_3d_box_seen_consistently_lives_its_life_and_scores_as_configured():
    config = {"birth_rate_hz": 20.0, "mean_life_s": 1.5, "shadow_fraction": 0.0, "range_m": [5.0, 40.0],
              "probability": 1.0, "score_mean": 0.6, "score_concentration": 12.0}
    scenario = _scenario(ghosts=config)
    first_seen, last_seen, scores, shared = {}, {}, [], 0
    for frame, output, model in _run(scenario, np.zeros((0, 9)), 400):
        alive = model.ghosts.ids
        for ghost in alive.tolist():
            first_seen.setdefault(ghost, frame)
            last_seen[ghost] = frame
        seen: dict[int, list] = {}
        for camera in range(len(output.batch.cameras)):
            clutter = output.batch.false_positives(camera)
            rows = np.nonzero(clutter["causes"] > 0)[0]
            ghost_rows = [r for r in rows if clutter["causes"][r] & Cause.GHOST]
            for ghost, row in zip(output.batch.ghost_ids[camera].tolist(), ghost_rows, strict=True):
                seen.setdefault(ghost, []).append((camera, clutter["boxes3d"][row], clutter["boxes2d"][row]))
                scores.append(clutter["scores"][row])
        for views in seen.values():
            box3d = views[0][1]
            projection = project_boxes(box3d[None], RIG, EGO)
            for camera, other3d, box2d in views:
                np.testing.assert_array_equal(other3d, box3d)  # one 3D box for every camera
                np.testing.assert_allclose(box2d, projection.boxes[camera, 0])  # its projection in each
            shared += len(views) > 1
    assert shared > 20
    ended = [g for g in first_seen if last_seen[g] < 399]
    lives = np.array([last_seen[g] - first_seen[g] + 1 for g in ended]) / scenario.frame_rate_hz
    assert lives.mean() == pytest.approx(1.5, rel=0.10)
    a, b = 0.6 * 12.0, 0.4 * 12.0
    assert stats.kstest(scores, stats.beta(a, b).cdf).pvalue > 0.01


def test_reid_roc_auc_is_the_configured_one():
    target = 0.8
    scenario = _scenario(detection={"probability": 1.0},
                         embedding={"target_auc": target, "lookalike_weight": 0.3, "viewpoint_weight": 0.3,
                                    "occlusion_sigma": 0.0})
    boxes = _cars_ahead(300)
    embeddings = [output.batch.embeddings[0] for _, output, _ in _run(scenario, boxes, 2)]  # CAM_FRONT
    similarity = embeddings[0] @ embeddings[1].T  # (actor at frame 0) × (actor at frame 1)
    same = np.diag(similarity)
    different = similarity[~np.eye(len(boxes), dtype=bool)]
    assert roc_auc(same, different) == pytest.approx(target, abs=0.02)


def test_scores_fall_with_localisation_error():
    scenario = _scenario(detection={"probability": 1.0},
                         box3d={"depth_sigma_m": 1.0, "depth_sigma_per_m": 0.0},
                         score={"error_gain": 0.5, "error_scale_m": 1.0, "sigma": 0.05})
    boxes = _cars_ahead(2000)
    _, output, _ = next(_run(scenario, boxes, 1))
    estimates, scores = output.batch.det_boxes3d[0], output.batch.scores[0]  # CAM_FRONT
    error = np.hypot(*(estimates[:, :2] - boxes[:, :2]).T)
    assert stats.spearmanr(error, scores).statistic < -0.5


@pytest.mark.parametrize(("table", "expected"), [
    ('[sensor.box3d]\ncorrelation_time_s = -1.0', "sensor.box3d.correlation_time_s: Input should be greater"),
    ('[sensor.confusion.matrix]\ncar = { car = 0.5, truck = 0.2 }', "sensor.confusion.matrix: row 'car' sums to 0.7"),
    ('[sensor]\npreset = "yolo"', "sensor.preset: unknown detector preset 'yolo'; known: perfect, ideal_noise"),
    ('[sensor.embedding]\ntarget_auc = 0.4', "sensor.embedding.target_auc: Input should be greater than 0.5"),
    ('[sensor.embedding]\ntarget_auc = 1.2', "sensor.embedding.target_auc: Input should be less than or equal to 1"),
])
def test_bad_detector_settings_are_one_line_errors_naming_key_and_file(tmp_path, table, expected):
    path = tmp_path / "bad.toml"
    path.write_text('extends = "highway_surround6"\n' + table + "\n")
    with pytest.raises(ScenarioError) as error:
        load_scenario(path)
    message = str(error.value)
    assert "\n" not in message and str(path) in message and expected in message, message


def test_a_preset_is_overridable_key_by_key(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text('extends = "highway_surround6"\n[sensor]\npreset = "monodis"\n[sensor.box3d]\nsize_sigma = 0.01\n')
    mine, preset = load_scenario(path).sensor, Scenario.model_validate({"name": "p", "sensor": {"preset": "monodis"}})
    assert mine.box3d.size_sigma == 0.01
    assert mine.box3d.correlation_time_s == preset.sensor.box3d.correlation_time_s > 0
    assert mine.ghosts == preset.sensor.ghosts


def test_same_scenario_and_seed_give_the_same_bytes_under_a_realistic_preset(tmp_path):
    from simrig.pipeline.generate import generate

    path = tmp_path / "s.toml"
    path.write_text('extends = "highway_surround6"\n[render]\nvisibility = false\n[sensor]\npreset = "monodis"\n'
                    '[sensor.ghosts]\nbirth_rate_hz = 5.0\n')
    scenario = load_scenario(path)
    hashes = []
    for run in ("a", "b"):
        manifest = generate(scenario, seed=3, out=tmp_path / run, frames=25).manifest
        hashes.append({name: entry["sha256"] for name, entry in manifest["files"].items()})
    assert hashes[0] == hashes[1]
    other = generate(scenario, seed=4, out=tmp_path / "c", frames=25).manifest
    assert other["files"]["detections"]["sha256"] != hashes[0]["detections"]


def _appearance(dimension=512, **settings) -> dict:
    return {"dimension": dimension, "occlusion_sigma": 0.0, **settings}


def test_reid_drift_has_memory_an_actor_looks_less_like_itself_the_longer_the_gap():
    """Mean cosine of one actor's observations g frames apart, from the model's definition in a high dimension
    (where |e|² concentrates at S = 1 + s_f² + s_s² + σ²): (1 + s_f²·φ_f^g + s_s²·φ_s^g) / S."""
    sigma, fast, tau_fast, slow, tau_slow = 0.3, 0.6, 0.5, 0.5, 5.0
    scenario = _scenario(detection={"probability": 1.0}, embedding=_appearance(
        sigma=sigma, drift_sigma=fast, drift_time_s=tau_fast, slow_drift_sigma=slow, slow_drift_time_s=tau_slow))
    frames = [output.batch.embeddings[0] for _, output, _ in _run(scenario, _cars_ahead(60), 41)]  # CAM_FRONT
    total = 1 + fast**2 + slow**2 + sigma**2
    for gap in (1, 5, 20, 40):
        measured = np.mean([np.sum(frames[t] * frames[t + gap], axis=1).mean() for t in range(41 - gap)])
        expected = (1 + fast**2 * np.exp(-gap * 0.1 / tau_fast) + slow**2 * np.exp(-gap * 0.1 / tau_slow)) / total
        assert measured == pytest.approx(expected, abs=0.01), gap


def test_reid_drift_draws_change_nothing_but_the_embeddings():
    boxes = _cars_ahead(30)
    runs = []
    for drift in (0.0, 0.7):
        scenario = _scenario(detection={"probability": 0.8}, box3d={"depth_sigma_m": 0.5},
                             embedding=_appearance(dimension=16, sigma=0.3, drift_sigma=drift, slow_drift_sigma=drift))
        runs.append([output.batch for _, output, _ in _run(scenario, boxes, 5)])
    for plain, drifting in zip(*runs, strict=True):
        np.testing.assert_array_equal(plain.detected, drifting.detected)
        np.testing.assert_array_equal(plain.det_boxes3d, drifting.det_boxes3d)
        np.testing.assert_array_equal(plain.scores, drifting.scores)
    assert not np.allclose(np.nan_to_num(runs[0][-1].embeddings), np.nan_to_num(runs[1][-1].embeddings))
