"""Shapley values of a game over removals, exactly or by permutation sampling.

The game: ``u(R)`` = a vector of metric values when the cause groups ``R`` are removed from the detector;
``u(∅)`` is the actual run and ``u(N)`` the perfect sensor. A group's share is its Shapley value

    φ_i = Σ_{R ⊆ N∖{i}} |R|! (k − |R| − 1)! / k! · (u(R ∪ {i}) − u(R))

(Shapley, "A value for n-person games", 1953), so Σ_i φ_i = u(N) − u(∅) = perfect − actual (efficiency), and a
group whose removal never changes anything gets 0 (null player). Sampled: φ_i is the mean marginal
u(P_i ∪ {i}) − u(P_i) over random orders of the groups, P_i the groups before i (Castro, Gómez and Tejada,
"Polynomial calculation of the Shapley value based on sampling", 2009); each order is paired with its
reverse (antithetic sampling), and the half-width of a 95 % confidence interval is given per group: Student's t
(with few pairs a normal quantile would understate it badly) over the pairs' means, or over the single orders'
marginals where that is wider — a count metric's few pair means are often equal, which alone would claim a
zero-width interval, and an order and its reverse usually err in opposite directions, so the single orders' interval
is the cautious one.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import t as student_t

from simrig.seeding import stream_generator

Coalition = frozenset[str]


def all_coalitions(players: Sequence[str]) -> list[Coalition]:
    """Every subset of ``players`` (2^k), smallest first.

    >>> [sorted(c) for c in all_coalitions(["a", "b"])]
    [[], ['a'], ['b'], ['a', 'b']]
    """
    return [frozenset(subset) for size in range(len(players) + 1)
            for subset in itertools.combinations(players, size)]


def exact_shares(players: Sequence[str], values: Mapping[Coalition, np.ndarray]) -> dict[str, np.ndarray]:
    """Exact Shapley values ``{player: (M,) array}`` of the game ``values`` (every coalition of ``players``).

    >>> v = {frozenset(): 0.0, frozenset("a"): 1.0, frozenset("b"): 2.0, frozenset("ab"): 5.0}
    >>> {p: float(s) for p, s in exact_shares(["a", "b"], {c: np.array(x) for c, x in v.items()}).items()}
    {'a': 2.0, 'b': 3.0}
    """
    k = len(players)
    weight = [math.factorial(size) * math.factorial(k - size - 1) / math.factorial(k) for size in range(k)]
    shares = {}
    for player in players:
        others = [p for p in players if p != player]
        total = np.zeros_like(np.asarray(values[frozenset()], dtype=float))
        for coalition in all_coalitions(others):
            total = total + weight[len(coalition)] * (np.asarray(values[coalition | {player}], dtype=float)
                                                      - np.asarray(values[coalition], dtype=float))
        shares[player] = total
    return shares


def coalition_order(coalition: Coalition) -> tuple[int, list[str]]:
    """Sort key of coalitions: smallest first, then by their groups' names (the order they are run and named in).

    >>> [sorted(c) for c in sorted([frozenset("b"), frozenset(), frozenset("ac"), frozenset("a")], key=coalition_order)]
    [[], ['a'], ['b'], ['a', 'c']]
    """
    return len(coalition), sorted(coalition)


def sample_orders(players: Sequence[str], samples: int, seed: int) -> list[tuple[str, ...]]:
    """``samples`` random orders of ``players`` (rounded up to an even count): each drawn order followed by its
    reverse. Same seed, same orders."""
    rng = stream_generator("explain_orders", seed)
    orders = []
    for _ in range((samples + 1) // 2):
        order = tuple(players[i] for i in rng.permutation(len(players)))
        orders += [order, order[::-1]]
    return orders


def prefixes(orders: Sequence[Sequence[str]]) -> set[Coalition]:
    """Every coalition the orders visit (each order's prefixes, the empty and the full one included)."""
    return {frozenset(order[:size]) for order in orders for size in range(len(order) + 1)}


@dataclass(frozen=True)
class SampledShares:
    """Sampled Shapley values ``{player: (M,)}`` and the half-widths of their 95 % confidence intervals (NaN
    from a single antithetic pair, which gives no interval)."""

    shares: dict[str, np.ndarray]
    half_width: dict[str, np.ndarray]


def sampled_shares(players: Sequence[str], orders: Sequence[Sequence[str]],
                   values: Mapping[Coalition, np.ndarray]) -> SampledShares:
    """Shapley values estimated from ``orders`` (:func:`sample_orders`: antithetic pairs, each pair's mean
    one sample of the interval estimate)."""
    marginals = {player: [] for player in players}
    for order in orders:
        before: Coalition = frozenset()
        for player in order:
            after = before | {player}
            marginals[player].append(np.asarray(values[after], dtype=float) - np.asarray(values[before], dtype=float))
            before = after
    shares, half = {}, {}
    for player, rows in marginals.items():
        rows = np.array(rows)
        pairs = rows.reshape(-1, 2, *rows.shape[1:]).mean(axis=1) if len(rows) % 2 == 0 else rows
        shares[player] = rows.mean(axis=0)
        if len(pairs) < 2:  # one pair: no spread to estimate, no interval
            half[player] = np.full(rows.shape[1:], np.nan)
            continue
        half[player] = np.maximum(_half_width(pairs), _half_width(rows))
    return SampledShares(shares, half)


def _half_width(samples: np.ndarray) -> np.ndarray:
    """Half-width of the 95 % Student's t interval of the mean of ``samples`` ``(n, M)``."""
    n = len(samples)
    return student_t.ppf(0.975, n - 1) * samples.std(axis=0, ddof=1) / math.sqrt(n)
