"""``simrig detector fit``: the detector model's parameters from detections joined to ground truth.

The input is a simrig dataset (its ``sensor_truth`` says which detection came from which actor; only
what a real log also has is used: boxes, scores, which object a detection is, whether it was in view,
occluded, truncated or far — never the sampled causes ``burst``, ``ghost`` or ``duplicate``). Estimators,
each named in the written TOML:

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

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..causes import Cause, cause_masks
from ..dataset import Dataset
from ..errors import SimrigError
from .measure import _STRUCTURAL, consecutive_pairs, depth_errors, lag1, linked_errors

BAND_M = 10.0
_LAGS = 4


@dataclass
class Fit:
    """Fitted ``[sensor]`` tables and one note per parameter (how, or why not)."""

    sensor: dict
    notes: list[str]


def _wrap(angle: np.ndarray) -> np.ndarray:
    return (angle + np.pi) % (2 * np.pi) - np.pi


def sigma_vs_range(errors: np.ndarray, distance: np.ndarray, columns: int = 1) -> tuple[float, float]:
    """(a, b) of σ(d) = a + b·d from per-band standard deviations of ``errors`` (``(R,)`` or ``(R, k)``
    pooled), weighted by the band's count."""
    errors = errors.reshape(len(errors), -1)
    band = np.floor(distance / BAND_M).astype(int)
    centres, sigmas, weights = [], [], []
    for b in np.unique(band):
        rows = band == b
        values = errors[rows].ravel()
        values = values[np.isfinite(values)]
        if len(values) < 30:
            continue
        centres.append(distance[rows].mean())
        sigmas.append(np.sqrt(np.mean(values**2)))
        weights.append(len(values))
    if len(centres) < 2:
        values = errors[np.isfinite(errors)]
        return (float(np.sqrt(np.mean(values**2))) if len(values) else 0.0), 0.0
    design = np.column_stack([np.ones(len(centres)), centres]) * np.sqrt(weights)[:, None]
    a, b = np.linalg.lstsq(design, np.array(sigmas) * np.sqrt(weights), rcond=None)[0]
    return float(a), float(b)


def _tau(rho: float, period: float) -> float:
    return float(-period / np.log(rho)) if 0.0 < rho < 1.0 else 0.0


def fit_dataset(path: Path | str) -> Fit:
    """Fit the detector model of the simrig dataset at ``path``."""
    dataset = Dataset.open(path)
    period = 1.0 / float(dataset.scenario["frame_rate_hz"])
    links = linked_errors(dataset)
    if len(links["frame"]) < 100:
        raise SimrigError(f"{path}: only {len(links['frame'])} detections of actors; too few to fit a detector")
    truth, estimate, centre = links["truth"], links["estimate"], links["centre"]
    ray = truth[:, :3] - centre
    distance = np.linalg.norm(ray, axis=1)
    unit = ray / distance[:, None]
    across = np.cross(np.array([0.0, 0.0, 1.0]), unit)
    across /= np.linalg.norm(across, axis=1, keepdims=True)
    depth = depth_errors(links)
    lateral = np.einsum("ij,ij->i", estimate[:, :3] - truth[:, :3], across)
    size = estimate[:, 3:6] / truth[:, 3:6] - 1.0
    yaw = _wrap(estimate[:, 6] - truth[:, 6])
    flipped = np.abs(yaw) > np.pi / 2
    yaw_gauss = np.where(flipped, np.nan, yaw)
    velocity = estimate[:, 7:9] - truth[:, 7:9]
    notes = []

    depth_a, depth_b = sigma_vs_range(depth, distance)
    fitted, scales = {}, []
    for name, values in (("lateral_sigma_m", lateral), ("size_sigma", size), ("yaw_sigma_deg", np.degrees(yaw_gauss)),
                         ("velocity_sigma_mps", velocity)):
        a, b = sigma_vs_range(values, distance)
        fitted[name] = max(a, 0.0)
        if b > 0 and a > 0:
            scales.append(a / b)
    distance_scale = float(np.median(scales)) if scales else None
    notes.append("box3d σ: RMS per 10 m range band, weighted least squares σ(d) = a + b·d; distance_scale_m = "
                 f"median a/b over lateral, size, yaw, velocity ({', '.join(f'{s:.1f}' for s in scales)} m)")

    a, b = consecutive_pairs(links["frame"], links["camera"], links["actor"])
    depth_normal = depth / (depth_a + depth_b * distance)
    size_sigma = fitted["size_sigma"] * (1.0 + distance / distance_scale if distance_scale else 1.0)
    size_normal = size[:, 0] / size_sigma
    tau = _tau(lag1(depth_normal, a, b), period)
    size_tau = _tau(lag1(size_normal, a, b), period)
    notes.append(f"correlation times: τ = −Δt/ln ρ from {len(a)} consecutive-frame pairs")
    flip_p = float(flipped.mean())
    rho_flip = lag1(flipped.astype(float), a, b)
    flip_duration = period / ((1.0 - rho_flip) * (1.0 - flip_p)) if rho_flip > 0.05 and flip_p > 0 else 0.0
    same = _same_time_pairs(links)
    shared = lag1(depth_normal, *same) if len(same[0]) >= 30 else float("nan")
    if not np.isfinite(shared):
        notes.append("shared_fraction: not identifiable (fewer than 30 actor sightings by two cameras at once)")
    notes.append(f"shared_fraction: correlation of normalised depth errors over {len(same[0])} two-camera sightings")

    detection, burst_note = _fit_misses(dataset, period)
    notes.append(burst_note)
    score = _fit_scores(dataset, links, distance)
    notes.append("score: least squares on [1, q, 1 − exp(−e / 1 m), min(1, d / 60 m)]")
    clutter_rate = _clutter_rate(dataset)
    notes.append("clutter.rate_per_frame: all unmatched detections (clutter, ghosts and duplicates are not "
                 "separable from detections and truth alone)")
    notes.append("not fitted: detection ramps, box2d, embedding, ghosts, duplicates, confusion (defaults)")
    box3d = {"depth_sigma_m": max(depth_a, 0.0), "depth_sigma_per_m": max(depth_b, 0.0), **fitted,
             "yaw_flip_probability": flip_p, "correlation_time_s": tau, "size_correlation_time_s": size_tau,
             "shared_fraction": float(np.clip(shared, 0.0, 1.0)) if np.isfinite(shared) else 0.0,
             "yaw_flip_duration_s": flip_duration}
    if distance_scale:
        box3d["distance_scale_m"] = distance_scale
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
    miss = (sensor.column("detection").to_numpy()[real] < 0)[eligible].astype(float)
    m = float(miss.mean())
    lookup = {(int(k), int(f)): i for i, (k, f) in enumerate(zip(key, frame, strict=True))}
    covariance, counts = [], []
    for lag in range(1, _LAGS + 1):
        pairs = [(i, lookup.get((int(key[i]), int(frame[i]) + lag))) for i in range(len(frame))]
        a = np.array([i for i, j in pairs if j is not None], dtype=np.int64)
        b = np.array([j for _, j in pairs if j is not None], dtype=np.int64)
        covariance.append(float(np.mean((miss[a] - m) * (miss[b] - m))) if len(a) else 0.0)
        counts.append(len(a))
    c = np.array(covariance)
    if c[0] <= 1e-4 or np.any(c <= 0):
        return ({"probability": round(1.0 - m, 6), "burst_fraction": 0.0},
                f"detection: p = 1 − miss rate {m:.3f}; no miss bursts found (lag-1 covariance {c[0]:.2g})")
    lags = np.arange(1, _LAGS + 1)
    slope, intercept = np.polyfit(lags, np.log(c), 1, w=np.sqrt(counts))
    lam, amplitude = float(np.exp(slope)), float(np.exp(intercept))
    if not 0.0 < lam < 1.0:
        return ({"probability": round(1.0 - m, 6), "burst_fraction": 0.0},
                f"detection: miss autocovariance does not decay (λ = {lam:.3f}); bursts not identifiable")
    g = min(1.0, amplitude / (1.0 - m) + (1.0 - m))
    pi = max(0.0, 1.0 - (1.0 - m) / g)
    burst = period / ((1.0 - pi) * (1.0 - lam))
    return ({"probability": round(g, 6), "burst_fraction": round(pi, 6), "burst_mean_s": round(burst, 6)},
            f"detection: Gilbert–Elliott moments on {len(miss)} eligible (actor, camera) frames: miss rate "
            f"{m:.3f}, autocovariance at lags 1–{_LAGS} {', '.join(f'{v:.4f}' for v in c)} (λ = {lam:.3f})")


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
    design = np.column_stack([np.ones(len(error)), quality, 1.0 - np.exp(-error), np.minimum(1.0, distance / 60.0)])
    score = links["score"]
    inside = (score > 0.02) & (score < 0.999)  # clipped scores would bias the fit
    coef = np.linalg.lstsq(design[inside], score[inside], rcond=None)[0]
    residual = score[inside] - design[inside] @ coef
    return {"base": round(float(np.clip(coef[0], 0, 1)), 6), "gain": round(float(np.clip(coef[1], 0, 1)), 6),
            "error_gain": round(float(np.clip(-coef[2], 0, 1)), 6), "error_scale_m": 1.0,
            "distance_gain": round(float(np.clip(-coef[3], 0, 1)), 6), "distance_scale_m": 60.0,
            "sigma": round(float(residual.std()), 6)}


def _clutter_rate(dataset: Dataset) -> float:
    sensor = dataset.table("sensor_truth")
    false = int(np.sum(sensor.column("actor_id").to_numpy() < 0))
    return false / (dataset.frame_count * len(dataset.rig.camera_names))


def fit_to_toml(detections: Path, truth: Path | None, out: Path) -> str:
    """Fit and write ``out`` (a TOML file with a ``[sensor]`` table a scenario can copy); returns a summary."""
    import tomli_w

    if not Path(detections).is_dir():
        raise SimrigError(f"--detections {str(detections)!r}: expected a simrig dataset folder; nuScenes "
                          "detection-results JSON input is not supported yet")
    if truth is not None:
        raise SimrigError("--truth: a simrig dataset carries its own ground truth; leave --truth out")
    fit = fit_dataset(detections)
    header = "".join(f"# {note}\n" for note in [f"fitted by simrig detector fit from {detections}", *fit.notes])
    text = header + tomli_w.dumps({"sensor": fit.sensor})
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text, encoding="utf-8")
    return text + f"\nwritten to {out}"


__all__ = ["Cause", "Fit", "fit_dataset", "fit_to_toml", "sigma_vs_range"]
