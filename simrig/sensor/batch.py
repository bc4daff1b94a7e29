"""The working record of the detector at one frame, for every camera of the rig at once, which every sensor
effect reads and updates."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..types import Camera


@dataclass(frozen=True, eq=False)
class FrameContext:
    """Frame-level facts shared by all cameras: index, timestamp [s], ego yaw [rad], actor ids and distances
    [m] from the ego (for ``nearest = k`` choices)."""

    frame: int
    timestamp: float
    ego_yaw: float
    actor_ids: np.ndarray
    ego_distance: np.ndarray


@dataclass(eq=False)
class SensorBatch:
    """Everything the detectors of ``C`` cameras (rig order) know and decide at one frame, vectorised over
    cameras × the ``N`` actors of the frame (every camera sees the same actor list; most are out of its view).

    Inputs (ground truth, never shown to a tracker): ``classes`` ``(N,)``; ``boxes3d`` ``(C, N, 9)`` world
    frame, each camera's at its capture time (:mod:`.capture`; the same rows for every camera of a synchronous
    rig); per camera ``world_from_camera`` ``(C, 4, 4)`` at its capture time; per camera and actor
    ``boxes2d`` ``(C, N, 4)`` pixels (NaN where not in view), ``truncation``, ``visible_fraction`` (1 −
    occlusion; 0 where unknown or hidden) and ``distance`` [m] from the camera's optical centre to the box
    centre, ``in_view`` — each ``(C, N)``.

    Effects then set ``probability`` (of a detection), ``causes`` (:class:`~simrig.causes.Cause` bit masks),
    ``noise_factor`` — each ``(C, N)`` — and per camera ``yaw_offset`` [rad] and ``silenced`` (no output at
    all, not even clutter) ``(C,)``; draw ``detected`` and fill the outputs of detected actors:
    ``det_boxes2d`` ``(C, N, 4)``, ``det_boxes3d`` ``(C, N, 9)``, ``scores``, ``embeddings`` ``(C, N, D)``
    and ``labels`` (the class reported; the true class unless confused); per camera the false positives
    (``clutter[c]``: clutter, ghosts and duplicates, each row with its ``causes``) and the ghosts it reports
    (``ghost_ids[c]``); last, each detection's position in its camera's list (``detection_index`` ``(C, N)``,
    −1 for a miss; ``clutter_index[c]``).

    A camera's random draws come from its own stream per effect, so the numbers do not depend on how many
    cameras are processed together.
    """

    context: FrameContext
    cameras: tuple[Camera, ...]
    world_from_camera: np.ndarray
    classes: np.ndarray
    boxes3d: np.ndarray
    boxes2d: np.ndarray
    truncation: np.ndarray
    visible_fraction: np.ndarray
    distance: np.ndarray
    in_view: np.ndarray

    def __post_init__(self) -> None:
        c, n = self.in_view.shape
        self.probability = np.where(self.in_view, 1.0, 0.0)
        self.causes = np.zeros((c, n), dtype=np.int64)
        self.noise_factor = np.ones((c, n))
        self.yaw_offset = np.zeros(c)
        self.silenced = np.zeros(c, dtype=bool)
        self.detected = np.zeros((c, n), dtype=bool)
        self.det_boxes2d = np.full((c, n, 4), np.nan)
        self.det_boxes3d = np.full((c, n, 9), np.nan)
        self.scores = np.full((c, n), np.nan)
        self.embeddings: np.ndarray | None = None
        self.labels = np.tile(np.asarray(self.classes, dtype=object), (c, 1))
        self.ghost_ids: list[np.ndarray] = [np.empty(0, dtype=np.int64)] * c
        self.clutter: list[dict[str, np.ndarray]] = [{} for _ in range(c)]
        self.detection_index = np.full((c, n), -1, dtype=np.int64)
        self.clutter_index: list[np.ndarray] = [np.empty(0, dtype=np.int64)] * c
        self.image_width = np.array([camera.width for camera in self.cameras], dtype=float)
        self.image_height = np.array([camera.height for camera in self.cameras], dtype=float)

    def add_false_positives(self, camera_index: int, boxes2d: np.ndarray, boxes3d: np.ndarray, scores: np.ndarray,
                            labels: np.ndarray, embeddings: np.ndarray, cause: int) -> None:
        """Append false positives to camera ``camera_index`` (pixel boxes ``(K, 4)``, world boxes ``(K, 9)``,
        scores, labels, unit embeddings ``(K, D)``) with one :class:`~simrig.causes.Cause` bit mask for all."""
        k = len(scores)
        new = {"boxes2d": np.asarray(boxes2d, dtype=float).reshape(k, 4),
               "boxes3d": np.asarray(boxes3d, dtype=float).reshape(k, 9),
               "scores": np.asarray(scores, dtype=float), "labels": np.asarray(labels, dtype=object),
               "embeddings": np.asarray(embeddings, dtype=np.float32),
               "causes": np.full(k, int(cause), dtype=np.int64)}
        old = self.clutter[camera_index]
        self.clutter[camera_index] = new if not old else {
            key: np.concatenate([old[key], value]) for key, value in new.items()}

    def false_positives(self, index: int) -> dict[str, np.ndarray]:
        """Camera ``index``'s false positives (empty arrays of the right shapes when it has none)."""
        clutter = self.clutter[index]
        if clutter:
            return clutter
        d = 0 if self.embeddings is None else self.embeddings.shape[2]
        return {"boxes2d": np.empty((0, 4)), "boxes3d": np.empty((0, 9)), "scores": np.empty(0),
                "labels": np.empty(0, dtype=object), "embeddings": np.empty((0, d), dtype=np.float32),
                "causes": np.empty(0, dtype=np.int64)}

    @property
    def actor_ids(self) -> np.ndarray:
        return self.context.actor_ids

    def __len__(self) -> int:
        """The number of actors ``N``."""
        return len(self.classes)
