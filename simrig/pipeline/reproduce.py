"""Whether a dataset's manifest tells the truth about what made it: the scenario and seed it records, generated
again for the first frames, give the dataset's own first frames.

A manifest's SHA-256 guards its files against damage, not against an edit that re-hashes them: one that names
another seed passes every hash. Generation is deterministic (same scenario and seed, same bytes), so regenerating
the opening frames — the traffic's spawn, the ego's pose, every actor's box — tells a seed or scenario that did
not make the dataset, at the cost of one short generation (a second or two). ``simrig info --verify`` runs it.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import pyarrow as pa
import pyarrow.compute as pc

from simrig.scenarios import ScenarioError
from simrig.scenarios.schema import scenario_from_record
from simrig.scenarios.timing_schema import latency_beyond

from ..dataset import Dataset
from ..errors import DatasetError
from .generate import generate

COMPARED = ("ego_poses", "ground_truth")
"""The tables whose opening rows must match: where the ego is and every actor's box (the seed's traffic)."""


def check_reproduces(dataset: Dataset) -> str | None:
    """``None`` when the scenario and seed the manifest of ``dataset`` records regenerate its opening frames
    byte for byte; a :class:`DatasetError` naming the table and frame otherwise. Returns a note instead for a
    dataset simrig did not generate (an import) or one whose opening frames a regeneration cannot make alone (a
    closed-loop drive: the ego there drives on a tracker's perception)."""
    if dataset.source is not None:
        return "not regenerated: an imported dataset records no simrig generation"
    if "drive" in dataset.manifest:
        return "not regenerated: a closed-loop drive's world depends on the tracker that drove it"
    where = f"dataset {str(dataset.path)!r}"
    scenario = scenario_from_record(dataset.scenario, where)
    frames = _opening_frames(scenario, dataset.frame_count)
    with tempfile.TemporaryDirectory(prefix="simrig-reproduce-") as folder:
        try:
            made = Dataset.open(generate(scenario, seed=dataset.seed, out=Path(folder) / "opening",
                                         frames=frames).path)
        except ScenarioError as error:
            raise DatasetError(f"{where}: its manifest's scenario cannot be generated again ({error})") from None
        for table in COMPARED:
            mine, again = _opening(dataset, table, frames), _opening(made, table, frames)
            if not mine.equals(again):
                frame = _first_difference(mine, again)
                raise DatasetError(
                    f"{where}: scenario {scenario.name!r} with seed {dataset.seed} does not give its {table} at "
                    f"frame {frame}: the manifest does not describe what made this dataset (edited and re-hashed?)")
    return None


def _opening_frames(scenario, frames: int) -> int:
    """The fewest frames (1, 2, 4, … up to the dataset's) that the scenario's detection latency lets generate."""
    count = 1
    while count < frames and latency_beyond(scenario, count):
        count *= 2
    return min(count, frames)


def _opening(dataset: Dataset, table: str, frames: int) -> pa.Table:
    """The rows of ``table`` in the first ``frames`` frames."""
    rows = dataset.columns(table)
    return rows.filter(pc.less(rows.column("frame"), frames))


def _first_difference(mine: pa.Table, again: pa.Table) -> int:
    """The first frame at which two tables' rows differ."""
    for frame in sorted(set(mine.column("frame").to_pylist()) | set(again.column("frame").to_pylist())):
        if not mine.filter(pc.equal(mine.column("frame"), frame)).equals(
                again.filter(pc.equal(again.column("frame"), frame))):
            return frame
    return 0
