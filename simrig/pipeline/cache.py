"""Datasets cached by content: the folder's name is a hash of everything that determines the bytes.

Same scenario (every resolved key), seed, frame count and simrig version → same key → the dataset is generated
once and reused. Generation is atomic (:class:`~simrig.dataset.writer.DatasetWriter`), so an interrupted one
leaves no folder that looks complete and the next call generates it again.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from simrig.dataset.reader import Dataset
from simrig.errors import DatasetError, DatasetExistsError
from simrig.scenarios import Scenario

KEY_LENGTH = 20
"""[hex digits] of the SHA-256 kept in a key (80 bits)."""


def dataset_key(scenario: Scenario, seed: int, frames: int | None) -> str:
    """The content key of (``scenario``, ``seed``, ``frames``); ``frames`` None means the scenario's own.

    >>> from simrig.scenarios import load_scenario
    >>> s = load_scenario("highway_surround6")
    >>> dataset_key(s, 0, None) == dataset_key(s, 0, s.frames) != dataset_key(s, 1, None)
    True
    """
    from simrig.version import __version__

    identity = {
        "scenario": scenario.model_dump(mode="json"),
        "seed": int(seed),
        "frames": int(scenario.frames if frames is None else frames),
        "simrig": __version__,
    }
    text = json.dumps(identity, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:KEY_LENGTH]


def cached_dataset(scenario: Scenario, seed: int, frames: int | None, root: Path | str) -> Dataset:
    """The dataset of (``scenario``, ``seed``, ``frames``) in ``root/KEY``, generated there if absent."""
    from simrig.pipeline.generate import generate

    out = Path(root) / dataset_key(scenario, seed, frames)
    try:
        return Dataset.open(out)
    except DatasetError:
        pass
    try:
        generate(scenario, seed=seed, out=out, frames=frames, overwrite=out.exists())
    except DatasetExistsError:  # another process finished the same key first: same bytes
        pass
    return Dataset.open(out)
