"""CollabMOT (Ninh and Kim, IEEE Access 2024): per-camera trackers on a stereo pair whose tracklets repair each
other's identity switches through global ids.

Each frame: both single-camera trackers step on their camera's detections; every reported box updates its
tracklet and, when its detection carries an embedding, the tracklet's appearance EMA (Eq. 3-4, the occlusion
ratio measured among the tracker's own boxes of that camera); local tracklet resurfacing runs; the
candidates (tracklets reported now whose box is at least ``min_height_px`` tall) are associated across the
pair (Eq. 2, 5, 8-9, Alg. 1-2, Eq. 6); a lost ego tracklet reconnected to a current one has its gap
interpolated ω frames later (Eq. 7), and the boxes are discarded if the connection is revoked.

Output (online, the default, §III-F): at each frame the ego camera's boxes, each under its tracklet's global id
*at that time step* when it has one (else its local id). ``step`` is the whole answer: nothing said about a
frame is revised later, so interpolated gap boxes (which belong to past frames) are not output.

``semi_online=True`` (:class:`SemiOnlineCollabMOT`, reported as "semi-online" wherever it appears) adds
``finish()``, which replaces every frame's answer after the last frame: the interpolated gap boxes of §III-E,
and — simrig's departure, not the paper's — each tracklet's frames before its first global id relabelled with
the id it got later (unbounded hindsight). Two boxes under one id in a frame (a resurfaced pair) are merged
(mean box).
"""

from __future__ import annotations

import time
from collections import defaultdict

import numpy as np

from simrig.types import Box2D, Rig, SensorFrame, Track

from ..boxes2d import occlusion_ratios
from ..camera_tracking import FrameCounter
from ..deepsort import DeepSort
from ..detections import LABELS, detection_arrays
from ..sort import Sort
from .affinity import affinity, remote_side
from .association import associate
from .interpolation import fill_gap, ready_at
from .resurfacing import resurface
from .tracklets import NO_ID, Tracklet, update_feature

SINGLE_CAMERA_TRACKERS = {"sort": Sort, "deepsort": DeepSort}
"""The per-camera trackers CollabMOT can run on either camera, by name."""


class CollabMOT:
    """See the module docstring; parameters default to the paper's values (§IV-C1, Appendix)."""

    revises_past = False
    """Whether the tracker keeps what it needs to revise past frames in ``finish()`` (semi-online)."""

    def __init__(self, *, ego_tracker: str = "sort", remote_tracker: str = "sort", ego_camera: str = "left",
                 remote_camera: str = "right", alpha: float = 0.9, occlusion_limit: float = 0.5,
                 appearance_limit: float = 0.1, weight_appearance: float = 1.0, weight_position: float = 1.0,
                 bbox_margin_px: float = 10.0, min_height_px: float = 10.0, interpolation_depth: int = 2,
                 interpolation_iou: float = 0.5, interpolation_occlusion: float = 0.5, merged_iou: float = 0.3,
                 coappearance_limit: int = 5, interpolate: bool = True):
        for role, name in (("ego_tracker", ego_tracker), ("remote_tracker", remote_tracker)):
            if name not in SINGLE_CAMERA_TRACKERS:
                raise ValueError(f"{role} must be one of {', '.join(SINGLE_CAMERA_TRACKERS)}, got {name!r}")
        if ego_camera == remote_camera:
            raise ValueError(f"ego_camera and remote_camera must differ, both are {ego_camera!r}")
        for name, value in (("alpha", alpha), ("occlusion_limit", occlusion_limit),
                            ("interpolation_iou", interpolation_iou),
                            ("interpolation_occlusion", interpolation_occlusion), ("merged_iou", merged_iou)):
            if not 0 <= value <= 1:
                raise ValueError(f"{name} must be in [0, 1], got {value}")
        if not 0 < appearance_limit <= 2:
            raise ValueError(f"appearance_limit must be in (0, 2] (a cosine distance), got {appearance_limit}")
        if interpolation_depth < 1 or coappearance_limit < 1 or min_height_px < 0 or bbox_margin_px < 0:
            raise ValueError("interpolation_depth and coappearance_limit must be ≥ 1, min_height_px and "
                             "bbox_margin_px ≥ 0")
        self.trackers = (ego_tracker, remote_tracker)
        self.cameras = (ego_camera, remote_camera)
        self.alpha, self.occlusion_limit, self.appearance_limit = alpha, occlusion_limit, appearance_limit
        self.weights = (weight_appearance, weight_position)
        self.margin, self.min_height = bbox_margin_px, min_height_px
        self.depth, self.interpolation_iou, self.interpolation_occlusion = (
            interpolation_depth, interpolation_iou, interpolation_occlusion)
        self.merged_iou, self.coappearance_limit, self.interpolate = merged_iou, coappearance_limit, interpolate
        self.counter = FrameCounter()
        self._clear()

    def _clear(self) -> None:
        self.single = {}
        self.tracklets: dict[str, dict[int, Tracklet]] = {"ego": {}, "remote": {}}
        self.ego_boxes: dict[int, list[tuple[Tracklet, np.ndarray]]] = {}
        self.pending: list[tuple[Tracklet, Tracklet, int]] = []
        self.filled: list[tuple[Tracklet, Tracklet, int, dict[int, np.ndarray]]] = []
        self.frames: list[int] = []
        self._connected: set[tuple[int, int]] = set()
        self._next_global = 1
        self._output_ids: dict[tuple[str, int], int] = {}
        self.association_seconds: list[float] = []
        self.restarts = 0
        self.linked_pairs = 0
        self._reconnected: set[tuple[int, int]] = set()

    def reset(self, *, rig: Rig, seed: int | None = None) -> None:
        """Start a sequence on ``rig``, which must have both cameras; ``seed`` is unused (deterministic)."""
        for camera in self.cameras:
            if camera not in rig.camera_names:
                raise ValueError(f"camera {camera!r} is not in rig {rig.name!r} "
                                 f"(cameras: {', '.join(rig.camera_names)}); set ego_camera/remote_camera")
        self._clear()
        self.counter.reset()
        self.rig = rig
        self.single = {role: SINGLE_CAMERA_TRACKERS[name]() for role, name in zip(("ego", "remote"), self.trackers,
                                                                                      strict=True)}
        self.camera_of = {"ego": rig.camera(self.cameras[0]), "remote": rig.camera(self.cameras[1])}
        self.relp = remote_side(self.camera_of["ego"], self.camera_of["remote"])

    def _new_global_id(self) -> int:
        value = self._next_global
        self._next_global += 1
        return value

    # -- one frame ---------------------------------------------------------------------------------------
    def step(self, frame: SensorFrame) -> list[Track]:
        if not self.single:
            raise ValueError(f"frame {frame.frame}: call reset(rig=...) before step")
        detections = detection_arrays(frame, require_3d=False)
        frames = self.counter.advance(frame)
        t = frame.frame
        self.frames.append(t)
        present: dict[str, list[Tracklet]] = {}
        for role in ("ego", "remote"):
            index = frame.rig.camera_names.index(self.camera_of[role].name)
            present[role] = self._observe(role, t, detections.take(detections.cameras == index), frames)
        for role in ("ego", "remote"):
            resurface(present[role], merged_iou=self.merged_iou, coappearance_limit=self.coappearance_limit)
        start = time.perf_counter()
        ego = [c for c in present["ego"] if self._tall(c, t)]
        remote = [c for c in present["remote"] if self._tall(c, t)]
        cost = affinity(ego, remote, t, relp=self.relp, ego_camera=self.camera_of["ego"],
                        remote_camera=self.camera_of["remote"], appearance_limit=self.appearance_limit,
                        margin=self.margin, weight_appearance=self.weights[0], weight_position=self.weights[1])
        result = associate(ego, remote, cost, ego_all=list(self.tracklets["ego"].values()),
                           remote_all=list(self.tracklets["remote"].values()), limit=self.appearance_limit,
                           new_id=self._new_global_id)
        self.association_seconds.append(time.perf_counter() - start)
        self.restarts += result.restarts
        self.linked_pairs += len(result.links)
        self._reconnected |= {(id(lost), id(current)) for lost, current in result.reconnections if lost.camera == "ego"}
        if self.interpolate and self.revises_past:  # gap boxes belong to past frames: semi-online only
            self._connect([(lost, current) for lost, current in result.reconnections if lost.camera == "ego"])
        self._interpolate(t)
        for tracklet in present["ego"]:
            tracklet.ids[t] = tracklet.global_id
        return self._tracks([(t, tracklet.label, tracklet.scores[t], tracklet.boxes[t], self._key(tracklet))
                             for tracklet in present["ego"]])[t]

    def _observe(self, role: str, t: int, detections, frames: int) -> list[Tracklet]:
        """Step one camera's tracker and fold its reports into the tracklets; returns those reported now."""
        reports = self.single[role].step(detections, frames)
        if not reports:
            if role == "ego":
                self.ego_boxes[t] = []
            return []
        boxes = np.stack([r.box for r in reports])
        occlusion = occlusion_ratios(boxes)
        out = []
        for report, box, occluded in zip(reports, boxes, occlusion, strict=True):
            tracklet = self.tracklets[role].setdefault(report.track_id, Tracklet(role, report.track_id, report.label))
            tracklet.boxes[t] = box
            tracklet.scores[t] = report.score
            row = report.detection
            if row >= 0:
                update_feature(tracklet, detections.embeddings[row], float(detections.scores[row]), float(occluded),
                               alpha=self.alpha, occlusion_limit=self.occlusion_limit)
            out.append(tracklet)
        if role == "ego":
            self.ego_boxes[t] = list(zip(out, boxes, strict=True))
        return out

    def _tall(self, tracklet: Tracklet, t: int) -> bool:
        box = tracklet.boxes[t]
        return box[3] - box[1] >= self.min_height

    def _connect(self, reconnections: list[tuple[Tracklet, Tracklet]]) -> None:
        """Queue each new ego reconnection for interpolation, from the most recent lost tracklet only (an
        older one's gap would span the newer one's boxes)."""
        latest: dict[int, tuple[Tracklet, Tracklet]] = {}
        for lost, current in reconnections:
            if lost.last < current.first and (id(current) not in latest or lost.last > latest[id(current)][0].last):
                latest[id(current)] = (lost, current)
        for lost, current in latest.values():
            key = (id(lost), id(current))
            if key not in self._connected:
                self._connected.add(key)
                self.pending.append((lost, current, current.global_id))

    def _interpolate(self, t: int) -> None:
        """Fill the gaps whose ω frames have passed; drop connections revoked since."""
        waiting = []
        for lost, current, g in self.pending:
            if current.global_id != g or lost.global_id != g:
                continue
            if t < ready_at(lost, current, self.depth):
                waiting.append((lost, current, g))
                continue
            boxes = fill_gap(lost, current, depth=self.depth, iou_limit=self.interpolation_iou,
                             occlusion_limit=self.interpolation_occlusion, others_at=self._ego_boxes_at)
            if boxes:
                self.filled.append((lost, current, g, boxes))
        self.pending = waiting
        self.filled = [entry for entry in self.filled
                       if entry[0].global_id == entry[2] and entry[1].global_id == entry[2]]

    def mechanism(self) -> dict[str, int]:
        """What the collaboration did in the sequence so far: ``linked`` (ego, remote) pairs summed over frames,
        ``reconnected`` lost ego tracklets continued through a global id (each pair once), ``relabelled`` ego
        tracklets reported under an id another ego tracklet had before them, ``interpolated`` gap boxes filled
        (semi-online only)."""
        first_owner: dict[tuple[str, int], int] = {}
        relabelled = 0
        for tracklet in sorted(self.tracklets["ego"].values(), key=lambda c: (c.first, c.local_id)):
            keys = {self._key(tracklet, g) for g in tracklet.ids.values() if g > 0}
            owners = {first_owner.setdefault(key, tracklet.local_id) for key in keys}
            relabelled += any(owner != tracklet.local_id for owner in owners)
        return {"linked": self.linked_pairs, "reconnected": len(self._reconnected), "relabelled": relabelled,
                "interpolated": sum(len(boxes) for *_, boxes in self.filled)}

    def _ego_boxes_at(self, frame: int) -> np.ndarray:
        boxes = [box for _, box in self.ego_boxes.get(frame, [])]
        return np.stack(boxes) if boxes else np.zeros((0, 4))

    # -- output ----------------------------------------------------------------------------------------
    def _key(self, tracklet: Tracklet, global_id: int | None = None) -> tuple[str, int]:
        g = tracklet.global_id if global_id is None else global_id
        return ("global", g) if g > 0 else ("local", tracklet.local_id)

    def _tracks(self, rows) -> dict[int, list[Track]]:
        """Tracks per frame from (frame, label, score, box, key) rows; one box per id and frame (mean box)."""
        grouped: dict[tuple[int, tuple[str, int]], list] = defaultdict(list)
        for frame, label, score, box, key in rows:
            grouped[(frame, key)].append((label, score, box))
        out: dict[int, list[Track]] = defaultdict(list)
        camera = self.camera_of["ego"].name
        for (frame, key), members in grouped.items():
            if key not in self._output_ids:
                self._output_ids[key] = len(self._output_ids) + 1
            box = np.mean([m[2] for m in members], axis=0)
            label = max(members, key=lambda m: m[1])[0]
            score = max(m[1] for m in members)
            out[frame].append(Track(self._output_ids[key], LABELS[label], float(score),
                                    boxes2d={camera: Box2D(*(float(v) for v in box))}))
        for frame in out:
            out[frame].sort(key=lambda track: track.track_id)
        return out


class SemiOnlineCollabMOT(CollabMOT):
    """CollabMOT with hindsight: ``finish()`` revises the past (see the module docstring). Not the paper's
    per-time-step output; every table that shows it says "semi-online"."""

    revises_past = True

    @staticmethod
    def _revised_ids(tracklet: Tracklet) -> dict[int, int]:
        """frame → global id for the semi-online output: a frame where the tracklet had none takes the next
        one it got, or else the last one it had (−1 if it never had one)."""
        frames = sorted(tracklet.boxes)
        ids = [tracklet.ids.get(frame, NO_ID) for frame in frames]
        later, after = NO_ID, []
        for g in reversed(ids):
            later = g if g > 0 else later
            after.append(later)
        after.reverse()
        out, before = {}, NO_ID
        for frame, g, nxt in zip(frames, ids, after, strict=True):
            before = g if g > 0 else before
            out[frame] = g if g > 0 else (nxt if nxt > 0 else before)
        return out

    def finish(self) -> list[tuple[int, list[Track]]]:
        """The semi-online output of every frame stepped (see the module docstring)."""
        rows = []
        for tracklet in self.tracklets["ego"].values():
            for frame, g in self._revised_ids(tracklet).items():
                rows.append((frame, tracklet.label, tracklet.scores[frame], tracklet.boxes[frame],
                             self._key(tracklet, g)))
        for lost, current, g, boxes in self.filled:
            score = min(lost.scores[lost.last], current.scores[current.first])
            rows += [(frame, current.label, score, box, ("global", g)) for frame, box in boxes.items()]
        tracks = self._tracks(rows)
        return [(frame, tracks.get(frame, [])) for frame in self.frames]


def collabmot(*, ego_tracker: str = "sort", remote_tracker: str = "sort", ego_camera: str = "left",
              remote_camera: str = "right", alpha: float = 0.9, occlusion_limit: float = 0.5,
              appearance_limit: float = 0.1, weight_appearance: float = 1.0, weight_position: float = 1.0,
              bbox_margin_px: float = 10.0, min_height_px: float = 10.0, interpolation_depth: int = 2,
              interpolation_iou: float = 0.5, interpolation_occlusion: float = 0.5, merged_iou: float = 0.3,
              coappearance_limit: int = 5, interpolate: bool = True, semi_online: bool = False) -> CollabMOT:
    """CollabMOT on a stereo pair; registered as ``collabmot``. Online (the id at each time step, §III-F)
    unless ``semi_online``: then the answer for past frames is revised after the last frame (interpolated gap
    boxes, hindsight relabel)."""
    params = {k: v for k, v in locals().items() if k != "semi_online"}
    return SemiOnlineCollabMOT(**params) if semi_online else CollabMOT(**params)
