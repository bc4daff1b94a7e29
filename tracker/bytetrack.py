"""ByteTrack on one camera (Zhang, Sun, Jiang, Yu, Weng, Yuan, Luo, Liu, Wang: "ByteTrack: Multi-Object
Tracking by Associating Every Detection Box", ECCV 2022), after its public ``BYTETracker``.

Filter: the DeepSORT filter ByteTrack uses (constant velocity on centre, aspect and height, noise proportional
to the height; :mod:`.deepsort`). Each frame, detections split by score: high (≥ ``track_thresh``, 0.5) and
low (> ``low_thresh``, 0.1, below track_thresh):

1. high detections against every activated track, tracked or lost (1 − IoU ≤ ``match_thresh`` = 0.8);
2. low detections against the tracked (not lost) tracks still unmatched (1 − IoU ≤ 0.5); tracked tracks left
   unmatched become lost;
3. remaining high detections against the unconfirmed tracks (born last frame; 1 − IoU ≤ 0.7); an unconfirmed
   track left unmatched is removed;
4. remaining high detections with score ≥ track_thresh + 0.1 start unconfirmed tracks (activated at once on
   the first frame);
5. a lost track is removed after ``track_buffer`` frames (ByteTrack's 30 frames at 30 Hz is 1 s; the default
   here is 10 frames, 1 s at simrig's 10 Hz).

Output: activated tracks updated this frame (their filter's box). Pairs of different classes never match.
Choices: one Hungarian per stage (scipy; ByteTrack uses ``lap.lapjv`` with the same thresholds); ByteTrack's
score fusion of the IoU cost (an MOT17 option, off for its other benchmarks) is not applied.
"""

from __future__ import annotations

import numpy as np

from .assignment import UNMATCHED, assign_into
from .boxes2d import iou
from .camera_tracking import LocalTrack, PerCameraTracking
from .deepsort import DeepSortTrack, xyah_to_box
from .detections import DetectionArrays

_NO_EMBEDDING = np.zeros(0)


class ByteTrackTrack(DeepSortTrack):
    """A DeepSORT-filter track with ByteTrack's states: ``activated`` (confirmed) and ``lost``."""

    def __init__(self, track_id: int, box: np.ndarray, label: int, score: float, detection: int, activated: bool):
        super().__init__(track_id, box, label, score, _NO_EMBEDDING, detection, activated, budget=1)
        self.lost = False

    def box(self) -> np.ndarray:
        return xyah_to_box(self.kf.x)


class ByteTrack:
    """ByteTrack on one camera; see the module docstring."""

    def __init__(self, *, track_thresh: float = 0.5, low_thresh: float = 0.1, match_thresh: float = 0.8,
                 track_buffer: int = 10):
        if not 0 <= low_thresh <= track_thresh <= 1 or not 0 < match_thresh <= 1 or track_buffer < 1:
            raise ValueError("bytetrack: need 0 ≤ low_thresh ≤ track_thresh ≤ 1, match_thresh in (0, 1] and "
                             f"track_buffer ≥ 1; got {low_thresh}, {track_thresh}, {match_thresh}, {track_buffer}")
        self.track_thresh, self.low_thresh = track_thresh, low_thresh
        self.match_thresh, self.track_buffer = match_thresh, track_buffer
        self.tracks: list[ByteTrackTrack] = []
        self.frame_count = 0
        self._next_id = 1

    def _match(self, track_indices: list[int], rows: np.ndarray, detections: DetectionArrays, gate: float,
               owner: np.ndarray) -> None:
        """Hungarian on 1 − IoU between the tracks ``track_indices`` and the detections ``rows``; writes the
        matches into ``owner``."""
        if not track_indices or len(rows) == 0:
            return
        predicted = np.stack([self.tracks[i].box() for i in track_indices])
        cost = 1.0 - iou(predicted, detections.boxes2d[rows])
        labels = np.array([self.tracks[i].label for i in track_indices])
        cost = np.where(labels[:, None] == detections.labels[rows][None, :], cost, np.inf)
        assign_into(owner, rows, track_indices, cost, gate)

    def step(self, detections: DetectionArrays, frames: int = 1) -> list[LocalTrack]:
        for _ in range(frames):
            self.frame_count += 1
            for track in self.tracks:
                track.predict()
        owner = np.full(len(detections), UNMATCHED, dtype=np.int64)
        high = np.nonzero(detections.scores >= self.track_thresh)[0]
        low = np.nonzero((detections.scores > self.low_thresh) & (detections.scores < self.track_thresh))[0]
        activated = [i for i, t in enumerate(self.tracks) if t.confirmed]
        unconfirmed = [i for i, t in enumerate(self.tracks) if not t.confirmed]
        self._match(activated, high, detections, self.match_thresh, owner)
        taken = set(owner[owner != UNMATCHED].tolist())
        tracked_left = [i for i in activated if i not in taken and not self.tracks[i].lost]
        self._match(tracked_left, low, detections, 0.5, owner)
        self._match(unconfirmed, high[owner[high] == UNMATCHED], detections, 0.7, owner)

        updated: set[int] = set()
        for j in np.nonzero(owner != UNMATCHED)[0].tolist():
            track = self.tracks[owner[j]]
            track.update(detections.boxes2d[j], float(detections.scores[j]), _NO_EMBEDDING, j, n_init=1)
            track.lost = False
            updated.add(int(owner[j]))
        kept = []
        for i, track in enumerate(self.tracks):
            if i in updated:
                kept.append(track)
            elif not track.confirmed:
                continue  # an unconfirmed track missed once is removed
            elif track.time_since_update <= self.track_buffer:
                track.lost = True
                kept.append(track)
        self.tracks = kept
        first = self.frame_count == 1
        for j in high[owner[high] == UNMATCHED].tolist():
            if detections.scores[j] >= self.track_thresh + 0.1:
                self.tracks.append(ByteTrackTrack(self._next_id, detections.boxes2d[j], int(detections.labels[j]),
                                                  float(detections.scores[j]), j, activated=first))
                self._next_id += 1
        return [LocalTrack(t.track_id, t.box(), t.score, t.label, t.detection)
                for t in self.tracks if t.confirmed and t.time_since_update == 0]


def bytetrack(*, track_thresh: float = 0.5, low_thresh: float = 0.1, match_thresh: float = 0.8,
              track_buffer: int = 10, cameras: str = "") -> PerCameraTracking:
    """ByteTrack on every camera of the rig (or on the comma-separated ``cameras``), each camera on its own."""
    return PerCameraTracking(
        lambda: ByteTrack(track_thresh=track_thresh, low_thresh=low_thresh, match_thresh=match_thresh,
                          track_buffer=track_buffer),
        tuple(name for name in cameras.split(",") if name) or None,
    )
