"""Vectorised geometry: box corners, frame transforms, and projection of 3D boxes into cameras.

Projection clips each box face as a polygon, first against the camera's near plane in 3D, then against
the image rectangle in 2D (Sutherland–Hodgman, one half-space at a time, all polygons at once). Corners
behind the camera are never projected, so a box straddling the near plane is cut, not mirrored. The
2D box is the bounding box of the clipped silhouette (the union of the clipped faces), which is what an
annotator would draw around the visible part of the object inside the image.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from .types import EgoPose, Rig

# Corners of a unit box, (x forward, y left, z up) as multiples of (length, width, height) around the centre.
# Bottom face 0-3 counter-clockwise seen from above starting front-left, top face 4-7 above them.
_UNIT_CORNERS = np.array(
    [
        [0.5, 0.5, -0.5],
        [-0.5, 0.5, -0.5],
        [-0.5, -0.5, -0.5],
        [0.5, -0.5, -0.5],
        [0.5, 0.5, 0.5],
        [-0.5, 0.5, 0.5],
        [-0.5, -0.5, 0.5],
        [0.5, -0.5, 0.5],
    ]
)
BOX_FACES = np.array([[0, 1, 2, 3], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]])
"""Corner indices of the six faces, each an ordered (convex) quadrilateral."""


def box_corners(boxes: np.ndarray) -> np.ndarray:
    """Corners of 3D boxes.

    boxes: ``(N, ≥7)`` array with columns x, y, z [m] (centre), length, width, height [m], yaw [rad] —
    the first seven of :data:`simrig.types.BOX3D_FIELDS`. Returns ``(N, 8, 3)`` corners in the boxes' frame,
    ordered as :data:`BOX_FACES` expects.

    >>> box_corners(np.array([[0, 0, 1, 4, 2, 2, 0]]))[0, 0].tolist()
    [2.0, 1.0, 0.0]
    """
    boxes = np.asarray(boxes, dtype=float)
    local = _UNIT_CORNERS[None, :, :] * boxes[:, None, 3:6]
    cos, sin = np.cos(boxes[:, 6])[:, None], np.sin(boxes[:, 6])[:, None]
    x = cos * local[..., 0] - sin * local[..., 1] + boxes[:, None, 0]
    y = sin * local[..., 0] + cos * local[..., 1] + boxes[:, None, 1]
    z = local[..., 2] + boxes[:, None, 2]
    return np.stack([x, y, z], axis=-1)


def transform_points(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Apply 4×4 transforms to points: ``matrix`` (..., 4, 4) broadcast against ``points`` (..., 3)."""
    return np.einsum("...ij,...j->...i", matrix[..., :3, :3], points) + matrix[..., :3, 3]


def camera_from_world(rig: Rig, ego: EgoPose) -> np.ndarray:
    """``(C, 4, 4)`` transforms taking world points to each camera's OpenCV frame, in rig order."""
    return np.linalg.inv(ego.world_from_ego() @ _ego_from_cameras(rig))


@functools.lru_cache(maxsize=32)
def _ego_from_cameras(rig: Rig) -> np.ndarray:
    """``(C, 4, 4)``: each camera's fixed mounting (:meth:`~simrig.types.Camera.ego_from_camera`), read-only
    (asked for per frame and per projection: computed once per rig)."""
    out = np.stack([camera.ego_from_camera() for camera in rig.cameras])
    out.setflags(write=False)
    return out


def clip_convex_polygons(
    points: np.ndarray, count: np.ndarray, normals: np.ndarray, offsets: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Clip convex polygons to the half-spaces ``normal · p + offset ≥ 0`` (one per polygon).

    points: ``(M, K, D)`` vertices in order, the first ``count[m]`` valid; normals ``(M, D)``; offsets ``(M,)``.
    Returns vertices and the new ``(M,)`` counts; the array widens to ``K + 1`` (a convex polygon gains at
    most one vertex) only when some polygon is actually cut.
    """
    m, k, _ = points.shape
    index = np.arange(k)
    valid = index[None, :] < count[:, None]
    distance = np.einsum("mkd,md->mk", points, normals) + offsets[:, None]
    cut = np.nonzero((valid & (distance < 0.0)).any(axis=1))[0]
    if not len(cut):
        return points, count
    rows = np.arange(len(cut))[:, None]
    sub_points, sub_distance, sub_valid = points[cut], distance[cut], valid[cut]
    following = (index[None, :] + 1) % np.maximum(count[cut], 1)[:, None]
    distance_next = sub_distance[rows, following]
    inside, inside_next = sub_distance >= 0.0, distance_next >= 0.0
    crossing = sub_valid & (inside != inside_next)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(crossing, sub_distance / (sub_distance - distance_next), 0.0)
    intersection = sub_points + t[..., None] * (sub_points[rows, following] - sub_points)
    candidates = np.stack([sub_points, intersection], axis=2).reshape(len(cut), 2 * k, -1)
    keep = np.stack([sub_valid & inside, crossing], axis=2).reshape(len(cut), 2 * k)
    order = np.argsort(~keep, axis=1, kind="stable")[:, : k + 1]
    out = np.zeros((m, k + 1, points.shape[2]))
    out[:, :k] = points
    out[cut] = candidates[rows, order]
    new_count = count.copy()
    new_count[cut] = keep.sum(axis=1)
    return out, new_count


def _masked_bounds(points: np.ndarray, valid: np.ndarray, axis: int) -> tuple[np.ndarray, np.ndarray]:
    low = np.where(valid[..., None], points, np.inf).min(axis=axis)
    high = np.where(valid[..., None], points, -np.inf).max(axis=axis)
    return low, high


@dataclass(frozen=True, eq=False)
class Projection:
    """Boxes projected into every camera of a rig; arrays are ``(C, N, ...)`` in rig order.

    boxes: pixel boxes (x1, y1, x2, y2) of the silhouette clipped to the near plane and the image, NaN
    where not in view. unclipped: the same before clipping to the image (NaN where wholly behind the near
    plane). truncation: 1 − area(boxes) / area(unclipped) in [0, 1], NaN where not in view.
    depth: camera-frame z of each box centre [m]. in_view: some part of the box is in front of the near
    plane and inside the image, with positive area.
    """

    boxes: np.ndarray
    unclipped: np.ndarray
    truncation: np.ndarray
    depth: np.ndarray
    in_view: np.ndarray


@functools.lru_cache(maxsize=32)
def _camera_parameters(rig: Rig) -> np.ndarray:
    """``(C, 7)``: fx, fy, cx, cy [px], width, height [px], near [m] of each camera, in rig order (read-only)."""
    out = np.array([[cam.fx, cam.fy, cam.cx, cam.cy, cam.width, cam.height, cam.near] for cam in rig.cameras])
    out.setflags(write=False)
    return out


def _frustum_candidates(centres: np.ndarray, radii: np.ndarray, rig: Rig) -> np.ndarray:
    """``(C, N)`` mask of boxes whose bounding sphere (camera-frame ``centres`` (C, N, 3), ``radii`` (N,))
    reaches into each camera's viewing frustum; a conservative pre-test, exact clipping follows."""
    params = _camera_parameters(rig)
    fx, fy, cx, cy, width, height, near = (params[:, i, None] for i in range(7))
    x, y, z = centres[..., 0], centres[..., 1], centres[..., 2]
    margin = -radii[None, :]
    return (
        (z - near >= margin)
        & ((fx * x + cx * z) / np.hypot(fx, cx) >= margin)
        & ((-fx * x + (width - cx) * z) / np.hypot(fx, width - cx) >= margin)
        & ((fy * y + cy * z) / np.hypot(fy, cy) >= margin)
        & ((-fy * y + (height - cy) * z) / np.hypot(fy, height - cy) >= margin)
    )


def near_clipped_face_pixels(
    faces: np.ndarray, cameras: np.ndarray, rig: Rig
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Camera-frame box faces ``(P, F, 4, 3)`` seen by camera index ``cameras`` ``(P,)``, clipped to the near
    plane (z ≥ near) and projected to pixels.

    Returns ``pixels`` ``(P·F, K, 2)``, vertex ``count`` ``(P·F,)`` and the ``(P·F,)`` camera index of each face
    polygon; vertices past a polygon's count are meaningless. A face wholly behind the near plane has count 0.
    """
    polygons = faces.reshape(-1, 4, 3)
    m = len(polygons)
    camera_of = np.repeat(cameras, faces.shape[1])
    params = _camera_parameters(rig)
    fx, fy, cx, cy, near = (params[camera_of, i] for i in (0, 1, 2, 3, 6))
    normal = np.zeros((m, 3))
    normal[:, 2] = 1.0
    polygons, count = clip_convex_polygons(polygons, np.full(m, 4), normal, -near)  # keep z >= near
    valid = np.arange(polygons.shape[1])[None, :] < count[:, None]
    z = np.where(valid, polygons[..., 2], 1.0)
    pixels = np.stack(
        [fx[:, None] * polygons[..., 0] / z + cx[:, None], fy[:, None] * polygons[..., 1] / z + cy[:, None]],
        axis=-1,
    )
    return pixels, count, camera_of


def _clip_faces_to_image(
    faces: np.ndarray, cameras: np.ndarray, rig: Rig
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Bounds of camera-frame box faces ``(P, 6, 4, 3)`` seen by camera index ``cameras`` ``(P,)``.

    Returns (low, high) of the silhouette clipped to the near plane and the image, and (low, high) of the
    silhouette clipped to the near plane only; ``(P, 2)`` pixels each, ±inf where nothing is left.
    """
    p = len(faces)
    pixels, count, camera_of = near_clipped_face_pixels(faces, cameras, rig)
    m = len(pixels)
    valid = np.arange(pixels.shape[1])[None, :] < count[:, None]
    unclipped = _masked_bounds(pixels.reshape(p, -1, 2), valid.reshape(p, -1), 1)

    params = _camera_parameters(rig)
    width, height = params[camera_of, 4], params[camera_of, 5]
    zeros, ones = np.zeros(m), np.ones(m)
    for normal, offset in (
        (np.stack([ones, zeros], 1), zeros),  # x >= 0
        (np.stack([-ones, zeros], 1), width),  # x <= width
        (np.stack([zeros, ones], 1), zeros),  # y >= 0
        (np.stack([zeros, -ones], 1), height),  # y <= height
    ):
        pixels, count = clip_convex_polygons(pixels, count, normal, offset)
    valid = np.arange(pixels.shape[1])[None, :] < count[:, None]
    clipped = _masked_bounds(pixels.reshape(p, -1, 2), valid.reshape(p, -1), 1)
    return (*clipped, *unclipped)


def project_boxes(boxes: np.ndarray, rig: Rig, ego: EgoPose) -> Projection:
    """Project world-frame 3D boxes (``(N, ≥7)``, :data:`~simrig.types.BOX3D_FIELDS` order) into every camera."""
    return _project_boxes_from(boxes, rig, camera_from_world(rig, ego)[:, None])


def project_boxes_at(boxes: np.ndarray, rig: Rig, egos: list[EgoPose], pose_of_box: np.ndarray,
                     offsets: np.ndarray | None = None) -> Projection:
    """:func:`project_boxes` for boxes of several frames at once: box ``i`` seen from ego pose
    ``egos[pose_of_box[i]]`` — the same numbers as one :func:`project_boxes` call per pose. ``offsets``
    ``(F, C)`` [s]: camera ``c`` of pose ``f`` fires that long after the pose's time; the ego and each box move
    on at their velocities until then (:func:`project_boxes_per_camera`)."""
    if offsets is None:
        world_from_ego = np.stack([ego.world_from_ego() for ego in egos])  # (F, 4, 4)
        transforms = np.linalg.inv(world_from_ego[:, None] @ _ego_from_cameras(rig))  # (F, C, 4, 4)
        return _project_boxes_from(boxes, rig, np.swapaxes(transforms[pose_of_box], 0, 1))
    boxes = np.asarray(boxes, dtype=float)
    delta = np.asarray(offsets, dtype=float)[pose_of_box].T  # (C, N) [s]
    world_from_ego = np.array([[ego.moved(float(d)).world_from_ego() for d in row]
                               for ego, row in zip(egos, offsets, strict=True)]).reshape(len(egos), -1, 4, 4)
    transforms = np.linalg.inv(world_from_ego @ _ego_from_cameras(rig))  # (F, C, 4, 4)
    shifts = np.zeros((*delta.shape, 3))
    shifts[..., :2] = np.nan_to_num(boxes[None, :, 7:9]) * delta[..., None]
    return _project_boxes_from(boxes, rig, _after_shift(np.swapaxes(transforms[pose_of_box], 0, 1), shifts))


def cameras_from_world_at(rig: Rig, egos: list[EgoPose]) -> np.ndarray:
    """``(C, 4, 4)``: camera ``c``'s world → OpenCV transform with the ego at ``egos[c]`` (each camera seen at
    its own capture time)."""
    world_from_ego = np.stack([ego.world_from_ego() for ego in egos])  # (C, 4, 4)
    return np.linalg.inv(world_from_ego @ _ego_from_cameras(rig))


def project_boxes_per_camera(boxes: np.ndarray, rig: Rig, egos: list[EgoPose], shifts: np.ndarray) -> Projection:
    """:func:`project_boxes` with each camera ``c`` on the ego at ``egos[c]`` and seeing box ``n`` moved by
    ``shifts[c, n]`` ``(C, N, 3)`` [m, world frame] — the boxes of one frame at every camera's capture time
    (moving a box by Δ before projecting it equals moving the camera by −Δ: one transform per camera and box)."""
    shifts = np.asarray(shifts, dtype=float)
    transforms = np.broadcast_to(cameras_from_world_at(rig, egos)[:, None], (*shifts.shape[:2], 4, 4))
    return _project_boxes_from(boxes, rig, _after_shift(transforms, shifts))


def _after_shift(transforms: np.ndarray, shifts: np.ndarray) -> np.ndarray:
    """``(C, N, 4, 4)`` world → camera ``transforms`` applied after moving box ``n`` by ``shifts[c, n]`` [m]."""
    out = np.array(transforms, copy=True)
    out[..., :3, 3] += np.einsum("cnij,cnj->cni", out[..., :3, :3], shifts)
    return out


def _project_boxes_from(boxes: np.ndarray, rig: Rig, transforms: np.ndarray) -> Projection:
    """Project world-frame 3D boxes (``(N, ≥7)``) into every camera with ``transforms`` ``(C, N, 4, 4)`` taking
    each box's world frame to each camera's (``(C, 1, 4, 4)``: one pose for every box)."""
    boxes = np.asarray(boxes, dtype=float)
    if boxes.ndim != 2 or boxes.shape[1] < 7:
        raise ValueError(f"boxes: expected shape (N, 9) in BOX3D_FIELDS order, got {boxes.shape}")
    n, c = len(boxes), len(rig.cameras)
    centres = transform_points(transforms, boxes[None, :, :3])  # (C, N, 3)
    radii = 0.5 * np.linalg.norm(boxes[:, 3:6], axis=1)
    camera_index, box_index = np.nonzero(_frustum_candidates(centres, radii, rig))

    clipped = np.full((c, n, 4), np.nan)
    unclipped = np.full((c, n, 4), np.nan)
    if len(camera_index):
        pair_transforms = transforms[camera_index, box_index if transforms.shape[1] > 1 else 0, None]  # (P, 1, 4, 4)
        corners = transform_points(pair_transforms, box_corners(boxes[box_index]))  # (P, 8, 3)
        low, high, raw_low, raw_high = _clip_faces_to_image(corners[:, BOX_FACES], camera_index, rig)
        clipped[camera_index, box_index] = np.concatenate([low, high], axis=-1)
        unclipped[camera_index, box_index] = np.concatenate([raw_low, raw_high], axis=-1)
    clipped[~np.isfinite(clipped)] = np.nan
    unclipped[~np.isfinite(unclipped)] = np.nan

    area = (clipped[..., 2] - clipped[..., 0]) * (clipped[..., 3] - clipped[..., 1])
    unclipped_area = (unclipped[..., 2] - unclipped[..., 0]) * (unclipped[..., 3] - unclipped[..., 1])
    in_view = area > 0.0  # False for NaN
    with np.errstate(invalid="ignore", divide="ignore"):
        truncation = np.where(in_view, np.clip(1.0 - area / unclipped_area, 0.0, 1.0), np.nan)
    clipped[~in_view] = np.nan
    return Projection(
        boxes=clipped, unclipped=unclipped, truncation=truncation, depth=centres[..., 2], in_view=in_view
    )


def viewing_bearings(boxes3d: np.ndarray, camera_centre: np.ndarray) -> np.ndarray:
    """[rad] in (−π, π] the bearing of each camera's ray to each box in the box's own frame (0: the camera sees the
    back, ±π the front, ±π/2 a side); ``boxes3d`` ``(K, ≥7)`` world frame, ``camera_centre`` ``(3,)`` or
    ``(K, 3)``.

    >>> boxes = np.array([[10.0, 0.0, 0, 4, 2, 1, 0.0], [10.0, 0.0, 0, 4, 2, 1, np.pi]])
    >>> np.rad2deg(viewing_bearings(boxes, np.zeros(3))).round(6).tolist()  # behind a car, then facing one
    [0.0, 180.0]
    """
    ray = boxes3d[:, :2] - camera_centre[..., :2]
    return np.pi - (np.pi - (np.arctan2(ray[:, 1], ray[:, 0]) - boxes3d[:, 6])) % (2 * np.pi)


def as_estimated(boxes: np.ndarray, true: EgoPose, estimate: EgoPose) -> np.ndarray:
    """World-frame boxes ``(..., 9)`` as a stack that localises with ``estimate`` instead of ``true`` reports
    them: measured relative to the ego, put back into the world with the estimated pose (positions rotated
    about the ego and moved with it, yaw and velocity rotated)."""
    turn = estimate.yaw - true.yaw
    c, s = math.cos(turn), math.sin(turn)
    out = np.array(boxes, dtype=float, copy=True)
    dx, dy = out[..., 0] - true.x, out[..., 1] - true.y
    out[..., 0] = estimate.x + c * dx - s * dy
    out[..., 1] = estimate.y + s * dx + c * dy
    out[..., 6] = (out[..., 6] + turn + np.pi) % (2 * np.pi) - np.pi
    vx, vy = out[..., 7].copy(), out[..., 8]
    out[..., 7] = c * vx - s * vy
    out[..., 8] = s * vx + c * vy
    return out
