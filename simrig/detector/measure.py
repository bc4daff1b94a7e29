"""``simrig detector measure``: how a dataset's detector errs, in the terms published detectors are judged by.

* nuScenes true-positive errors and AP (:mod:`.nuscenes_metrics`) of every camera's detections pooled per
  frame (a frame is a nuScenes sample), per class then averaged. Ground truth counts when some camera sees
  it (the camera stand-in for the devkit's "has lidar points"); ground truth and predictions beyond the
  class range from the ego (devkit ``filter_eval_boxes``: 50 m for cars, trucks and buses, 40 m for
  motorcycles) are dropped.
* Recall and precision at the 2 m threshold by distance band from the ego; recall by visibility band
  (the best visible fraction over the cameras that see it, nuScenes' 0–40–60–80–100% bins).
* Re-ID distances of the detections' embeddings by frame gap, in the form a real re-ID model's are published
  (:mod:`.reid`), beside the source's values.
* From the dataset's ``sensor_truth`` (which detection each actor produced in each camera): the lag-1
  autocorrelation of the depth error (range from the camera, estimate minus truth) over consecutive
  frames of one (actor, camera) pair, and the mean length [frames, s] of runs of misses of an actor in one
  camera while it stays in view with nothing but chance or the burst process against it (runs cut by
  the pair's first or last frame are left out: their length is unknown).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from simrig.scenarios.evaluation_schema import NUSCENES_CLASS_RANGE_M, VEHICLE_CLASS_RANGE_M

from ..causes import Cause, cause_masks
from ..dataset import Dataset
from ..dataset.delivery import embedding_matrix
from ..dataset.ground_truth import per_label
from ..geometry import camera_from_world, viewing_bearings
from ..types import BOX3D_FIELDS, EgoPose
from .nuscenes_metrics import DIST_THRESHOLDS, TP_METRICS, TP_THRESHOLD, accumulate, calc_ap, calc_tp, match_class
from .reid import EmbeddingLog, ReidRow, format_table, reid_table

DISTANCE_BANDS_M = (0.0, 10.0, 20.0, 30.0, 40.0, 50.0)
VISIBILITY_BANDS = (0.0, 0.4, 0.6, 0.8, 1.0 + 1e-9)
_STRUCTURAL = int(Cause.OUT_OF_VIEW | Cause.TRUNCATED | Cause.OCCLUDED | Cause.FAR | Cause.SCHEDULED_OCCLUSION
                  | Cause.SCHEDULED_MISS | Cause.BLACKOUT | Cause.DROPPED_FRAME)
"""Causes that make a miss expected (not the detector's chance or burst)."""


@dataclass
class Measurement:
    """What ``measure`` reports (see the module docstring); errors [m, 1−IoU, rad, m/s]."""

    dataset: str
    frames: int
    frame_rate_hz: float
    mAP: float
    mATE: float
    mASE: float
    mAOE: float
    mAVE: float
    per_class: dict
    recall_by_distance: dict
    precision_by_distance: dict
    recall_by_visibility: dict
    depth_error_lag1: float
    depth_error_pairs: int
    miss_burst_frames: float
    miss_burst_s: float
    miss_bursts: int
    reid: list[ReidRow]

    def to_json(self) -> str:
        return json.dumps(asdict(self), indent=2)

    def table(self) -> str:
        """A readable summary."""
        lines = [
            f"dataset  {self.dataset} ({self.frames} frames at {self.frame_rate_hz:g} Hz)",
            f"nuScenes TP errors (2 m matching, per class then mean): mATE {self.mATE:.3f} m  mASE {self.mASE:.3f}"
            f"  mAOE {self.mAOE:.3f} rad  mAVE {self.mAVE:.3f} m/s   mAP {self.mAP:.3f}",
            "class        GT     ATE    ASE    AOE    AVE     AP",
            *(f"{name:<10} {row['gt']:>5} {row['trans_err']:.3f}  {row['scale_err']:.3f}  {row['orient_err']:.3f}  "
              f"{row['vel_err']:.3f}  {row['ap']:.3f}" for name, row in self.per_class.items()),
            "distance band [m]  " + "  ".join(f"{band:>9}" for band in self.recall_by_distance),
            "  recall           " + "  ".join(f"{v:>9.3f}" for v in self.recall_by_distance.values()),
            "  precision        " + "  ".join(f"{v:>9.3f}" for v in self.precision_by_distance.values()),
            "visibility band    " + "  ".join(f"{band:>9}" for band in self.recall_by_visibility),
            "  recall           " + "  ".join(f"{v:>9.3f}" for v in self.recall_by_visibility.values()),
            f"depth error lag-1 autocorrelation {self.depth_error_lag1:.3f} ({self.depth_error_pairs} pairs)",
            f"mean miss burst {self.miss_burst_frames:.2f} frames = {self.miss_burst_s:.3f} s "
            f"({self.miss_bursts} bursts)",
            *([format_table(self.reid)] if self.reid else ["re-ID: the detections carry no embeddings"]),
        ]
        return "\n".join(lines)


def _column(table, name: str) -> np.ndarray:
    return table.column(name).to_numpy(zero_copy_only=False)


def _boxes(table) -> np.ndarray:
    return np.column_stack([_column(table, name) for name in BOX3D_FIELDS]) if table.num_rows else np.empty((0, 9))


def _bands(edges: tuple[float, ...], unit: str) -> list[str]:
    return [f"{low:g}-{min(high, 100 if unit == '%' else high):g}{unit}" for low, high in zip(edges, edges[1:],
                                                                                               strict=False)]


def _rate(hit: np.ndarray, value: np.ndarray, edges: tuple[float, ...], labels: list[str]) -> dict:
    out = {}
    for label, low, high in zip(labels, edges, edges[1:], strict=False):
        inside = (value >= low) & (value < high)
        out[label] = float(hit[inside].mean()) if inside.any() else float("nan")
    return out


def measure(path: Path | str) -> Measurement:
    """Measure the detector of the dataset at ``path``."""
    dataset = Dataset.open(path)
    rate = float(dataset.scenario["frame_rate_hz"])
    truth, detections = dataset.table("ground_truth"), dataset.table("detections")
    ego = dataset.table("ego_poses")
    ego_xy = np.column_stack([_column(ego, "x"), _column(ego, "y")])
    frame_row = {int(f): i for i, f in enumerate(_column(ego, "frame"))}
    cameras = dataset.rig.camera_names
    c = len(cameras)

    gt_frame, gt_boxes = _column(truth, "frame"), _boxes(truth)
    gt_class = np.asarray(truth.column("class").to_pylist(), dtype=object)
    in_view = _column(dataset.table("projections"), "in_view").reshape(-1, c)
    occlusion = _column(dataset.table("visibility"), "occlusion").reshape(-1, c)
    visible = np.nanmax(np.where(in_view, 1.0 - occlusion, np.nan), axis=1, initial=-1.0)
    visible = np.where(np.any(in_view & np.isfinite(occlusion), axis=1), visible, np.nan)
    gt_rows = np.array([frame_row[int(f)] for f in gt_frame], dtype=np.int64)
    gt_range = np.hypot(*(gt_boxes[:, :2] - ego_xy[gt_rows]).T) if len(gt_rows) else np.empty(0)
    gt_limit = per_label(gt_class, NUSCENES_CLASS_RANGE_M.__getitem__)
    gt_keep = in_view.any(axis=1) & (gt_range < gt_limit)  # the devkit's filter_eval_boxes: strictly closer

    det_frame, det_boxes = _column(detections, "frame"), _boxes(detections)
    det_class = np.asarray(detections.column("label").to_pylist(), dtype=object)
    det_score = _column(detections, "score")
    det_rows = np.array([frame_row[int(f)] for f in det_frame], dtype=np.int64)
    det_range = np.hypot(*(det_boxes[:, :2] - ego_xy[det_rows]).T) if len(det_rows) else np.empty(0)
    det_keep = det_range < per_label(det_class, NUSCENES_CLASS_RANGE_M.__getitem__)

    per_class, gt_hit, det_hit = {}, np.zeros(len(gt_frame), dtype=bool), np.zeros(len(det_frame), dtype=bool)
    for name in VEHICLE_CLASS_RANGE_M:
        g = np.nonzero(gt_keep & (gt_class == name))[0]
        p = np.nonzero(det_keep & (det_class == name))[0]
        if not len(g):
            continue
        aps = []
        for threshold in DIST_THRESHOLDS:
            matches = match_class(gt_frame[g], gt_boxes[g], det_frame[p], det_boxes[p], det_score[p], threshold)
            data = accumulate(matches)
            aps.append(calc_ap(data))
            if threshold == TP_THRESHOLD:
                row = {"gt": int(len(g)), **{metric: calc_tp(data, metric) for metric in TP_METRICS}}
                gt_hit[g[matches.matched_gt[matches.matched_gt >= 0]]] = True
                det_hit[p[matches.matched_gt >= 0]] = True
        per_class[name] = {**row, "ap": float(np.mean(aps))}
    means = {metric: float(np.mean([row[metric] for row in per_class.values()])) if per_class else float("nan")
             for metric in (*TP_METRICS, "ap")}

    distance_labels = _bands(DISTANCE_BANDS_M, " m")
    visibility_labels = _bands(tuple(round(100 * e) for e in VISIBILITY_BANDS), "%")
    lag1, pairs = _depth_lag1(dataset)
    bursts = _miss_bursts(dataset)
    burst_frames = float(np.mean(bursts)) if len(bursts) else float("nan")
    return Measurement(
        dataset=str(path), frames=dataset.frame_count, frame_rate_hz=rate, mAP=means["ap"],
        mATE=means["trans_err"], mASE=means["scale_err"], mAOE=means["orient_err"], mAVE=means["vel_err"],
        per_class=per_class,
        recall_by_distance=_rate(gt_hit[gt_keep], gt_range[gt_keep], DISTANCE_BANDS_M, distance_labels),
        precision_by_distance=_rate(det_hit[det_keep], det_range[det_keep], DISTANCE_BANDS_M, distance_labels),
        recall_by_visibility=_rate(gt_hit[gt_keep], np.nan_to_num(visible[gt_keep], nan=-1.0), VISIBILITY_BANDS,
                                   visibility_labels),
        depth_error_lag1=lag1, depth_error_pairs=pairs,
        miss_burst_frames=burst_frames, miss_burst_s=burst_frames / rate, miss_bursts=int(len(bursts)),
        reid=reid_table(log) if (log := embedding_log(dataset)).embeddings.shape[1] else [],
    )


def pooled_reid(paths: list[Path | str]) -> list[ReidRow]:
    """The re-ID table over several datasets, each one sequence."""
    return reid_table(EmbeddingLog.concatenate([embedding_log(Dataset.open(path)) for path in paths]))


def embedding_log(dataset: Dataset) -> EmbeddingLog:
    """The embeddings of the dataset's detections of actors (not of clutter, ghosts or duplicates), each with
    its frame, camera index and actor id; one sequence."""
    links = linked_errors(dataset)
    column = dataset.table("detections").column("embedding")
    lengths = np.diff(column.combine_chunks().offsets.to_numpy())
    embeddings = embedding_matrix(column, int(lengths.max()) if len(lengths) else 0)[links["row"]]
    keep = np.isfinite(embeddings).all(axis=1)
    bearing = viewing_bearings(links["truth"][keep], links["centre"][keep])
    return EmbeddingLog(np.zeros(int(keep.sum()), dtype=np.int64), links["frame"][keep].astype(np.int64),
                        links["camera"][keep], links["actor"][keep].astype(np.int64), embeddings[keep].astype(float),
                        bearing=bearing, position=links["centre"][keep])


def linked_errors(dataset: Dataset) -> dict[str, np.ndarray]:
    """Every detection of an actor joined to its truth via ``sensor_truth``: frame, camera index, actor id,
    true and detected boxes ``(R, 9)``, the camera's optical centre in the world ``(R, 3)``, score, labels and
    the detection's row in the ``detections`` table."""
    detections, truth = dataset.table("detections"), dataset.table("ground_truth")
    sensor = dataset.table("sensor_truth")
    cameras = dataset.rig.camera_names
    camera_of = {name: i for i, name in enumerate(cameras)}
    s_actor, s_det = _column(sensor, "actor_id"), _column(sensor, "detection")
    real = (s_actor >= 0) & (s_det >= 0)
    s_frame = _column(sensor, "frame")[real]
    s_camera = np.array([camera_of[name] for name in np.asarray(sensor.column("camera").to_pylist())[real]],
                        dtype=np.int64)
    s_actor, s_det = s_actor[real], s_det[real]
    width = int(s_det.max()) + 1 if len(s_det) else 1
    d_frame, d_index = _column(detections, "frame"), _column(detections, "index")
    d_camera = np.array([camera_of[name] for name in np.asarray(detections.column("camera").to_pylist())],
                        dtype=np.int64)
    width = max(width, int(d_index.max()) + 1 if len(d_index) else 1)
    d_key = (d_frame.astype(np.int64) * len(cameras) + d_camera) * width + d_index
    s_key = (s_frame.astype(np.int64) * len(cameras) + s_camera) * width + s_det
    order = np.argsort(d_key)
    det_row = order[np.searchsorted(d_key[order], s_key)]
    t_frame, t_actor = _column(truth, "frame"), _column(truth, "actor_id")
    t_key = t_frame.astype(np.int64) * (1 << 32) + t_actor
    t_order = np.argsort(t_key)
    truth_row = t_order[np.searchsorted(t_key[t_order], s_frame.astype(np.int64) * (1 << 32) + s_actor)]
    ego = dataset.table("ego_poses")
    poses = [EgoPose(*(float(v) for v in row)) for row in zip(*(_column(ego, n) for n in ("x", "y", "z", "yaw")),
                                                                strict=True)]
    frame_row = {int(f): i for i, f in enumerate(_column(ego, "frame"))}
    centres = np.array([np.linalg.inv(camera_from_world(dataset.rig, pose))[:, :3, 3] for pose in poses])
    centre = centres[[frame_row[int(f)] for f in s_frame], s_camera] if len(s_frame) else np.empty((0, 3))
    return {"frame": s_frame, "camera": s_camera, "actor": s_actor, "truth": _boxes(truth)[truth_row],
            "estimate": _boxes(detections)[det_row], "centre": centre,
            "score": _column(detections, "score")[det_row],
            "label": np.asarray(detections.column("label").to_pylist(), dtype=object)[det_row], "row": det_row,
            "true_label": np.asarray(truth.column("class").to_pylist(), dtype=object)[truth_row]}


def consecutive_pairs(frame: np.ndarray, camera: np.ndarray, actor: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Row pairs (a, b) of one (actor, camera) at frames t and t + 1."""
    order = np.lexsort((frame, camera, actor))
    same = (actor[order][1:] == actor[order][:-1]) & (camera[order][1:] == camera[order][:-1])
    next_frame = frame[order][1:] == frame[order][:-1] + 1
    keep = same & next_frame
    return order[:-1][keep], order[1:][keep]


def depth_errors(links: dict[str, np.ndarray]) -> np.ndarray:
    """Range error [m] of each linked detection's centre from its camera (estimate minus truth)."""
    return (np.linalg.norm(links["estimate"][:, :3] - links["centre"], axis=1)
            - np.linalg.norm(links["truth"][:, :3] - links["centre"], axis=1))


def lag1(values: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Pearson correlation of ``values[a]`` with ``values[b]`` (NaN with fewer than 3 pairs)."""
    if len(a) < 3:
        return float("nan")
    return float(np.corrcoef(values[a], values[b])[0, 1])


def _depth_lag1(dataset: Dataset) -> tuple[float, int]:
    links = linked_errors(dataset)
    a, b = consecutive_pairs(links["frame"], links["camera"], links["actor"])
    return lag1(depth_errors(links), a, b), int(len(a))


def miss_runs(frame: np.ndarray, key: np.ndarray, eligible: np.ndarray, detected: np.ndarray) -> np.ndarray:
    """Lengths [frames] of runs of misses bounded by detections on both sides within stretches of
    consecutive eligible frames of one ``key`` (rows sorted any way)."""
    order = np.lexsort((frame, key))
    frame, key, eligible, detected = frame[order], key[order], eligible[order], detected[order]
    runs, current, open_run = [], 0, False
    previous_key, previous_frame = None, None
    for k, f, ok, hit in zip(key.tolist(), frame.tolist(), eligible.tolist(), detected.tolist(), strict=True):
        if k != previous_key or f != previous_frame + 1 or not ok:
            current, open_run = 0, False
        if ok:
            if hit:
                if open_run and current:
                    runs.append(current)
                current, open_run = 0, True
            elif open_run:
                current += 1
        previous_key, previous_frame = k, f
    return np.array(runs, dtype=float)


def _miss_bursts(dataset: Dataset) -> np.ndarray:
    sensor = dataset.table("sensor_truth")
    actor = _column(sensor, "actor_id")
    real = actor >= 0
    causes = cause_masks(sensor.column("causes").filter(real).to_pylist())
    cameras = {name: i for i, name in enumerate(dataset.rig.camera_names)}
    camera = np.array([cameras[name] for name in np.asarray(sensor.column("camera").to_pylist())[real]])
    key = actor[real] * 64 + camera
    return miss_runs(_column(sensor, "frame")[real], key, (causes & _STRUCTURAL) == 0,
                     _column(sensor, "detection")[real] >= 0)
