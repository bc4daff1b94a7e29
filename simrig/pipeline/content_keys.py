"""Content keys: a hash of everything that determines a dataset's bytes (:func:`dataset_key`) or its world's
(:func:`world_key`), so that equal inputs find the dataset made before (:mod:`simrig.pipeline.cache`)."""

from __future__ import annotations

import hashlib
import json

from simrig.scenarios import Scenario
from simrig.scenarios.perturbation_schema import WORLD_KINDS
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
    dumped = scenario.model_dump(mode="json")
    identity = {key: value for key, value in dumped.items() if key not in NOT_WORLD and key != "perturbations"}
    identity["perturbations"] = [(index, p) for index, (p, model) in enumerate(
        zip(dumped["perturbations"], scenario.perturbations, strict=True)) if model.kind in WORLD_KINDS]
    identity |= {"seed": int(seed), "frames": int(scenario.frames if frames is None else frames),
                 "simrig": __version__}
    text = json.dumps(identity, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:KEY_LENGTH]


def drive_key(scenario: Scenario, seed: int, frames: int | None, drive: dict) -> str:
    """The world key of a closed-loop drive (:mod:`simrig.pipeline.drive`): its world depends on everything — the
    detector's draws and the tracker steer the ego — so the key is the dataset's key with the drive's record."""
    text = json.dumps({"dataset": dataset_key(scenario, seed, frames), "drive": drive}, sort_keys=True,
                      separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:KEY_LENGTH]
