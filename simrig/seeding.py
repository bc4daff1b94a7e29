"""Every random stream simrig draws from, in one registry, and the named streams of a scenario run.

:data:`STREAMS` names every stream: the seed it descends from (:data:`ROOTS`: the scenario's, a collection's, a
search's, the one a tracker's ``reset`` is given, an analysis function's, or none), its key, and what it draws.
A stream's ``numpy.random.SeedSequence`` is the seed's child at the key's spawn key (``spawned``) or the seed
and the key together as entropy (the older derivation a few streams keep, so that their documented outputs
stay the same). Adding a stream never changes the others, and the order in which they are asked for does not
matter.

>>> streams = RandomStreams(7)
>>> bool(streams.generator("population").random() == RandomStreams(7).generator("population").random())
True
>>> bool(stream_generator("explain_orders", 7).random() == stream_generator("explain_orders", 7).random())
True
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass

import numpy as np

ROOTS: dict[str, str] = {
    "scenario": "the scenario run's seed (--seed): every cause of error of the run has its own stream",
    "collection": "a collection's seed: its sequences' seeds and settings",
    "search": "a search's seed: each sampler's proposals, re-seeded per evaluation index",
    "tracker": "the seed a tracker's reset() is given (a degraded tracker's own draws)",
    "analysis": "the seed an analysis is given (bootstrap, pair sampling, fitting; 0 by default), one stream "
                "per analysis, never mixed with another stream",
    "fixed": "no seed: the same draws every time",
}
"""What each stream's seed is."""


@dataclass(frozen=True)
class Stream:
    """One random stream: its ``root`` (a key of :data:`ROOTS`), its ``key`` (spawn key when ``spawned``,
    otherwise appended to the seed as entropy) and what it ``draws``."""

    root: str
    key: tuple[int, ...]
    spawned: bool
    draws: str


def _search_key(sampler: str) -> tuple[int]:
    """A search sampler's key: the CRC-32 of its name (how the search has always keyed its samplers)."""
    return (zlib.crc32(sampler.encode()),)


STREAMS: dict[str, Stream] = {
    "traffic": Stream("scenario", (0,), True, "highway-env's own seed (road and behaviour randomness)"),
    "population": Stream("scenario", (1,), True, "where, which and how fast new vehicles appear"),
    "sensor": Stream("scenario", (2,), True, "per sensor effect and camera: (effect key, camera index)"),
    "embeddings": Stream("scenario", (3,), True, "per actor id: its identity embedding"),
    "perturbations": Stream("scenario", (4,), True, "per perturbation and frame: e.g. whether a frame is dropped"),
    "capture": Stream("scenario", (5,), True, "capture-time jitter, per camera and frame"),
    "latency": Stream("scenario", (6,), True, "random detection latency, per camera and frame"),
    "ego_pose": Stream("scenario", (7,), True, "the ego-pose estimate's noise and drift, per frame"),
    "explain_orders": Stream("scenario", (20,), True, "the permutations of cause groups an explanation samples"),
    "collection_settings": Stream("collection", (0,), True, "the Latin-hypercube draws of every sequence's settings"),
    "collection_seeds": Stream("collection", (1,), True, "per sequence index: its scenario seed"),
    **{f"search_{name}": Stream("search", _search_key(name), False, f"the {name} sampler's seed, per evaluation index")
       for name in ("tpe", "cmaes", "random")},
    "degraded_identity": Stream("tracker", (1,), False, "a degraded tracker's identity changes"),
    "degraded_velocity": Stream("tracker", (2,), False, "a degraded tracker's velocity noise"),
    "planning_road": Stream("fixed", (), False, "the empty planning road's spawner (the scorer's planner): it "
                            "spawns no traffic, so nothing is drawn"),
    "paired_bootstrap": Stream("analysis", (), False, "the bootstrap of a paired difference over seeds"),
    "ratio_bootstrap": Stream("analysis", (), False, "the bootstrap of a pooled ratio over seeds"),
    "seed_bootstrap": Stream("analysis", (), False, "the metric-validity study's resampled seeds"),
    "reid_pairs": Stream("analysis", (), False, "the pairs a re-ID table samples from an embedding log"),
    "appearance_fit_pairs": Stream("analysis", (), False, "the pairs an appearance fit measures its moments on"),
    "appearance_fit_model": Stream("analysis", (), False, "the fit's simulated pairs, per effective dimension"),
    "feature_shuffles": Stream("analysis", (), False, "the learned association's permutation importances"),
}
"""Every random stream, by name. Append new names with new keys; never change a key."""

STREAM_KEYS: dict[str, int] = {name: stream.key[0] for name, stream in STREAMS.items()
                               if stream.root == "scenario" and stream.spawned}
"""Spawn key of each named stream of a scenario run."""


def stream_sequence(name: str, seed: int | None = None, *sub: int) -> np.random.SeedSequence:
    """The ``SeedSequence`` of stream ``name`` for ``seed`` (none for a ``fixed`` stream), optionally a numbered
    sub-stream (per camera, per evaluation index, …)."""
    try:
        stream = STREAMS[name]
    except KeyError:
        raise KeyError(f"unknown random stream {name!r}; known: {', '.join(STREAMS)}") from None
    if stream.root == "fixed" and seed is not None:
        raise ValueError(f"random stream {name!r} takes no seed")
    if stream.root != "fixed" and seed is None:
        raise ValueError(f"random stream {name!r} needs the {stream.root} seed")
    seed = 0 if seed is None else int(seed)
    if stream.spawned:
        return np.random.SeedSequence(seed, spawn_key=(*stream.key, *sub))
    return np.random.SeedSequence([seed, *stream.key, *sub])


def stream_generator(name: str, seed: int | None = None, *sub: int) -> np.random.Generator:
    """A fresh ``Generator`` for stream ``name`` (:func:`stream_sequence`)."""
    return np.random.Generator(np.random.PCG64(stream_sequence(name, seed, *sub)))


class RandomStreams:
    """Named, independent random streams of one scenario run."""

    def __init__(self, seed: int):
        if not isinstance(seed, int | np.integer) or seed < 0:
            raise ValueError(f"seed: must be a non-negative integer, got {seed!r}")
        self.seed = int(seed)

    def sequence(self, name: str, *sub: int) -> np.random.SeedSequence:
        """The ``SeedSequence`` of stream ``name`` (optionally a numbered sub-stream, e.g. per camera)."""
        if name not in STREAM_KEYS:
            raise KeyError(f"unknown random stream {name!r}; known: {', '.join(STREAM_KEYS)}")
        return stream_sequence(name, self.seed, *sub)

    def generator(self, name: str, *sub: int) -> np.random.Generator:
        """A fresh ``Generator`` for stream ``name``."""
        return np.random.Generator(np.random.PCG64(self.sequence(name, *sub)))

    def integer_seed(self, name: str) -> int:
        """A 31-bit integer seed for libraries that take one (highway-env's ``reset(seed=...)``)."""
        return int(self.sequence(name).generate_state(1, dtype=np.uint32)[0] >> 1)
