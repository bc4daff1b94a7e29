"""Counts: what a metric unit returns for one sequence. Counts add up across sequences, cameras and classes;
every ratio is computed from the summed counts, once, in :mod:`simrig.scoring.ratios`."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

Counts = dict[str, float | np.ndarray]
"""Field name → a number, or an array over HOTA's α thresholds."""


def sum_counts(parts: Iterable[Counts]) -> Counts:
    """Field-wise sum of several sequences' counts (all must have the same fields).

    >>> sum_counts([{"TP": 1, "FN": 2}, {"TP": 3, "FN": 0}])
    {'TP': 4, 'FN': 2}
    """
    parts = list(parts)
    if not parts:
        raise ValueError("sum_counts: nothing to sum")
    fields = parts[0].keys()
    for part in parts[1:]:
        if part.keys() != fields:
            raise ValueError(f"sum_counts: fields differ: {sorted(fields)} vs {sorted(part.keys())}")
    return {name: sum((part[name] for part in parts[1:]), start=parts[0][name]) for name in fields}
