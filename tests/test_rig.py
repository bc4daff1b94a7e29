"""Rig presets: layout, fields of view and the overlap they promise."""

import math

import numpy as np
import pytest
from simrig.scenarios.schema import RigConfig

from simrig.rig import build_rig, rig_from_dict, rig_to_dict


def _neighbour_overlaps_deg(rig):
    cameras = sorted(rig.cameras, key=lambda cam: cam.yaw % (2 * math.pi))
    overlaps = []
    for a, b in zip(cameras, cameras[1:] + cameras[:1], strict=True):
        gap = (b.yaw - a.yaw) % (2 * math.pi)
        overlaps.append(math.degrees((a.horizontal_fov + b.horizontal_fov) / 2 - gap))
    return overlaps


def test_surround6_is_nuscenes_like():
    rig = build_rig(RigConfig(preset="surround6"))
    assert rig.camera_names == (
        "CAM_FRONT", "CAM_FRONT_LEFT", "CAM_BACK_LEFT", "CAM_BACK", "CAM_BACK_RIGHT", "CAM_FRONT_RIGHT"
    )
    yaws = {cam.name: round(math.degrees(cam.yaw)) for cam in rig.cameras}
    assert yaws == {"CAM_FRONT": 0, "CAM_FRONT_LEFT": 55, "CAM_BACK_LEFT": 110, "CAM_BACK": 180,
                    "CAM_BACK_RIGHT": -110, "CAM_FRONT_RIGHT": -55}
    assert all((cam.width, cam.height) == (1600, 900) for cam in rig.cameras)
    back, front = rig.camera("CAM_BACK"), rig.camera("CAM_FRONT")
    assert back.horizontal_fov > front.horizontal_fov
    np.testing.assert_allclose(_neighbour_overlaps_deg(rig), [10.0] * 6, atol=1e-9)


@pytest.mark.parametrize("overlap", [0.0, 10.0, 25.0])
def test_overlap_knob_sets_every_neighbour_overlap(overlap):
    np.testing.assert_allclose(
        _neighbour_overlaps_deg(build_rig(RigConfig(preset="surround6", overlap_deg=overlap))), [overlap] * 6,
        atol=1e-9,
    )
    ring = build_rig(RigConfig(preset="ring", cameras_count=5, overlap_deg=overlap))
    np.testing.assert_allclose([math.degrees(c.horizontal_fov) for c in ring.cameras], [72.0 + overlap] * 5)
    np.testing.assert_allclose(_neighbour_overlaps_deg(ring), [overlap] * 5, atol=1e-9)


def test_stereo_pair_is_kitti_like():
    rig = build_rig(RigConfig(preset="stereo"))
    left, right = rig.camera("left"), rig.camera("right")
    assert left.position[1] - right.position[1] == pytest.approx(0.54)
    assert left.yaw == right.yaw == 0.0
    assert (left.width, left.height) == (1242, 375)
    assert left.fx == pytest.approx(721.5, abs=5.0)  # KITTI's f
    narrow = build_rig(RigConfig(preset="stereo", baseline_m=0.14))
    assert narrow.camera("left").position[1] - narrow.camera("right").position[1] == pytest.approx(0.14)


def test_camera_axes_follow_opencv_convention():
    cam = build_rig(RigConfig(preset="surround6")).camera("CAM_FRONT_LEFT")
    rotation = cam.ego_from_camera()[:3, :3]
    forward, right, down = rotation[:, 2], rotation[:, 0], rotation[:, 1]
    np.testing.assert_allclose(forward, [math.cos(cam.yaw), math.sin(cam.yaw), 0.0], atol=1e-12)
    np.testing.assert_allclose(down, [0.0, 0.0, -1.0], atol=1e-12)
    np.testing.assert_allclose(right, np.cross(forward, [0.0, 0.0, 1.0]), atol=1e-12)  # right = forward × up
    np.testing.assert_allclose(np.cross(right, down), forward, atol=1e-12)  # a right-handed frame


def test_rig_round_trips_through_json():
    rig = build_rig(RigConfig(preset="ring", cameras_count=4))
    assert rig_from_dict(rig_to_dict(rig)) == rig


def test_unknown_camera_name_lists_the_rig_cameras():
    with pytest.raises(KeyError, match="left, right"):
        build_rig(RigConfig(preset="stereo")).camera("CAM_FRONT")
