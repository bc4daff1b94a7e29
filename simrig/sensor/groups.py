"""Cause groups: the switches of the detector model that a counterfactual run turns off.

A group names one kind of imperfection of the detector. Removing it makes that effect perfect while every
effect keeps drawing exactly the numbers it draws with the group on (each effect has its own random stream
and draws a fixed count per actor, camera and frame), so the other groups' draws stay bit-identical — the
common random numbers the explainer (:mod:`simrig.explain`) relies on.

================== ==========================================================================================
group              removing it
================== ==========================================================================================
``occlusion``      the rendered occlusion: every actor in view is seen as fully visible (probability, score,
                   embedding noise), before any scheduled occlusion
``truncation``     the image border's cut: every actor in view is seen as untruncated
``far_range``      the detector's range falloff: p no longer drops between ``full_range_m`` and ``max_range_m``
``random_misses``  p_max becomes 1 and the Gilbert–Elliott miss bursts never start
``localisation``   2D box noise and the monocular 3D error (position, size, yaw, flips, velocity) become 0
``false_positives`` clutter and ghosts are drawn but not reported
``confusion``      every label is the true class
``reid``           the embedding is the actor's noise-free appearance
``duplicates``     same-camera duplicate boxes (failed NMS) are drawn but not reported
``cross_camera``   an actor detected by several cameras is reported by the best one only (largest visible
                   fraction × (1 − truncation), then largest true box, then rig order) — an imperfection only
                   for a tracker scored in 3D: scored per camera in 2D, each camera's ground truth holds the
                   actor, so the other cameras' detections are not duplicates there
``trigger``        every camera fires at the frame's tick and reports its true time (no trigger offsets,
                   jitter or clock skew: :mod:`.capture`)
``latency``        every detection reaches the tracker in its own frame
``ego_pose``       the tracker is given the true ego pose (and the detections are placed with it)
``KIND#I``         scheduled sensor perturbation ``I`` of the scenario (e.g. ``occlude#0``) is not applied
================== ==========================================================================================
"""

from __future__ import annotations

from simrig.scenarios import Scenario
from simrig.scenarios.perturbation_schema import WORLD_KINDS
from simrig.scenarios.timing_schema import TIMING_TABLES, timing_tables_set

from .capture import TIMING_GROUPS

DETECTOR_GROUPS: tuple[str, ...] = ("occlusion", "truncation", "far_range", "random_misses", "localisation",
                                    "false_positives", "confusion", "reid", "duplicates", "cross_camera")
"""The detector's own cause groups, in reporting order (scheduled windows follow them)."""


def _window_groups(scenario: Scenario) -> tuple[str, ...]:
    """One group per scheduled sensor perturbation, named ``KIND#INDEX`` (its index in ``perturbations``,
    the name its events carry in a dataset's frames table)."""
    return tuple(f"{config.kind}#{index}" for index, config in enumerate(scenario.perturbations)
                 if config.kind not in WORLD_KINDS)


def _timing_groups(scenario: Scenario) -> tuple[str, ...]:
    """The capture-timing groups whose table ``scenario`` sets (an ideal rig has none to remove)."""
    set_tables = timing_tables_set(scenario.sensor)
    return tuple(group for group, table in zip(TIMING_GROUPS, TIMING_TABLES, strict=True) if table in set_tables)


def all_groups(scenario: Scenario) -> tuple[str, ...]:
    """Every group that can be removed from ``scenario``'s detector (present or not); the capture-timing groups
    only where the scenario sets them."""
    return DETECTOR_GROUPS + _timing_groups(scenario) + _window_groups(scenario)


def present_groups(scenario: Scenario, camera_count: int, scored_in_3d: bool = True) -> tuple[str, ...]:
    """The groups that are imperfections of ``scenario``'s detector (a rig of ``camera_count`` cameras, for a
    tracker scored in 3D or, ``scored_in_3d`` false, per camera in 2D); the others change nothing and their
    Shapley share is exactly 0 without running anything."""
    s = scenario.sensor
    d, b3 = s.detection, s.box3d
    present = {
        "occlusion": scenario.render.visibility,
        "truncation": True,
        "far_range": True,
        "random_misses": d.probability < 1.0 or d.burst_fraction > 0,
        "localisation": s.box2d.relative_sigma > 0 or any(
            value > 0 for value in (b3.depth_sigma_m, b3.depth_sigma_per_m, b3.lateral_sigma_m, b3.size_sigma,
                                    b3.yaw_sigma_deg, b3.yaw_flip_probability, b3.velocity_sigma_mps)),
        "false_positives": s.clutter.rate_per_frame > 0 or s.ghosts.birth_rate_hz > 0,
        "confusion": any(row.get(true, 0.0) < sum(row.values()) for true, row in s.confusion.matrix.items()),
        "reid": s.embedding.sigma > 0 or s.embedding.target_auc is not None or s.embedding.occlusion_sigma > 0
                or s.embedding.truncation_sigma > 0 or s.embedding.drift_sigma > 0 or s.embedding.slow_drift_sigma > 0,
        "duplicates": s.duplicates.probability > 0,
        "cross_camera": camera_count > 1 and scored_in_3d,
    }
    return tuple(name for name in DETECTOR_GROUPS if present[name]) + _timing_groups(scenario) + _window_groups(
        scenario)


def check_groups(names, scenario: Scenario) -> frozenset[str]:
    """``names`` as a frozenset, or a ``ValueError`` naming the first unknown group and the known ones."""
    known = all_groups(scenario)
    for name in names:
        if name not in known:
            raise ValueError(f"unknown cause group {name!r}; {scenario.name!r} has: {', '.join(known)}")
    return frozenset(names)
