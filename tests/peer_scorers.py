"""Test oracles: TrackEval and py-motmetrics run on the same rows simrig scores (dev extras only).

Rows are flat arrays sorted by frame: ground truth (frame, id, box) and tracker (frame, id, box), pixel boxes
(x1, y1, x2, y2). TrackEval's own IoU is used, so the oracle also checks simrig's similarity.
"""

from __future__ import annotations

import numpy as np
from trackeval.datasets._base_dataset import _BaseDataset
from trackeval.metrics import CLEAR, HOTA, Identity


def trackeval_data(frames, gt_frame, gt_id, gt_box, tr_frame, tr_id, tr_box) -> dict:
    """The ``data`` dict TrackEval's metrics take for one sequence (ids relabelled 0…n−1, as its datasets do)."""
    gt_unique, gt_dense = np.unique(gt_id, return_inverse=True)
    tr_unique, tr_dense = np.unique(tr_id, return_inverse=True)
    data = {"gt_ids": [], "tracker_ids": [], "similarity_scores": []}
    for frame in frames:
        g = np.nonzero(gt_frame == frame)[0]
        t = np.nonzero(tr_frame == frame)[0]
        data["gt_ids"].append(gt_dense[g].reshape(-1))
        data["tracker_ids"].append(tr_dense[t].reshape(-1))
        data["similarity_scores"].append(
            _BaseDataset._calculate_box_ious(gt_box[g].reshape(-1, 4), tr_box[t].reshape(-1, 4), box_format="x0y0x1y1")
        )
    data.update(
        num_timesteps=len(frames), num_gt_ids=len(gt_unique), num_tracker_ids=len(tr_unique),
        num_gt_dets=len(gt_id), num_tracker_dets=len(tr_id),
    )
    return data


def trackeval_metrics(sequences: dict[str, dict]) -> dict[str, dict]:
    """TrackEval's HOTA, CLEAR and Identity per sequence and combined (``COMBINED_SEQ``), summary values."""
    metrics = {"HOTA": HOTA(), "CLEAR": CLEAR({"PRINT_CONFIG": False}), "Identity": Identity({"PRINT_CONFIG": False})}
    per_sequence = {name: {key: metric.eval_sequence(data) for key, metric in metrics.items()}
                    for name, data in sequences.items()}
    combined = {key: metric.combine_sequences({name: res[key] for name, res in per_sequence.items()})
                for key, metric in metrics.items()}
    return {**per_sequence, "COMBINED_SEQ": combined}


def flatten(result: dict) -> dict[str, float]:
    """TrackEval's nested result → {metric name: value}; HOTA arrays are averaged over α like its summaries."""
    out = {}
    for field, value in result["HOTA"].items():
        out[field] = float(np.mean(value))
    for field, value in {**result["CLEAR"], **result["Identity"]}.items():
        out[field] = float(value)
    return out


def motmetrics_module():
    """py-motmetrics with the numpy-2 shim the notes describe (``np.asfarray`` was removed in numpy 2)."""
    if not hasattr(np, "asfarray"):
        setattr(np, "asfarray", lambda a, dtype=float: np.asarray(a, dtype))  # noqa: B010
    import motmetrics

    return motmetrics


def random_scene(rng: np.random.Generator, frames: int, objects: int, *, crowded: bool = False):
    """Ground truth of ``objects`` boxes drifting over ``frames`` frames (each present for a random span) and a
    tracker that jitters, misses, swaps and fragments them and adds false positives. Ids are unique per frame.
    Returns (gt_frame, gt_id, gt_box, tr_frame, tr_id, tr_box), sorted by frame."""
    spread = 120.0 if crowded else 600.0
    start = rng.uniform(0, spread, size=(objects, 2))
    velocity = rng.normal(0, 4.0, size=(objects, 2))
    size = rng.uniform(20, 80, size=(objects, 2))
    first = rng.integers(0, frames // 2, size=objects)
    last = np.minimum(frames - 1, first + rng.integers(frames // 4, frames, size=objects))
    gt, tr = [], []
    next_track = 1000
    track_of = {o: o + 1 for o in range(objects)}
    for frame in range(frames):
        if rng.random() < 0.05 and objects >= 2:  # identity swap between two objects
            a, b = rng.choice(objects, 2, replace=False)
            track_of[a], track_of[b] = track_of[b], track_of[a]
        for o in range(objects):
            if not first[o] <= frame <= last[o]:
                continue
            xy = start[o] + velocity[o] * frame
            box = np.concatenate([xy, xy + size[o]])
            gt.append((frame, 100 + o, box))
            if rng.random() < 0.03:  # fragmentation: a new track id
                track_of[o] = next_track
                next_track += 1
            if rng.random() < 0.15:
                continue  # miss
            gt_jitter = rng.normal(0, 0.12, size=4) * np.concatenate([size[o], size[o]])
            tr.append((frame, track_of[o], box + gt_jitter))
        for _ in range(rng.poisson(0.5)):  # false positives with fresh ids
            xy = rng.uniform(0, spread, size=2)
            tr.append((frame, next_track, np.concatenate([xy, xy + rng.uniform(20, 80, size=2)])))
            next_track += 1
    tr = _unique_per_frame(tr)
    return (*_columns(gt), *_columns(tr))


def _unique_per_frame(rows):
    seen, out = set(), []
    for frame, ident, box in rows:
        if (frame, ident) not in seen:
            seen.add((frame, ident))
            out.append((frame, ident, box))
    return out


def _columns(rows):
    if not rows:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros((0, 4))
    frame = np.array([r[0] for r in rows], dtype=np.int64)
    ident = np.array([r[1] for r in rows], dtype=np.int64)
    box = np.array([r[2] for r in rows], dtype=float)
    order = np.argsort(frame, kind="stable")
    return frame[order], ident[order], box[order]
