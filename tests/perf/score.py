"""Benchmark: simrig's scorer against the peer implementations, side by side in one process on the same data.

Run explicitly (not part of the test suite)::

    python tests/perf/score.py [--repeats 3] [--frames 200] [--boxes 10000]

1. 2D — HOTA + CLEAR + Identity over every (camera, class) of a generated ``highway_surround6`` dataset
   (seed 0), scored against a degraded copy of its ground truth (2 px jitter, 10 % misses, an id swap per
   actor). simrig: building its sequences (IoU included) and counting; TrackEval 1.3.0: building its per-frame
   ``data`` (its own IoU) and ``eval_sequence`` + ``combine_sequences`` of its three metric classes.
2. 3D — the AMOTA family of one class on a synthetic highway with ``--boxes`` ground-truth boxes (a tracker
   with 0.5 m noise, misses, id swaps, false positives). simrig: :func:`simrig.scoring.amota.amota_family`;
   the nuScenes devkit (1.2.0): ``TrackingEvaluation.accumulate`` on ``TrackingBox`` objects built beforehand
   (not timed), plus the few lines of ``TrackingEval.evaluate`` that pick the best threshold and average.
   The devkit pins numpy < 2, so it is installed in the benchmark's own environment without dependencies::

       pip install -e '.[dev]' && pip install --no-deps nuscenes-devkit
       pip install scikit-learn pyquaternion cachetools

   Two shims: ``np.asfarray`` for py-motmetrics on numpy 2, and the devkit's ``merge_event_dataframes``
   rewritten with ``pandas.concat`` (it calls ``DataFrame.append``, removed in pandas 2). Without the devkit
   the 3D part reports simrig alone.

Targets: 2D at least 3× faster than TrackEval; AMOTA on 10,000 boxes in under 2 s. Runs alternate
between the two sides; the table reports the best of ``--repeats`` and the value differences, and is written
to ``reports/perf/score.md``.
"""

from __future__ import annotations

import argparse
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from peer_scorers import motmetrics_module  # noqa: E402  (tests/ helpers)
from simrig.scenarios import load_scenario  # noqa: E402

from simrig.dataset import Dataset  # noqa: E402
from simrig.dataset.ground_truth import load_ground_truth  # noqa: E402
from simrig.dataset.tracks_file import TrackRows  # noqa: E402
from simrig.pipeline.generate import generate  # noqa: E402
from simrig.scoring.amota import amota_family  # noqa: E402
from simrig.scoring.bev import bev_sequence  # noqa: E402
from simrig.scoring.clear import CLEAR  # noqa: E402
from simrig.scoring.counts import sum_counts  # noqa: E402
from simrig.scoring.hota import HOTA  # noqa: E402
from simrig.scoring.identity import Identity  # noqa: E402
from simrig.scoring.inputs import camera_sequences  # noqa: E402
from simrig.scoring.ratios import clear_ratios, hota_ratios, identity_ratios  # noqa: E402
from simrig.scoring.sequence import frame_slices  # noqa: E402

REPORT = Path(__file__).resolve().parents[2] / "reports" / "perf" / "score.md"
COMPARED_2D = ("HOTA", "DetA", "AssA", "LocA", "MOTA", "MOTP", "IDSW", "Frag", "IDF1")
COMPARED_3D = ("AMOTA", "AMOTP", "MOTAR", "MOTA", "MOTP", "RECALL", "IDS", "FRAG", "MT", "ML", "TP", "FP", "FN")


# ----------------------------------------------------------------------------------------------- 2D
def degraded_rows(truth, rng) -> TrackRows:
    rows, cams = np.nonzero(truth.in_view)
    keep = rng.random(len(rows)) > 0.1
    rows, cams = rows[keep], cams[keep]
    boxes = truth.boxes2d[rows, cams] + rng.normal(0, 2.0, size=(len(rows), 4))
    boxes[:, 2:] = np.maximum(boxes[:, 2:], boxes[:, :2] + 1.0)
    swap_frame = rng.integers(0, len(truth.frames), size=truth.actor_id.max() + 1)
    ids = truth.actor_id[rows] + 100000 * (truth.frame[rows] > swap_frame[truth.actor_id[rows]])
    order = np.lexsort((cams, truth.frame[rows]))
    names = np.array(truth.rig.camera_names, dtype=object)
    return TrackRows(truth.frame[rows][order], ids[order], truth.label[rows][order], np.ones(len(rows)),
                     boxes[order], names[cams][order])


def simrig_2d(truth, tracks):
    counts = [{**HOTA().count(s), **CLEAR().count(s), **Identity().count(s)} for s in camera_sequences(truth, tracks)]
    total = sum_counts(counts)
    return {**hota_ratios(total), **clear_ratios(total), **identity_ratios(total)}


def trackeval_2d(truth, tracks):
    from trackeval.datasets._base_dataset import _BaseDataset
    from trackeval.metrics import CLEAR as TeClear
    from trackeval.metrics import HOTA as TeHota
    from trackeval.metrics import Identity as TeIdentity

    metrics = {"HOTA": TeHota(), "CLEAR": TeClear({"PRINT_CONFIG": False}),
               "Identity": TeIdentity({"PRINT_CONFIG": False})}
    per_sequence = {}
    for c, camera in enumerate(truth.rig.camera_names):
        for label in sorted(set(truth.label.tolist()) | set(tracks.label.tolist())):
            g = np.nonzero(truth.in_view[:, c] & (truth.label == label))[0]
            t = np.nonzero((tracks.camera == camera) & (tracks.label == label))[0]
            if len(g) == 0 and len(t) == 0:
                continue
            gt_ids, gt_dense = np.unique(truth.actor_id[g], return_inverse=True)
            tr_ids, tr_dense = np.unique(tracks.track_id[t], return_inverse=True)
            gs, ts = frame_slices(truth.frame[g], truth.frames), frame_slices(tracks.frame[t], truth.frames)
            gt_boxes, tr_boxes = truth.boxes2d_in(g, c), tracks.boxes[t]
            data = {"gt_ids": [gt_dense[a:b] for a, b in gs], "tracker_ids": [tr_dense[a:b] for a, b in ts],
                    "similarity_scores": [_BaseDataset._calculate_box_ious(gt_boxes[a:b], tr_boxes[c0:c1],
                                                                          box_format="x0y0x1y1")
                                          for (a, b), (c0, c1) in zip(gs, ts, strict=True)],
                    "num_timesteps": len(truth.frames), "num_gt_ids": len(gt_ids), "num_tracker_ids": len(tr_ids),
                    "num_gt_dets": len(g), "num_tracker_dets": len(t)}
            per_sequence[f"{camera}/{label}"] = {k: m.eval_sequence(data) for k, m in metrics.items()}
    out = {}
    for key, metric in metrics.items():
        combined = metric.combine_sequences({name: res[key] for name, res in per_sequence.items()})
        out.update({field: float(np.mean(value)) for field, value in combined.items()})
    return out


# ----------------------------------------------------------------------------------------------- 3D
def synthetic_highway(boxes: int, rng):
    """Ground truth on a 4-lane road (40 objects) and a degraded tracker; rows (frame, id, x, y, vx, vy[, score])."""
    objects, frames = 40, boxes // 40
    lane = rng.integers(0, 4, objects) * 3.5
    x0, speed = rng.uniform(-60, 60, objects), rng.uniform(-3, 3, objects)
    gt, tracks, next_id, track_of, score_of = [], [], 10000, {o: o for o in range(objects)}, {}
    for f in range(frames):
        for o in range(objects):
            x = x0[o] + speed[o] * 0.1 * f
            gt.append((f, o, x, lane[o], speed[o], 0.0))
            if rng.random() < 0.02:
                track_of[o], next_id = next_id, next_id + 1
            if rng.random() < 0.15:
                continue
            t = track_of[o]
            score = score_of.setdefault(t, rng.uniform(0.3, 1.0))
            noise = rng.normal(0, 0.5, 2)
            tracks.append((f, t, x + noise[0], lane[o] + noise[1], speed[o] + rng.normal(0, 0.5), 0.0, score))
        for _ in range(rng.poisson(2.0)):
            tracks.append((f, next_id, rng.uniform(-60, 60), rng.uniform(0, 10.5), 0.0, 0.0, rng.uniform(0, 0.6)))
            next_id += 1
    return np.array(gt), np.array(tracks), frames


def simrig_3d(gt, tracks, frames):
    seq = bev_sequence("car", np.arange(frames), gt[:, 0].astype(int), gt[:, 1].astype(int), gt[:, 2:4],
                       gt[:, 4:6], tracks[:, 0].astype(int), tracks[:, 1].astype(int), tracks[:, 2:4],
                       tracks[:, 4:6], tracks[:, 6])
    return amota_family(seq).metrics


def devkit_available() -> bool:
    try:
        motmetrics_module()
        import nuscenes.eval.tracking.algo  # noqa: F401
    except ImportError:
        return False
    return True


def devkit_inputs(gt, tracks, frames):
    """The devkit's in-memory input: scene → timestamp → [TrackingBox]; scores already averaged per track."""
    from nuscenes.eval.common.config import config_factory
    from nuscenes.eval.tracking.data_classes import TrackingBox

    config_factory("tracking_nips_2019")  # registers the class names and the 40 thresholds, as the devkit does

    def box(row, score, is_gt):
        return TrackingBox(sample_token=str(int(row[0])), translation=(row[2], row[3], 0.0), size=(1.9, 4.6, 1.6),
                           rotation=(1.0, 0.0, 0.0, 0.0), velocity=(row[4], row[5]), ego_translation=(0, 0, 0),
                           num_pts=-1, tracking_id=str(int(row[1])), tracking_name="car",
                           tracking_score=score if not is_gt else -1.0)
    gt_frames = {f: [] for f in range(frames)}
    pred_frames = {f: [] for f in range(frames)}
    for row in gt:
        gt_frames[int(row[0])].append(box(row, -1.0, True))
    for row in tracks:
        pred_frames[int(row[0])].append(box(row, float(row[6]), False))
    return {"scene": gt_frames}, {"scene": pred_frames}


def devkit_3d(tracks_gt, tracks_pred):
    import pandas as pd
    from nuscenes.eval.common.config import config_factory
    from nuscenes.eval.common.utils import center_distance
    from nuscenes.eval.tracking.algo import TrackingEvaluation
    from nuscenes.eval.tracking.data_classes import TrackingMetricData
    from nuscenes.eval.tracking.mot import MOTAccumulatorCustom

    def merge_event_dataframes(dfs, **_):  # the devkit's merge, with pandas.concat instead of DataFrame.append
        frames, next_frame = [], 0
        for df in dfs:
            df = (df.events if isinstance(df, MOTAccumulatorCustom) else df).copy()
            df.index = df.index.map(lambda x, offset=next_frame: (x[0] + offset, x[1]))
            next_frame = max(next_frame, int(df.index.get_level_values(0).max()) + 1) if len(df) else next_frame
            frames.append(df)
        return pd.concat(frames) if frames else MOTAccumulatorCustom.new_event_dataframe()

    MOTAccumulatorCustom.merge_event_dataframes = staticmethod(merge_event_dataframes)
    config = config_factory("tracking_nips_2019")
    worst = config.metric_worst
    evaluation = TrackingEvaluation(tracks_gt, tracks_pred, "car", center_distance, config.dist_th_tp,
                                    config.min_recall, TrackingMetricData.nelem, worst, verbose=False)
    md = evaluation.accumulate()
    best = int(np.nanargmax(md.mota))
    out = {name.upper(): float(md.get_metric(name)[best])
           for name in ("motar", "mota", "motp", "recall", "ids", "frag", "mt", "ml", "tp", "fp", "fn")}
    for name, source in (("AMOTA", "motar"), ("AMOTP", "motp")):
        values = np.array(md.get_metric(source), dtype=float)
        values[np.isnan(values)] = worst[name.lower()]
        out[name] = float(np.mean(values))
    return out


# ----------------------------------------------------------------------------------------------- main
def best_of(repeats, *sides):
    times = [[] for _ in sides]
    results = [None] * len(sides)
    for _ in range(repeats):
        for i, side in enumerate(sides):
            start = time.perf_counter()
            results[i] = side()
            times[i].append(time.perf_counter() - start)
    return [min(t) for t in times], results


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--boxes", type=int, default=10000)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    lines = ["# Scoring speed: simrig against TrackEval and the nuScenes devkit", "",
             f"Command: `python tests/perf/score.py --repeats {args.repeats} --frames {args.frames} "
             f"--boxes {args.boxes}`", "",
             f"Machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}; "
             "best of the repeats, sides alternating.", ""]

    with tempfile.TemporaryDirectory() as folder:
        generate(load_scenario("highway_surround6"), seed=0, out=Path(folder) / "d", frames=args.frames,
                 progress=False)
        truth = load_ground_truth(Dataset.open(Path(folder) / "d"))
    tracks = degraded_rows(truth, rng)
    (t_simrig, t_te), (m_simrig, m_te) = best_of(args.repeats, lambda: simrig_2d(truth, tracks),
                                                 lambda: trackeval_2d(truth, tracks))
    gt_boxes = int(truth.in_view.sum())
    diff = max(abs(m_simrig[name] - m_te[name]) for name in COMPARED_2D)
    lines += ["## 2D: HOTA + CLEAR + Identity, every (camera, class) of highway_surround6", "",
              f"{args.frames} frames, 6 cameras, {gt_boxes} ground-truth boxes, {len(tracks)} tracker boxes.", "",
              "| side | seconds | speed-up vs TrackEval |", "| --- | ---: | ---: |",
              f"| TrackEval 1.3.0 | {t_te:.3f} | 1.0× |",
              f"| simrig | {t_simrig:.3f} | {t_te / t_simrig:.1f}× |", "",
              f"Largest difference over {', '.join(COMPARED_2D)}: {diff:.1e} "
              f"(HOTA {m_simrig['HOTA']:.4f}, MOTA {m_simrig['MOTA']:.4f}, IDF1 {m_simrig['IDF1']:.4f}).", "",
              f"Target: ≥ 3× faster — {'met' if t_te / t_simrig >= 3 else 'MISSED'}.", ""]

    gt, pred, frames = synthetic_highway(args.boxes, rng)
    lines += [f"## 3D: AMOTA family, one class, {len(gt)} ground-truth boxes ({frames} frames × 40), "
              f"{len(pred)} tracker boxes", ""]
    if devkit_available():
        tracks_gt, tracks_pred = devkit_inputs(gt, pred, frames)
        (t_simrig3, t_devkit), (m3, md) = best_of(args.repeats, lambda: simrig_3d(gt, pred, frames),
                                                  lambda: devkit_3d(tracks_gt, tracks_pred))
        lines += ["| side | seconds | speed-up vs devkit |", "| --- | ---: | ---: |",
                  f"| nuScenes devkit 1.2.0 | {t_devkit:.2f} | 1.0× |",
                  f"| simrig | {t_simrig3:.3f} | {t_devkit / t_simrig3:.0f}× |", "",
                  "| metric | simrig | devkit |", "| --- | ---: | ---: |"]
        lines += [f"| {name} | {m3[name]:.6g} | {md[name]:.6g} |" for name in COMPARED_3D]
        agree = all(abs(m3[name] - md[name]) <= 1e-9 for name in COMPARED_3D)
        lines += ["", f"Values {'agree within 1e-9' if agree else 'DIFFER (see the table)'}."]
    else:
        (t_simrig3,), (m3,) = best_of(args.repeats, lambda: simrig_3d(gt, pred, frames))
        lines += [f"simrig: {t_simrig3:.3f} s (AMOTA {m3['AMOTA']:.4f}). The nuScenes devkit is not installed "
                  "here; see this script's docstring to run it alongside."]
    lines += ["", f"Target: under 2 s — {'met' if t_simrig3 < 2.0 else 'MISSED'} ({t_simrig3:.3f} s).", ""]
    text = "\n".join(lines)
    print(text)
    REPORT.parent.mkdir(parents=True, exist_ok=True)
    REPORT.write_text(text + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
