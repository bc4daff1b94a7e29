"""Every random stream of a scenario run, derived from its one seed.

Streams are children of ``numpy.random.SeedSequence(seed)`` addressed by a fixed spawn key per name, so
adding a stream never changes the others and the order in which they are asked for does not matter.

>>> streams = RandomStreams(7)
>>> bool(streams.generator("population").random() == RandomStreams(7).generator("population").random())
True
"""

from __future__ import annotations

import numpy as np

STREAM_KEYS: dict[str, int] = {
    "traffic": 0,  # highway-env's own seed (road and behaviour randomness)
    "population": 1,  # where, which and how fast new vehicles appear
    "sensor": 2,  # per sensor effect and camera: (effect key, camera index)
    "embeddings": 3,  # per actor id: its identity embedding
    "perturbations": 4,  # per perturbation and frame: e.g. whether a frame is dropped
    "capture": 5,  # capture-time jitter, per camera and frame
    "latency": 6,  # random detection latency, per camera and frame
    "ego_pose": 7,  # the ego-pose estimate's noise and drift, per frame
}
"""Spawn key of each named stream. Append new names with new numbers; never renumber."""


class RandomStreams:
    """Named, independent random streams of one scenario run."""

    def __init__(self, seed: int):
        if not isinstance(seed, int | np.integer) or seed < 0:
            raise ValueError(f"seed: must be a non-negative integer, got {seed!r}")
        self.seed = int(seed)

    def sequence(self, name: str, *sub: int) -> np.random.SeedSequence:
        """The ``SeedSequence`` of stream ``name`` (optionally a numbered sub-stream, e.g. per camera)."""
        try:
            key = STREAM_KEYS[name]
        except KeyError:
            raise KeyError(f"unknown random stream {name!r}; known: {', '.join(STREAM_KEYS)}") from None
        return np.random.SeedSequence(self.seed, spawn_key=(key, *sub))

    def generator(self, name: str, *sub: int) -> np.random.Generator:
        """A fresh ``Generator`` for stream ``name``."""
        return np.random.Generator(np.random.PCG64(self.sequence(name, *sub)))

    def integer_seed(self, name: str) -> int:
        """A 31-bit integer seed for libraries that take one (highway-env's ``reset(seed=...)``)."""
        return int(self.sequence(name).generate_state(1, dtype=np.uint32)[0] >> 1)
