"""``simrig generate --space``: a collection of datasets sampled from a scenario space.

* :mod:`~simrig.collection.space` — the space file (the format ``simrig search`` reads) checked for generation,
  a choice of base scenario included;
* :mod:`~simrig.collection.sampling` — the settings of every sequence: a Latin hypercube, so every range and
  every weighted choice is present in a known share;
* :mod:`~simrig.collection.plan` — sequences, their seeds and folders (shards), and the worker that makes one;
* :mod:`~simrig.collection.index` — the index table: one row per sequence (settings, seed, shard, counts);
* :mod:`~simrig.collection.run` — :func:`generate_collection`: resumable, on the local pool or Ray.
"""

from .run import CollectionRun, generate_collection
from .space import GenerationSpace, load_generation_space

__all__ = ["CollectionRun", "GenerationSpace", "generate_collection", "load_generation_space"]
