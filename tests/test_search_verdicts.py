"""The sequential verdict (Wald's SPRT): its boundaries by hand, the fixed-sample size by direct binomial sums,
and its error rates and run counts on a process whose failure rate is known by construction."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simrig.testing import assert_rate_below, sequential_test
from simrig.testing.sequential import InconclusiveError, fixed_sample_size


def _bernoulli(rate: float, stream: int):
    """A 'tracker' that fails seed s with probability ``rate``: independent draws, known rate by construction."""
    return lambda seed: bool(np.random.default_rng([stream, seed]).random() < rate)


def test_the_boundaries_follow_walds_formulas_on_a_tiny_case():
    # p0 = 0.1, p1 = 0.3, alpha = beta = 0.05: reject at ln 20 = 2.996, accept at ln 0.05 = -2.996; a failure
    # adds ln 3 = 1.0986, a pass ln(0.7 / 0.9) = -0.2513; so three failures in a row reject (3.30 >= 2.996,
    # 2.20 < 2.996), and passes alone accept after ceil(2.996 / 0.2513) = 12 runs.
    fail_fast = sequential_test(lambda seed: True, p0=0.1, p1=0.3)
    assert (fail_fast.passed, fail_fast.runs, fail_fast.failures) == (False, 3, 3)
    assert fail_fast.llr == pytest.approx(3 * math.log(3))
    pass_fast = sequential_test(lambda seed: False, p0=0.1, p1=0.3)
    assert (pass_fast.passed, pass_fast.runs) == (True, math.ceil(math.log(20) / -math.log(7 / 9)))
    seen = []
    sequential_test(lambda seed: seen.append(seed) or False, p0=0.1, p1=0.3, first_seed=100)
    assert seen == list(range(100, 112))


def test_the_fixed_sample_size_is_the_smallest_binomial_test_of_those_error_rates():
    def tail(n, p, low, high):
        return sum(math.comb(n, k) * p**k * (1 - p) ** (n - k) for k in range(low, high + 1))

    n, c = fixed_sample_size(0.1, 0.3)
    assert tail(n, 0.1, c, n) <= 0.05 and tail(n, 0.3, 0, c - 1) <= 0.05
    smaller = n - 1  # no critical count works with one run fewer
    assert not any(tail(smaller, 0.1, k, smaller) <= 0.05 and tail(smaller, 0.3, 0, k - 1) <= 0.05
                   for k in range(smaller + 2))


def test_assert_rate_below_raises_with_the_verdict_and_rejects_bad_settings():
    with pytest.raises(AssertionError, match="failure rate is not below 0.2 at 95% confidence: FAILED"):
        assert_rate_below(lambda seed: True, 0.2)
    with pytest.raises(ValueError, match="need 0 < good_rate < rate < 1"):
        assert_rate_below(lambda seed: False, 0.2, good_rate=0.3)
    with pytest.raises(InconclusiveError, match="no decision after 5 runs"):
        sequential_test(lambda seed: seed % 2 == 0, p0=0.3, p1=0.5, max_runs=5)


@pytest.mark.parametrize(("true_rate", "should_pass", "most_wrong"), [
    # outside the indifference zone (0.05, 0.10): right in >= 95% of 200 repeats
    (0.0, True, 10), (0.025, True, 10), (0.15, False, 10), (0.2, False, 10),
    # at its edges the error rates are alpha and beta themselves (5%): with 200 repeats the count of wrong
    # decisions is then at most Binomial(200, 0.05), whose 99th percentile is 18
    (0.05, True, 18), (0.10, False, 18),
])
def test_200_repeats_decide_right_with_fewer_runs_than_the_fixed_test(true_rate, should_pass, most_wrong):
    p0, p1 = 0.05, 0.10  # "fails in under 10% of seeds at 95% confidence", indifferent below 5%
    fixed_n, _ = fixed_sample_size(p0, p1)
    verdicts = [sequential_test(_bernoulli(true_rate, stream), p0=p0, p1=p1) for stream in range(200)]
    wrong = sum(v.passed != should_pass for v in verdicts)
    assert wrong <= most_wrong
    assert np.mean([v.runs for v in verdicts]) < fixed_n


@pytest.mark.slow
def test_the_readme_example_decides_on_a_real_tracker_in_a_few_seeds(simrig_scenario):
    from simrig.testing import run_tracker

    scenario = simrig_scenario("cut_in", frames=50, traffic={"vehicles": 4}, render={"visibility": False})

    def switched(seed):  # one Bernoulli trial per scenario seed: more than one identity switch
        return run_tracker("saga", scenario, seed=seed).metrics3d["overall"]["IDS"] > 1

    verdict = assert_rate_below(switched, 0.5, confidence=0.95, good_rate=0.1)
    # accepted at the first pass that brings k ln 5 + passes ln(5 / 9) to ln 0.05 or below (6 runs with k = 0)
    k = verdict.failures
    assert verdict.passed and verdict.runs == k + math.ceil((math.log(20) + k * math.log(5)) / -math.log(5 / 9))
