"""``simrig detector fit`` on a nuScenes log: a detection-results JSON against the devkit's tables.

The log is made here with known error magnitudes: the ground truth of a generated 2 Hz dataset (nuScenes' key
frame rate) is exported with ``simrig export --format nuscenes``, and each true box gets a detection drawn with
a seeded generator from the documented model (depth along the ego's horizontal line of sight with
σ(d) = a + b·d as an AR(1) of correlation time τ per object, the other errors white with σ·(1 + d / D), yaw flips,
Gilbert–Elliott misses per object, a score linear in the model's terms, Poisson clutter per sample away from
every object). The fit must give back what was drawn.
"""

import json
import tomllib

import numpy as np
import pytest
from simrig.scenarios import load_scenario

from simrig.cli import main
from simrig.dataset import Dataset
from simrig.formats.nuscenes.samples import sample_token
from simrig.pipeline.generate import generate

KNOWN = {"depth_a": 0.15, "depth_b": 0.01, "lateral": 0.1, "size": 0.05, "yaw_deg": 4.0, "flip": 0.05,
         "velocity": 0.3, "scale": 50.0, "tau": 1.5, "p": 0.9, "burst_fraction": 0.15, "burst_s": 1.5, "base": 0.8,
         "error_gain": 0.3, "distance_gain": 0.2, "score_sigma": 0.05, "clutter_per_sample": 1.2}
SCENE = """extends = "highway_surround6"
frames = 200
frame_rate_hz = 2.0
[render]
visibility = false
[traffic]
vehicles = 40
window_radius_m = 50.0
spawn_min_distance_m = 35.0
"""


def _detections(dataset: Dataset, seed: int) -> dict:
    """A detection-results document drawn from ``dataset``'s ground truth with the errors in :data:`KNOWN`."""
    k, rng = KNOWN, np.random.default_rng(seed)
    truth = dataset.ground_truth
    ego = np.array([[e.x, e.y] for e in truth.egos])
    position = {int(f): i for i, f in enumerate(truth.frames)}
    times = np.asarray(truth.timestamps, dtype=float)
    row_frame = np.array([position[int(f)] for f in truth.frame])
    n = len(row_frame)
    depth_z, bad = np.zeros(n), np.zeros(n, dtype=bool)
    for actor in np.unique(truth.actor_id):
        rows = np.nonzero(truth.actor_id == actor)[0]
        z, in_burst, last = rng.standard_normal(), rng.random() < k["burst_fraction"], None
        for r in rows[np.argsort(row_frame[rows])]:
            if last is not None:
                dt = times[row_frame[r]] - times[last]
                rho = np.exp(-dt / k["tau"])
                z = rho * z + np.sqrt(1.0 - rho**2) * rng.standard_normal()
                leave = 1.0 - np.exp(-dt / k["burst_s"])  # a stay in the bad state lasts burst_s on average
                enter = leave * k["burst_fraction"] / (1.0 - k["burst_fraction"])  # stationary share π
                in_burst = rng.random() >= leave if in_burst else rng.random() < enter
            depth_z[r], bad[r], last = z, in_burst, row_frame[r]
    boxes = truth.boxes
    ray = boxes[:, :2] - ego[row_frame]
    distance = np.hypot(*ray.T)
    unit = ray / distance[:, None]
    across = np.column_stack([-unit[:, 1], unit[:, 0]])
    growth = 1.0 + distance / k["scale"]
    estimate = boxes.copy()
    estimate[:, :2] = (ego[row_frame] + unit * (distance + depth_z * (k["depth_a"] + k["depth_b"] * distance))[:, None]
                       + across * (rng.standard_normal(n) * k["lateral"] * growth)[:, None])
    estimate[:, 3:6] *= 1.0 + rng.standard_normal((n, 3)) * (k["size"] * growth)[:, None]
    estimate[:, 6] += rng.standard_normal(n) * np.radians(k["yaw_deg"]) * growth + np.pi * (rng.random(n) < k["flip"])
    estimate[:, 7:9] += rng.standard_normal((n, 2)) * (k["velocity"] * growth)[:, None]
    error = np.hypot(*(estimate[:, :2] - boxes[:, :2]).T)
    score = (k["base"] - k["error_gain"] * (1.0 - np.exp(-error)) - k["distance_gain"] * np.minimum(1.0, distance / 60)
             + rng.standard_normal(n) * k["score_sigma"])
    detected = ~bad & (rng.random(n) < k["p"])
    name, dataset_seed = dataset.scenario["name"], dataset.seed
    results: dict[str, list] = {sample_token(name, dataset_seed, f): [] for f in truth.frames}

    def add(frame, box, label, confidence):
        token = sample_token(name, dataset_seed, frame)
        results[token].append({
            "sample_token": token, "translation": [float(v) for v in box[:3]],
            "size": [float(box[4]), float(box[3]), float(box[5])],
            "rotation": [float(np.cos(box[6] / 2)), 0.0, 0.0, float(np.sin(box[6] / 2))],
            "velocity": [float(v) for v in box[7:9]], "detection_name": str(label),
            "detection_score": float(confidence), "attribute_name": ""})

    for r in np.nonzero(detected)[0]:
        add(int(truth.frame[r]), estimate[r], truth.label[r], score[r])
    for j, frame in enumerate(truth.frames):
        others = boxes[row_frame == j, :2]
        for _ in range(rng.poisson(k["clutter_per_sample"])):
            while True:  # within 45 m of the ego, more than 5 m from every object: never a match
                angle, radius = rng.uniform(0, 2 * np.pi), 45.0 * np.sqrt(rng.random())
                xy = ego[j] + radius * np.array([np.cos(angle), np.sin(angle)])
                if not len(others) or np.min(np.hypot(*(others - xy).T)) > 5.0:
                    break
            add(int(frame), np.r_[xy, 0.8, 4.5, 1.8, 1.5, rng.uniform(-np.pi, np.pi), 0.0, 0.0], "car",
                rng.uniform(0.05, 0.5))
    return {"meta": {"use_camera": True, "use_lidar": False, "use_radar": False, "use_map": False,
                     "use_external": False}, "results": results}


@pytest.fixture(scope="module")
def log(tmp_path_factory):
    """(dataset folder, exported nuScenes root, detection-results JSON)."""
    root = tmp_path_factory.mktemp("nuscenes_log")
    (root / "scene.toml").write_text(SCENE)
    generate(load_scenario(root / "scene.toml"), seed=0, out=root / "ds", progress=False)
    assert main(["export", "--format", "nuscenes", str(root / "ds"), "--out", str(root / "nuscenes")]) == 0
    (root / "detections.json").write_text(json.dumps(_detections(Dataset.open(root / "ds"), seed=0)))
    return root / "ds", root / "nuscenes", root / "detections.json"


# Relative tolerances: three standard deviations of each fitted value over 20 seeds of the drawing above on this
# scene (≈ 2,100 boxes, 1,500 matched; the means were within 1 sd of the truth for every key).
TOLERANCE = {("box3d", "depth_sigma_m"): 0.42, ("box3d", "depth_sigma_per_m"): 0.25,
             ("box3d", "lateral_sigma_m"): 0.23, ("box3d", "size_sigma"): 0.15, ("box3d", "yaw_sigma_deg"): 0.2,
             ("box3d", "velocity_sigma_mps"): 0.16, ("box3d", "yaw_flip_probability"): 0.3,
             ("box3d", "correlation_time_s"): 0.25, ("box3d", "distance_scale_m"): 0.25,
             ("detection", "burst_mean_s"): 0.5, ("score", "base"): 0.03, ("score", "error_gain"): 0.07,
             ("score", "distance_gain"): 0.12, ("score", "sigma"): 0.05, ("clutter", "rate_per_frame"): 0.18}


def test_fit_of_a_nuscenes_log_gives_back_the_errors_it_was_drawn_with(log, tmp_path, capsys):
    _, tables, detections = log
    out = tmp_path / "sensor.toml"
    assert main(["detector", "fit", "--detections", str(detections), "--truth", str(tables), "--out", str(out)]) == 0
    capsys.readouterr()
    text = out.read_text()
    fitted = tomllib.loads(text)["sensor"]
    k = KNOWN
    expected = {("box3d", "depth_sigma_m"): k["depth_a"], ("box3d", "depth_sigma_per_m"): k["depth_b"],
                ("box3d", "lateral_sigma_m"): k["lateral"], ("box3d", "size_sigma"): k["size"],
                ("box3d", "yaw_sigma_deg"): k["yaw_deg"], ("box3d", "velocity_sigma_mps"): k["velocity"],
                ("box3d", "yaw_flip_probability"): k["flip"], ("box3d", "correlation_time_s"): k["tau"],
                ("box3d", "distance_scale_m"): k["scale"], ("detection", "burst_mean_s"): k["burst_s"],
                ("score", "base"): k["base"], ("score", "error_gain"): k["error_gain"],
                ("score", "distance_gain"): k["distance_gain"], ("score", "sigma"): k["score_sigma"],
                ("clutter", "rate_per_frame"): k["clutter_per_sample"] / 6}  # --cameras defaults to nuScenes' 6
    for (table, key), value in expected.items():
        assert fitted[table][key] == pytest.approx(value, rel=TOLERANCE[table, key]), (table, key)
    detection = fitted["detection"]
    # p and the bad-state share trade off against each other; the detection rate (1 − π)·p is tight (sd 0.016).
    assert (1 - detection["burst_fraction"]) * detection["probability"] == pytest.approx(
        (1 - k["burst_fraction"]) * k["p"], abs=0.05)
    assert fitted["box3d"]["size_correlation_time_s"] < 0.3  # drawn white: ρ ≈ 0 (3 sd of 20 seeds: 0.26 s)
    assert fitted["box3d"]["yaw_flip_duration_s"] == 0.0  # flips drawn afresh every sample
    assert fitted["score"]["gain"] == 0.0 and "shared_fraction" not in fitted["box3d"]
    for reason in ("no cameras", "shared_fraction: not fitted", "gain (the visible-fraction", "per sample",
                   "--cameras 6", "detection ramps not fitted", "Δt = 0.5 s"):
        assert reason in text, reason
    # The written [sensor] table is one a scenario takes as it is.
    scenario = tmp_path / "fitted.toml"
    scenario.write_text('extends = "highway_surround6"\n' + text)
    assert load_scenario(scenario).sensor.box3d.correlation_time_s == fitted["box3d"]["correlation_time_s"]


def test_the_dataset_its_exported_tables_and_their_import_are_the_same_ground_truth(log, tmp_path):
    dataset, tables, detections = log
    from simrig.detector.fit_nuscenes import fit_nuscenes

    assert main(["import", "--format", "nuscenes", str(tables), "--out", str(tmp_path / "imported")]) == 0
    fitted = fit_nuscenes(detections, tables, cameras=3).sensor
    assert fit_nuscenes(detections, dataset, cameras=3).sensor == fitted
    assert fit_nuscenes(detections, tmp_path / "imported", cameras=3).sensor == fitted
    assert fitted["clutter"]["rate_per_frame"] == pytest.approx(2 * fit_nuscenes(detections, tables).sensor[
        "clutter"]["rate_per_frame"], abs=1.5e-6)  # per sample ÷ 3 cameras against ÷ 6; each rounded to 1e-6, so
    # they differ by up to 0.5e-6 + 2 × 0.5e-6


@pytest.mark.parametrize("case", ["unknown token", "neither", "truth with a dataset", "no truth"])
def test_fit_refuses_a_bad_log_in_one_line(log, tmp_path, capsys, case):
    dataset, tables, detections = log
    document = json.loads(detections.read_text())
    document["results"]["nowhere-seed0-000007"] = []
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(document, indent=1))
    args, start = {
        "unknown token": (["--detections", str(bad), "--truth", str(tables)], f"{bad}:"),
        "neither": (["--detections", str(detections), "--truth", str(tmp_path)], "--truth"),
        "truth with a dataset": (["--detections", str(dataset), "--truth", str(tables)], "--truth"),
        "no truth": (["--detections", str(detections)], "--truth"),
    }[case]
    assert main(["detector", "fit", *args, "--out", str(tmp_path / "s.toml")]) == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith(f"simrig: error: {start}") and "\n" not in error, error
    if case == "unknown token":
        assert "unknown sample token 'nowhere-seed0-000007'" in error
    assert not (tmp_path / "s.toml").exists()
