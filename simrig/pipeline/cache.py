"""Datasets cached by content: the folder's name is a hash of everything that determines the bytes.

Same scenario (every resolved key), seed, frame count and simrig version → same key → the dataset is generated
once and reused. Generation is atomic (:class:`~simrig.dataset.writer.DatasetWriter`), so an interrupted one
leaves no folder that looks complete and the next call generates it again.
"""

from __future__ import annotations

from pathlib import Path

from simrig.dataset.outputs import check_output_path, write_text_atomic
from simrig.dataset.reader import Dataset
from simrig.errors import DatasetError, DatasetExistsError
from simrig.pipeline.content_keys import KEY_LENGTH, dataset_key, world_key
from simrig.scenarios import Scenario

WORLDS_FOLDER = "worlds"
"""Under a cache root: one small file per world key naming a complete dataset of that world."""


def check_cache_folder(root: Path) -> None:
    """Refuse ``root`` as a dataset cache unless it is new, empty or holds only what a cache holds (datasets named
    by their content key, :data:`WORLDS_FOLDER`, partial folders): never a dataset or a user's folder."""
    check_output_path(root, what="--cache")
    if not root.is_dir():
        return
    foreign = [entry.name for entry in root.iterdir()
               if not (entry.name == WORLDS_FOLDER or entry.name.startswith(".")
                       or (len(entry.name) == KEY_LENGTH and all(c in "0123456789abcdef" for c in entry.name)))]
    if foreign:
        raise DatasetError(f"--cache {str(root)!r} holds {foreign[0]!r}, which no dataset cache holds: simrig caches "
                           "datasets only in a new or empty folder or an earlier cache; choose another --cache")


def cached_dataset(scenario: Scenario, seed: int, frames: int | None, root: Path | str) -> Dataset:
    """The dataset of (``scenario``, ``seed``, ``frames``) in ``root/KEY``, generated there if absent.

    When the cache already holds a dataset of the same world (:func:`world_key`: a sweep over detector
    settings), only the sensor model is run on that dataset's traffic and visibility: same bytes, no
    simulation, no rendering."""
    from simrig.pipeline.generate import generate

    root = Path(root)
    out = root / dataset_key(scenario, seed, frames)
    try:
        return Dataset.open(out)
    except DatasetError:
        pass
    world = world_key(scenario, seed, frames)
    try:
        generate(scenario, seed=seed, out=out, frames=frames, overwrite=out.exists(),
                 world_from=_world_dataset(root, world))
    except DatasetExistsError:  # another process finished the same key first: same bytes
        pass
    dataset = Dataset.open(out)
    _remember_world(root, world, out.name)
    return dataset


def _world_dataset(root: Path, world: str) -> Dataset | None:
    """A complete dataset of ``world`` in the cache, if one is known."""
    marker = root / WORLDS_FOLDER / world
    try:
        dataset = Dataset.open(root / marker.read_text(encoding="utf-8").strip())
    except (OSError, DatasetError):
        return None
    return dataset if dataset.manifest.get("world_key") == world else None


def _remember_world(root: Path, world: str, dataset_name: str) -> None:
    """Record (atomically) that ``root/dataset_name`` is a complete dataset of ``world``."""
    folder = root / WORLDS_FOLDER
    folder.mkdir(parents=True, exist_ok=True)
    write_text_atomic(folder / world, dataset_name)
