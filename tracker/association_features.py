"""Features of a (track, detection) pair for a learned association (:mod:`.learned`), the same in training and
in tracking: the tracker computes them from its own state, a training loader from the same tracker's state
(:mod:`simrig.collection.pairs`).

For tracks with predicted world-frame boxes ẑ (N, 7) [m, rad], innovation covariances S (N, 7, 7), appearance
unit vectors (N, D) (a row of NaN: none yet), seconds since their last update and updates so far, and detections
(M, ≥ 7) world-frame boxes with scores, unit embeddings (M, D) and ranges from the ego [m], the feature tensor is
(N, M, F) in the order of :data:`TRACK_FEATURES`:

- ``mahalanobis``: √((z − ẑ)ᵀ S⁻¹ (z − ẑ)), the hand-set gate's quantity [-];
- ``distance_m``: bird's-eye-view centre distance [m];
- ``heading``: 1 − |cos Δθ| [-] (a box facing backwards is as good as one facing forwards);
- ``log_volume_ratio``: |ln(V_detection / V_track)| [-];
- ``appearance``: cosine distance 1 − a·b of the track's and the detection's appearance [-] (1 when either has
  none), and ``has_appearance`` (1 or 0);
- ``since_update_s``: the track's seconds since its last update, this frame's step included [s];
- ``score``: the detection's score [-]; ``log_hits``: ln(1 + the track's updates) [-];
- ``range_m``: the detection's distance from the ego [m] (its noise grows with range).

Cross-camera pairs of detections (:func:`detection_pair_features`) use the geometric and appearance features of
two detections: ``distance_m``, ``heading``, ``log_volume_ratio``, ``appearance``, ``has_appearance``,
``min_score``, ``range_m`` (the nearer one's).
"""

from __future__ import annotations

import numpy as np

from .costs import bev_distance, mahalanobis

TRACK_FEATURES = ("mahalanobis", "distance_m", "heading", "log_volume_ratio", "appearance", "has_appearance",
                  "since_update_s", "score", "log_hits", "range_m")
DETECTION_PAIR_FEATURES = ("distance_m", "heading", "log_volume_ratio", "appearance", "has_appearance", "min_score",
                           "range_m")
MIN_SIZE_M = 0.1
"""[m] box sides are floored here before volumes are compared (a degenerate estimate is not −inf)."""


def _volumes(boxes: np.ndarray) -> np.ndarray:
    return np.prod(np.maximum(boxes[:, 3:6], MIN_SIZE_M), axis=1)


def _appearance(first: np.ndarray, second: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(cosine distance, both have one) of every pair of rows of two (·, D) unit-vector arrays (NaN rows: none)."""
    if first.shape[1] == 0 or second.shape[1] == 0:
        shape = (len(first), len(second))
        return np.ones(shape), np.zeros(shape)
    has_first, has_second = np.isfinite(first).all(axis=1), np.isfinite(second).all(axis=1)
    similarity = np.nan_to_num(first) @ np.nan_to_num(second).T
    both = has_first[:, None] & has_second[None, :]
    return np.where(both, 1.0 - similarity, 1.0), both.astype(float)


def _shared(first: np.ndarray, second: np.ndarray, first_embedding: np.ndarray,
            second_embedding: np.ndarray) -> dict[str, np.ndarray]:
    """The features two sets of boxes share: distance, heading, volume ratio, appearance."""
    appearance, has = _appearance(first_embedding, second_embedding)
    return {
        "distance_m": bev_distance(first, second),
        "heading": 1.0 - np.abs(np.cos(first[:, None, 6] - second[None, :, 6])),
        "log_volume_ratio": np.abs(np.log(_volumes(second)[None, :] / _volumes(first)[:, None])),
        "appearance": appearance,
        "has_appearance": has,
    }


def track_pair_features(predicted: np.ndarray, innovation: np.ndarray, track_embeddings: np.ndarray,
                        since_update_s: np.ndarray, hits: np.ndarray, boxes: np.ndarray, scores: np.ndarray,
                        embeddings: np.ndarray, ranges_m: np.ndarray) -> np.ndarray:
    """(N, M, F) features of every (track, detection) pair, in :data:`TRACK_FEATURES` order (see the module)."""
    n, m = len(predicted), len(boxes)
    columns = _shared(predicted, boxes, track_embeddings, embeddings)
    columns["mahalanobis"] = mahalanobis(predicted, innovation, boxes)
    columns["since_update_s"] = np.broadcast_to(np.asarray(since_update_s, float)[:, None], (n, m))
    columns["score"] = np.broadcast_to(np.asarray(scores, float)[None, :], (n, m))
    columns["log_hits"] = np.broadcast_to(np.log1p(np.asarray(hits, float))[:, None], (n, m))
    columns["range_m"] = np.broadcast_to(np.asarray(ranges_m, float)[None, :], (n, m))
    return np.stack([columns[name] for name in TRACK_FEATURES], axis=-1)


def detection_pair_features(boxes: np.ndarray, scores: np.ndarray, embeddings: np.ndarray,
                            ranges_m: np.ndarray) -> np.ndarray:
    """(M, M, G) features of every pair of one frame's detections, in :data:`DETECTION_PAIR_FEATURES` order."""
    columns = _shared(boxes, boxes, embeddings, embeddings)
    columns["min_score"] = np.minimum(scores[:, None], scores[None, :])
    columns["range_m"] = np.minimum(ranges_m[:, None], ranges_m[None, :])
    return np.stack([columns[name] for name in DETECTION_PAIR_FEATURES], axis=-1)
