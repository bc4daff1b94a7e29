"""nuScenes sample tokens of a simrig dataset's frames, and the scene of each frame of a nuScenes import.

A generated dataset's frame ``F`` is the sample ``SCENARIO-seedN-FFFFFF`` (:func:`sample_token`, as
``simrig export --format nuscenes`` writes it); an imported nuScenes dataset keeps its source's own tokens and
scenes in its ``sample_tokens`` file (:mod:`simrig.formats.nuscenes.ground_truth`).
"""

from __future__ import annotations

import json

import numpy as np

SAMPLE_TOKENS_FILE = "sample_tokens"
"""The manifest key of an imported nuScenes dataset's tokens (``{"tokens": [...], "scenes": [...]}``)."""


def sample_token(scenario: str, seed: int, frame: int) -> str:
    """The nuScenes sample token of a generated dataset's frame."""
    return f"{scenario}-seed{seed}-{int(frame):06d}"


def sample_tokens(dataset) -> dict[str, int]:
    """nuScenes sample token → frame of a :class:`~simrig.dataset.Dataset`: an imported nuScenes dataset's own
    tokens, otherwise :func:`sample_token` of each frame."""
    if SAMPLE_TOKENS_FILE in dataset.manifest["files"]:
        tokens = json.loads(dataset.files.read(SAMPLE_TOKENS_FILE))["tokens"]
        return {token: frame for frame, token in enumerate(tokens)}
    frames = dataset.table("ego_poses").column("frame").to_numpy()
    return {sample_token(dataset.scenario["name"], dataset.seed, int(f)): int(f) for f in frames}


def scene_of_frame(dataset) -> np.ndarray | None:
    """``(F,)`` the scene index of every frame of an imported dataset made of several scenes (a nuScenes
    import: track ids are per scene), or ``None``."""
    if SAMPLE_TOKENS_FILE not in dataset.manifest["files"]:
        return None
    scenes = json.loads(dataset.files.read(SAMPLE_TOKENS_FILE)).get("scenes") or []
    out = np.zeros(dataset.frame_count, dtype=np.int64)
    for index, scene in enumerate(scenes):
        out[scene["first_frame"]:scene["first_frame"] + scene["frames"]] = index
    return out
