"""The working record of one camera's detector at one frame, which every sensor effect reads and updates."""

from __future__ import annotations

from dataclasses import dataclass, field

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
class CameraBatch:
    """Everything one camera's detector knows and decides at one frame, vectorised over the ``N`` actors.

    Inputs (ground truth, never shown to a tracker): ``boxes3d`` ``(N, 9)`` world frame; ``boxes2d`` ``(N, 4)``
    pixels (NaN where not in view); ``truncation``, ``visible_fraction`` (1 − occlusion; 0 where unknown or
    hidden) and ``distance`` [m] from the camera's optical centre to the box centre; ``in_view``.

    Effects then set ``probability`` (of a detection), ``causes`` (:class:`~.causes.Cause` bit masks),
    ``noise_factor`` and ``yaw_offset`` [rad], ``silenced`` (no output at all, not even clutter), draw
    ``detected`` and fill the outputs of detected actors: ``det_boxes2d``, ``det_boxes3d``, ``scores``,
    ``embeddings`` and ``labels`` (the class reported; the true class unless confused), plus the false
    positives (``clutter``: clutter, ghosts and duplicates, each row with its ``causes``); last, each
    detection's position in the camera's list (``detection_index``, −1 for a miss; ``clutter_index``).
    """

    context: FrameContext
    camera: Camera
    camera_index: int
    world_from_camera: np.ndarray
    classes: np.ndarray
    boxes3d: np.ndarray
    boxes2d: np.ndarray
    truncation: np.ndarray
    visible_fraction: np.ndarray
    distance: np.ndarray
    in_view: np.ndarray
    probability: np.ndarray = None
    causes: np.ndarray = None
    noise_factor: np.ndarray = None
    yaw_offset: float = 0.0
    silenced: bool = False
    detected: np.ndarray = None
    det_boxes2d: np.ndarray = None
    det_boxes3d: np.ndarray = None
    scores: np.ndarray = None
    embeddings: np.ndarray = None
    labels: np.ndarray = None
    ghost_ids: np.ndarray = None
    clutter: dict[str, np.ndarray] = field(default_factory=dict)
    detection_index: np.ndarray = None
    clutter_index: np.ndarray = None

    def __post_init__(self) -> None:
        n = len(self.classes)
        self.probability = np.where(self.in_view, 1.0, 0.0)
        self.causes = np.zeros(n, dtype=np.int64)
        self.noise_factor = np.ones(n)
        self.detected = np.zeros(n, dtype=bool)
        self.det_boxes2d = np.full((n, 4), np.nan)
        self.det_boxes3d = np.full((n, 9), np.nan)
        self.scores = np.full(n, np.nan)
        self.labels = self.classes

    def add_false_positives(self, boxes2d: np.ndarray, boxes3d: np.ndarray, scores: np.ndarray,
                            labels: np.ndarray, embeddings: np.ndarray, cause: int) -> None:
        """Append false positives (pixel boxes ``(K, 4)``, world boxes ``(K, 9)``, scores, labels, unit
        embeddings ``(K, D)``) with one :class:`~simrig.causes.Cause` bit mask for all of them."""
        k = len(scores)
        new = {"boxes2d": np.asarray(boxes2d, dtype=float).reshape(k, 4),
               "boxes3d": np.asarray(boxes3d, dtype=float).reshape(k, 9),
               "scores": np.asarray(scores, dtype=float), "labels": np.asarray(labels, dtype=object),
               "embeddings": np.asarray(embeddings, dtype=np.float32),
               "causes": np.full(k, int(cause), dtype=np.int64)}
        if not self.clutter:
            self.clutter = new
            return
        self.clutter = {key: np.concatenate([self.clutter[key], value]) for key, value in new.items()}

    @property
    def actor_ids(self) -> np.ndarray:
        return self.context.actor_ids

    def __len__(self) -> int:
        return len(self.classes)
