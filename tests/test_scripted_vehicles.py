"""The world perturbations added for planner-aware scores: a lead vehicle braking hard and a stalled
vehicle, checked on the ground truth they produce."""

from __future__ import annotations

import numpy as np
import pytest
from simrig.scenarios import ScenarioError, load_scenario
from simrig.scenarios.overrides import with_setting

from simrig.pipeline.generate import generate


def _track_of(dataset, prefix: str) -> tuple[int, np.ndarray, np.ndarray]:
    """The scripted vehicle's id, and its frames and speeds [m/s] along its heading."""
    event = next(e["event"] for e in dataset.manifest["events"] if e["event"].startswith(prefix))
    actor = int(event.split("id=")[1].split()[0])
    truth = dataset.ground_truth
    rows = np.flatnonzero(truth.actor_id == actor)
    boxes = truth.boxes[rows]
    speed = boxes[:, 7] * np.cos(boxes[:, 6]) + boxes[:, 8] * np.sin(boxes[:, 6])
    return actor, truth.frame[rows], speed


def test_the_lead_vehicle_brakes_at_the_set_deceleration_and_stays_stopped(tmp_path):
    """From the window's last frame the car loses deceleration × 1/frame rate of speed per frame (8 m/s² at
    10 Hz: 0.8 m/s a frame) until no more than one frame's braking is left; then it stands still for good."""
    scenario = with_setting(load_scenario("lead_brake"), "render.visibility", False)
    out = tmp_path / "lead"
    generate(scenario, seed=100, out=out, frames=100)
    from simrig.dataset import Dataset

    dataset = Dataset.open(out)
    assert any(e["event"].startswith("lead_brake#0 brakes at 8 m/s²") and e["frame"] == 50
               for e in dataset.manifest["events"])
    _, frames, speed = _track_of(dataset, "lead_brake#0 spawned")
    before = speed[frames == 50][0]
    expected = before - 0.8 * np.arange(40)
    moving = int(np.argmax(expected <= 0.8))  # frames after 50 until no more than 0.8 m/s is left
    after = speed[frames >= 50]
    assert after[:moving] == pytest.approx(expected[:moving], abs=1e-9)
    assert moving > 10 and np.all(after[moving:] == 0.0)


def test_a_stalled_vehicle_stands_still_and_bad_settings_are_refused(tmp_path):
    scenario = with_setting(load_scenario("stalled_vehicle"), "render.visibility", False)
    out = tmp_path / "stalled"
    generate(scenario, seed=100, out=out, frames=40)
    from simrig.dataset import Dataset

    _, frames, speed = _track_of(Dataset.open(out), "stalled#0 spawned")
    assert len(frames) == 40 and np.all(np.abs(speed) < 0.05)
    for bad, key in (({"deceleration_mps2": 12.0}, "deceleration_mps2"), ({"offset_m": -5.0}, "offset_m")):
        with pytest.raises(ScenarioError, match=key):
            with_setting(scenario, "perturbations", [{"kind": "lead_brake", "frames": [0, 10], **bad}])
    with pytest.raises(ScenarioError, match="relative_speed_mps"):
        with_setting(scenario, "perturbations", [{"kind": "stalled", "frames": [0, 10], "relative_speed_mps": 3.0}])
