"""Scoring one camera (``simrig score --camera``) and semi-online trackers (``finish``) through ``run_tracker``."""

import pytest
from simrig.trackers import register

from simrig.cli import main
from simrig.errors import TracksError
from simrig.pipeline.track import run_tracker
from simrig.scoring import score


def test_one_camera_scores_as_that_camera_does_in_the_full_report(small_dataset, tmp_path):
    run = run_tracker(small_dataset, "sort", tmp_path / "sort")
    full = score(small_dataset, run.out)
    camera = small_dataset.rig.camera_names[0]
    alone = score(small_dataset, run.out, camera=camera)
    assert alone.metrics3d is None and list(alone.metrics2d["per_camera"]) == [camera]
    for name, value in full.metrics2d["per_camera"][camera].items():
        assert alone.metrics2d["overall"][name] == pytest.approx(value, nan_ok=True), name
    assert set(alone.errors.column("camera").to_pylist()) <= {camera}
    assert alone.settings["camera"] == camera


def test_an_unknown_camera_is_named(small_dataset, tmp_path, capsys):
    run = run_tracker(small_dataset, "sort", tmp_path / "sort")
    with pytest.raises(TracksError, match="--camera 'left'.*CAM_FRONT"):
        score(small_dataset, run.out, camera="left")
    assert main(["score", str(small_dataset.path), str(run.out), "--camera", "left"]) == 2
    assert "--camera 'left'" in capsys.readouterr().err


class Revising:
    """Reports nothing online, then one track on every frame when asked to finish (a semi-online tracker)."""

    def reset(self, *, rig, seed=None):
        self.frames, self.camera = [], rig.camera_names[0]

    def step(self, frame):
        self.frames.append(frame.frame)
        return []

    def finish(self):
        from simrig.types import ActorClass, Box2D, Track
        return [(f, [Track(7, ActorClass.CAR, 0.5, boxes2d={self.camera: Box2D(0, 0, 10, 10)})]) for f in self.frames]


def test_run_tracker_writes_what_finish_returns(small_dataset, tmp_path):
    register("test-revising", Revising, replace=True)
    run = run_tracker(small_dataset, "test-revising", tmp_path / "revising")
    assert run.track_rows == run.frames == small_dataset.frame_count
