"""The sequences of a collection: each one's settings, scenario seed and folder, and the worker that makes one.

Folders are sharded, ``shards/SSSS/NNNNNN`` (shard ``index // shard_size``, sequence index zero-padded), so no
folder holds more than ``shard_size`` datasets. A sequence's dataset depends on its scenario and seed alone: the
same bytes whichever worker, engine or run makes it, and a finished one is kept when a collection resumes.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from simrig.scenarios import Scenario
from simrig.scenarios.space_file import Candidate

from ..dataset import Dataset
from ..dataset.outputs import check_no_links
from ..errors import DatasetError
from ..pipeline.generate import generate
from .index import sequence_counts

SHARDS_FOLDER = "shards"


@dataclass(frozen=True)
class SequenceTask:
    """One sequence to make: its 0-based ``index``, ``shard``, ``folder`` (relative to the collection), scenario
    ``seed``, sampled ``candidate`` and the ``scenario`` it gives, and the collection's absolute ``root`` (a Ray
    task may run in another working folder)."""

    index: int
    shard: int
    folder: str
    seed: int
    candidate: Candidate
    scenario: Scenario
    root: str


def sequence_folder(index: int, shard_size: int) -> tuple[int, str]:
    """The shard of sequence ``index`` and its folder relative to the collection."""
    shard = index // shard_size
    return shard, f"{SHARDS_FOLDER}/{shard:04d}/{index:06d}"


def make_sequence(task: SequenceTask) -> tuple[dict, bool]:
    """Make the dataset of ``task`` unless its folder already holds it (the same scenario and seed); its counts for
    the index (:func:`~simrig.collection.index.sequence_counts`) and whether it was made now."""
    check_no_links(Path(task.root), task.folder, what="collection folder")
    out = Path(task.root) / task.folder
    dataset = _finished(out, task)
    made = dataset is None
    if made:
        generate(task.scenario, seed=task.seed, out=out, overwrite=out.exists())
        dataset = Dataset.open(out)
    return sequence_counts(dataset), made


def _finished(out: Path, task: SequenceTask) -> Dataset | None:
    try:
        dataset = Dataset.open(out)
    except DatasetError:
        return None
    if dataset.seed != task.seed or dataset.scenario != task.scenario.model_dump(mode="json"):
        return None
    return dataset
