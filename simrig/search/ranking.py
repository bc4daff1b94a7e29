"""Ranking a search's evaluations: the objective's estimate, whether one fails, the first that failed, the best
candidates (what the confirmation stream reruns)."""

from __future__ import annotations

import math

import numpy as np

from .evaluate import Estimate
from .fragments import Evaluation
from .space import SearchSpace

CONFIRM = "confirm"
"""The stream of the best candidates rerun on seeds the optimiser never saw."""


def objective_of(space: SearchSpace, evaluation: Evaluation) -> Estimate:
    return Estimate.of(evaluation.values(space.config.objective.metric))


def fails(space: SearchSpace, evaluation: Evaluation) -> bool:
    """Whether the mean of the failure metric over the evaluation's seeds is past the threshold."""
    failure = space.config.objective.failure
    if failure is None:
        return False
    return failure.fails(Estimate.of(evaluation.values(space.config.objective.failure_metric)).mean)


def first_failure(space: SearchSpace, evaluations: list[Evaluation]) -> int | None:
    """The 1-based number of the first failing evaluation, None when none failed."""
    return next((e.index + 1 for e in evaluations if fails(space, e)), None)


def best_candidates(space: SearchSpace, evaluations: list[Evaluation], count: int) -> list[Evaluation]:
    """The ``count`` best distinct candidates by mean objective (NaN last; ties by index)."""
    sign = -1.0 if space.config.objective.direction == "maximize" else 1.0
    ranked = sorted(evaluations, key=lambda e: (math.isnan(objective_of(space, e).mean),
                                                sign * np.nan_to_num(objective_of(space, e).mean), e.index))
    chosen, seen = [], set()
    for evaluation in ranked:
        key = repr(sorted(evaluation.candidate.items()))
        if key not in seen:
            seen.add(key)
            chosen.append(evaluation)
    return chosen[:count]
