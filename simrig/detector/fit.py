"""``simrig detector fit``: the detector model's parameters from detections joined to ground truth.

The input is a simrig dataset (its ``sensor_truth`` says which detection came from which actor; only
what a real log also has is used: boxes, scores, which object a detection is, whether it was in view,
occluded, truncated or far — never the sampled causes ``burst``, ``ghost`` or ``duplicate``), or a nuScenes
detection-results JSON with nuScenes ground truth (:mod:`.fit_nuscenes`, which :func:`fit_to_toml` hands it
to). The estimators (:mod:`.estimators`, shared by both), each named in the written TOML:

* σ of depth, lateral, size, yaw and velocity errors: the standard deviation per 10 m band of the true
  range from the camera, fitted by weighted least squares with σ(d) = a + b·d. Depth keeps (a, b); the
  others give σ = a and D = a / b, and ``distance_scale_m`` is the median D (none when b ≤ 0).
* Yaw flips: errors beyond 90° (their share is ``yaw_flip_probability``); the Gaussian yaw σ uses the rest.
* ``correlation_time_s``, ``size_correlation_time_s``: τ = −Δt / ln ρ from the lag-1 correlation ρ of the
  range-normalised depth (size) errors of one (actor, camera) over consecutive frames.
* ``shared_fraction``: the correlation of normalised depth errors of one actor seen by two cameras at once.
* ``yaw_flip_duration_s``: from the flip indicator's lag-1 correlation ρ_f: Δt / ((1 − ρ_f)(1 − p_flip)).
* Misses (Gilbert–Elliott with a detection probability p in the good state), on (actor, camera) frames with
  nothing structural against detection: the miss indicator's autocovariance is C_k = A·λ^k for k ≥ 1 with
  λ the hidden chain's lag-1 correlation and A = p²·π(1 − π); a weighted fit of log C_k on k = 1…4 gives
  λ and A; with the miss rate m, p = A / (1 − m) + (1 − m), the bad-state share π = 1 − (1 − m) / p and the
  mean burst Δt / ((1 − π)(1 − λ)).
* Scores: least squares of the score on [1, q, 1 − exp(−e / 1 m), min(1, d / 60 m)] (q = visible fraction ×
  (1 − truncation), e the BEV centre error); σ the residual standard deviation.
* ``clutter.rate_per_frame``: unmatched detections per camera and frame (clutter, ghosts and duplicates
  cannot be told apart from detections and truth alone, so all count as clutter).

Not fitted (kept at the defaults, listed in the file): the visibility, truncation and range ramps, 2D box
noise, embeddings, ghosts, duplicates and class confusion.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..causes import Cause, cause_masks
from ..dataset import Dataset
from ..dataset.outputs import write_text_atomic
from ..errors import SimrigError
from .estimators import Fit, box_errors, fit_box3d, fit_scores, gilbert_elliott, sigma_vs_range
from .measure import _STRUCTURAL, consecutive_pairs, lag1, linked_errors


def fit_dataset(path: Path | str) -> Fit:
    """Fit the detector model of the simrig dataset at ``path``."""
    dataset = Dataset.open(path)
    period = 1.0 / float(dataset.scenario["frame_rate_hz"])
    links = linked_errors(dataset)
    if len(links["frame"]) < 100:
        raise SimrigError(f"{path}: only {len(links['frame'])} detections of actors; too few to fit a detector")
    errors = box_errors(links["truth"], links["estimate"], links["centre"])
    distance = errors["distance"]
    notes = []
    pairs = consecutive_pairs(links["frame"], links["camera"], links["actor"])
    box3d, depth_normal = fit_box3d(errors, pairs, period, notes)
    same = _same_time_pairs(links)
    shared = lag1(depth_normal, *same) if len(same[0]) >= 30 else float("nan")
    if np.isfinite(shared):
        notes.append(f"shared_fraction: correlation of normalised depth errors over {len(same[0])} two-camera "
                     "sightings")
    else:
        notes.append(f"shared_fraction: not identifiable ({len(same[0])} actor sightings by two cameras at once, "
                     "fewer than 30); written as 0")
    box3d["shared_fraction"] = float(np.clip(shared, 0.0, 1.0)) if np.isfinite(shared) else 0.0

    detection, burst_note = _fit_misses(dataset, period)
    notes.append(burst_note)
    score = _fit_scores(dataset, links, distance)
    notes.append("score: least squares on [1, q, 1 − exp(−e / 1 m), min(1, d / 60 m)]")
    clutter_rate = _clutter_rate(dataset)
    notes.append("clutter.rate_per_frame: all unmatched detections (clutter, ghosts and duplicates are not "
                 "separable from detections and truth alone)")
    notes.append("not fitted: detection ramps, box2d, embedding, ghosts, duplicates, confusion (defaults)")
    sensor = {"detection": detection, "box3d": {k: round(float(v), 6) for k, v in box3d.items()},
              "score": score, "clutter": {"rate_per_frame": round(clutter_rate, 6)}}
    return Fit(sensor, notes)


def _same_time_pairs(links: dict) -> tuple[np.ndarray, np.ndarray]:
    """Row pairs of one actor at one frame seen by two cameras (first two cameras in rig order)."""
    order = np.lexsort((links["camera"], links["actor"], links["frame"]))
    f, act = links["frame"][order], links["actor"][order]
    same = (f[1:] == f[:-1]) & (act[1:] == act[:-1])
    return order[:-1][same], order[1:][same]


def _fit_misses(dataset: Dataset, period: float) -> tuple[dict, str]:
    sensor = dataset.table("sensor_truth")
    actor = sensor.column("actor_id").to_numpy()
    real = actor >= 0
    causes = cause_masks(sensor.column("causes").filter(real).to_pylist())
    eligible = (causes & _STRUCTURAL) == 0
    cameras = {name: i for i, name in enumerate(dataset.rig.camera_names)}
    camera = np.array([cameras[n] for n in np.asarray(sensor.column("camera").to_pylist())[real]])
    frame = sensor.column("frame").to_numpy()[real][eligible]
    key = (actor[real] * 64 + camera)[eligible]
    miss = (sensor.column("detection").to_numpy()[real] < 0)[eligible]
    return gilbert_elliott(key, frame, miss, period, "eligible (actor, camera) frames")


def _fit_scores(dataset: Dataset, links: dict, distance: np.ndarray) -> dict:
    projections, visibility = dataset.table("projections"), dataset.table("visibility")
    cameras = dataset.rig.camera_names
    c = len(cameras)
    truth = dataset.table("ground_truth")
    t_frame, t_actor = truth.column("frame").to_numpy(), truth.column("actor_id").to_numpy()
    key = t_frame.astype(np.int64) * (1 << 32) + t_actor
    order = np.argsort(key)
    row = order[np.searchsorted(key[order], links["frame"].astype(np.int64) * (1 << 32) + links["actor"])]
    occlusion = visibility.column("occlusion").to_numpy().reshape(-1, c)[row, links["camera"]]
    truncation = projections.column("truncation").to_numpy().reshape(-1, c)[row, links["camera"]]
    quality = np.nan_to_num(1.0 - occlusion, nan=1.0) * (1.0 - np.nan_to_num(truncation, nan=1.0))
    error = np.hypot(*(links["estimate"][:, :2] - links["truth"][:, :2]).T)
    return fit_scores(links["score"], error, distance, quality)


def _clutter_rate(dataset: Dataset) -> float:
    sensor = dataset.table("sensor_truth")
    false = int(np.sum(sensor.column("actor_id").to_numpy() < 0))
    return false / (dataset.frame_count * len(dataset.rig.camera_names))


def fit_to_toml(detections: Path, truth: Path | None, out: Path, cameras: int | None = None) -> str:
    """Fit and write ``out`` (a TOML file with a ``[sensor]`` table a scenario can copy); returns a summary.
    ``detections``: a simrig dataset folder (its own ground truth; no ``truth``), or a nuScenes detection-results
    JSON with ``truth`` the nuScenes tables or a simrig dataset (:mod:`.fit_nuscenes`; ``cameras`` divides its
    per-sample clutter rate, 6 when ``None``)."""
    import tomli_w

    detections = Path(detections)
    if detections.is_dir():
        if truth is not None:
            raise SimrigError("--truth: a simrig dataset carries its own ground truth; leave --truth out")
        if cameras is not None:
            raise SimrigError("--cameras: only for a nuScenes detection-results JSON (a simrig dataset has its rig)")
        fit = fit_dataset(detections)
    elif detections.is_file():
        from .fit_nuscenes import NUSCENES_CAMERAS, fit_nuscenes

        if truth is None:
            raise SimrigError(f"--truth: {str(detections)!r} is a detection-results JSON; give its ground truth (the "
                              "nuScenes tables folder or a simrig dataset)")
        fit = fit_nuscenes(detections, Path(truth), NUSCENES_CAMERAS if cameras is None else cameras)
    else:
        raise SimrigError(f"--detections {str(detections)!r}: no such file or folder (a simrig dataset folder or a "
                          "nuScenes detection-results JSON)")
    source = f"{detections}" + (f" against {truth}" if truth is not None else "")
    header = "".join(f"# {note}\n" for note in [f"fitted by simrig detector fit from {source}", *fit.notes])
    text = header + tomli_w.dumps({"sensor": fit.sensor})
    out.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out, text)
    return text + f"\nwritten to {out}"


__all__ = ["Cause", "Fit", "fit_dataset", "fit_to_toml", "sigma_vs_range"]
