"""A dataset summarised: the counts ``simrig info`` prints, and its lines (:meth:`simrig.dataset.Dataset.summary`
is the front door)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .arrow_columns import string_codes
from .delivery import capture_arrays

if TYPE_CHECKING:
    from .reader import Dataset


def _timing_summary(dataset: Dataset) -> list[str]:
    """The ``timing`` line of :meth:`summary` for a dataset with capture timing (none otherwise): the spread
    of the capture times, how many detections arrive late or never, the ego-pose error."""
    parts = []
    if dataset.has_table("captures"):
        captures = capture_arrays(dataset)
        c = len(dataset.rig.cameras)
        fired = captures["fired"]
        offset = (captures["capture_time"] - np.repeat(np.arange(dataset.frame_count), c)
                  / float(dataset.scenario["frame_rate_hz"]))[fired]
        detections = dataset.columns("detections", ["frame", "camera"])
        captured = detections.column("frame").to_numpy().astype(np.int64)
        codes = {name: code for code, name in enumerate(dataset.rig.camera_names)}
        when = captures["arrival_frame"][captured * c + string_codes(detections.column("camera"), codes,
                                                                      f"{dataset.path}: detections camera")]
        late = int((when > captured).sum())
        never = int((when >= dataset.frame_count).sum())
        parts.append(f"captures {1000 * offset.min():+.0f} to {1000 * offset.max():+.0f} ms after the tick"
                     f"{'' if fired.all() else f', {int((~fired).sum())} camera-frames without an image'}; "
                     f"{late} of {len(when)} detections late, {never} after the last frame")
    if dataset.has_table("ego_estimates"):
        true, given = dataset.columns("ego_poses"), dataset.columns("ego_estimates")
        error = np.hypot(*(given.column(axis).to_numpy() - true.column(axis).to_numpy() for axis in "xy"))
        parts.append(f"ego pose estimated (position error up to {error.max():.2f} m)")
    return [f"timing    {'; '.join(parts)}"] if parts else []


def summary_counts(dataset: Dataset) -> dict[str, int | float]:
    """What :meth:`summary` reports, as numbers: ``actors`` (distinct), ``actors_per_frame_min``/``_max``/
    ``_mean``, ``truth_rows``, ``projection_rows``, ``in_view_pairs`` (actor-camera pairs in view),
    ``detections``, ``false_positives`` (clutter), ``missed_pairs`` (pairs in view with no detection),
    ``dropped_frames``; and per class the distinct actors under ``class_counts`` (a dict)."""
    truth = dataset.columns("ground_truth", ["frame", "actor_id", "class"])
    ids = truth.column("actor_id").to_numpy()
    class_counts = {}
    unique_ids, first = np.unique(ids, return_index=True)
    if len(truth):
        first_classes = np.asarray(truth.column("class").take(first).to_pylist(), dtype=object)
        names, counts = np.unique(first_classes.astype(str), return_counts=True)
        class_counts = dict(zip(names.tolist(), counts.tolist(), strict=True))
    per_frame = np.bincount(truth.column("frame").to_numpy(), minlength=dataset.frame_count)
    truth_rows = len(truth)
    del truth
    projection_rows, in_view_pairs = 0, 0
    for group in dataset.batches("projections", ["in_view"]):
        projection_rows += len(group)
        in_view_pairs += int(group.column("in_view").to_numpy(zero_copy_only=False).sum())
    clutter, delivered = 0, 0
    for group in dataset.batches("sensor_truth", ["actor_id", "detection"]):
        truth_actor = group.column("actor_id").to_numpy()
        clutter += int(np.sum(truth_actor < 0))
        delivered += int(np.sum((truth_actor >= 0) & (group.column("detection").to_numpy() >= 0)))
    dropped = int(dataset.columns("frames", ["dropped"]).column("dropped").to_numpy(zero_copy_only=False).sum())
    return {
        "actors": len(unique_ids), "class_counts": class_counts,
        "actors_per_frame_min": int(per_frame.min()), "actors_per_frame_max": int(per_frame.max()),
        "actors_per_frame_mean": float(per_frame.mean()), "truth_rows": truth_rows,
        "projection_rows": projection_rows, "in_view_pairs": in_view_pairs,
        "detections": dataset.num_rows("detections"), "false_positives": clutter,
        "missed_pairs": in_view_pairs - delivered, "dropped_frames": dropped,
    }


def summary(dataset: Dataset) -> str:
    """A few readable lines: scenario, seed, frames, actors, rig, rows, events, capture timing."""
    counts = summary_counts(dataset)
    class_counts = counts["class_counts"]
    scenario = dataset.scenario
    event_text = ", ".join(f"{event['event']} at frame {event['frame']}" for event in dataset.manifest["events"])
    lines = [
        f"dataset   {dataset.path}",
        f"scenario  {scenario['name']} ({scenario['traffic']['env']}), seed {dataset.seed}",
        f"frames    {dataset.frame_count} at {scenario['frame_rate_hz']:g} Hz "
        f"({dataset.frame_count / scenario['frame_rate_hz']:.1f} s)",
        f"actors    {counts['actors']} distinct "
        f"({', '.join(f'{k} {v}' for k, v in class_counts.items()) or 'none'}); "
        f"{_span(counts['actors_per_frame_min'], counts['actors_per_frame_max'])} per frame, "
        f"mean {counts['actors_per_frame_mean']:.1f}",
        f"rig       {dataset.rig.name}: {', '.join(dataset.rig.camera_names) or 'no cameras (3D only)'}",
        f"rows      ground_truth {counts['truth_rows']}, projections {counts['projection_rows']} "
        f"({counts['in_view_pairs']} in view)",
        (f"sensor    {counts['detections']} detections ({counts['false_positives']} false positives), "
         f"{counts['missed_pairs']} actor-camera pairs in view missed; {counts['dropped_frames']} frames dropped; "
         f"visibility {dataset.manifest.get('visibility', 'not measured')}") if dataset.source is None
        else "sensor    none (an imported dataset holds ground truth only)",
        f"events    {event_text or 'none'}",
        *_timing_summary(dataset),
    ]
    source = dataset.source
    if source is not None:
        kinds = "3D and 2D" if dataset.has_3d and dataset.has_2d else "3D only" if dataset.has_3d else "2D only"
        lines.append(f"source    imported from {source['format']} ({source['path']}): {kinds}"
                     f" ground truth; rig {'calibrated' if source.get('calibrated_rig') else 'unknown'}; "
                     "no detections, error causes unknown")
    return "\n".join(lines)


def _span(low: int, high: int) -> str:
    """``"39–40"``, or ``"40"`` when both ends are one number."""
    return str(low) if low == high else f"{low}–{high}"
