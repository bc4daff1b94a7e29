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

if not os.environ.get("PYOPENGL_PLATFORM"):  # unset or empty: headless EGL (must precede the first OpenGL import)
    os.environ["PYOPENGL_PLATFORM"] = "egl"

import numpy as np  # noqa: E402

if "infty" not in np.__dict__:  # pyrender 0.1.45 still uses np.infty (scene bounds), removed in numpy 2
    np.infty = np.inf  # noqa: NPY201  (without the noqa, ruff --fix rewrites this line into a no-op)

from ..errors import RenderPlatformError  # noqa: E402


def _platform_error(error: BaseException) -> RenderPlatformError:
    """The one-line error for an OpenGL platform that cannot render offscreen here."""
    platform = os.environ.get("PYOPENGL_PLATFORM")
    detail = " ".join(str(part) for part in getattr(error, "args", ()) if part) or type(error).__name__
    return RenderPlatformError(
        f"cannot render offscreen with PYOPENGL_PLATFORM={platform!r} ({type(error).__name__}: {detail}); simrig "
        "renders headless with EGL: unset PYOPENGL_PLATFORM or set it to egl (or turn rendering off: "
        "render.visibility = false in the scenario)")


try:
    import pyrender  # noqa: E402
except (ImportError, OSError) as _error:  # the platform's GL library cannot be loaded (osmesa without OSMesa)
    raise _platform_error(_error) from None
import trimesh  # noqa: E402

from ..geometry import camera_from_world  # noqa: E402
from ..road import RoadMarkings  # noqa: E402
from ..types import ActorClass, Camera, EgoPose, Rig  # noqa: E402
from .road import GROUND_HALF_SIZE_M, painted_quads  # noqa: E402
from .segmentation import SegmentationPass  # noqa: E402
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
    ActorClass.PEDESTRIAN: (0.60, 0.30, 0.70),
    ActorClass.BICYCLE: (0.15, 0.60, 0.65),
}
"""Base colour (RGB in [0, 1]) of each class in colour renders."""


@functools.cache
def offscreen_renderer() -> pyrender.OffscreenRenderer:
    """The process's one offscreen renderer (never deleted: see the module docstring); a
    :class:`~simrig.errors.RenderPlatformError` when the OpenGL platform cannot make one."""
    try:
        return pyrender.OffscreenRenderer(64, 64)
    except (ValueError, RuntimeError, ImportError, OSError, AttributeError) as error:  # glx without a display, ...
        raise _platform_error(error) from None


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


class RigScene:
    """One scene per run: a pool of vehicle nodes per class, the road, and a camera node.

    Call :meth:`set_frame` with the frame's actors, then :meth:`visible_pixel_counts` or :meth:`colour`
    per camera. Segmentation renders draw all actors in one call (:mod:`.segmentation`); colour renders
    draw the node pools, which are reused across frames (poses are updated, nothing is rebuilt).
    """

    def __init__(self, markings: RoadMarkings | None = None):
        self.renderer = offscreen_renderer()
        self.scene = pyrender.Scene(bg_color=(0.62, 0.75, 0.88, 1.0), ambient_light=(0.35, 0.35, 0.35))
        self._meshes = {actor_class: _class_mesh(actor_class) for actor_class in ActorClass}
        self._pools: dict[ActorClass, list[pyrender.Node]] = {actor_class: [] for actor_class in ActorClass}
        self.renderer._platform.make_current()  # the pass's buffers and shader live in pyrender's context
        self._segmentation = SegmentationPass(
            {actor_class: _triangle_positions(mesh) for actor_class, mesh in self._meshes.items()}
        )
        self._classes: list[ActorClass] = []
        self._poses = np.zeros((0, 4, 4))
        self._segmentation_stale = self._nodes_stale = False
        self._camera_node: pyrender.Node | None = None
        self._camera_key: tuple | None = None
        self.scene.add(pyrender.DirectionalLight(color=np.ones(3), intensity=3.0), pose=_sun_pose())
        self._road_node = None
        if markings is not None:
            self._road_node = self.scene.add(_road_mesh(markings))
        self._ego_xy = np.zeros(2)

    # ------------------------------------------------------------------ actors
    def _node(self, actor_class: ActorClass, index: int) -> pyrender.Node:
        pool = self._pools[actor_class]
        while len(pool) <= index:
            pool.append(self.scene.add(self._meshes[actor_class], pose=_parked()))
        return pool[index]

    def set_frame(self, ego: EgoPose, classes: np.ndarray, boxes: np.ndarray) -> None:
        """Place the frame's actors: ``classes`` ``(N,)`` names, ``boxes`` ``(N, ≥7)`` world-frame boxes
        (centre [m], size [m], yaw [rad]); the ego itself is not drawn."""
        self._ego_xy = np.array([ego.x, ego.y])
        self._classes = [ActorClass(name) for name in classes]
        self._poses = np.array([self._actor_pose(box) for box in np.asarray(boxes, dtype=float)]).reshape(-1, 4, 4)
        self._segmentation_stale = self._nodes_stale = True
        if self._road_node is not None:
            pose = np.eye(4)
            pose[:2, 3] = -self._ego_xy
            self.scene.set_pose(self._road_node, pose)

    def _place_nodes(self) -> list[pyrender.Node]:
        """Move the node pools to the frame's poses (colour renders draw the nodes; unused ones are parked);
        returns the actors' nodes in :meth:`set_frame` order."""
        used = dict.fromkeys(ActorClass, 0)
        nodes = []
        for actor_class, pose in zip(self._classes, self._poses, strict=True):
            node = self._node(actor_class, used[actor_class])
            used[actor_class] += 1
            self.scene.set_pose(node, pose)
            nodes.append(node)
        for actor_class, pool in self._pools.items():
            for node in pool[used[actor_class]:]:
                self.scene.set_pose(node, _parked())
        self._nodes_stale = False
        return nodes

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
        counted in a segmentation render at the camera's resolution (:mod:`.segmentation`: one draw call)."""
        self._use_camera(camera, rig, ego)
        self.renderer._platform.make_current()  # pyrender's context (the process's one: see the docstring)
        if self._segmentation_stale:
            self._segmentation.set_actors(self._classes, self._poses)
            self._segmentation_stale = False
        projection = self._camera_node.camera.get_projection_matrix(width=camera.width, height=camera.height)
        return self._segmentation.counts(
            self.scene.get_pose(self._camera_node), projection, camera.width, camera.height
        )

    def colour(self, camera: Camera, rig: Rig, ego: EgoPose) -> np.ndarray:
        """``(H, W, 3)`` uint8 lit colour image of ``camera`` at its resolution."""
        if self._nodes_stale:
            self._place_nodes()
        self._use_camera(camera, rig, ego)
        image, _ = self.renderer.render(self.scene)
        return np.ascontiguousarray(image[..., :3])


def _road_mesh(markings: RoadMarkings) -> pyrender.Mesh:
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


def _triangle_positions(mesh: pyrender.Mesh) -> np.ndarray:
    """``(K, 3)`` float32 vertex positions of a one-primitive, unindexed mesh: what pyrender draws."""
    (primitive,) = mesh.primitives
    if primitive.indices is not None:
        raise ValueError("expected an unindexed (smooth=False) mesh")
    return primitive.positions


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
