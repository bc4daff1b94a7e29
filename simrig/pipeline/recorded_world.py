"""The world of an existing dataset, for a generation that reruns only the sensor model
(``generate(..., world_from=...)``): its ground truth, its measured visibility and the projection of its boxes
— no simulation and no rendering.

A process that reruns the sensor on one world many times (``simrig explain``'s counterfactual coalitions,
each worker dozens of them) keeps the frames of the last world it read whole, up to
:data:`MEMO_FRAMES_LIMIT` frames, and serves later reruns from memory. The frames are the same objects each
time; the sensor model only reads them.
"""

from __future__ import annotations

import time
from typing import Protocol

import numpy as np

from simrig.dataset import Dataset
from simrig.geometry import Projection, project_boxes
from simrig.render.visibility import Visibility
from simrig.types import GroundTruthFrame

MEMO_FRAMES_LIMIT = 1000
"""Worlds of at most this many frames are kept in memory after a complete pass (≈ 0.1 KiB per frame, actor
and camera: ~5 MiB for the default 200-frame surround run); longer ones are read from disk on every pass."""

Frame = tuple[GroundTruthFrame, Projection, Visibility]
_memo: tuple[tuple[str, str], list[Frame]] | None = None


class StageClock(Protocol):
    """Where the per-stage seconds go (the generator's ``StageTimes``)."""

    traffic: float
    projection: float
    visibility: float


class RecordedWorld:
    """The frames of ``dataset`` in order, as ``generate`` consumes them: ground truth (with the frame's
    world events from the manifest), the projection recomputed with ``rig`` (a pure function of the boxes,
    cheaper than reading it back) and the recorded visibility counts."""

    def __init__(self, dataset: Dataset, rig):
        self.rig = rig
        self.markings = dataset.road_markings()
        self._key = (str(dataset.manifest.get("manifest_sha256")), str(dataset.manifest.get("world_key")))
        self._remembered = _memo[1] if _memo is not None and _memo[0] == self._key else None
        self._kept: list[Frame] | None = [] if dataset.frame_count <= MEMO_FRAMES_LIMIT else None
        self._frame_count = dataset.frame_count
        if self._remembered is not None:
            return
        self._states = dataset.ground_truth_frames()
        table = dataset.table("visibility")
        self._frames = table.column("frame").to_numpy()
        self._visible = table.column("visible_px").to_numpy().astype(np.int64)
        self._silhouette = table.column("silhouette_px").to_numpy().astype(np.int64)
        self._rendered = dataset.manifest.get("visibility") == "rendered"
        self._events: dict[int, list[str]] = {}
        for event in dataset.manifest.get("events", []):
            self._events.setdefault(int(event["frame"]), []).append(event["event"])

    def frame(self, frame: int, times: StageClock) -> Frame:
        """Frame ``frame`` (frames are asked for in order, from 0)."""
        if self._remembered is not None:
            return self._remembered[frame]
        tick = time.perf_counter()
        recorded = next(self._states)
        state = GroundTruthFrame(frame=recorded.frame, timestamp=recorded.timestamp, ego=recorded.ego,
                                 actor_ids=recorded.actor_ids, classes=recorded.classes, boxes=recorded.boxes,
                                 events=tuple(self._events.get(recorded.frame, ())),
                                 collisions=recorded.collisions)
        times.traffic += time.perf_counter() - tick
        tick = time.perf_counter()
        projection = project_boxes(state.boxes, self.rig, state.ego)
        times.projection += time.perf_counter() - tick
        tick = time.perf_counter()
        if self._rendered:
            lo, hi = np.searchsorted(self._frames, [frame, frame + 1])
            shape = (len(state.actor_ids), len(self.rig.cameras))
            visibility = Visibility.from_counts(self._visible[lo:hi].reshape(shape).T,
                                                self._silhouette[lo:hi].reshape(shape).T)
        else:
            visibility = Visibility.unmeasured(projection)
        times.visibility += time.perf_counter() - tick
        if self._kept is not None:
            self._kept.append((state, projection, visibility))
        return state, projection, visibility

    def close(self) -> None:
        """Remember this world's frames when a whole pass was read (and the world is short enough)."""
        global _memo
        if self._remembered is None and self._kept is not None and len(self._kept) == self._frame_count:
            _memo = (self._key, self._kept)
