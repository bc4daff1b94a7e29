"""``generate_collection``: ``count`` sequences sampled from a space, made on the local pool or Ray, resumable, into
one folder with an index table.

The folder::

    collection.json       what the collection is (space, bases, seed, count, shard size) and whether it is complete
    index.parquet         one row per sequence (:mod:`simrig.collection.index`); written last: no index, not complete
    shards/SSSS/NNNNNN/   one dataset per sequence (:mod:`simrig.collection.plan`)

Each dataset is written whole or not at all (the dataset writer publishes a finished folder by renaming it), so a
kill leaves only finished datasets and hidden partial folders that the next run removes; a rerun with the same
space, seed and count keeps every finished dataset and makes the rest. The bytes depend on the space, its bases,
the seed and the count only: not on the engine, the workers, the order in which sequences finish, or interruptions.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from tqdm import tqdm

from simrig.scenarios import ScenarioError
from simrig.scenarios.search_schema import MAX_SEQUENCES
from simrig.scenarios.space_file import SpaceError

from ..dataset.manifest import write_json_atomic
from ..dataset.outputs import check_no_links, check_output_path, check_own_folder, folder_lock, write_table_atomic
from ..engine_names import ENGINES
from ..pipeline.generate import check_generable
from ..pools import Interrupted, map_on, require_ray
from ..reading import read_capped
from ..version import __version__
from .index import index_table
from .plan import SHARDS_FOLDER, SequenceTask, make_sequence, sequence_folder
from .sampling import sample_candidates, sequence_seed
from .space import GenerationSpace, load_generation_space

COLLECTION_FILE = "collection.json"
INDEX_FILE = "index.parquet"
IDENTITY_KEYS = ("format", "space", "bases", "seed", "count", "shard_size")
"""What must match for a rerun to resume a collection (``collection.json``)."""


@dataclass(frozen=True)
class CollectionRun:
    """What a collection run did: its folder, how many sequences it holds, how many were finished earlier and how
    many were made now."""

    out: Path
    sequences: int
    kept: int
    made: int

    @property
    def index(self) -> Path:
        return self.out / INDEX_FILE


class CollectionInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped a collection; :meth:`message` says what was kept."""

    def __init__(self, out: Path, finished: int, count: int):
        super().__init__(out, finished, count)
        self.out, self.finished, self.count = out, finished, count

    def message(self) -> str:
        return (f"interrupted: {self.finished} of {self.count} sequences are finished in {str(self.out)!r} and kept; "
                "the running ones' work is lost; the same command resumes")


def generate_collection(space: str | Path | GenerationSpace, *, count: int, out: Path | str | None = None,
                        seed: int = 0, shard_size: int = 100, engine: str = "local", workers: int | None = None,
                        address: str | None = None, progress: bool = False) -> CollectionRun:
    """Sample ``count`` sequences of ``space`` (a catalog name, a file or a loaded space) with the collection
    ``seed`` and make every one not yet finished in ``out`` (default ``runs/collections/NAME``). Everything is
    checked before any work: the space, the count, every sampled scenario, the folder."""
    _check_options(count, seed, shard_size, engine, workers)
    if not isinstance(space, GenerationSpace):
        space = load_generation_space(space)
    candidates = sample_candidates(space.dimensions, count, seed)
    out = Path(out) if out is not None else Path("runs") / "collections" / space.config.name
    root = str(out.absolute())
    tasks = [_task(space, index, candidate, seed, shard_size, root) for index, candidate in enumerate(candidates)]
    description = {
        "format": "simrig collection",
        "space": space.config.model_dump(mode="json"),
        "bases": {name: scenario.model_dump(mode="json") for name, scenario in space.bases.items()},
        "seed": seed, "count": count, "shard_size": shard_size, "simrig": __version__,
    }
    check_output_path(out, what="--out")
    check_own_folder(out, what="collection folder", marker=COLLECTION_FILE, marker_keys=IDENTITY_KEYS,
                     made=(SHARDS_FOLDER,))
    out.mkdir(parents=True, exist_ok=True)
    with folder_lock(out, "simrig generate --space"):
        _check_same_collection(out, description)
        for task in tasks:  # before any work; make_sequence checks its own folder again as it writes
            check_no_links(out, task.folder, what="collection folder")
        (out / INDEX_FILE).unlink(missing_ok=True)  # from here until the end, the folder must not look finished
        write_json_atomic(out / COLLECTION_FILE, {**description, "complete": False})
        rows, kept = _make(tasks, out, engine, workers, address, progress, space.config.name)
        write_table_atomic(index_table(rows, space.names), out / INDEX_FILE)
        write_json_atomic(out / COLLECTION_FILE, {**description, "complete": True})
    return CollectionRun(out, count, kept, count - kept)


def _check_options(count: int, seed: int, shard_size: int, engine: str, workers: int | None) -> None:
    if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= MAX_SEQUENCES:
        raise SpaceError(f"--count {count!r}: must be a whole number of sequences from 1 to {MAX_SEQUENCES:,}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise SpaceError(f"--seed {seed!r}: must be a non-negative integer")
    if isinstance(shard_size, bool) or not isinstance(shard_size, int) or not 1 <= shard_size <= MAX_SEQUENCES:
        raise SpaceError(f"--shard-size {shard_size!r}: must be a whole number from 1 to {MAX_SEQUENCES:,}")
    if engine not in ENGINES:
        raise SpaceError(f"--engine {engine!r}: choose one of {', '.join(ENGINES)}")
    if engine == "ray":
        require_ray()
    if workers is not None and workers < 1:
        raise SpaceError(f"--workers {workers}: must be at least 1")


def _task(space: GenerationSpace, index: int, candidate: dict, seed: int, shard_size: int, root: str) -> SequenceTask:
    try:
        scenario = space.scenario_for(candidate)
        check_generable(scenario)
    except ScenarioError as error:
        raise SpaceError(f"space file {str(space.path)!r}: sequence {index} samples {candidate}, which is not a "
                          f"valid scenario: {error}") from None
    shard, folder = sequence_folder(index, shard_size)
    return SequenceTask(index, shard, folder, sequence_seed(seed, index), candidate, scenario, root)


def _check_same_collection(out: Path, description: dict) -> None:
    """A folder holding another collection (another space, bases, seed, count or shard size) is not resumed."""
    path = out / COLLECTION_FILE
    if not path.exists():
        return
    try:
        earlier = json.loads(read_capped(path, "collection file", SpaceError).decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise SpaceError(f"{path}: not a collection file simrig wrote ({error}); choose another --out") from None
    if not isinstance(earlier, dict):
        raise SpaceError(f"{path}: not a collection file simrig wrote; choose another --out")
    differ = [key for key in IDENTITY_KEYS if earlier.get(key) != description[key]]
    if differ:
        verb = "differs" if len(differ) == 1 else "differ"
        raise SpaceError(f"--out {str(out)!r} holds another collection (its {' and '.join(differ)} {verb}): a rerun "
                          "resumes only the same space, seed, count and shard size; choose another --out")


def _make(tasks: list[SequenceTask], out: Path, engine: str, workers: int | None, address: str | None,
          progress: bool, name: str) -> tuple[list[dict], int]:
    """Every task's index row, made on ``engine``; how many were finished earlier."""
    results = map_on(engine, make_sequence, tasks, workers, address)
    rows, kept = [], 0
    bar = tqdm(total=len(tasks), unit="seq", disable=not progress, desc=f"collection {name}")
    with bar:
        try:
            for task, (counts, made) in results:
                rows.append({"sequence": task.index, "shard": task.shard, "folder": task.folder, "seed": task.seed,
                             "scenario": task.scenario.name, "settings": task.candidate, "counts": counts})
                kept += not made
                bar.update(1)
        except Interrupted:
            raise CollectionInterrupted(out, len(rows), len(tasks)) from None
        except KeyboardInterrupt:  # arrived while a finished sequence was being recorded
            results.close()
            raise CollectionInterrupted(out, len(rows), len(tasks)) from None
    return rows, kept
