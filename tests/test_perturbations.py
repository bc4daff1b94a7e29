"""Scheduled perturbations end to end: generated datasets say what happened, when, and why."""

import numpy as np
import pyarrow.compute as pc
import pytest
from simrig.scenarios import load_scenario

from simrig.dataset import Dataset
from simrig.pipeline.generate import generate

P_MAX = 0.95


@pytest.fixture(scope="module")
def perturbed(tmp_path_factory):
    path = tmp_path_factory.mktemp("scenario") / "perturbed.toml"
    path.write_text(
        'extends = "highway_surround6"\nframes = 60\n'
        "[traffic]\nvehicles = 15\nwindow_radius_m = 100.0\nspawn_min_distance_m = 70.0\nego_lane = 1\n"
        f"[sensor.detection]\nprobability = {P_MAX}\n"
        '[[perturbations]]\nkind = "occlude"\nnearest = 1\nframes = [20, 40]\n'
        '[[perturbations]]\nkind = "drop_frames"\nframes = [50, 52]\n'
        '[[perturbations]]\nkind = "occluder"\nframes = [0, 59]\nlane_offset = 1\noffset_m = -30.0\n'
        "relative_speed_mps = 3.0\n"
    )
    out = tmp_path_factory.mktemp("data") / "d"
    generate(load_scenario(path), seed=6, out=out)
    return Dataset.open(out)


def _occluded_actor(dataset):
    events = dataset.table("frames").column("events").to_pylist()
    [text] = [e for e in events[20] if e.startswith("occlude#0")]
    assert all(text in frame_events for frame_events in events[20:41])
    assert not any(e.startswith("occlude#0") for e in events[41])
    return int(text.split("actors=")[1].split()[0])


def test_a_scheduled_occlusion_hides_the_actor_in_its_window_and_says_why(perturbed):
    actor = _occluded_actor(perturbed)
    truth = perturbed.table("sensor_truth").filter(pc.equal(pc.field("actor_id"), actor))
    visibility = perturbed.table("visibility").filter(pc.equal(pc.field("actor_id"), actor))
    frames = truth.column("frame").to_numpy()
    detection = truth.column("detection").to_numpy()
    causes = truth.column("causes").to_pylist()
    columns = (visibility.column(name).to_pylist() for name in ("frame", "camera", "silhouette_px"))
    in_view = {(f, c) for f, c, s in zip(*columns, strict=True) if s > 0}
    cameras = truth.column("camera").to_pylist()
    window = (frames >= 20) & (frames <= 40)
    seen_in_window = [i for i in np.nonzero(window)[0] if (frames[i], cameras[i]) in in_view]
    assert len(seen_in_window) >= 21  # the nearest actor is in view of some camera in every frame
    for i in seen_in_window:
        assert detection[i] == -1
        assert {"occluded", "scheduled_occlusion"} <= set(causes[i])
    # Outside the window, where nothing else affected it, it is detected at the configured rate.
    clean = [i for i in np.nonzero(~window)[0] if not causes[i] and (frames[i], cameras[i]) in in_view]
    probability = truth.column("probability").to_numpy()[clean]
    np.testing.assert_allclose(probability, P_MAX)
    rate = float(np.mean(detection[clean] >= 0))
    assert abs(rate - P_MAX) <= 4 * np.sqrt(P_MAX * (1 - P_MAX) / len(clean)), (rate, len(clean))


def test_dropped_frames_reach_no_tracker_and_are_recorded(perturbed):
    dropped = perturbed.table("frames").column("dropped").to_pylist()
    assert [i for i, d in enumerate(dropped) if d] == [50, 51, 52]
    assert [f.frame for f in perturbed.sensor_frames()] == [f for f in range(60) if f not in (50, 51, 52)]
    truth = perturbed.table("sensor_truth").filter(pc.equal(pc.field("frame"), 51))
    assert all(d == -1 for d in truth.column("detection").to_pylist())
    in_view = [c for c, a in zip(truth.column("causes").to_pylist(), truth.column("actor_id").to_pylist(), strict=True)
               if "out_of_view" not in c and a >= 0]
    assert in_view and all("dropped_frame" in c for c in in_view)


def test_an_occluder_truck_drives_in_the_next_lane_for_its_window(perturbed):
    events = [e["event"] for e in perturbed.manifest["events"]]
    spawned = [e for e in events if e.startswith("occluder#2 spawned")]
    assert len(spawned) == 1
    actor = int(spawned[0].split("id=")[1].split()[0])
    truth = perturbed.table("ground_truth").filter(pc.equal(pc.field("actor_id"), actor))
    assert set(truth.column("class").to_pylist()) == {"truck"}
    assert truth.num_rows == 60
    ego_y = perturbed.table("ego_poses").column("y").to_numpy()
    lateral = truth.column("y").to_numpy() - ego_y
    assert np.all(np.abs(lateral - 4.0) < 0.5)  # one 4 m lane to the ego's left, all the time


def test_sensor_frames_carry_no_ground_truth(perturbed):
    frame = next(perturbed.sensor_frames())
    dimension = perturbed.scenario["sensor"]["embedding"]["dimension"]  # the scenario's, whatever its preset
    for detections in frame.detections.values():
        for detection in detections:
            assert not hasattr(detection, "actor_id")
            assert detection.embedding is not None and detection.embedding.shape == (dimension,)
