"""Detector presets: named ``[sensor]`` tables a scenario picks with ``[sensor] preset = "…"`` and overrides
key by key. Each realistic preset was calibrated with ``simrig detector measure`` on generated
``highway_surround6`` datasets against the published nuScenes-val true-positive errors of its detector
family (reports/fidelity/presets.md gives the commands and the measured values):

* ``monodis``, ``centernet``, ``km3d`` — mATE / mASE / mAOE / mAVE of MonoDIS, CenterNet and KM3D in Table 1
  of the SAGA-Track paper.
* ``bevformer_small`` — mATE 0.721 m, mAOE 0.407 rad, mAVE 0.436 m/s from the RoboBEV benchmark
  (``docs/results/BEVFormer-Small.md``); its mASE 0.279 is RoboBEV's clean-set value in the same table.
* ``ideal_noise`` — simrig's original detector model (white noise, no ghosts): the defaults.
* ``perfect`` — exact boxes, velocities and identities for every object the visibility and range rules let
  a camera see; no misses by chance, no false positives.

The realistic presets share the temporal structure (correlation times, miss bursts, persistent flips,
ghosts, duplicates, confusion, re-ID AUC) from the sources in the README's "Detector model" section; only
the error magnitudes are fitted per family.
"""

from __future__ import annotations

import json
from typing import Any

from .merge import merge

_NO_NOISE = {"depth_sigma_m": 0.0, "depth_sigma_per_m": 0.0, "lateral_sigma_m": 0.0, "size_sigma": 0.0,
             "yaw_sigma_deg": 0.0, "yaw_flip_probability": 0.0, "velocity_sigma_mps": 0.0}


REID_FASTREID_MOT17: dict[str, Any] = {
    "dimension": 12, "sigma": 0.445, "drift_sigma": 0.635, "drift_time_s": 0.73, "slow_drift_sigma": 0.68,
    "slow_drift_time_s": 10.8, "occlusion_sigma": 0.5, "truncation_sigma": 0.3, "distance_scale_m": 100.0,
    "lookalike_weight": 0.3, "viewpoint_weight": 0.15,
}
"""The realistic presets' re-ID: distances by frame gap like FastReID SBS50's on MOT17 val (pedestrians; the
source and the check are in :mod:`simrig.detector.reid`), calibrated on the catalog's worlds at 10 Hz by
``tests/calibration/reid_preset.py`` (reports/fidelity/reid.md)."""


def _camera_detector(depth_per_m: float, lateral: float, size: float, yaw_deg: float, flip: float,
                     velocity: float, recall: float) -> dict[str, Any]:
    """A realistic camera detector's tables with the fitted error magnitudes."""
    return {
        "detection": {"probability": recall, "burst_fraction": 0.08, "burst_mean_s": 0.6, "full_range_m": 40.0,
                      "max_range_m": 80.0},
        "box2d": {"relative_sigma": 0.05},
        "box3d": {"depth_sigma_m": 0.15, "depth_sigma_per_m": depth_per_m, "lateral_sigma_m": lateral,
                  "size_sigma": size, "yaw_sigma_deg": yaw_deg, "yaw_flip_probability": flip,
                  "velocity_sigma_mps": velocity, "distance_scale_m": 40.0, "correlation_time_s": 0.8,
                  "size_correlation_time_s": 2.0, "shared_fraction": 0.3, "yaw_flip_duration_s": 0.4},
        "score": {"base": 0.35, "gain": 0.55, "sigma": 0.08, "error_gain": 0.25, "error_scale_m": 1.0,
                  "distance_gain": 0.15, "distance_scale_m": 60.0},
        "clutter": {"rate_per_frame": 0.3, "score_range": [0.05, 0.6]},
        "embedding": REID_FASTREID_MOT17,
        "ghosts": {"birth_rate_hz": 0.5, "mean_life_s": 1.0, "shadow_fraction": 0.5, "score_mean": 0.45,
                   "score_concentration": 8.0},
        "duplicates": {"probability": 0.03},
        "confusion": {"matrix": {"car": {"car": 0.96, "truck": 0.03, "bus": 0.01},
                                 "truck": {"truck": 0.85, "car": 0.08, "bus": 0.07},
                                 "bus": {"bus": 0.85, "truck": 0.12, "car": 0.03},
                                 "motorcycle": {"motorcycle": 0.97, "car": 0.03}}},
    }


PRESETS: dict[str, dict[str, Any]] = {
    "perfect": {
        "detection": {"probability": 1.0},
        "box2d": {"relative_sigma": 0.0},
        "box3d": _NO_NOISE,
        "score": {"base": 1.0, "gain": 0.0, "sigma": 0.0},
        "clutter": {"rate_per_frame": 0.0},
        "embedding": {"sigma": 0.0, "occlusion_sigma": 0.0},
    },
    "ideal_noise": {},
    "monodis": _camera_detector(0.0426, 0.319, 0.0896, 22.6, 0.05, 0.706, 0.85),
    "centernet": _camera_detector(0.0381, 0.288, 0.0870, 23.1, 0.055, 0.737, 0.85),
    "km3d": _camera_detector(0.0412, 0.307, 0.0992, 18.3, 0.045, 0.741, 0.85),
    "bevformer_small": _camera_detector(0.0380, 0.288, 0.0933, 16.3, 0.03, 0.224, 0.9),
}
"""Preset name → its ``[sensor]`` tables (values the scenario does not set)."""


def _merge_tables(base: dict[str, Any], override: dict[str, Any]) -> dict[str, Any]:
    """``override`` on top of ``base``, tables merged key by key (the scenario loader's rule). ``base`` is taken as
    a file would give it (pairs as lists): scenarios are validated strictly with JSON's rules, where a tuple is
    not an array."""
    return merge(json.loads(json.dumps(base)), override)


def with_preset(raw: dict[str, Any]) -> dict[str, Any]:
    """A scenario's raw table (as read from a file) with its ``[sensor] preset`` laid under its own sensor keys,
    so the scenario's keys override the preset's key by key. Done on the raw table, before validation: the
    schema validates files strictly with JSON's rules, and a validator that rewrites a table would hand the
    strict validation Python values instead. An unknown preset is left for the schema to report."""
    sensor = raw.get("sensor")
    if not isinstance(sensor, dict) or not isinstance(sensor.get("preset"), str) or sensor["preset"] not in PRESETS:
        return raw
    merged = _merge_tables(PRESETS[sensor["preset"]], sensor)
    rows = sensor.get("confusion", {}).get("matrix") if isinstance(sensor.get("confusion"), dict) else None
    if isinstance(rows, dict) and isinstance(merged.get("confusion", {}).get("matrix"), dict):
        # a row of the confusion matrix is one distribution: the scenario's row replaces the preset's whole
        # (merged key by key, a row {car = 0.8, truck = 0.2} would keep the preset's bus share and not sum to 1)
        merged["confusion"]["matrix"].update(rows)
    return {**raw, "sensor": merged}
