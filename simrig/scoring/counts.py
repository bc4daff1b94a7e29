"""Counts: what a metric unit returns for one sequence. Counts add up across sequences, cameras and classes;
every ratio is computed from the summed counts, once, in :mod:`simrig.scoring.ratios`.

A metric unit (TrackEval's shape: :class:`~simrig.scoring.hota.HOTA`, :class:`~simrig.scoring.clear.CLEAR`,
:class:`~simrig.scoring.identity.Identity`) declares its ``name``, the count ``fields`` it returns, the ``outputs``
its ``ratios`` compute, and ``empty()`` (its counts of a sequence with nothing in it). :func:`combine` sums
each unit's fields by name and computes its ratios once.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Protocol

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


class MetricUnit(Protocol):
    """What :func:`combine` needs of a metric unit."""

    name: str
    fields: tuple[str, ...]
    outputs: tuple[str, ...]

    def empty(self) -> Counts: ...

    def ratios(self, counts: Counts) -> dict[str, float]: ...


def combine(units: Sequence[MetricUnit], parts: Iterable[Mapping[str, Counts]]) -> dict[str, float]:
    """Every unit's values over ``parts`` (each: unit name → that unit's counts of one sequence): the unit's
    declared fields summed by name, then its ratios computed once; with no parts, the ratios of empty counts
    (as the peers define them: counts 0, ratios by TrackEval's ``max(1, …)`` denominators).

    >>> class Hits:
    ...     name, fields, outputs = "hits", ("TP", "FN"), ("Re",)
    ...     def empty(self): return {"TP": 0.0, "FN": 0.0}
    ...     def ratios(self, c): return {"Re": c["TP"] / max(1.0, c["TP"] + c["FN"]), "TP": c["TP"]}
    >>> combine([Hits()], [{"hits": {"TP": 1.0, "FN": 1.0}}, {"hits": {"FN": 2.0, "TP": 3.0}}])
    {'Re': 0.5714285714285714, 'TP': 4.0}
    >>> combine([Hits()], [])
    {'Re': 0.0, 'TP': 0.0}
    """
    parts = list(parts)
    values: dict[str, float] = {}
    for unit in units:
        selected = [part[unit.name] for part in parts]
        for counts in selected:
            if set(counts) != set(unit.fields):
                raise ValueError(f"{unit.name}: counts have fields {sorted(counts)}, the unit declares "
                                 f"{sorted(unit.fields)}")
        total = sum_counts(selected) if selected else unit.empty()
        values |= unit.ratios(total)
    return values
