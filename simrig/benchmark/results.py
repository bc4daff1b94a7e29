"""The bench's files: a fragment per finished (cell, tracker), and the tables assembled from them.

Layout of a bench folder::

    fragments/CELL/TRACKER_KEY.json   one finished tracker on one cell (written atomically)
    results.parquet                   one row per point × tracker (RESULTS columns + param.* + metrics + failure)
    causes.parquet                    errors by cause: one row per point × tracker × dimension × cause × kind
    cameras.parquet                   2D metrics per point × tracker × camera (and the ground truth ignored there)
    timings.parquet                   seconds per cell × tracker (machine-dependent, so kept out of results)
    bench.json                        the suite, its cells' scenarios, and whether the tables are complete

Fragments are the unit of resumption: a rerun skips every (cell, tracker) that has one. The tables are
rebuilt from fragments at the end of a run and written atomically; they are removed when a run starts, so
an interrupted run never leaves tables that look complete. Rows follow the plan's order, never the order in
which cells finished, so every engine writes the same bytes.
"""

from __future__ import annotations

import math
from pathlib import Path

import pyarrow as pa

from simrig.reading import read_json

from ..dataset.manifest import write_json_atomic
from .evaluate import CAMERA_METRICS, METRIC_COLUMNS, Outcome
from .plan import Plan, tracker_key

FRAGMENTS = "fragments"
RESULTS = "results.parquet"
CAUSES = "causes.parquet"
TIMINGS = "timings.parquet"
CAMERAS = "cameras.parquet"
TABLES = (RESULTS, CAUSES, TIMINGS, CAMERAS)
POINT_COLUMNS = ("suite", "scenario", "rig", "sweep", "value", "seed", "frames", "cell", "tracker", "scored")
"""Leading columns of both tables: ``sweep`` is the swept parameter ("" for a scenario's own settings),
``scored`` is ``3d``, ``2d`` (a 2D-only tracker scored over every camera) or the one camera a tracker is
scored on."""
CAMERA_COLUMNS = (*CAMERA_METRICS, "boxes", "ignored")
"""Metric columns of ``cameras.parquet`` (``boxes``: ground truth in view; ``ignored``: of those, ignored)."""
FAILURE = "failure"
"""Last column of the results: why a tracker has no metrics on a cell (``timeout: ...``); null when it ran."""
PARAMETER_PREFIX = "param."
"""``param.NAME``: the cell's value of every parameter the suite sweeps (null where it does not apply)."""


def fragment_path(out: Path, cell: str, key: str) -> Path:
    return out / FRAGMENTS / cell / f"{key}.json"


def write_fragment(out: Path, outcome: Outcome, dataset_s: float) -> None:
    """Record one finished (cell, tracker) atomically."""
    path = fragment_path(out, outcome.cell, outcome.tracker_key)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_json_atomic(path, {
        "cell": outcome.cell, "tracker_key": outcome.tracker_key,
        "metrics": {name: _json_number(value) for name, value in outcome.metrics.items()},
        "causes": [list(row) for row in outcome.causes],
        "failure": outcome.failure,
        "seconds": {name: None if math.isnan(value) else value for name, value in
                    (("dataset", dataset_s), ("tracking", outcome.tracking_s), ("scoring", outcome.scoring_s))},
        "scored": outcome.scored,
        "per_camera": outcome.per_camera,
    })


def _json_number(value: float) -> float | str | None:
    """A metric for a fragment's JSON: null for NaN, ``"inf"``/``"-inf"`` for an infinite value (a least time to
    collision where nothing ever closed in), which JSON has no number for; :func:`_number` reads it back."""
    if math.isnan(value):
        return None
    return value if math.isfinite(value) else ("inf" if value > 0 else "-inf")


def _number(value: float | str | None) -> float | None:
    """A fragment's metric as a number (:func:`_json_number`'s inverse)."""
    if isinstance(value, str):
        if value not in ("inf", "-inf"):
            raise ValueError(f"bench fragment metric {value!r}: not a number, 'inf' or '-inf'")
        return float(value)
    return value


def finished(out: Path) -> set[tuple[str, str]]:
    """Every (cell, tracker key) with a fragment in ``out``."""
    return {(path.parent.name, path.stem) for path in (out / FRAGMENTS).glob("*/*.json")}


def _read(out: Path, cell: str, key: str) -> dict:
    path = fragment_path(out, cell, key)
    try:
        return read_json(path, "bench fragment", ValueError)
    except (OSError, ValueError) as error:
        raise FileNotFoundError(f"bench fragment {str(path)!r} is missing or unreadable: {error}") from None


def assemble(plan: Plan, out: Path) -> dict[str, pa.Table]:
    """The results, causes and timings tables of every point of ``plan`` from the fragments in ``out``."""
    fragments = {(cell, key): _read(out, cell, key) for cell, pairs in plan.work().items() for key, _ in pairs}
    rows, causes, cameras = [], [], []
    for point in plan.points:
        for entry in plan.trackers_of(plan.cells[point.cell][0]):
            fragment = fragments[(point.cell, tracker_key(entry, plan.suite))]
            head = {"suite": plan.suite.name, "scenario": point.scenario, "rig": point.rig, "sweep": point.sweep,
                    "value": point.value, "seed": point.seed, "frames": point.frames, "cell": point.cell,
                    "tracker": entry.name, "scored": fragment.get("scored", entry.camera or "3d")}
            cameras += [head | {"camera": camera} | {name: values.get(name) for name in CAMERA_COLUMNS}
                        for camera, values in fragment.get("per_camera", {}).items()]
            settings = {PARAMETER_PREFIX + name: value for name, value in point.settings}
            rows.append(head | settings | {name: _number(fragment["metrics"].get(name)) for name in METRIC_COLUMNS}
                        | {"failure": fragment.get("failure") or None})
            causes += [head | {"dimension": dim, "cause": cause, "kind": kind, "count": count}
                       for dim, cause, kind, count in fragment["causes"]]
    timings = [{"cell": cell, "tracker": entry.name,
                **{f"{name}_s": value for name, value in fragments[(cell, key)]["seconds"].items()}}
               for cell, pairs in plan.work().items() for key, entry in pairs]
    return {
        RESULTS: pa.Table.from_pylist(rows, schema=_results_schema(plan.parameters)),
        CAUSES: pa.Table.from_pylist(causes, schema=_causes_schema()),
        CAMERAS: pa.Table.from_pylist(cameras, schema=pa.schema(
            _point_fields() + [("camera", pa.string())] + [(name, pa.float64()) for name in CAMERA_COLUMNS])),
        TIMINGS: pa.Table.from_pylist(timings, schema=pa.schema([
            ("cell", pa.string()), ("tracker", pa.string()), ("dataset_s", pa.float64()),
            ("tracking_s", pa.float64()), ("scoring_s", pa.float64())])),
    }


def _point_fields() -> list[tuple[str, pa.DataType]]:
    types = {"value": pa.float64(), "seed": pa.int64(), "frames": pa.int64()}
    return [(name, types.get(name, pa.string())) for name in POINT_COLUMNS]


def _results_schema(parameters: tuple[str, ...]) -> pa.Schema:
    return pa.schema(_point_fields() + [(PARAMETER_PREFIX + name, pa.float64()) for name in parameters]
                     + [(name, pa.float64()) for name in METRIC_COLUMNS] + [(FAILURE, pa.string())])


def _causes_schema() -> pa.Schema:
    return pa.schema(_point_fields() + [("dimension", pa.string()), ("cause", pa.string()),
                                        ("kind", pa.string()), ("count", pa.int64())])

