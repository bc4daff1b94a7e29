"""Visibility: pyrender segmentation counts against hand-built scenes and continuous polygon geometry."""

import numpy as np
import pytest
from scipy.spatial import ConvexHull
from simrig.scenarios.schema import RigConfig

from simrig.classes import CLASS_SPECS
from simrig.geometry import box_corners, camera_from_world, project_boxes, transform_points
from simrig.render.meter import VisibilityMeter
from simrig.render.scene import RigScene
from simrig.render.shapes import part_boxes
from simrig.rig import build_rig
from simrig.types import ActorClass, EgoPose

EGO = EgoPose(0.0, 0.0, 0.0, 0.0)
SCALE = 0.5  # the default visibility resolution: 800 × 450 for the surround cameras


def _box(actor_class, x, y, yaw=0.0):
    spec = CLASS_SPECS[ActorClass(actor_class)]
    return [x, y, spec.height / 2, spec.length, spec.width, spec.height, yaw, 0.0, 0.0]


class _Frame:
    def __init__(self, classes, boxes):
        self.ego, self.classes = EGO, np.array(classes, dtype=object)
        self.boxes = np.array(boxes, dtype=float)


@pytest.fixture(scope="module")
def meter():
    return VisibilityMeter(build_rig(RigConfig()), SCALE, RigScene())


def _occlusion(meter, classes, boxes, camera="CAM_FRONT"):
    frame = _Frame(classes, boxes)
    rig = build_rig(RigConfig())
    visibility = meter.measure(frame, project_boxes(frame.boxes, rig, EGO))
    return visibility, rig.camera_names.index(camera)


def test_a_truck_between_the_ego_and_a_car_hides_the_car_from_the_front_camera(meter):
    car, truck = _box("car", 30.0, 0.0), _box("truck", 15.0, 0.0)
    visibility, front = _occlusion(meter, ["car", "truck"], [car, truck])
    assert visibility.occlusion[front, 0] > 0.9
    assert visibility.occlusion[front, 1] == pytest.approx(0.0, abs=1e-3)  # nothing in front of the truck
    alone, front = _occlusion(meter, ["car"], [car])
    assert alone.occlusion[front, 0] < 0.05
    assert alone.silhouette_px[front, 0] == visibility.silhouette_px[front, 0]  # the silhouette ignores others


def _polygon_area(points):
    x, y = points[:, 0], points[:, 1]
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _clip(polygon, a, b, c):
    """Sutherland–Hodgman step: keep a·x + b·y + c ≤ 0 (written here independently of simrig.geometry)."""
    out = []
    for p, q in zip(polygon, np.roll(polygon, -1, axis=0), strict=True):
        dp, dq = a * p[0] + b * p[1] + c, a * q[0] + b * q[1] + c
        if dp <= 0:
            out.append(p)
        if (dp < 0) != (dq < 0) and dp != dq:
            out.append(p + dp / (dp - dq) * (q - p))
    return np.array(out).reshape(-1, 2)


def _hull_polygons(box, camera_index, rig):
    """Ordered hull polygon [px] of each (wholly in front) part of a car, at the visibility resolution."""
    parts = part_boxes(np.array([box]), np.array(["car"], dtype=object))[0]
    transform = camera_from_world(rig, EGO)[camera_index]
    camera = rig.cameras[camera_index]
    polygons = []
    for part in parts:
        points = transform_points(transform, box_corners(part[None])[0])
        assert (points[:, 2] > camera.near).all()
        pixels = np.stack([camera.fx * points[:, 0] / points[:, 2] + camera.cx,
                           camera.fy * points[:, 1] / points[:, 2] + camera.cy], axis=1)
        hull = ConvexHull(pixels)
        polygons.append(pixels[hull.vertices])
    return polygons


def _union_area(polygons, bounds=None):
    """Area of the union of two convex polygons, optionally clipped to the image (0, 0)–(w, h)."""
    if bounds is not None:
        w, h = bounds
        polygons = [_clip(_clip(_clip(_clip(p, -1, 0, 0), 1, 0, -w), 0, -1, 0), 0, 1, -h) for p in polygons]
    a, b = polygons
    both = a
    for p, q in zip(b, np.roll(b, -1, axis=0), strict=True):  # keep the side of each edge b lies on
        edge = q - p
        normal = np.array([edge[1], -edge[0]])
        inside_sign = np.sign(np.dot(normal, b.mean(axis=0) - p))
        both = _clip(both, *(-inside_sign * normal), inside_sign * np.dot(normal, p)) if len(both) else both
    overlap = _polygon_area(both) if len(both) >= 3 else 0.0
    return sum(_polygon_area(p) if len(p) >= 3 else 0.0 for p in polygons) - overlap


@pytest.mark.parametrize("lateral", [0.0, 5.5, 6.5, 7.0, 7.5])
def test_unoccluded_visible_fraction_matches_the_analytic_in_image_fraction(meter, lateral):
    """A lone car 12 m ahead slides out of the front camera's left edge. The fraction of its silhouette
    that the renderer shows equals the continuous in-image fraction of the parts' projected hulls.

    Tolerance: counting pixel centres instead of integrating area errs only in pixels cut by the outline,
    at most about one per unit of perimeter: |count − area| ≤ perimeter, so the fractions may differ by
    perimeter / area (3–6 % here). Measured differences are far smaller (see the assertion message).
    """
    box = _box("car", 12.0, lateral)
    rig = meter.rig
    front = rig.camera_names.index("CAM_FRONT")
    camera = rig.cameras[front]
    polygons = _hull_polygons(box, front, rig)
    full_area = _union_area(polygons)
    in_image_area = _union_area(polygons, bounds=(camera.width, camera.height))
    perimeter = sum(np.linalg.norm(p - np.roll(p, -1, axis=0), axis=1).sum() for p in polygons)
    visibility, _ = _occlusion(meter, ["car"], [box])
    rendered_fraction = visibility.visible_px[front, 0] / full_area
    analytic_fraction = in_image_area / full_area
    assert analytic_fraction > 0.05
    assert abs(rendered_fraction - analytic_fraction) <= perimeter / full_area, (rendered_fraction, analytic_fraction)
    assert abs(visibility.visible_px[front, 0] - visibility.silhouette_px[front, 0]) <= 2  # unoccluded: ≈ 0
    assert visibility.occlusion[front, 0] < 0.01


def test_renders_are_deterministic_and_nodes_are_reused(meter):
    boxes = [_box("car", 30.0, 0.0), _box("truck", 15.0, 3.5), _box("bus", -20.0, -3.5), _box("motorcycle", 8.0, -3.5)]
    classes = ["car", "truck", "bus", "motorcycle"]
    first, _ = _occlusion(meter, classes, boxes)
    nodes = len(meter.scene.scene.mesh_nodes)
    second, _ = _occlusion(meter, classes, boxes)
    np.testing.assert_array_equal(first.visible_px, second.visible_px)
    assert len(meter.scene.scene.mesh_nodes) == nodes
    assert (first.visible_px[:, 2] > 0).sum() >= 1  # the bus behind is seen by a back camera



def test_scene_bounds_work_under_numpy_2(meter):
    # pyrender computes scene bounds (used by shadows and viewers) with np.infty, which numpy 2 removed.
    scene = RigScene()
    scene.set_frame(EGO, np.array(["car"], dtype=object), np.array([_box("car", 10.0, 0.0)]))
    scene.colour(build_rig(RigConfig()).cameras[0], build_rig(RigConfig()), EGO)  # places the nodes
    assert scene.scene.bounds[1, 0] == pytest.approx(10.0 + CLASS_SPECS[ActorClass.CAR].length / 2)


def test_an_empty_pyopengl_platform_counts_as_unset():
    # PYOPENGL_PLATFORM="" (a shell's `export PYOPENGL_PLATFORM=`) once kept PyOpenGL off EGL and every render
    # failed on a machine without a display; empty now means "choose for me", as unset does.
    import os
    import subprocess
    import sys

    code = ("from simrig.render.scene import RigScene; from simrig.rig import build_rig; "
            "from simrig.scenarios.schema import RigConfig; from simrig.types import EgoPose; "
            "import os; rig = build_rig(RigConfig()); scene = RigScene(); "
            "image = scene.colour(rig.cameras[0], rig, EgoPose(0.0, 0.0, 0.0, 0.0)); "
            "print(os.environ['PYOPENGL_PLATFORM'], image.shape)")
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")} | {"PYOPENGL_PLATFORM": ""}
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split()[0] == "egl"
