"""Coverage of a search: how many evaluations fell in each bin of each dimension, so a user sees what was never
tried (a bin with 0) — the optimiser concentrates where the objective is bad, random sampling spreads evenly.

Bins: every choice of a ``choices`` dimension; every integer of an integer range (window start and length
included) with at most :data:`BINS` values, else :data:`BINS` runs of consecutive integers; :data:`BINS`
equal-width bins of a float range (log-spaced for a log range).

>>> from simrig.scenarios.search_schema import Dimension
>>> dimension = Dimension(path="rig.overlap_deg", low=0.0, high=10.0)
>>> [label for label, _ in bins(dimension, dimension.path)]
['[0, 2)', '[2, 4)', '[4, 6)', '[6, 8)', '[8, 10]']
>>> counts(dimension, dimension.path, [0.0, 1.9, 2.0, 10.0])
[2, 1, 0, 0, 1]
>>> [label for label, _ in bins(Dimension(path="frames", low=1, high=12), "frames")]
['1–3', '4–6', '7–8', '9–10', '11–12']
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from simrig.scenarios.search_schema import Dimension

BINS = 5
"""[-] bins of a continuous range (and of an integer range with more values than this)."""


def _range(dimension: Dimension, name: str) -> tuple[float, float, bool]:
    """(low, high, integer) of the parameter ``name`` of ``dimension``."""
    if dimension.kind == "window":
        low, high = dimension.start if name.endswith(".start") else dimension.length
        return low, high, True
    return dimension.low, dimension.high, dimension.integer


def bins(dimension: Dimension, name: str) -> list[tuple[str, Callable[[object], bool]]]:
    """(label, membership test) of every bin of parameter ``name``, in order."""
    if dimension.kind == "choice":
        return [(repr(choice), lambda v, c=choice: v == c) for choice in dimension.choices]
    low, high, integer = _range(dimension, name)
    if integer:  # single values, or BINS runs of consecutive integers
        groups = np.array_split(np.arange(int(low), int(high) + 1), min(BINS, int(high - low) + 1))
        return [(str(g[0]) if len(g) == 1 else f"{g[0]}–{g[-1]}",
                 lambda v, a=int(g[0]), b=int(g[-1]): a <= v <= b) for g in groups]
    edges = (np.geomspace(low, high, BINS + 1) if dimension.log else np.linspace(low, high, BINS + 1)).tolist()
    out = []
    for index in range(BINS):
        a, b = edges[index], edges[index + 1]
        last = index == BINS - 1
        label = f"[{a:.4g}, {b:.4g}{']' if last else ')'}"
        out.append((label, lambda v, a=a, b=b, last=last: a <= v <= b if last else a <= v < b))
    return out


def counts(dimension: Dimension, name: str, values: list) -> list[int]:
    """Evaluations per bin of parameter ``name`` among ``values``."""
    return [sum(1 for v in values if inside(v)) for _, inside in bins(dimension, name)]
