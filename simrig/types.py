"""The records every simrig package shares: poses, boxes, cameras, frames, detections, tracks.

Import-light on purpose: numpy and the standard library only (no highway-env, pyrender or pyarrow), so
that a tracker can be written and tested against these records alone.

Frames and units
----------------
* World frame: right-handed, metres, x along the road, y to the left, z up; yaw in radians,
  counter-clockwise from +x.
* Ego frame: the same axes attached to the ego vehicle; origin at the centre of its footprint on the road.
* Camera frame: OpenCV convention (x right, y down, z forward), metres.
* Time: seconds. 2D boxes: pixels, (x1, y1, x2, y2) with (0, 0) the top-left corner of the image.

Arrays of boxes use the column orders :data:`BOX3D_FIELDS` and :data:`BOX2D_FIELDS`.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from .names import path_part

BOX3D_FIELDS: tuple[str, ...] = ("x", "y", "z", "length", "width", "height", "yaw", "vx", "vy")
"""Column order of an ``(N, 9)`` array of 3D boxes: centre [m], size [m], yaw [rad], velocity [m/s]."""

BOX2D_FIELDS: tuple[str, ...] = ("x1", "y1", "x2", "y2")
"""Column order of an ``(N, 4)`` array of 2D boxes [px]."""


class ActorClass(enum.StrEnum):
    """Object classes. The string value is what the dataset stores. Traffic simulates the vehicles (car, truck,
    bus, motorcycle); pedestrians and bicycles come only from imported ground truth (``simrig import``) and the
    tracks scored on it (nuScenes' names)."""

    CAR = "car"
    TRUCK = "truck"
    BUS = "bus"
    MOTORCYCLE = "motorcycle"
    PEDESTRIAN = "pedestrian"
    BICYCLE = "bicycle"


def _readonly(array: np.ndarray, dtype, shape_tail: tuple[int, ...], name: str) -> np.ndarray:
    """Copy ``array`` to ``dtype``, check its trailing shape and freeze it."""
    out = np.array(array, dtype=dtype, copy=True)
    if out.shape[1:] != shape_tail and shape_tail != ():
        raise ValueError(f"{name}: expected shape (N, {', '.join(map(str, shape_tail))}), got {out.shape}")
    out.setflags(write=False)
    return out


@dataclass(frozen=True, slots=True)
class EgoPose:
    """Pose of the ego vehicle in the world frame.

    x, y, z: origin of the ego frame [m] (centre of the footprint, on the road); yaw [rad] CCW from +x;
    vx, vy: velocity [m/s] in the world frame.
    """

    x: float
    y: float
    z: float
    yaw: float
    vx: float = 0.0
    vy: float = 0.0

    def moved(self, seconds: float) -> EgoPose:
        """The pose ``seconds`` later at constant velocity (heading and velocity unchanged).

        >>> EgoPose(1.0, 2.0, 0.0, 0.0, vx=10.0).moved(0.04).x
        1.4
        """
        return EgoPose(self.x + self.vx * seconds, self.y + self.vy * seconds, self.z, self.yaw, self.vx, self.vy)

    def world_from_ego(self) -> np.ndarray:
        """4×4 homogeneous transform taking ego-frame points to the world frame."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return np.array(
            [[c, -s, 0.0, self.x], [s, c, 0.0, self.y], [0.0, 0.0, 1.0, self.z], [0.0, 0.0, 0.0, 1.0]]
        )


@dataclass(frozen=True, slots=True)
class Box3D:
    """A 3D box in the world frame: centre (x, y, z) [m], size (length along yaw, width, height) [m],
    yaw [rad] CCW from +x, velocity (vx, vy) [m/s]."""

    x: float
    y: float
    z: float
    length: float
    width: float
    height: float
    yaw: float
    vx: float = 0.0
    vy: float = 0.0

    def as_array(self) -> np.ndarray:
        """The box as a ``(9,)`` array in :data:`BOX3D_FIELDS` order."""
        return np.array([getattr(self, name) for name in BOX3D_FIELDS], dtype=float)


@dataclass(frozen=True, slots=True)
class Box2D:
    """An axis-aligned pixel box (x1, y1) top-left to (x2, y2) bottom-right [px]."""

    x1: float
    y1: float
    x2: float
    y2: float

    def as_array(self) -> np.ndarray:
        """The box as a ``(4,)`` array in :data:`BOX2D_FIELDS` order."""
        return np.array([self.x1, self.y1, self.x2, self.y2], dtype=float)

    @property
    def area(self) -> float:
        """Area [px²]; 0 for an empty box."""
        return max(0.0, self.x2 - self.x1) * max(0.0, self.y2 - self.y1)


@dataclass(frozen=True, slots=True)
class Camera:
    """A pinhole camera mounted on the ego vehicle.

    Intrinsics: image size ``width`` × ``height`` [px], focal lengths ``fx``, ``fy`` [px], principal point
    ``cx``, ``cy`` [px] (measured from the top-left corner).
    Extrinsics: optical centre ``position`` (x, y, z) [m] in the ego frame; orientation as ``yaw`` [rad]
    (direction of the optical axis, CCW from the ego's +x), ``pitch`` [rad] (positive tilts the axis up) and
    ``roll`` [rad] about the optical axis. ``near`` [m] is the near clipping distance used both by the
    analytic projection and the renderer.
    """

    name: str
    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    position: tuple[float, float, float]
    yaw: float
    pitch: float = 0.0
    roll: float = 0.0
    near: float = 0.1

    @property
    def intrinsics(self) -> np.ndarray:
        """3×3 camera matrix K [px]."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def horizontal_fov(self) -> float:
        """Horizontal field of view [rad] for a principal point at the image centre."""
        return 2.0 * math.atan(self.width / (2.0 * self.fx))

    def ego_from_camera(self) -> np.ndarray:
        """4×4 transform taking camera-frame points (OpenCV: x right, y down, z forward) to the ego frame."""
        cy_, sy_ = math.cos(self.yaw), math.sin(self.yaw)
        cp, sp = math.cos(self.pitch), math.sin(self.pitch)
        cr, sr = math.cos(self.roll), math.sin(self.roll)
        # Axes of a level camera looking along ego +x: forward = +x, right = -y, down = -z.
        level = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
        roll = np.array([[cr, -sr, 0.0], [sr, cr, 0.0], [0.0, 0.0, 1.0]])  # about the camera's z axis
        pitch = np.array([[cp, 0.0, -sp], [0.0, 1.0, 0.0], [sp, 0.0, cp]])  # about ego y, up is positive
        yaw = np.array([[cy_, -sy_, 0.0], [sy_, cy_, 0.0], [0.0, 0.0, 1.0]])
        out = np.eye(4)
        out[:3, :3] = yaw @ pitch @ level @ roll
        out[:3, 3] = self.position
        return out


@dataclass(frozen=True, slots=True)
class Rig:
    """A named set of cameras on the ego vehicle, in a fixed order."""

    name: str
    cameras: tuple[Camera, ...]

    def __post_init__(self) -> None:
        names = [camera.name for camera in self.cameras]
        for name in names:  # a camera name becomes a folder (images/NAME/) and an export file name
            path_part(name, f"rig {self.name!r}: camera name")
        if len(set(names)) != len(names):
            raise ValueError(f"rig {self.name!r}: camera names must be unique, got {names}")

    @property
    def camera_names(self) -> tuple[str, ...]:
        return tuple(camera.name for camera in self.cameras)

    def camera(self, name: str) -> Camera:
        """The camera called ``name``; a ``KeyError`` naming the rig's cameras otherwise."""
        for camera in self.cameras:
            if camera.name == name:
                return camera
        raise KeyError(f"rig {self.name!r} has no camera {name!r}; cameras: {', '.join(self.camera_names)}")


@dataclass(frozen=True, eq=False)
class CameraGroundTruth:
    """Exact ground truth of every actor as one camera sees it; arrays aligned with the frame's actors.

    boxes: ``(N, 4)`` pixel boxes (:data:`BOX2D_FIELDS`), NaN where the actor is not in view; the box is
    the bounding box of the actor's silhouette after clipping to the near plane and to the image.
    truncation: ``(N,)`` fraction [0, 1] of the unclipped projected box lying outside the image (NaN where
    not in view). depth: ``(N,)`` camera-frame z of the box centre [m]. in_view: ``(N,)`` bool.
    occlusion: ``(N,)`` occlusion ratio [0, 1], 1 − visible / unoccluded silhouette pixels (NaN where not in
    view or not measured); the visible fraction of an actor in the image is ``1 − occlusion``.
    """

    boxes: np.ndarray
    truncation: np.ndarray
    depth: np.ndarray
    in_view: np.ndarray
    occlusion: np.ndarray | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "boxes", _readonly(self.boxes, float, (4,), "boxes"))
        if self.occlusion is None:
            object.__setattr__(self, "occlusion", np.full(len(self.boxes), np.nan))
        for name, dtype in (("truncation", float), ("depth", float), ("in_view", bool), ("occlusion", float)):
            object.__setattr__(self, name, _readonly(getattr(self, name), dtype, (), name))


EGO_ID = -1
"""The actor id that stands for the ego in a collision (the ego has no actor id of its own)."""
OBSTACLE_ID = -2
"""The actor id that stands for a fixed obstacle of the road (the end of a ramp's acceleration lane) in a collision."""


@dataclass(frozen=True, slots=True)
class Collision:
    """Two road users whose footprints met during a frame (:mod:`simrig.world.collisions`).

    first, second: actor ids, ``first <= second`` (:data:`EGO_ID` the ego, :data:`OBSTACLE_ID` a fixed obstacle);
    closing_speed [m/s]: how fast their centres approached each other at the step they met; geometry: their
    footprints touch or overlap (the verdict); highway_env: highway-env flagged both crashed at that step (recorded
    beside it: the two should always agree; a row where one says no, with ``first == second``, is a vehicle
    highway-env flagged without touching anything)."""

    first: int
    second: int
    closing_speed: float
    geometry: bool = True
    highway_env: bool = True


@dataclass(frozen=True, eq=False)
class GroundTruthFrame:
    """Everything true at one time step (never given to a tracker).

    frame: index from 0; timestamp [s]; ego: the ego pose; actor_ids: ``(N,)`` int64 ids, unique and
    stable for an actor's lifetime; classes: ``(N,)`` class names (:class:`ActorClass` values);
    boxes: ``(N, 9)`` world-frame boxes in :data:`BOX3D_FIELDS` order; cameras: per camera name, the
    actors' projections; events: the perturbation events active at this frame (for cause attribution);
    collisions: the collisions that happened during the step to this frame.
    """

    frame: int
    timestamp: float
    ego: EgoPose
    actor_ids: np.ndarray
    classes: np.ndarray
    boxes: np.ndarray
    cameras: Mapping[str, CameraGroundTruth] = field(default_factory=dict)
    events: tuple[str, ...] = ()
    collisions: tuple[Collision, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "actor_ids", _readonly(self.actor_ids, np.int64, (), "actor_ids"))
        object.__setattr__(self, "classes", _readonly(self.classes, object, (), "classes"))
        object.__setattr__(self, "boxes", _readonly(self.boxes, float, (len(BOX3D_FIELDS),), "boxes"))
        n = len(self.actor_ids)
        if len(self.classes) != n or len(self.boxes) != n:
            raise ValueError(
                f"frame {self.frame}: {n} actor ids but {len(self.classes)} classes and {len(self.boxes)} boxes"
            )


@dataclass(frozen=True, eq=False)
class Detection:
    """One detection from one camera: pixel ``box``, confidence ``score`` in [0, 1], class ``label``,
    optionally a monocular 3D estimate ``box3d`` in the world frame and an appearance ``embedding``
    (unit vector). Carries no ground-truth id. ``capture_time`` [s]: when its camera took the image, as the
    camera reports it (None: at the frame's timestamp); ``late``: it was captured in an earlier frame and
    arrived after that frame's step."""

    box: Box2D
    score: float
    label: ActorClass
    box3d: Box3D | None = None
    embedding: np.ndarray | None = None
    capture_time: float | None = None
    late: bool = False


LABELS: tuple[ActorClass, ...] = tuple(ActorClass)
"""Class codes: a detection's ``label`` code indexes this tuple (``LABELS[0]`` is ``car``)."""


@dataclass(frozen=True, eq=False)
class DetectionArrays:
    """One frame's detections from every camera as flat arrays, ``M`` rows: cameras in rig order, detections
    in camera order (row ``j`` of every array is one detection).

    boxes3d: ``(M, 9)`` world-frame boxes in :data:`BOX3D_FIELDS` order [m, rad, m/s], a row of NaN where a
    detection has no 3D estimate; boxes2d: ``(M, 4)`` pixel boxes [px]; scores: ``(M,)`` in [0, 1];
    labels: ``(M,)`` int codes into :data:`LABELS`; cameras: ``(M,)`` int index of the camera in the rig;
    embeddings: ``(M, D)`` appearance unit vectors, a row of NaN where a detection has none (``D`` = 0 when
    none has one); capture_times: ``(M,)`` [s] when each detection's image was taken, as its camera reports it
    (NaN: at the frame's timestamp, which is what a dataset of a synchronous rig gives); late: ``(M,)`` bool,
    captured in an earlier frame and delivered now (:mod:`simrig.scenarios.timing_schema`).
    """

    boxes3d: np.ndarray
    boxes2d: np.ndarray
    scores: np.ndarray
    labels: np.ndarray
    cameras: np.ndarray
    embeddings: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), dtype=np.float32))
    capture_times: np.ndarray | None = None
    late: np.ndarray | None = None

    def __post_init__(self) -> None:
        m = len(self.scores)
        if len(self.embeddings) != m:
            object.__setattr__(self, "embeddings", np.full((m, 0), np.nan, dtype=np.float32))
        if self.capture_times is None or len(self.capture_times) != m:
            object.__setattr__(self, "capture_times", np.full(m, np.nan))
        if self.late is None or len(self.late) != m:
            object.__setattr__(self, "late", np.zeros(m, dtype=bool))
        for name in ("boxes3d", "boxes2d", "scores", "labels", "cameras", "embeddings", "capture_times", "late"):
            getattr(self, name).setflags(write=False)  # a tracker cannot change what the next one sees

    def __len__(self) -> int:
        return len(self.scores)

    def take(self, rows: np.ndarray) -> DetectionArrays:
        """The detections at ``rows`` (an index or boolean array), in that order."""
        return DetectionArrays(
            self.boxes3d[rows], self.boxes2d[rows], self.scores[rows], self.labels[rows], self.cameras[rows],
            self.embeddings[rows], self.capture_times[rows], self.late[rows],
        )

    @staticmethod
    def empty() -> DetectionArrays:
        return DetectionArrays(
            np.zeros((0, 9)), np.zeros((0, 4)), np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        )

    def detections(self, camera_names: tuple[str, ...]) -> dict[str, tuple[Detection, ...]]:
        """The same detections as :class:`Detection` objects per camera name (every camera present)."""
        out: dict[str, list[Detection]] = {name: [] for name in camera_names}
        has_3d = ~np.isnan(self.boxes3d[:, 0])
        has_embedding = np.isfinite(self.embeddings).all(axis=1) & (self.embeddings.shape[1] > 0)
        for row in range(len(self)):
            out[camera_names[self.cameras[row]]].append(Detection(
                box=Box2D(*self.boxes2d[row].tolist()),
                score=float(self.scores[row]),
                label=LABELS[self.labels[row]],
                box3d=Box3D(*self.boxes3d[row].tolist()) if has_3d[row] else None,
                embedding=self.embeddings[row] if has_embedding[row] else None,
                capture_time=float(self.capture_times[row]) if np.isfinite(self.capture_times[row]) else None,
                late=bool(self.late[row]),
            ))
        return {name: tuple(items) for name, items in out.items()}


class SensorFrame:
    """What a tracker sees at one time step: frame index, timestamp [s], the ego pose, the rig, and the
    detections of every camera.

    The detections are held as :class:`DetectionArrays` (``frame.arrays``: what the dataset reader gives
    and what the reference trackers use, no per-detection objects). ``frame.detections`` is a view of the
    same detections as a mapping camera name → tuple of :class:`Detection` (an empty tuple when a camera
    reports nothing), built on first use. A frame can be made from either: pass ``detections`` (a mapping,
    as a user's test does) or ``arrays``. ``images``: per camera name, the path of that camera's image for
    this frame, when the dataset has images (empty otherwise). Immutable.
    """

    __slots__ = ("frame", "timestamp", "ego", "rig", "images", "_arrays", "_detections")

    def __init__(
        self,
        frame: int,
        timestamp: float,
        ego: EgoPose,
        rig: Rig,
        detections: Mapping[str, tuple[Detection, ...]] | None = None,
        *,
        arrays: DetectionArrays | None = None,
        images: Mapping[str, str] | None = None,
    ) -> None:
        if detections is not None and arrays is not None:
            raise ValueError(f"frame {frame}: give detections or arrays, not both")
        for name, value in (("frame", frame), ("timestamp", timestamp), ("ego", ego), ("rig", rig),
                            ("images", dict(images or {})), ("_arrays", arrays),
                            ("_detections", None if detections is None else dict(detections))):
            object.__setattr__(self, name, value)
        if detections is None and arrays is None:
            object.__setattr__(self, "_arrays", DetectionArrays.empty())

    def __setattr__(self, name: str, value) -> None:
        raise AttributeError(f"SensorFrame is immutable: cannot set {name!r}")

    def __repr__(self) -> str:
        count = len(self._arrays) if self._arrays is not None else sum(map(len, self._detections.values()))
        return f"SensorFrame(frame={self.frame}, timestamp={self.timestamp}, rig={self.rig.name!r}, {count} detections)"

    def replace(self, **changes) -> SensorFrame:
        """A copy with ``changes`` (as :func:`dataclasses.replace`); new ``detections`` replace the arrays and
        new ``arrays`` replace the detections."""
        values = {"frame": self.frame, "timestamp": self.timestamp, "ego": self.ego, "rig": self.rig,
                  "images": self.images}
        if "detections" not in changes and "arrays" not in changes:
            if self._arrays is not None:
                values["arrays"] = self._arrays
            else:
                values["detections"] = self._detections
        unknown = set(changes) - {"frame", "timestamp", "ego", "rig", "images", "detections", "arrays"}
        if unknown:
            raise TypeError(f"SensorFrame has no field {sorted(unknown)[0]!r}")
        return SensorFrame(**{**values, **changes})

    __replace__ = replace  # copy.replace (Python 3.13)

    @property
    def detections(self) -> Mapping[str, tuple[Detection, ...]]:
        """Per camera name, the tuple of :class:`Detection` objects (a view of :attr:`arrays`)."""
        if self._detections is None:
            object.__setattr__(self, "_detections", self._arrays.detections(self.rig.camera_names))
        return self._detections

    @property
    def arrays(self) -> DetectionArrays | None:
        """The detections as :class:`DetectionArrays` when the frame was made from arrays (the dataset reader
        does); None for a frame made from :class:`Detection` objects (convert it with
        ``simrig.trackers.detections.detection_arrays``, which checks every value)."""
        return self._arrays


@dataclass(frozen=True, eq=False)
class Track:
    """One output of a tracker at one time step: ``track_id``, class ``label``, confidence ``score``,
    and either a world-frame ``box3d`` (3D trackers; velocity in the box) or per-camera pixel boxes
    ``boxes2d`` (2D trackers), or both."""

    track_id: int
    label: ActorClass
    score: float
    box3d: Box3D | None = None
    boxes2d: Mapping[str, Box2D] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.box3d is None and not self.boxes2d:
            raise ValueError(f"track {self.track_id}: needs a 3D box or at least one per-camera 2D box")
