"""The suite's worst cell for its first tracker, looked at closely: a bird's-eye plot of the whole sequence
with the identity switches marked, a camera mosaic at the first switch, and the list of switches.

The worst cell is the one where the first tracker switches identities most (ties: lower HOTA, then the cell
key). Its dataset comes from the bench's cache, or is generated again; the tracker is run again on it (same
dataset and seed: the same tracks), and the rerun must reproduce the results table's numbers.
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import pyarrow.parquet as pq

from simrig.dataset.tracks_file import TRACKS3D_FILE
from simrig.figures.birds_eye import plot_bev
from simrig.figures.mosaic import render_mosaic
from simrig.pipeline.cache import cached_dataset
from simrig.pipeline.track import run_tracker
from simrig.scenarios.schema import scenario_from_record

from ..dataset import Dataset
from ..errors import DatasetError
from ..scoring import score
from .groups import group_of
from .load import BenchResults, ReportError


@dataclass(frozen=True)
class WorstCell:
    """The chosen cell, its results row, the IDS rows of the rerun and the figures written."""

    row: dict
    switches: list[dict]
    bev: Path
    mosaic: Path
    mosaic_frame: int


def choose(bench: BenchResults) -> tuple[dict, dict]:
    """(results row, tracker entry) of the worst cell for the suite's first tracker."""
    entry = bench.trackers[0]
    rows = bench.unique_cells(bench.results[bench.results["tracker"] == entry["name"]])
    if not len(rows):
        raise ReportError(f"results.parquet holds no row of the suite's first tracker {entry['name']!r}")
    group = group_of(rows["scored"].iloc[0])
    rows = rows[rows[group.switches].notna()]  # a cell where the tracker failed (timed out) has no count
    if not len(rows):
        raise ReportError(f"{entry['name']!r} has no identity-switch count in any cell (it failed everywhere)")
    rows = rows.assign(_hota=rows["2d_HOTA"].fillna(math.inf))
    ordered = rows.sort_values([group.switches, "_hota", "cell"], ascending=[False, True, True], kind="stable")
    return ordered.iloc[0].drop("_hota").to_dict(), entry


def _dataset(bench: BenchResults, cell: str, scratch: Path) -> Dataset:
    cache = Path(bench.description["cache"]) / cell
    try:
        return Dataset.open(cache)
    except DatasetError:
        spec = bench.description["cells"][cell]
        scenario = scenario_from_record(spec["scenario"])  # a resolved dump holds keys a file may not set
        return cached_dataset(scenario, spec["seed"], spec["frames"], scratch)


def inspect_worst(bench: BenchResults, out: Path) -> WorstCell:
    """Choose the worst cell, rerun its first tracker, and write ``worst-bev.png`` and ``worst-mosaic.png``
    into ``out``."""
    row, entry = choose(bench)
    group = group_of(row["scored"])
    with tempfile.TemporaryDirectory(prefix="simrig-report-") as scratch:
        dataset = _dataset(bench, row["cell"], Path(scratch))
        run = run_tracker(dataset, entry["tracker"], Path(scratch) / "tracks", dict(entry.get("params") or {}),
                          seed=int(row["seed"]))
        report = score(dataset, run.tracks, camera=entry.get("camera"))
        errors = report.errors.to_pandas()
        switches = errors[(errors["kind"] == "IDS") & (errors["dimension"] == group.dimension)]
        if len(switches) != int(row[group.switches]):
            raise ReportError(f"cell {row['cell']}: rerunning {entry['name']} gave {len(switches)} identity "
                              f"switches, the results table says {int(row[group.switches])}; the bench folder "
                              "does not match this simrig (rerun the bench)")
        tracks_file = run.out / TRACKS3D_FILE
        tracks3d = pq.read_table(tracks_file) if tracks_file.exists() else None
        switches = switches.sort_values(["frame", "actor_id"], kind="stable")
        numbered = [(int(frame), int(actor)) for frame, actor in zip(switches["frame"], switches["actor_id"],
                                                                     strict=True)]
        title = (f"{row['scenario']} seed {row['seed']}" + (f", {row['sweep']} = {row['value']:g}" if row["sweep"]
                 else "") + f": {entry['name']}, {len(switches)} identity switches")
        bev = plot_bev(dataset, tracks3d, numbered, title, out / "worst-bev.png")
        frame = int(switches["frame"].min()) if len(switches) else dataset.frame_count // 2
        mosaic = render_mosaic(dataset.path, frame, out / "worst-mosaic.png", tracks=run.out)
    listed = switches[["frame", "camera", "class", "actor_id", "previous_track_id", "track_id", "causes"]]
    return WorstCell(row, listed.to_dict("records"), bev, mosaic, frame)
