"""Re-ID distances measured the way a real re-ID model's are published.

The distance of two embeddings is d = 0.5 · (1 − cos) (0 identical, 1 opposite), the scale of the Roboflow
``trackers`` re-ID guide (``docs/guides/reid.md`` of roboflow/trackers), which measured FastReID SBS50 (trained on
MOT17) on MOT17 validation: 5,000 same-identity and 10,000 different-identity pairs per row, the share of each
at d ≤ 0.20 and ≤ 0.25, and the ROC AUC of d separating them, per band of frame gaps (:data:`SOURCE`). That
source is pedestrian re-ID: no published vehicle (VeRi-776) distance distribution by frame gap was found, so
simrig's default detector is calibrated to it, and ``simrig detector fit --embeddings`` fits a user's own.

Pairs, within one sequence (a dataset, or one ``sequence`` of a log), each sequence giving the same number:

* same identity: one actor seen by one camera at frames t and t + g, g in the band (drawn uniformly over
  the pairs that exist, from at most :data:`ANCHORS` anchor rows);
* different identity: an anchor row and a row of another actor seen by the same camera g frames later, g
  drawn uniformly in the band;
* the row "same frame, other camera": one actor (or two actors) seen by two cameras at the same frame;
* where the log knows each observation's viewing bearing and camera position (a simrig dataset does), the same
  pairs again by the angle between the two cameras' rays to the actor (:data:`VIEW_BINS_DEG`) and by the
  distance between the two cameras (the baseline): the cross-view table. Two synchronised cameras see an actor
  alike when their rays are close, whatever the rig; no published vehicle re-ID figure of distance by viewing
  angle was found to set beside it, so these rows have no source column.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simrig.seeding import stream_generator

from ..errors import SimrigError
from ..sensor.appearance import roc_auc

GAP_BANDS: tuple[tuple[int, int], ...] = ((1, 1), (2, 5), (6, 15), (16, 30), (31, 60), (61, 120), (121, 240))
"""[frames] the source's bands of frame gaps, inclusive."""
THRESHOLDS = (0.20, 0.25)
"""Distances at which the shares of pairs are reported."""
SAME_PAIRS, DIFFERENT_PAIRS = 5000, 10000
"""Pairs per row, as in the source."""
ANCHORS = 20000
"""At most this many anchor rows per sequence and band (bounds the work on long logs)."""
SOURCE: dict[str, tuple[float, float, float]] = {
    "1": (0.998, 0.980, 0.017), "2-5": (0.987, 0.876, 0.016), "6-15": (0.957, 0.674, 0.011),
    "16-30": (0.929, 0.514, 0.011), "31-60": (0.899, 0.398, 0.009), "61-120": (0.865, 0.318, 0.008),
    "121-240": (0.854, 0.287, 0.008),
}
"""The source's (ROC AUC, same-identity share at d ≤ 0.2, different-identity share at d ≤ 0.2) per gap band."""
SOURCE_POOLED = {"1-30": (0.68, 0.79, 0.011, 0.029)}
"""The source's shares for pairs 1–30 frames apart: same at 0.20 and 0.25, different at 0.20 and 0.25."""
CROSS_CAMERA = "same frame, other camera"
VIEW_BINS_DEG: tuple[tuple[float, float], ...] = ((0, 2), (2, 5), (5, 15), (15, 45), (45, 90), (90, 180))
"""[deg] bins of the angle between two cameras' rays to one actor at one frame (the last includes 180°)."""


@dataclass(frozen=True, eq=False)
class EmbeddingLog:
    """Embeddings of identified objects: per row ``sequence``, ``frame``, ``camera`` (codes, ``(R,)`` int64),
    ``identity`` ``(R,)`` int64 and unit ``embeddings`` ``(R, D)``; optionally, per row, the ``bearing`` [rad] the
    camera saw the object along (in the object's frame) and the camera's position ``(R, 3)`` [m, world frame]."""

    sequence: np.ndarray
    frame: np.ndarray
    camera: np.ndarray
    identity: np.ndarray
    embeddings: np.ndarray
    bearing: np.ndarray | None = None
    position: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.frame)

    @staticmethod
    def concatenate(logs: list[EmbeddingLog]) -> EmbeddingLog:
        """One log of several, each its own sequence (numbered in order)."""
        dimensions = {log.embeddings.shape[1] for log in logs if len(log)}
        if len(dimensions) > 1:
            raise SimrigError(f"embeddings of different lengths {sorted(dimensions)}: one length expected")
        geometry = all(log.bearing is not None and log.position is not None for log in logs)
        return EmbeddingLog(
            sequence=np.concatenate([np.full(len(log), i, dtype=np.int64) for i, log in enumerate(logs)]),
            **{name: np.concatenate([getattr(log, name) for log in logs])
               for name in ("frame", "camera", "identity", "embeddings", *(("bearing", "position") if geometry
                                                                           else ()))})


def distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """d = 0.5 · (1 − cos) of row pairs of unit vectors ``(P, D)``.

    >>> distance(np.array([[1.0, 0.0], [1.0, 0.0]]), np.array([[0.0, 1.0], [-1.0, 0.0]])).tolist()
    [0.5, 1.0]
    """
    return 0.5 * (1.0 - np.einsum("pd,pd->p", a, b))


def same_identity_pairs(frame, camera, identity, low, high, rng) -> tuple[np.ndarray, np.ndarray]:
    """Rows (a, b) of one identity and camera with frame[b] − frame[a] in [low, high] (uniform over those that
    exist, from a sample of anchors)."""
    if not len(frame):
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    width = int(frame.max()) + high + 2
    key = (identity * (int(camera.max()) + 1) + camera) * width + frame
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    anchors = rng.permutation(len(key))[:ANCHORS]
    firsts, seconds = [], []
    for gap in range(low, high + 1):
        target = key[anchors] + gap
        at = np.minimum(np.searchsorted(sorted_key, target), len(key) - 1)
        hit = sorted_key[at] == target
        firsts.append(anchors[hit])
        seconds.append(order[at[hit]])
    return np.concatenate(firsts), np.concatenate(seconds)


def _other_pairs(group: np.ndarray, identity: np.ndarray, camera: np.ndarray, target: np.ndarray,
                 anchors: np.ndarray, rng, *, other_camera: bool) -> tuple[np.ndarray, np.ndarray]:
    """For each anchor a random row of group ``target[i]`` (rows keyed by ``group``) of another identity (and,
    with ``other_camera``, another camera); anchors with none drawn are dropped."""
    order = np.argsort(group, kind="stable")
    start = np.searchsorted(group[order], target, side="left")
    stop = np.searchsorted(group[order], target, side="right")
    some = stop > start
    anchors, start, stop = anchors[some], start[some], stop[some]
    partner = order[start + (rng.random(len(anchors)) * (stop - start)).astype(np.int64)]
    keep = identity[partner] != identity[anchors]
    if other_camera:
        keep &= camera[partner] != camera[anchors]
    return anchors[keep], partner[keep]


def different_identity_pairs(frame, camera, identity, low, high, count, rng) -> tuple[np.ndarray, np.ndarray]:
    """Up to ``count`` rows (a, b) of two identities seen by one camera, frame[b] − frame[a] uniform in
    [low, high]."""
    if not len(frame):
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    width = int(frame.max()) + high + 2
    group = camera * width + frame
    firsts, seconds, found = [], [], 0
    for _ in range(20):
        anchors = rng.integers(len(frame), size=4 * count)
        gaps = rng.integers(low, high + 1, size=len(anchors))
        a, b = _other_pairs(group, identity, camera, group[anchors] + gaps, anchors, rng, other_camera=False)
        firsts.append(a)
        seconds.append(b)
        found += len(a)
        if found >= count:
            break
    return np.concatenate(firsts)[:count], np.concatenate(seconds)[:count]


def cross_camera_pairs(frame, camera, identity) -> tuple[np.ndarray, np.ndarray]:
    """Every pair of rows of one identity seen by two cameras at the same frame."""
    if not len(frame):
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    key = identity * (int(frame.max()) + 1) + frame
    order = np.lexsort((camera, key))
    firsts, seconds = [], []
    for offset in range(1, int(camera.max()) + 1):
        a, b = order[:-offset], order[offset:]
        keep = (key[a] == key[b]) & (camera[a] != camera[b])
        firsts.append(a[keep])
        seconds.append(b[keep])
    if not firsts:
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    return np.concatenate(firsts), np.concatenate(seconds)


def _cross_camera_strangers(frame, camera, identity, count, rng) -> tuple[np.ndarray, np.ndarray]:
    """Up to ``count`` pairs of rows of two identities seen by two cameras at the same frame."""
    if not len(frame):
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    anchors = rng.integers(len(frame), size=4 * count)
    a, b = _other_pairs(frame, identity, camera, frame[anchors], anchors, rng, other_camera=True)
    return a[:count], b[:count]


def within_sequences(log: EmbeddingLog) -> tuple[np.ndarray, np.ndarray]:
    """(camera, identity) codes made unique per sequence, so that no pair the samplers above draw crosses
    sequences (pairs are within one camera or of one identity)."""
    cameras, identities = int(log.camera.max()) + 1, int(log.identity.max()) + 1
    return log.sequence * cameras + log.camera, log.sequence * identities + log.identity


@dataclass(frozen=True)
class ReidRow:
    """One row of the re-ID table: pair counts, shares at :data:`THRESHOLDS` of same- and different-identity
    pairs (NaN without pairs), ROC AUC and median distances."""

    gaps: str
    same_pairs: int
    different_pairs: int
    same_below: tuple[float, ...]
    different_below: tuple[float, ...]
    auc: float
    same_median: float
    different_median: float

    @staticmethod
    def of(gaps: str, same: np.ndarray, different: np.ndarray) -> ReidRow:
        def below(values: np.ndarray) -> tuple[float, ...]:
            return tuple(float(np.mean(values <= t)) if len(values) else float("nan") for t in THRESHOLDS)

        auc = roc_auc(-same, -different) if len(same) and len(different) else float("nan")
        return ReidRow(gaps, int(len(same)), int(len(different)), below(same), below(different), auc,
                       float(np.median(same)) if len(same) else float("nan"),
                       float(np.median(different)) if len(different) else float("nan"))


def _split_sample(per_sequence: list[tuple[np.ndarray, np.ndarray]], count: int, rng) -> tuple:
    """The same number of pairs from each sequence that has some (as many as the scarcest allows up to
    ``count`` / sequences), pooled."""
    have = [pairs for pairs in per_sequence if len(pairs[0])]
    if not have:
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    each = min(max(count // len(have), 1), min(len(pairs[0]) for pairs in have))
    picks = [rng.permutation(len(pairs[0]))[:each] for pairs in have]
    return (np.concatenate([pairs[0][pick] for pairs, pick in zip(have, picks, strict=True)]),
            np.concatenate([pairs[1][pick] for pairs, pick in zip(have, picks, strict=True)]))


def reid_table(log: EmbeddingLog, *, seed: int = 0) -> list[ReidRow]:
    """The re-ID table of ``log``: a row per gap band of :data:`GAP_BANDS`, the pooled 1–30 frame row and the
    cross-camera row (:data:`CROSS_CAMERA`). Deterministic for a given ``seed``."""
    rng = stream_generator("reid_pairs", seed)
    sequences = [np.nonzero(log.sequence == s)[0] for s in np.unique(log.sequence)]
    rows: list[ReidRow] = []
    bands = [*GAP_BANDS, (1, 30)]
    for low, high in bands:
        same, different = [], []
        for rows_of in sequences:
            frame, camera, identity = log.frame[rows_of], log.camera[rows_of], log.identity[rows_of]
            a, b = same_identity_pairs(frame, camera, identity, low, high, rng)
            same.append((rows_of[a], rows_of[b]))
            a, b = different_identity_pairs(frame, camera, identity, low, high, DIFFERENT_PAIRS, rng)
            different.append((rows_of[a], rows_of[b]))
        rows.append(_row(log, f"{low}" if low == high else f"{low}-{high}", _split_sample(same, SAME_PAIRS, rng),
                         _split_sample(different, DIFFERENT_PAIRS, rng)))
    same, different = [], []
    for rows_of in sequences:
        frame, camera, identity = log.frame[rows_of], log.camera[rows_of], log.identity[rows_of]
        a, b = cross_camera_pairs(frame, camera, identity)
        pick = rng.permutation(len(a))[:SAME_PAIRS]
        same.append((rows_of[a[pick]], rows_of[b[pick]]))
        c, d = _cross_camera_strangers(frame, camera, identity, DIFFERENT_PAIRS, rng)
        different.append((rows_of[c], rows_of[d]))
    same, different = _split_sample(same, SAME_PAIRS, rng), _split_sample(different, DIFFERENT_PAIRS, rng)
    rows.append(_row(log, CROSS_CAMERA, same, different))
    return rows + cross_view_rows(log, same, different)


def cross_view_rows(log: EmbeddingLog, same: tuple, different: tuple) -> list[ReidRow]:
    """The cross-view table (module docstring): the same-frame, other-camera pairs ``same`` by the angle between
    the two rays and by baseline, each against all of ``different`` (two actors, two cameras, one frame); none
    when the log has no geometry."""
    if log.bearing is None or log.position is None or not len(same[0]):
        return []
    e = log.embeddings
    distances = distance(e[same[0]], e[same[1]])
    strangers = distance(e[different[0]], e[different[1]])
    angle = np.rad2deg(np.abs((log.bearing[same[0]] - log.bearing[same[1]] + np.pi) % (2 * np.pi) - np.pi))
    rows = []
    for low, high in VIEW_BINS_DEG:
        inside = (angle >= low) & ((angle < high) | (high == VIEW_BINS_DEG[-1][1]))
        rows.append(ReidRow.of(f"other camera, rays {low:g}-{high:g} deg", distances[inside], strangers))
    baseline = np.round(np.linalg.norm(log.position[same[0]] - log.position[same[1]], axis=1), 2)
    for value in np.unique(baseline):
        rows.append(ReidRow.of(f"other camera, {value:.2f} m apart", distances[baseline == value], strangers))
    return rows


def _row(log: EmbeddingLog, gaps: str, same: tuple, different: tuple) -> ReidRow:
    e = log.embeddings
    return ReidRow.of(gaps, distance(e[same[0]], e[same[1]]), distance(e[different[0]], e[different[1]]))


def _percent(value: float) -> str:
    return "     -" if not np.isfinite(value) else f"{100 * value:5.1f}%"


def _median(value: float) -> str:
    return "    -" if not np.isfinite(value) else f"{value:.3f}"


def format_table(rows: list[ReidRow]) -> str:
    """The table as text, with the source's values beside each row that has them."""
    lines = [
        "re-ID distance d = 0.5·(1 − cos); share of pairs at d ≤ 0.20 / 0.25; source: FastReID SBS50 on MOT17 val "
        "(pedestrians)",
        "gap [frames]             pairs same/diff   same≤.20 same≤.25  diff≤.20 diff≤.25    AUC  median same/diff "
        "| source: same≤.20 diff≤.20    AUC",
    ]
    for row in rows:
        source = SOURCE.get(row.gaps)
        pooled = SOURCE_POOLED.get(row.gaps)
        beside = (f"{_percent(source[1])}   {_percent(source[2])}   {source[0]:.3f}" if source else
                  f"{_percent(pooled[0])}   {_percent(pooled[2])}       -" if pooled else "  (not in the source)")
        auc = f"{row.auc:.3f}" if np.isfinite(row.auc) else "    -"
        lines.append(f"{row.gaps:<30} {row.same_pairs:>5}/{row.different_pairs:<5}  "
                     f"{_percent(row.same_below[0])}   {_percent(row.same_below[1])}  "
                     f"{_percent(row.different_below[0])}   {_percent(row.different_below[1])}   {auc}  "
                     f"{_median(row.same_median)} / {_median(row.different_median)}  | {beside}")
    return "\n".join(lines)
