"""The shared records: import-light, validated, immutable."""

import subprocess
import sys

import numpy as np
import pytest

from simrig.types import ActorClass, Box2D, Box3D, EgoPose, GroundTruthFrame, Track


def test_records_import_without_simulator_renderer_or_arrow():
    # The reference trackers need scipy (Hungarian, filterpy) and shapely, nothing of the simulator.
    code = (
        "import sys, simrig.types, simrig.trackers\n"
        "heavy = {'highway_env', 'pyrender', 'pyarrow', 'gymnasium', 'pydantic'} & set(sys.modules)\n"
        "print(sorted(heavy))"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "[]"


def test_ego_pose_transform_rotates_then_translates():
    pose = EgoPose(10.0, 5.0, 0.0, np.pi / 2)
    point = pose.world_from_ego() @ np.array([1.0, 0.0, 0.0, 1.0])  # 1 m ahead of the ego
    np.testing.assert_allclose(point[:3], [10.0, 6.0, 0.0], atol=1e-12)


def test_ground_truth_arrays_are_frozen_and_checked():
    frame = GroundTruthFrame(
        frame=0, timestamp=0.0, ego=EgoPose(0, 0, 0, 0), actor_ids=[1, 2], classes=["car", "bus"],
        boxes=np.zeros((2, 9)),
    )
    with pytest.raises(ValueError):
        frame.boxes[0, 0] = 1.0
    with pytest.raises(ValueError, match="2 actor ids but 1 classes"):
        GroundTruthFrame(frame=3, timestamp=0.3, ego=EgoPose(0, 0, 0, 0), actor_ids=[1, 2], classes=["car"],
                         boxes=np.zeros((2, 9)))
    with pytest.raises(ValueError, match=r"boxes: expected shape \(N, 9\)"):
        GroundTruthFrame(frame=0, timestamp=0.0, ego=EgoPose(0, 0, 0, 0), actor_ids=[1], classes=["car"],
                         boxes=np.zeros((1, 7)))


def test_a_track_needs_a_box():
    with pytest.raises(ValueError, match="track 4"):
        Track(track_id=4, label=ActorClass.CAR, score=0.9)
    track = Track(track_id=4, label=ActorClass.CAR, score=0.9, boxes2d={"left": Box2D(0, 0, 10, 10)})
    assert track.boxes2d["left"].area == 100.0
    assert Box3D(1, 2, 3, 4, 5, 6, 0.5).as_array().tolist() == [1, 2, 3, 4, 5, 6, 0.5, 0, 0]
