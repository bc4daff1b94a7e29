"""The estimators ``simrig detector fit`` shares between its inputs (a simrig dataset, a nuScenes log).

Each takes matched (truth, estimate) rows, whatever joined them, and returns ``[sensor]`` keys with a note:

* :func:`box_errors`: the errors of a 3D estimate in the frame of the line of sight from a viewpoint
  ``centre`` (the camera for a dataset, the ego for a log without cameras): depth [m] (range of the estimate
  minus range of the truth), lateral [m] (horizontally across the ray), relative size (length, width,
  height), yaw [rad] (Gaussian part; flips, beyond 90°, apart) and velocity [m/s] (x, y).
* :func:`fit_box3d`: σ of each error per 10 m band of the true range, fitted by weighted least squares with
  σ(d) = a + b·d. Depth keeps (a, b); the others give σ = a and D = a / b, and ``distance_scale_m`` is the
  median D (none when b ≤ 0). Yaw flips: their share is ``yaw_flip_probability``. Correlation times
  τ = −Δt / ln ρ from the lag-1 correlation ρ of the range-normalised depth (size) errors over row pairs one
  period Δt apart; ``yaw_flip_duration_s`` from the flip indicator's lag-1 correlation ρ_f:
  Δt / ((1 − ρ_f)(1 − p_flip)).
* :func:`gilbert_elliott`: misses of a two-state Markov chain with a detection probability p in the good
  state and none in the bad one: the miss indicator's autocovariance is C_k = A·λ^k for k ≥ 1 with λ the
  hidden chain's lag-1 correlation and A = p²·π(1 − π); a weighted fit of log C_k on k = 1…4 gives λ and A;
  with the miss rate m, p = A / (1 − m) + (1 − m), the bad-state share π = 1 − (1 − m) / p and the mean burst
  Δt / ((1 − π)(1 − λ)).
* :func:`fit_scores`: least squares of the score on [1, q, 1 − exp(−e / 1 m), min(1, d / 60 m)] (q the
  visible fraction × (1 − truncation) where known, e the BEV centre error, d the range); σ the residual
  standard deviation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .measure import depth_errors, lag1

BAND_M = 10.0
LAGS = 4


@dataclass
class Fit:
    """Fitted ``[sensor]`` tables and one note per parameter (how, or why not)."""

    sensor: dict
    notes: list[str]


def wrap(angle: np.ndarray) -> np.ndarray:
    """Angles [rad] into [−π, π)."""
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


def _correlation_time(rho: float, period: float) -> float:
    """τ = −Δt / ln ρ [s] of an AR(1) sampled every ``period`` [s] (0 unless 0 < ρ < 1)."""
    return float(-period / np.log(rho)) if 0.0 < rho < 1.0 else 0.0


def box_errors(truth: np.ndarray, estimate: np.ndarray, centre: np.ndarray) -> dict[str, np.ndarray]:
    """Errors of the estimated boxes ``(R, 9)`` against the true ones seen from ``centre`` ``(R, 3)`` (see
    the module docstring): distance, depth, lateral, size ``(R, 3)``, yaw (NaN at flips), flipped,
    velocity ``(R, 2)``."""
    ray = truth[:, :3] - centre
    distance = np.linalg.norm(ray, axis=1)
    unit = ray / distance[:, None]
    across = np.cross(np.array([0.0, 0.0, 1.0]), unit)
    across /= np.linalg.norm(across, axis=1, keepdims=True)
    yaw = wrap(estimate[:, 6] - truth[:, 6])
    flipped = np.abs(yaw) > np.pi / 2
    return {"distance": distance,
            "depth": depth_errors({"estimate": estimate, "truth": truth, "centre": centre}),
            "lateral": np.einsum("ij,ij->i", estimate[:, :3] - truth[:, :3], across),
            "size": estimate[:, 3:6] / truth[:, 3:6] - 1.0,
            "yaw": np.where(flipped, np.nan, yaw), "flipped": flipped,
            "velocity": estimate[:, 7:9] - truth[:, 7:9]}


def fit_box3d(errors: dict[str, np.ndarray], pairs: tuple[np.ndarray, np.ndarray], period: float,
              notes: list[str]) -> tuple[dict, np.ndarray]:
    """The ``[sensor.box3d]`` keys but ``shared_fraction`` from :func:`box_errors`' output, with ``pairs`` the
    row pairs one ``period`` [s] apart of one object (and camera); appends its notes to ``notes``. Also
    returns the range-normalised depth errors."""
    distance = errors["distance"]
    depth_a, depth_b = sigma_vs_range(errors["depth"], distance)
    fitted, scales = {}, []
    for name, values in (("lateral_sigma_m", errors["lateral"]), ("size_sigma", errors["size"]),
                         ("yaw_sigma_deg", np.degrees(errors["yaw"])), ("velocity_sigma_mps", errors["velocity"])):
        a, b = sigma_vs_range(values, distance)
        fitted[name] = max(a, 0.0)
        if b > 0 and a > 0:
            scales.append(a / b)
    distance_scale = float(np.median(scales)) if scales else None
    notes.append("box3d σ: RMS per 10 m range band, weighted least squares σ(d) = a + b·d; distance_scale_m = "
                 f"median a/b over lateral, size, yaw, velocity ({', '.join(f'{s:.1f}' for s in scales)} m)")
    a, b = pairs
    depth_normal = errors["depth"] / (depth_a + depth_b * distance)
    size_sigma = fitted["size_sigma"] * (1.0 + distance / distance_scale if distance_scale else 1.0)
    tau = _correlation_time(lag1(depth_normal, a, b), period)
    size_tau = _correlation_time(lag1(errors["size"][:, 0] / size_sigma, a, b), period)
    notes.append(f"correlation times: τ = −Δt/ln ρ from {len(a)} pairs Δt = {period:.3g} s apart")
    flipped = errors["flipped"]
    flip_p = float(flipped.mean())
    rho_flip = lag1(flipped.astype(float), a, b)
    flip_duration = period / ((1.0 - rho_flip) * (1.0 - flip_p)) if rho_flip > 0.05 and flip_p > 0 else 0.0
    box3d = {"depth_sigma_m": max(depth_a, 0.0), "depth_sigma_per_m": max(depth_b, 0.0), **fitted,
             "yaw_flip_probability": flip_p, "correlation_time_s": tau, "size_correlation_time_s": size_tau,
             "yaw_flip_duration_s": flip_duration}
    if distance_scale:
        box3d["distance_scale_m"] = distance_scale
    return box3d, depth_normal


def gilbert_elliott(key: np.ndarray, frame: np.ndarray, miss: np.ndarray, period: float,
                    what: str) -> tuple[dict, str]:
    """``[sensor.detection]`` probability and burst keys from the misses ``miss`` (bool) at ``frame`` of each
    ``key`` (an object, or an (object, camera) pair), frames ``period`` [s] apart; ``what`` names the rows in
    the note."""
    miss = miss.astype(float)
    m = float(miss.mean())
    lookup = {(int(k), int(f)): i for i, (k, f) in enumerate(zip(key, frame, strict=True))}
    covariance, counts = [], []
    for lag in range(1, LAGS + 1):
        pairs = [(i, lookup.get((int(key[i]), int(frame[i]) + lag))) for i in range(len(frame))]
        a = np.array([i for i, j in pairs if j is not None], dtype=np.int64)
        b = np.array([j for _, j in pairs if j is not None], dtype=np.int64)
        covariance.append(float(np.mean((miss[a] - m) * (miss[b] - m))) if len(a) else 0.0)
        counts.append(len(a))
    c = np.array(covariance)
    if c[0] <= 1e-4 or np.any(c <= 0):
        return ({"probability": round(1.0 - m, 6), "burst_fraction": 0.0},
                f"detection: p = 1 − miss rate {m:.3f} on {len(miss)} {what}; no miss bursts found (lag-1 "
                f"covariance {c[0]:.2g})")
    lags = np.arange(1, LAGS + 1)
    slope, intercept = np.polyfit(lags, np.log(c), 1, w=np.sqrt(counts))
    lam, amplitude = float(np.exp(slope)), float(np.exp(intercept))
    if not 0.0 < lam < 1.0:
        return ({"probability": round(1.0 - m, 6), "burst_fraction": 0.0},
                f"detection: miss autocovariance does not decay (λ = {lam:.3f}); bursts not identifiable")
    g = min(1.0, amplitude / (1.0 - m) + (1.0 - m))
    pi = max(0.0, 1.0 - (1.0 - m) / g)
    burst = period / ((1.0 - pi) * (1.0 - lam))
    return ({"probability": round(g, 6), "burst_fraction": round(pi, 6), "burst_mean_s": round(burst, 6)},
            f"detection: Gilbert–Elliott moments on {len(miss)} {what}: miss rate {m:.3f}, autocovariance at lags "
            f"1–{LAGS} {', '.join(f'{v:.4f}' for v in c)} (λ = {lam:.3f})")


def fit_scores(score: np.ndarray, error: np.ndarray, distance: np.ndarray, quality: np.ndarray | None) -> dict:
    """``[sensor.score]`` keys from matched detections' scores, BEV centre errors [m], ranges [m] and
    qualities q (``None`` when unknown: then ``gain`` is 0 and ``base`` the fitted intercept)."""
    columns = [np.ones(len(error)), *(() if quality is None else (quality,)), 1.0 - np.exp(-error),
               np.minimum(1.0, distance / 60.0)]
    design = np.column_stack(columns)
    inside = (score > 0.02) & (score < 0.999)  # clipped scores would bias the fit
    coef = np.linalg.lstsq(design[inside], score[inside], rcond=None)[0]
    residual = score[inside] - design[inside] @ coef
    gain = 0.0 if quality is None else coef[1]
    return {"base": round(float(np.clip(coef[0], 0, 1)), 6), "gain": round(float(np.clip(gain, 0, 1)), 6),
            "error_gain": round(float(np.clip(-coef[-2], 0, 1)), 6), "error_scale_m": 1.0,
            "distance_gain": round(float(np.clip(-coef[-1], 0, 1)), 6), "distance_scale_m": 60.0,
            "sigma": round(float(residual.std()), 6)}
