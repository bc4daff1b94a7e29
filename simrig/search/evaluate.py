"""One evaluation of a search: a scenario on several seeds, each generated (cached), tracked and scored in memory.

Runs in the calling process or in a pool process, so it takes and returns plain picklable values.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

from simrig.benchmark.evaluate import metric_values
from simrig.pipeline.cache import cached_dataset
from simrig.pipeline.track import run_tracker
from simrig.scenarios import Scenario
from simrig.scoring import ScoreReport, score

CONFIDENCE = 0.95
"""Level of the confidence interval reported for a mean over seeds."""


def run_seed(scenario: Scenario, seed: int, tracker: str, params: dict, cache: str) -> dict[str, float]:
    """Every overall metric (:data:`~simrig.benchmark.evaluate.METRIC_COLUMNS`) of ``tracker`` on ``scenario``
    with ``seed``; the dataset is taken from or added to the cache folder ``cache``."""
    return metric_values(score_seed(scenario, seed, tracker, params, cache))


def score_seed(scenario: Scenario, seed: int, tracker: str, params: dict, cache: str) -> ScoreReport:
    """The full score report of ``tracker`` on ``scenario`` with ``seed`` (tracks kept in memory)."""
    dataset = cached_dataset(scenario, seed, None, cache)
    run = run_tracker(dataset, tracker, None, dict(params), seed=seed)
    return score(dataset, run.tracks)


@dataclass(frozen=True)
class Estimate:
    """The mean of a metric over seeds and its two-sided Student-t confidence interval at :data:`CONFIDENCE`
    (NaN bounds with one seed, or when every value is NaN)."""

    mean: float
    low: float
    high: float
    count: int

    @classmethod
    def of(cls, values) -> Estimate:
        """The estimate of ``values`` (None and NaN left out): the half-width is t(0.975, n − 1)·s/√n.

        >>> e = Estimate.of([1.0, 2.0, 3.0])  # s = 1, t(0.975, 2) = 4.303
        >>> (e.mean, round(e.high - e.mean, 3))
        (2.0, 2.484)
        """
        array = np.asarray([v for v in values if v is not None and not math.isnan(v)], dtype=float)
        if len(array) == 0:
            return cls(math.nan, math.nan, math.nan, 0)
        mean = float(array.mean())
        if len(array) < 2:
            return cls(mean, math.nan, math.nan, 1)
        half = float(stats.t.ppf(0.5 + CONFIDENCE / 2, len(array) - 1) * array.std(ddof=1) / math.sqrt(len(array)))
        return cls(mean, mean - half, mean + half, len(array))
