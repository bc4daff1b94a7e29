"""Statistical verdicts: assert a failure rate with a confidence level, running only as many seeds as needed.

A tracker on a stochastic detector fails some seeds and not others, so one run is a flaky test. Here a rate is
decided by Wald's sequential probability ratio test ("Sequential Tests of Statistical Hypotheses", Abraham
Wald, 1945) on Bernoulli outcomes: H0 "the failure rate is ``good_rate``" against H1 "it is ``rate``". After
n runs with k failures the log-likelihood ratio is

    Λ = k·ln(p1/p0) + (n − k)·ln((1 − p1)/(1 − p0))

and the test stops at the first n where Λ ≥ ln(1/α) (fail: the rate is too high) or Λ ≤ ln β (pass). These
are the anytime-valid boundaries rather than Wald's approximate ln((1 − β)/α) and ln(β/(1 − α)): the
likelihood ratio is a nonnegative martingale with mean 1 under H0 (and its inverse under H1), so by Ville's
inequality the error rates are at most α (failing a tracker whose rate is ``good_rate``) and β (passing one
whose rate is ``rate``: ``confidence`` = 1 − β) exactly, not approximately — a test that is never flaky beyond
its stated rates — for a few more runs than Wald's boundaries need. On average it still needs fewer runs than
the fixed-sample test of the same error rates (:func:`fixed_sample_size`); reports/search/sprt.md has the
measured numbers.

Example — "a failure in at most 10% of seeds, at 95% confidence", on a process that fails 2% of the time:

>>> import numpy as np
>>> def fails(seed):  # in a real test: run_tracker("saga", scenario, seed=seed).metrics3d[...] > 0
...     return bool(np.random.default_rng(seed).random() < 0.02)
>>> verdict = assert_rate_below(fails, 0.10, confidence=0.95)
>>> verdict.passed, verdict.runs, verdict.failures
(True, 84, 2)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

MAX_RUNS = 100_000
"""A safety stop: Wald's test ends with probability 1, but a trial function that never decides should not hang."""


class InconclusiveError(AssertionError):
    """The sequential test reached ``max_runs`` without a decision."""


@dataclass(frozen=True)
class Verdict:
    """The decision of a sequential test: ``passed`` (the rate is acceptable), after ``runs`` runs (seeds
    ``first_seed`` …) with ``failures`` failures, and the final log-likelihood ratio ``llr``."""

    passed: bool
    runs: int
    failures: int
    llr: float
    p0: float
    p1: float
    alpha: float
    beta: float

    def __str__(self) -> str:
        outcome = "passed" if self.passed else "FAILED"
        return (f"{outcome}: {self.failures} failures in {self.runs} runs (Wald SPRT of failure rate "
                f"{self.p0:g} against {self.p1:g}, alpha {self.alpha:g}, beta {self.beta:g})")


def _check(p0: float, p1: float, alpha: float, beta: float) -> None:
    if not 0.0 < p0 < p1 < 1.0:
        raise ValueError(f"rates: need 0 < good_rate < rate < 1, got good_rate {p0} and rate {p1}")
    if not (0.0 < alpha < 0.5 and 0.0 < beta < 0.5):
        raise ValueError(f"error rates: need alpha and beta in (0, 0.5), got {alpha} and {beta}")


def sequential_test(trial: Callable[[int], bool], *, p0: float, p1: float, alpha: float = 0.05,
                    beta: float = 0.05, first_seed: int = 0, max_runs: int = MAX_RUNS) -> Verdict:
    """Wald's SPRT of failure rate ``p0`` (H0) against ``p1`` (H1) on ``trial(seed) -> failed``, seeds
    ``first_seed``, ``first_seed + 1``, … until a boundary is crossed."""
    _check(p0, p1, alpha, beta)
    upper, lower = math.log(1 / alpha), math.log(beta)  # Ville: P(sup LR >= 1/alpha | H0) <= alpha
    step_fail, step_pass = math.log(p1 / p0), math.log((1 - p1) / (1 - p0))
    llr, failures = 0.0, 0
    for runs in range(1, max_runs + 1):
        failed = bool(trial(first_seed + runs - 1))
        failures += failed
        llr += step_fail if failed else step_pass
        if llr >= upper or llr <= lower:
            return Verdict(llr <= lower, runs, failures, llr, p0, p1, alpha, beta)
    raise InconclusiveError(f"no decision after {max_runs} runs ({failures} failures): the failure rate is "
                            f"between {p0:g} and {p1:g}; widen the gap or raise max_runs")


def assert_rate_below(trial: Callable[[int], bool], rate: float, *, confidence: float = 0.95,
                      good_rate: float | None = None, false_alarm: float = 0.05, first_seed: int = 0,
                      max_runs: int = MAX_RUNS) -> Verdict:
    """Assert that ``trial(seed)`` fails with a rate below ``rate`` at ``confidence`` (a tracker failing at
    ``rate`` or more passes with probability at most 1 − ``confidence``); a tracker failing at ``good_rate``
    (default ``rate / 2``) fails the assertion with probability at most ``false_alarm``. Returns the verdict;
    an :class:`AssertionError` with it when the rate is too high."""
    verdict = sequential_test(trial, p0=rate / 2 if good_rate is None else good_rate, p1=rate,
                              alpha=false_alarm, beta=1 - confidence, first_seed=first_seed, max_runs=max_runs)
    if not verdict.passed:
        raise AssertionError(f"failure rate is not below {rate:g} at {confidence:.0%} confidence: {verdict}")
    return verdict


def fixed_sample_size(p0: float, p1: float, alpha: float = 0.05, beta: float = 0.05) -> tuple[int, int]:
    """The smallest fixed-sample test of the same error rates: (n runs, c) — fail when c or more failed, so
    that P(X ≥ c | p0) ≤ alpha and P(X < c | p1) ≤ beta for X ~ Binomial(n, p).

    >>> fixed_sample_size(0.1, 0.3)
    (41, 8)
    """
    from scipy.stats import binom

    _check(p0, p1, alpha, beta)
    n = 1
    while True:
        c = 0
        while binom.sf(c - 1, n, p0) > alpha:  # the smallest c with P(X ≥ c | p0) = sf(c − 1) ≤ alpha
            c += 1
        if binom.cdf(c - 1, n, p1) <= beta:
            return n, c
        n += 1
