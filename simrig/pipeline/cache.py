"""Datasets cached by content: the folder's name is a hash of everything that determines the bytes.

Same scenario (every resolved key), seed, frame count and simrig version → same key → the dataset is generated
once and reused. Generation is atomic (:class:`~simrig.dataset.writer.DatasetWriter`), so an interrupted one
leaves no folder that looks complete and the next call generates it again.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from simrig.dataset.outputs import write_text_atomic
from simrig.dataset.reader import Dataset
from simrig.errors import DatasetError, DatasetExistsError
from simrig.scenarios import Scenario
from simrig.version import __version__

KEY_LENGTH = 20
"""[hex digits] of the SHA-256 kept in a key (80 bits)."""


def dataset_key(scenario: Scenario, seed: int, frames: int | None) -> str:
    """The content key of (``scenario``, ``seed``, ``frames``); ``frames`` None means the scenario's own.

    >>> from simrig.scenarios import load_scenario
    >>> s = load_scenario("highway_surround6")
    >>> dataset_key(s, 0, None) == dataset_key(s, 0, s.frames) != dataset_key(s, 1, None)
    True
    """
    identity = {
        "scenario": scenario.model_dump(mode="json"),
        "seed": int(seed),
        "frames": int(scenario.frames if frames is None else frames),
        "simrig": __version__,
    }
    text = json.dumps(identity, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:KEY_LENGTH]


NOT_WORLD = ("name", "description", "sensor", "evaluation")
"""Scenario keys that change what the detector reports or how it is scored, never the world it sees."""
WORLDS_FOLDER = "worlds"
"""Under a cache root: one small file per world key naming a complete dataset of that world."""


def world_key(scenario: Scenario, seed: int, frames: int | None) -> str:
    """The content key of what a dataset's world is: traffic, rig, rendering, world perturbations (with their
    positions in the list, which seed their scripted vehicles), seed and frame count — everything but the
    detector. Two datasets with the same world key differ only in what the sensor model made of one world, so
    one can be made from the other without simulating or rendering (``generate(..., world_from=...)``).

    >>> from simrig.scenarios import load_scenario
    >>> from simrig.scenarios.overrides import with_setting
    >>> s = load_scenario("highway_surround6")
    >>> world_key(s, 0, None) == world_key(with_setting(s, "sensor.detection.probability", 0.5), 0, None)
    True
    >>> world_key(s, 0, None) == world_key(with_setting(s, "rig.overlap_deg", 0.0), 0, None)
    False
    """
    from simrig.scenarios.perturbation_schema import WORLD_KINDS

    dumped = scenario.model_dump(mode="json")
    identity = {key: value for key, value in dumped.items() if key not in NOT_WORLD and key != "perturbations"}
    identity["perturbations"] = [(index, p) for index, (p, model) in enumerate(
        zip(dumped["perturbations"], scenario.perturbations, strict=True)) if model.kind in WORLD_KINDS]
    identity |= {"seed": int(seed), "frames": int(scenario.frames if frames is None else frames),
                 "simrig": __version__}
    text = json.dumps(identity, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:KEY_LENGTH]


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
