"""The settings of every sequence of a collection, sampled from a space by a Latin hypercube.

A Latin hypercube ("A Comparison of Three Methods for Selecting Values of Input Variables in the Analysis of
Output from a Computer Code", McKay, Beckman and Conover, 1979; scipy's :class:`scipy.stats.qmc.LatinHypercube`)
puts exactly one of the ``count`` samples in each of ``count`` equal strata of every parameter. So every share
the space declares is met to within one sequence, not only on average: a choice of weight *w* is taken
``count · w`` times (rounded up or down), and a range's values are spread evenly over it. Rare settings (a
blackout in 5 % of sequences) are present in their share even in a small collection.

Each parameter maps its stratified uniform draw *u* ∈ [0, 1): a float range to ``low + u (high − low)`` (log-
uniform when ``log``), an integer range and a window's start and length to ``low + ⌊u (high − low + 1)⌋``, a
choice to the first choice whose cumulative weight exceeds *u*.

The draw comes from the collection's seed alone, on its own stream; each sequence's scenario seed is another,
so the settings and the traffic never share draws.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import qmc

from simrig.scenarios.search_schema import Dimension
from simrig.scenarios.space_file import Candidate
from simrig.seeding import stream_generator, stream_sequence

FIRST_SEQUENCE_SEED = 1_000_000
"""Sequence seeds are at least this: a collection never holds a seed the catalog, the benches or the docs use."""


def sequence_seed(collection_seed: int, index: int) -> int:
    """The scenario seed of sequence ``index`` (0-based) of the collection of ``collection_seed``: in
    [:data:`FIRST_SEQUENCE_SEED`, 2³¹), independent of how many sequences the collection has."""
    state = stream_sequence("collection_seeds", collection_seed, index).generate_state(1, np.uint32)[0]
    return FIRST_SEQUENCE_SEED + int(state >> 1) % (2**31 - FIRST_SEQUENCE_SEED)


def unit_draws(columns: int, count: int, collection_seed: int) -> np.ndarray:
    """(``count``, ``columns``) stratified uniform draws in [0, 1): one per stratum of width 1/``count`` in every
    column, the strata of different columns paired at random."""
    generator = stream_generator("collection_settings", collection_seed)
    return qmc.LatinHypercube(d=columns, rng=generator).random(count)


def sample_candidates(dimensions: tuple[Dimension, ...], count: int, collection_seed: int) -> list[Candidate]:
    """The values of every dimension for each of ``count`` sequences (a list of ``count`` candidates, by
    parameter name: :attr:`Dimension.names`)."""
    names = [name for dimension in dimensions for name in dimension.names]
    draws = unit_draws(len(names), count, collection_seed)
    columns: dict[str, list] = {}
    column = 0
    for dimension in dimensions:
        if dimension.kind == "window":
            (start, length), bounds = dimension.names, (dimension.start, dimension.length)
            for name, (low, high) in zip((start, length), bounds, strict=True):
                columns[name] = _integers(draws[:, column], low, high)
                column += 1
            continue
        u = draws[:, column]
        column += 1
        if dimension.kind == "choice":
            columns[dimension.path] = [dimension.choices[i] for i in choice_indices(u, dimension)]
        elif dimension.integer:
            columns[dimension.path] = _integers(u, dimension.low, dimension.high)
        elif dimension.log:
            low, high = math.log(dimension.low), math.log(dimension.high)
            columns[dimension.path] = np.exp(low + u * (high - low)).clip(dimension.low, dimension.high).tolist()
        else:
            columns[dimension.path] = (dimension.low + u * (dimension.high - dimension.low)).tolist()
    return [{name: columns[name][row] for name in names} for row in range(count)]


def choice_shares(dimension: Dimension) -> np.ndarray:
    """The share of each of a choice dimension's choices (its weights normalised; even when it has none)."""
    weights = np.ones(len(dimension.choices)) if dimension.weights is None else np.asarray(dimension.weights, float)
    return weights / weights.sum()


def choice_indices(u: np.ndarray, dimension: Dimension) -> np.ndarray:
    """The choice each uniform draw in ``u`` falls on, by the choices' cumulative shares."""
    edges = np.cumsum(choice_shares(dimension))
    return np.minimum(np.searchsorted(edges, u, side="right"), len(dimension.choices) - 1)


def _integers(u: np.ndarray, low: int, high: int) -> list[int]:
    return np.minimum(low + np.floor(u * (high - low + 1)).astype(np.int64), high).tolist()
