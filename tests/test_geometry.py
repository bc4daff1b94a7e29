"""Projection of 3D boxes into cameras, checked against pixel arithmetic from K done by hand."""

import math

import numpy as np
import pytest
from simrig.scenarios.schema import RigConfig

from simrig.geometry import box_corners, clip_convex_polygons, project_boxes
from simrig.rig import build_rig
from simrig.types import EgoPose

SURROUND = build_rig(RigConfig(preset="surround6"))
FRONT = SURROUND.camera("CAM_FRONT")  # at (1.5, 0, 1.6) on the ego, looking along +x
ORIGIN = EGO = EgoPose(0.0, 0.0, 0.0, 0.0)


def _box(x, y, z, length, width, height, yaw=0.0):
    return np.array([[x, y, z, length, width, height, yaw, 0.0, 0.0]])


def _in(rig, name, projection):
    return projection.in_view[rig.camera_names.index(name)]


def test_focal_length_follows_the_field_of_view():
    # 1600 px across 65°: f = 800 / tan(32.5°)
    assert FRONT.fx == pytest.approx(800.0 / math.tan(math.radians(32.5)))
    assert (FRONT.cx, FRONT.cy) == (800.0, 450.0)


def test_box_ten_metres_ahead_projects_to_the_pixel_box_from_k():
    # Near face 10 m in front of the camera: camera x = 1.5, face at x = 11.5, box 2 m long → centre 12.5.
    # Width 2 m (y ±1), height 2 m from the road (z 0..2); the camera is 1.6 m up.
    projection = project_boxes(_box(12.5, 0.0, 1.0, 2.0, 2.0, 2.0), SURROUND, ORIGIN)
    f = FRONT.fx
    expected = [800.0 - f * 1.0 / 10, 450.0 - f * 0.4 / 10, 800.0 + f * 1.0 / 10, 450.0 + f * 1.6 / 10]
    np.testing.assert_allclose(projection.boxes[0, 0], expected, rtol=0, atol=1e-9)
    assert projection.truncation[0, 0] == 0.0
    assert projection.depth[0, 0] == pytest.approx(11.0)  # centre depth: 12.5 − 1.5
    assert _in(SURROUND, "CAM_FRONT", projection).tolist() == [True]
    assert not _in(SURROUND, "CAM_BACK", projection)[0]


def test_projection_only_depends_on_the_relative_pose():
    # The same scene with the ego at (100, 50) facing +y (yaw 90°): the box is 12.5 m ahead along +y.
    ego = EgoPose(100.0, 50.0, 0.0, math.pi / 2)
    moved = project_boxes(_box(100.0, 62.5, 1.0, 2.0, 2.0, 2.0, yaw=math.pi / 2), SURROUND, ego)
    still = project_boxes(_box(12.5, 0.0, 1.0, 2.0, 2.0, 2.0), SURROUND, ORIGIN)
    np.testing.assert_allclose(moved.boxes, still.boxes, atol=1e-8)


def test_box_straddling_the_near_plane_is_clipped_not_mirrored():
    # In camera coordinates the box spans depth z ∈ [−5, 3], x ∈ [−3, −1] (left of the axis), y ∈ [0, 1.6]
    # (road to camera height). Ego frame: x = z + 1.5 ∈ [−3.5, 4.5], y = −x_cam ∈ [1, 3], z ∈ [0, 1.6].
    projection = project_boxes(_box(0.5, 2.0, 0.8, 8.0, 2.0, 1.6), SURROUND, ORIGIN)
    f = FRONT.fx
    # In front of the camera only z ∈ [0.1, 3] remains. Its right edge is x = −1 at z = 3 (u = cx − f/3);
    # everything else falls off the image to the left (u < 0) and below it (v > 900); the top face is at
    # the camera's height, so v = cy at every depth.
    np.testing.assert_allclose(projection.boxes[0, 0], [0.0, 450.0, 800.0 - f / 3.0, 900.0], atol=1e-9)
    # Projecting the eight corners naively would put the corners behind the camera on the right half of
    # the image (u = cx + f·(−3)/(−5) > cx): the clipped box must stay left of the centre.
    assert projection.boxes[0, 0, 2] < FRONT.cx
    assert projection.truncation[0, 0] > 0.5


def test_box_wholly_behind_a_camera_is_not_in_view():
    projection = project_boxes(_box(-20.0, 0.0, 1.0, 4.0, 2.0, 2.0), SURROUND, ORIGIN)
    assert not _in(SURROUND, "CAM_FRONT", projection)[0]
    assert np.isnan(projection.boxes[0, 0]).all()
    assert _in(SURROUND, "CAM_BACK", projection)[0]


def test_truncation_is_the_fraction_of_the_projected_box_outside_the_image():
    # Camera looking along +x at the ego origin, 90° field of view, 200×100 px: f = 100, cx = 100, cy = 50.
    rig = build_rig(
        RigConfig(
            preset="custom",
            cameras=[{"name": "c", "x_m": 0, "y_m": 0, "z_m": 1.0, "hfov_deg": 90, "width_px": 200, "height_px": 100}],
        )
    )
    # Near face at depth 10, spanning camera x ∈ [5, 15] (ego y ∈ [−15, −5]), 1 m deep, z from 0.5 to 1.5.
    projection = project_boxes(_box(10.5, -10.0, 1.0, 1.0, 10.0, 1.0), rig, ORIGIN)
    # Unclipped: left edge from the far face (u = 100 + 100·5/11), right from the near face (100 + 100·15/10).
    left, right = 100 + 100 * 5 / 11, 100 + 100 * 15 / 10
    np.testing.assert_allclose(projection.unclipped[0, 0, [0, 2]], [left, right])
    np.testing.assert_allclose(projection.boxes[0, 0, [0, 2]], [left, 200.0])
    assert projection.truncation[0, 0] == pytest.approx(1 - (200 - left) / (right - left))


def test_actor_in_the_overlap_of_two_neighbouring_cameras_appears_in_both():
    # CAM_FRONT covers bearings ±32.5°, CAM_FRONT_LEFT 55° ± 32.5°: they share 22.5°..32.5°.
    bearing, distance = math.radians(27.5), 30.0
    box = _box(distance * math.cos(bearing), distance * math.sin(bearing), 0.75, 2.2, 0.8, 1.5, yaw=bearing)
    projection = project_boxes(box, SURROUND, ORIGIN)
    seen = {name for name, row in zip(SURROUND.camera_names, projection.in_view[:, 0], strict=True) if row}
    assert seen == {"CAM_FRONT", "CAM_FRONT_LEFT"}
    assert (projection.truncation[:, 0][projection.in_view[:, 0]] == 0).all()  # wholly inside each image


def test_actor_to_the_left_appears_in_the_left_cameras_only():
    projection = project_boxes(_box(0.0, 5.0, 0.8, 4.6, 1.9, 1.6), SURROUND, ORIGIN)
    seen = {name for name, row in zip(SURROUND.camera_names, projection.in_view[:, 0], strict=True) if row}
    assert seen == {"CAM_FRONT_LEFT", "CAM_BACK_LEFT"}


def test_stereo_disparity_is_focal_times_baseline_over_depth():
    rig = build_rig(RigConfig(preset="stereo"))
    left, right = rig.camera("left"), rig.camera("right")
    for depth in (5.0, 20.0, 60.0):
        # Near face at the given depth, box centred on the ego's axis (between the two cameras).
        projection = project_boxes(_box(depth + 1.0, 0.0, 0.8, 2.0, 1.8, 1.6), rig, ORIGIN)
        centres = (projection.boxes[:, 0, 0] + projection.boxes[:, 0, 2]) / 2
        assert centres[0] - centres[1] == pytest.approx(left.fx * 0.54 / depth, rel=1e-12)
        assert right.fx == left.fx


def test_box_corners_follow_yaw():
    corners = box_corners(np.array([[0.0, 0.0, 0.0, 4.0, 2.0, 2.0, math.pi / 2]]))[0]
    # Yawed 90°: the front (length) points along +y.
    assert corners[:, 1].max() == pytest.approx(2.0)
    assert corners[:, 0].max() == pytest.approx(1.0)


def test_polygon_clipping_against_a_half_plane():
    square = np.array([[[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]]])
    # Keep x ≤ 1: normal (−1, 0), offset 1.
    points, count = clip_convex_polygons(square, np.array([4]), np.array([[-1.0, 0.0]]), np.array([1.0]))
    kept = points[0, : count[0]]
    assert count[0] == 4
    assert sorted(map(tuple, kept.round(12).tolist())) == [(0.0, 0.0), (0.0, 2.0), (1.0, 0.0), (1.0, 2.0)]


def test_empty_frame_projects_to_empty_arrays():
    projection = project_boxes(np.zeros((0, 9)), SURROUND, ORIGIN)
    assert projection.boxes.shape == (6, 0, 4)


def test_malformed_boxes_are_rejected_with_their_shape():
    with pytest.raises(ValueError, match=r"expected shape \(N, 9\).*\(3,\)"):
        project_boxes(np.zeros(3), SURROUND, ORIGIN)
