"""Calibrate the realistic presets' re-ID settings to a real re-ID model's distances (``simrig.detector.reid.SOURCE``).

Runs simrig's own appearance effect (:class:`simrig.sensor.appearance.Embeddings`) on the worlds of generated
datasets (their ground truth, projections, visibility and which actor each camera detected), for candidate
``[sensor.embedding]`` settings, measures the re-ID table as ``simrig detector measure`` does, and minimises the
squared misfit to the source's ROC AUC and same- and different-identity shares at d ≤ 0.2 per gap band
(Nelder–Mead on log-parameters). Development seeds only (< 100): the check runs on seeds ≥ 100.

    python tests/calibration/reid_preset.py --datasets DIR [DIR ...] [--iterations 60]
        [--set NAME=VALUE ...] [--free NAME ...] [--different-median D] [--check DIR ...]

DIR: datasets generated with the preset (``simrig generate highway_surround6 --seed 0 --out DIR``); only their
world and which actors were detected are used, so the preset's current embedding settings do not matter.
``--set``: a fixed setting other than the preset's (``dimension``, ``lookalike_weight``, ``colours``, ...);
``--free``: a further setting to fit (``lookalike_weight``, say); ``--different-median``: also match the median
different-identity distance of pairs 1–30 frames apart (the source's text gives its shares at 0.20 and 0.25 only;
its histogram's median is read from the figure); ``--check``: datasets of fresh seeds (≥ 100) on which the fitted
settings' table is printed, none of them used by the fit.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np
from scipy.optimize import minimize
from simrig.scenarios.sensor_presets import PRESETS
from simrig.scenarios.sensor_schema import EmbeddingConfig

from simrig.dataset import Dataset
from simrig.detector.measure import linked_errors
from simrig.detector.reid import GAP_BANDS, SOURCE, EmbeddingLog, format_table, reid_table
from simrig.geometry import camera_from_world
from simrig.seeding import RandomStreams
from simrig.sensor.appearance import Embeddings
from simrig.sensor.batch import FrameContext, SensorBatch
from simrig.types import EgoPose

FREE = ("sigma", "drift_sigma", "drift_time_s", "slow_drift_sigma", "slow_drift_time_s")


def world_frames(path: str) -> list[tuple[SensorBatch, np.ndarray]]:
    """Per frame of the dataset at ``path``: a sensor batch of its world and the (C, N) detected mask."""
    dataset = Dataset.open(path)
    rig = dataset.rig
    c = len(rig.cameras)
    truth = dataset.table("ground_truth").to_pandas()
    projections = dataset.table("projections").to_pandas()
    visibility = dataset.table("visibility").to_pandas()
    ego = dataset.table("ego_poses").to_pandas().set_index("frame")
    links = linked_errors(dataset)
    detected_keys = set(zip(links["frame"].tolist(), links["camera"].tolist(), links["actor"].tolist(), strict=True))
    frames = []
    for frame, rows in truth.groupby("frame", sort=True):
        boxes = rows[["x", "y", "z", "length", "width", "height", "yaw", "vx", "vy"]].to_numpy(float)
        ids = rows["actor_id"].to_numpy(np.int64)
        proj = projections[projections.frame == frame]
        vis = visibility[visibility.frame == frame]
        n = len(ids)
        in_view = proj["in_view"].to_numpy(bool).reshape(n, c).T
        truncation = proj["truncation"].to_numpy(float).reshape(n, c).T
        occlusion = vis["occlusion"].to_numpy(float).reshape(n, c).T
        pose = ego.loc[frame]
        world_from_camera = np.linalg.inv(camera_from_world(rig, EgoPose(pose.x, pose.y, pose.z, pose.yaw)))
        batch = SensorBatch(
            context=FrameContext(int(frame), float(pose.timestamp), float(pose.yaw), ids, np.zeros(n)),
            cameras=rig.cameras, world_from_camera=world_from_camera, classes=rows["class"].to_numpy(object),
            boxes3d=np.broadcast_to(boxes, (c, n, 9)), boxes2d=np.full((c, n, 4), np.nan), truncation=truncation,
            visible_fraction=np.where(in_view, np.nan_to_num(1.0 - occlusion, nan=0.0), 0.0),
            distance=np.linalg.norm(boxes[:, :3] - world_from_camera[:, None, :3, 3], axis=-1), in_view=in_view)
        detected = np.array([[(int(frame), camera, int(actor)) in detected_keys for actor in ids]
                             for camera in range(c)], dtype=bool).reshape(c, n)
        frames.append((batch, detected))
    return frames


def simulate(worlds: list[list], settings: dict, seed: int = 0) -> EmbeddingLog:
    """The embeddings the appearance effect gives every detected actor of ``worlds`` with ``settings``."""
    logs = []
    for index, frames in enumerate(worlds):
        effect = Embeddings(RandomStreams(seed + index), EmbeddingConfig(**settings), {"car": 1.0})
        rows = {"frame": [], "camera": [], "identity": [], "embeddings": []}
        for batch, detected in frames:
            batch.detected = detected
            effect.apply(batch)
            cameras, actors = np.nonzero(detected)
            rows["frame"].append(np.full(len(actors), batch.context.frame))
            rows["camera"].append(cameras)
            rows["identity"].append(batch.context.actor_ids[actors])
            rows["embeddings"].append(batch.embeddings[cameras, actors].astype(float))
        columns = (np.concatenate(rows[name]) for name in ("frame", "camera", "identity", "embeddings"))
        logs.append(EmbeddingLog(np.zeros(sum(map(len, rows["frame"])), dtype=np.int64), *columns))
    return EmbeddingLog.concatenate(logs)


def misfit(table, different_median: float | None = None) -> float:
    """Squared misfit to the source: AUC in units of 0.015, shares in units of 0.025 (same) and 0.005 (different);
    with ``different_median``, the pooled 1–30-frame row's median different-identity distance in units of 0.01."""
    total = 0.0
    if different_median is not None:
        pooled = next(row for row in table if row.gaps == "1-30")
        total += ((pooled.different_median - different_median) / 0.01) ** 2
    for row in table[:len(GAP_BANDS)]:
        auc, same, different = SOURCE[row.gaps]
        total += ((row.auc - auc) / 0.015) ** 2 + ((row.same_below[0] - same) / 0.025) ** 2 \
            + ((row.different_below[0] - different) / 0.005) ** 2
    return total


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--datasets", nargs="+", required=True)
    parser.add_argument("--iterations", type=int, default=60)
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    parser.add_argument("--different-median", type=float, default=None)
    parser.add_argument("--check", nargs="*", default=[])
    parser.add_argument("--free", action="append", default=[], metavar="NAME")
    args = parser.parse_args()
    free = FREE + tuple(args.free)
    worlds = [world_frames(path) for path in args.datasets]
    base = dict(PRESETS["bevformer_small"]["embedding"])
    for item in args.set:
        name, _, value = item.partition("=")
        base[name] = type(base[name])(float(value)) if name in base else float(value)
    start = np.log([base[name] for name in free])

    def objective(x: np.ndarray) -> float:
        settings = {**base, **dict(zip(free, np.exp(x).tolist(), strict=True))}
        if settings.get("lookalike_weight", 0) >= 1:
            return float("inf")
        value = misfit(reid_table(simulate(worlds, settings)), args.different_median)
        print(f"{value:9.2f}  " + "  ".join(f"{name}={settings[name]:.3f}" for name in free), flush=True)
        return value

    result = minimize(objective, start, method="Nelder-Mead",
                      options={"maxfev": args.iterations, "xatol": 1e-3, "fatol": 1e-2})
    best = {**base, **{name: round(float(v), 3) for name, v in zip(free, np.exp(result.x), strict=True)}}
    print(json.dumps(best, indent=2))
    for label, paths in (("fitted on", args.datasets), ("checked on", args.check)):
        if paths:
            print(f"\n{label}: {' '.join(paths)}")
            print(format_table(reid_table(simulate([world_frames(path) for path in paths], best))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
