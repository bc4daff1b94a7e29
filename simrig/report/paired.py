"""Paired comparisons of two trackers over sequences: the mean difference with a 95 % interval.

Two trackers run on the same detections of the same sequences (scenario × seed), so the difference of a metric
is taken per sequence and what a sequence does to both cancels. The interval is the BCa bootstrap of the mean
difference, resampling sequences (``scipy.stats.bootstrap``, 10,000 resamples, a fixed seed: the same numbers
give the same interval); where BCa is undefined (e.g. nearly all differences equal) the percentile interval.
A difference is called significant when its interval excludes 0 — a claim at the 5 % level for that one
comparison, not corrected for the many a report makes.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from simrig.seeding import stream_generator

RESAMPLES = 10_000
CONFIDENCE = 0.95


@dataclass(frozen=True)
class PairedDifference:
    """Mean of a − b over ``sequences`` paired sequences, its interval [low, high] (NaN without one: fewer than
    two sequences), and in how many sequences a was above / below b."""

    mean: float
    low: float
    high: float
    sequences: int
    above: int
    below: int

    @property
    def significant(self) -> bool:
        """The interval excludes 0."""
        return bool(np.isfinite(self.low) and (self.low > 0 or self.high < 0))

    def text(self, scale: float = 1.0, digits: int = 3) -> str:
        """``+0.012 [−0.004, +0.027]`` with ``n.s.`` when not significant (values × ``scale``).

        >>> PairedDifference(0.012, -0.004, 0.027, 10, 6, 4).text()
        '+0.012 [-0.004, +0.027] n.s.'
        >>> PairedDifference(2.0, 1.0, 3.0, 10, 9, 1).text(digits=1)
        '+2.0 [+1.0, +3.0]'
        """
        if not math.isfinite(self.mean):
            return "–"
        if not math.isfinite(self.low):
            return f"{self.mean * scale:+.{digits}f} (no interval: {self.sequences} sequence)"
        return (f"{self.mean * scale:+.{digits}f} [{self.low * scale:+.{digits}f}, {self.high * scale:+.{digits}f}]"
                + ("" if self.significant else " n.s."))


def paired_difference(a, b, *, seed: int = 0) -> PairedDifference:
    """The paired difference of metric values ``a`` and ``b`` (one per sequence, same order); sequences where
    either is NaN are left out.

    >>> d = paired_difference([0.5, 0.6, 0.7, 0.8], [0.4, 0.5, 0.6, 0.7])
    >>> round(d.mean, 6), round(d.low, 6), round(d.high, 6), d.significant
    (0.1, 0.1, 0.1, True)
    """
    from scipy.stats import bootstrap

    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape:
        raise ValueError(f"paired values: {a.shape} against {b.shape}; one value per sequence on each side")
    keep = np.isfinite(a) & np.isfinite(b)
    difference = a[keep] - b[keep]
    n = len(difference)
    above, below = int(np.sum(difference > 0)), int(np.sum(difference < 0))
    if n == 0:
        return PairedDifference(float("nan"), float("nan"), float("nan"), 0, 0, 0)
    mean = float(difference.mean())
    if n < 2:
        return PairedDifference(mean, float("nan"), float("nan"), n, above, below)
    if np.ptp(difference) <= 1e-12 * max(1.0, abs(mean)):
        return PairedDifference(mean, mean, mean, n, above, below)
    low = high = float("nan")
    for method in ("BCa", "percentile"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            interval = bootstrap((difference,), np.mean, n_resamples=RESAMPLES, confidence_level=CONFIDENCE,
                                 method=method, rng=stream_generator("paired_bootstrap", seed)).confidence_interval
        low, high = float(interval.low), float(interval.high)
        if math.isfinite(low) and math.isfinite(high):
            break
    return PairedDifference(mean, low, high, n, above, below)


def paired_ratio(a, b, *, seed: int = 0) -> tuple[float, float, float]:
    """The pooled ratio ``sum(a) / sum(b)`` of per-sequence counts (one value per sequence, same order) with its
    95 % BCa bootstrap interval over sequences resampled in pairs (NaN bounds when it cannot be formed).

    >>> ratio, low, high = paired_ratio([1, 2, 3, 4], [2, 4, 6, 8])
    >>> ratio, round(low, 6), round(high, 6)
    (0.5, 0.5, 0.5)
    """
    from scipy.stats import bootstrap

    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    keep = np.isfinite(a) & np.isfinite(b)
    a, b = a[keep], b[keep]
    ratio = float(a.sum() / b.sum()) if b.sum() else float("nan")
    if len(a) < 2 or not math.isfinite(ratio):
        return ratio, float("nan"), float("nan")
    if np.ptp(a / np.where(b == 0, np.nan, b)) == 0:
        return ratio, ratio, ratio
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        interval = bootstrap((a, b), lambda x, y, axis=-1: x.sum(axis=axis) / y.sum(axis=axis), paired=True,
                             vectorized=True, n_resamples=RESAMPLES, confidence_level=CONFIDENCE, method="BCa",
                             rng=stream_generator("ratio_bootstrap", seed)).confidence_interval
    return ratio, float(interval.low), float(interval.high)
