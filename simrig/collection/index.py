"""The index table of a collection (``index.parquet``): one row per sequence, for pandas or pyarrow to read.

Columns, in order: ``sequence`` (0-based), ``shard``, ``folder`` (the dataset's folder, relative to the
collection), ``seed`` (the scenario seed), ``scenario`` (the base scenario's name), one column per sampled
parameter (named by its dotted path; a window gives ``PATH.start`` and ``PATH.length``; a choice of tables or
lists, or of mixed types, is written as JSON text), then the dataset's counts: ``frames``, ``frame_rate_hz``,
``actors`` (distinct), ``actors_per_frame_min``/``_max``/``_mean``, ``in_view_pairs`` (actor-camera pairs in
view), ``detections``, ``false_positives``, ``missed_pairs``, ``dropped_frames``, ``events`` (world events:
crashes, ...) and ``ego_crashed``.
"""

from __future__ import annotations

import json
from typing import Any

import pyarrow as pa

from ..dataset import Dataset

COUNT_COLUMNS = ("actors", "actors_per_frame_min", "actors_per_frame_max", "actors_per_frame_mean", "in_view_pairs",
                 "detections", "false_positives", "missed_pairs", "dropped_frames")


def sequence_counts(dataset: Dataset) -> dict[str, Any]:
    """The index's counts of one dataset (plain numbers)."""
    counts = dataset.summary_counts()
    events = dataset.manifest["events"]
    return {
        "frames": dataset.frame_count,
        "frame_rate_hz": float(dataset.scenario["frame_rate_hz"]),
        **{name: counts[name] for name in COUNT_COLUMNS},
        "events": len(events),
        "ego_crashed": any(event["event"] == "ego_crashed" for event in events),
    }


def setting_column(values: list[Any]) -> pa.Array:
    """A sampled parameter's values as one typed column: booleans, integers, floats or strings as they are; a
    column of tables, lists or mixed types as JSON text (keys sorted)."""
    kinds = {type(value) for value in values}
    if kinds <= {bool} or kinds <= {int} or kinds <= {str} or kinds <= {int, float}:
        return pa.array(values, type=pa.float64() if float in kinds else None)
    return pa.array([json.dumps(value, sort_keys=True) for value in values], type=pa.string())


def index_table(rows: list[dict[str, Any]], names: tuple[str, ...]) -> pa.Table:
    """The index of ``rows`` (each: ``sequence``, ``shard``, ``folder``, ``seed``, ``scenario``, ``settings`` by
    parameter name, ``counts``), sorted by sequence; ``names`` orders the parameter columns."""
    rows = sorted(rows, key=lambda row: row["sequence"])
    columns: dict[str, pa.Array] = {
        "sequence": pa.array([row["sequence"] for row in rows], type=pa.int64()),
        "shard": pa.array([row["shard"] for row in rows], type=pa.int64()),
        "folder": pa.array([row["folder"] for row in rows], type=pa.string()),
        "seed": pa.array([row["seed"] for row in rows], type=pa.int64()),
        "scenario": pa.array([row["scenario"] for row in rows], type=pa.string()),
    }
    for name in names:
        columns[name] = setting_column([row["settings"][name] for row in rows])
    for name in rows[0]["counts"] if rows else ():
        columns[name] = pa.array([row["counts"][name] for row in rows])
    return pa.table(columns)
