"""The pyrender scene of one run: vehicle meshes, the road, and offscreen segmentation and colour renders.

Conventions, converted here once: simrig's cameras use the OpenCV frame (x right, y down, z forward);
pyrender's camera looks along −z with +y up, so a camera's pyrender pose is ``world_from_camera @
diag(1, −1, −1, 1)``. The scene is re-centred on the ego every frame (everything is placed relative to the
ego's position), which keeps float32 vertex coordinates precise kilometres down the road.

One OpenGL context per process (:func:`offscreen_renderer`): deleting a pyrender ``OffscreenRenderer``
tears down the EGL display every other renderer shares (measured with pyrender 0.1.45 on Mesa EGL), so simrig keeps
one and resizes its viewport per camera. Renders are deterministic: same inputs, same pixels.
"""

from __future__ import annotations

import functools
import os

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")  # headless: must precede the first OpenGL import

import numpy as np  # noqa: E402

if not hasattr(np, "infty"):  # pyrender 0.1.45 still uses np.infty, removed in numpy 2
    np.inf = np.inf

import pyrender  # noqa: E402
import trimesh  # noqa: E402

from ..geometry import camera_from_world  # noqa: E402
from ..road import RoadMarkings  # noqa: E402
from ..types import ActorClass, Camera, EgoPose, Rig  # noqa: E402
from .road import GROUND_HALF_SIZE_M, painted_quads  # noqa: E402
from .shapes import unit_parts  # noqa: E402

OPENCV_TO_OPENGL = np.diag([1.0, -1.0, -1.0, 1.0])
"""Right-multiplied into a camera's pose: OpenCV axes (y down, z forward) to OpenGL's (y up, z backward)."""
Z_FAR_M = 1000.0
"""[m] far clipping distance of every render; beyond any traffic window simrig allows."""
PARKED_Z_M = -1.0e4
"""[m] unused vehicle nodes wait this far below the road, outside every camera's view."""
CLASS_COLOURS = {
    ActorClass.CAR: (0.25, 0.42, 0.75),
    ActorClass.TRUCK: (0.85, 0.55, 0.15),
    ActorClass.BUS: (0.80, 0.20, 0.20),
    ActorClass.MOTORCYCLE: (0.20, 0.65, 0.35),
}
"""Base colour (RGB in [0, 1]) of each class in colour renders."""


@functools.cache
def offscreen_renderer() -> pyrender.OffscreenRenderer:
    """The process's one offscreen renderer (never deleted: see the module docstring)."""
    return pyrender.OffscreenRenderer(64, 64)


def _class_mesh(actor_class: ActorClass) -> pyrender.Mesh:
    """A unit-box-sized mesh of the class's parts, scaled to each actor's box by its node pose."""
    pieces = []
    for centre_size in unit_parts(actor_class):
        piece = trimesh.creation.box(extents=centre_size[3:])
        piece.apply_translation(centre_size[:3])
        pieces.append(piece)
    material = pyrender.MetallicRoughnessMaterial(
        baseColorFactor=(*CLASS_COLOURS[actor_class], 1.0), metallicFactor=0.1, roughnessFactor=0.7
    )
    return pyrender.Mesh.from_trimesh(trimesh.util.concatenate(pieces), material=material, smooth=False)


def seg_colour(slot: int) -> np.ndarray:
    """The exact 24-bit colour of node ``slot`` in a segmentation render (0 is the background).

    >>> seg_colour(0).tolist(), seg_colour(256).tolist()
    ([0, 0, 1], [0, 1, 1])
    """
    value = slot + 1
    return np.array([(value >> 16) & 255, (value >> 8) & 255, value & 255], dtype=np.uint8)


def decode_segmentation(image: np.ndarray) -> np.ndarray:
    """``(H, W)`` node slot of every pixel of a segmentation render, −1 for the background."""
    image = image.astype(np.int32)
    return ((image[..., 0] << 16) | (image[..., 1] << 8) | image[..., 2]) - 1


class RigScene:
    """One scene per run: a pool of vehicle nodes per class, the road, and a camera node.

    Call :meth:`set_frame` with the frame's actors, then :meth:`visible_pixel_counts` or :meth:`colour`
    per camera. Nodes are reused across frames (poses are updated, nothing is rebuilt).
    """

    def __init__(self, markings: RoadMarkings | None = None):
        self.renderer = offscreen_renderer()
        self.scene = pyrender.Scene(bg_color=(0.62, 0.75, 0.88, 1.0), ambient_light=(0.35, 0.35, 0.35))
        self._meshes = {actor_class: _class_mesh(actor_class) for actor_class in ActorClass}
        self._pools: dict[ActorClass, list[pyrender.Node]] = {actor_class: [] for actor_class in ActorClass}
        self._slot_of: dict[pyrender.Node, int] = {}
        self._active: list[pyrender.Node] = []
        self._camera_node: pyrender.Node | None = None
        self._camera_key: tuple | None = None
        self.scene.add(pyrender.DirectionalLight(color=np.ones(3), intensity=3.0), pose=_sun_pose())
        self._road_node = None
        if markings is not None:
            self._road_node = self.scene.add(road_mesh(markings))
        self._ego_xy = np.zeros(2)

    # ------------------------------------------------------------------ actors
    def _node(self, actor_class: ActorClass, index: int) -> pyrender.Node:
        pool = self._pools[actor_class]
        while len(pool) <= index:
            node = self.scene.add(self._meshes[actor_class], pose=_parked())
            self._slot_of[node] = len(self._slot_of)
            pool.append(node)
        return pool[index]

    def set_frame(self, ego: EgoPose, classes: np.ndarray, boxes: np.ndarray) -> None:
        """Place the frame's actors: ``classes`` ``(N,)`` names, ``boxes`` ``(N, ≥7)`` world-frame boxes
        (centre [m], size [m], yaw [rad]); the ego itself is not drawn."""
        self._ego_xy = np.array([ego.x, ego.y])
        used = dict.fromkeys(ActorClass, 0)
        active = []
        for name, box in zip(classes, np.asarray(boxes, dtype=float), strict=True):
            actor_class = ActorClass(name)
            node = self._node(actor_class, used[actor_class])
            used[actor_class] += 1
            self.scene.set_pose(node, self._actor_pose(box))
            active.append(node)
        for actor_class, pool in self._pools.items():
            for node in pool[used[actor_class]:]:
                self.scene.set_pose(node, _parked())
        self._active = active
        if self._road_node is not None:
            pose = np.eye(4)
            pose[:2, 3] = -self._ego_xy
            self.scene.set_pose(self._road_node, pose)

    def _actor_pose(self, box: np.ndarray) -> np.ndarray:
        """Node pose: the unit mesh scaled to the box, rotated by yaw, at the centre relative to the ego."""
        c, s = np.cos(box[6]), np.sin(box[6])
        pose = np.eye(4)
        pose[:3, :3] = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.diag(box[3:6])
        pose[:2, 3] = box[:2] - self._ego_xy
        pose[2, 3] = box[2]
        return pose

    # ------------------------------------------------------------------ cameras
    def _use_camera(self, camera: Camera, rig: Rig, ego: EgoPose) -> None:
        key = (camera.width, camera.height, camera.fx, camera.fy, camera.cx, camera.cy, camera.near)
        if key != self._camera_key:
            if self._camera_node is not None:
                self.scene.remove_node(self._camera_node)
            intrinsics = pyrender.IntrinsicsCamera(
                fx=camera.fx, fy=camera.fy, cx=camera.cx, cy=camera.cy, znear=camera.near, zfar=Z_FAR_M
            )
            self._camera_node = self.scene.add(intrinsics)
            self._camera_key = key
        index = rig.camera_names.index(camera.name)
        world_from_camera = np.linalg.inv(camera_from_world(rig, ego)[index])
        world_from_camera[:2, 3] -= self._ego_xy
        self.scene.set_pose(self._camera_node, world_from_camera @ OPENCV_TO_OPENGL)
        self.renderer.viewport_width, self.renderer.viewport_height = camera.width, camera.height

    def visible_pixel_counts(self, camera: Camera, rig: Rig, ego: EgoPose) -> np.ndarray:
        """``(N,)`` pixels of each actor (in :meth:`set_frame` order) visible in ``camera`` after occlusion,
        counted in a segmentation render at the camera's resolution."""
        self._use_camera(camera, rig, ego)
        seg_map = {node: seg_colour(slot) for node, slot in ((n, self._slot_of[n]) for n in self._active)}
        image, _ = self.renderer.render(self.scene, flags=pyrender.RenderFlags.SEG, seg_node_map=seg_map)
        slots = decode_segmentation(image)
        counts = np.bincount(slots[slots >= 0].ravel(), minlength=len(self._slot_of))
        return counts[[self._slot_of[node] for node in self._active]].astype(np.int64)

    def colour(self, camera: Camera, rig: Rig, ego: EgoPose) -> np.ndarray:
        """``(H, W, 3)`` uint8 lit colour image of ``camera`` at its resolution."""
        self._use_camera(camera, rig, ego)
        image, _ = self.renderer.render(self.scene)
        return np.ascontiguousarray(image[..., :3])


def road_mesh(markings: RoadMarkings) -> pyrender.Mesh:
    """One static mesh: a grey ground square under the map and every painted segment (:mod:`.road`)."""
    cx, cy = markings.centre
    h = GROUND_HALF_SIZE_M
    ground = np.array([[cx - h, cy - h, 0.0], [cx + h, cy - h, 0.0], [cx + h, cy + h, 0.0], [cx - h, cy + h, 0.0]])
    quads = painted_quads(markings)
    vertices = np.concatenate([ground, quads.reshape(-1, 3)])
    base = 4 * np.arange(len(quads) + 1)[:, None]
    faces = np.concatenate([base + [0, 1, 2], base + [0, 2, 3]])
    colours = np.concatenate([np.tile([90, 92, 96, 255], (4, 1)), np.tile([235, 235, 235, 255], (4 * len(quads), 1))])
    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, vertex_colors=colours.astype(np.uint8), process=False)
    return pyrender.Mesh.from_trimesh(mesh, smooth=False)


def _parked() -> np.ndarray:
    pose = np.eye(4)
    pose[2, 3] = PARKED_Z_M
    return pose


def _sun_pose() -> np.ndarray:
    """A directional light shining down and forward-left (pyrender lights point along their −z)."""
    elevation, azimuth = np.radians(50.0), np.radians(30.0)
    direction = -np.array([np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth), np.sin(elevation)])
    z = -direction
    x = np.cross([0.0, 0.0, 1.0], z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    pose = np.eye(4)
    pose[:3, :3] = np.stack([x, y, z], axis=1)
    return pose
