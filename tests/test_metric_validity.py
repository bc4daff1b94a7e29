"""Which metric predicts driving: the rank correlations against scipy, the orientation and capping on a bench whose
answer is known by construction, the report section, and the degraded tracker the study uses."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from scipy.stats import kendalltau, spearmanr
from simrig.trackers.degraded import DegradedTracker

from simrig.report.metric_validity import METRICS, OUTCOMES, TooFewCells, correlate, kendall_tau_b, spearman_rho
from simrig.types import ActorClass, Box3D, Track


def test_the_vectorised_correlations_equal_scipy_with_ties_and_missing_values():
    rng = np.random.default_rng(0)
    x = rng.integers(0, 5, size=(12, 40)).astype(float)  # many ties
    y = x + rng.integers(-3, 4, size=x.shape)
    x[3, 7] = np.nan  # one column with a missing configuration
    rho, tau = spearman_rho(x, y), kendall_tau_b(x, y)
    for column in range(x.shape[1]):
        keep = np.isfinite(x[:, column])
        assert rho[column] == pytest.approx(spearmanr(x[keep, column], y[keep, column]).statistic, abs=1e-12)
        assert tau[column] == pytest.approx(kendalltau(x[keep, column], y[keep, column]).statistic, abs=1e-12)
    assert np.isnan(spearman_rho(np.ones((5, 1)), np.arange(5.0)[:, None])[0])  # a constant metric says nothing
    assert np.isnan(kendall_tau_b(np.ones((5, 1)), np.arange(5.0)[:, None])[0])


def bench_rows(configurations: int = 6, seeds: int = 5, scenarios: tuple[str, ...] = ("a", "b")) -> pd.DataFrame:
    """A closed-loop bench's results where configuration k loses k metres of progress on every seed, AMOTA falls
    with k (so it agrees with driving), PKL rises with k (lower is better: agrees too), HOTA rises with k
    (disagrees), every drive has least TTC inf (capped: constant, so it says nothing) and IDF1 is noise."""
    rng = np.random.default_rng(1)
    rows = []
    for scenario in scenarios:
        for k in range(configurations):
            for seed in range(100, 100 + seeds):
                row = {column: float(rng.random()) for _, column, _ in (*METRICS, *OUTCOMES)}
                row |= {"scenario": scenario, "tracker": f"t{k}", "sweep": "", "value": np.nan, "seed": seed,
                        "3d_AMOTA": 1.0 - 0.1 * k + 0.001 * seed, "3d_PKL": 2.0 * k, "2d_HOTA": 0.1 * k,
                        "drive_progress_lost_m": float(k), "drive_min_ttc_s": np.inf}
                rows.append(row)
    return pd.DataFrame(rows)


def test_agreement_and_disagreement_known_by_construction():
    found = correlate(bench_rows(), replicates=300)
    for scenario in ("a", "b", "all"):
        assert found.spearman[(scenario, "AMOTA", "progress lost")] == pytest.approx(1.0)
        assert found.kendall[(scenario, "PKL", "progress lost")] == pytest.approx(1.0)
        assert found.spearman[(scenario, "HOTA", "progress lost")] == pytest.approx(-1.0)
        assert np.isnan(found.spearman[(scenario, "AMOTA", "least TTC")])
    assert found.interval("spearman", "all", "AMOTA", "progress lost") == pytest.approx((1.0, 1.0))
    point, low, high = found.difference("all", "AMOTA", "HOTA", "progress lost")
    assert point == pytest.approx(2.0) and low == pytest.approx(2.0) and high == pytest.approx(2.0)
    low, high = found.interval("spearman", "all", "IDF1", "progress lost")
    assert low < found.spearman[("all", "IDF1", "progress lost")] < high  # noise: a real interval around it
    assert found.configurations == {"a": 6, "b": 6}


def test_the_bootstrap_is_the_same_twice_and_too_few_cells_are_refused():
    first, second = correlate(bench_rows(), replicates=200), correlate(bench_rows(), replicates=200)
    key = ("all", "IDF1", "collision")
    assert np.array_equal(first.spearman_boot[key], second.spearman_boot[key], equal_nan=True)
    with pytest.raises(TooFewCells, match="4 seeds: the intervals over seeds need at least 5"):
        correlate(bench_rows(seeds=4))
    with pytest.raises(TooFewCells, match="scenario a: 3 configurations"):
        correlate(bench_rows(configurations=3))


def test_the_report_section_states_the_best_predictor_and_draws_the_figure(tmp_path):
    from simrig.report.load import BenchResults
    from simrig.report.validity_section import FIGURE, metric_validity_section

    bench = BenchResults(tmp_path, bench_rows(), pd.DataFrame(),
                         {"suite_settings": {"closed_loop": True, "scores_on": "reference"}})
    text = "\n".join(metric_validity_section(bench, tmp_path))
    assert "- **progress lost**: AMOTA, ρ +1.00 [+1.00, +1.00]" in text or "- **progress lost**: PKL, ρ +1.00" in text
    assert "ground-truth drive, the log, where the tracker ran open loop" in text and "6 on a, 6 on b" in text
    assert (tmp_path / FIGURE).read_bytes()[:4] == b"\x89PNG"
    calm = bench_rows().assign(drive_collision=0.0)  # no drive collided: that outcome orders nothing
    text = "\n".join(metric_validity_section(BenchResults(tmp_path, calm, pd.DataFrame(), {"suite_settings": {}}),
                                              tmp_path))
    assert "- **collision**: the same in every configuration (e.g. no drive collided): nothing to predict" in text
    assert "nan" not in text
    few = BenchResults(tmp_path, bench_rows(configurations=2), pd.DataFrame(), {"suite_settings": {}})
    assert "Not computed: scenario a: 2 configurations" in "\n".join(metric_validity_section(few, tmp_path))


class Counting:
    """A stand-in tracker: at frame t one track (id 7) at x = t with velocity (1, 0), and a second (id 8) from t=2."""

    def reset(self, *, rig, seed=None):
        self.frames = 0

    def step(self, frame):
        t = frame.timestamp
        tracks = [Track(7, ActorClass.CAR, 0.9, Box3D(t, 0, 0, 4, 2, 1.5, 0, 1.0, 0.0))]
        if t >= 2:
            tracks.append(Track(8, ActorClass.CAR, 0.9, Box3D(-t, 0, 0, 4, 2, 1.5, 0, 1.0, 0.0)))
        return tracks


def frames(count: int, dt: float = 1.0):
    return [SimpleNamespace(timestamp=i * dt, frame=i) for i in range(count)]


def run(tracker, count: int = 400, dt: float = 1.0, seed: int = 5):
    tracker.reset(rig=None, seed=seed)
    return [tracker.step(frame) for frame in frames(count, dt)]


def test_latency_returns_what_the_tracker_said_that_long_before():
    late = run(DegradedTracker(Counting(), latency_s=2.0, identity_change_hz=0, velocity_sigma_mps=0), count=6)
    assert late[0] == [] and late[1] == []
    assert [[t.box3d.x for t in tracks] for tracks in late[2:]] == [[0.0], [1.0], [2.0, -2.0], [3.0, -3.0]]


def test_identity_changes_at_the_rate_asked_and_velocity_noise_has_the_sigma_asked():
    rate, dt = 0.2, 0.5  # P(change per frame) = 1 - exp(-0.1)
    output = run(DegradedTracker(Counting(), latency_s=0, identity_change_hz=rate, velocity_sigma_mps=0), dt=dt,
                 count=2000)
    ids = [tracks[0].track_id for tracks in output]
    changes = sum(a != b for a, b in zip(ids[1:], ids[:-1], strict=True))
    expected = 1999 * -np.expm1(-rate * dt)
    assert abs(changes - expected) < 4 * np.sqrt(expected)  # binomial, 4 σ
    assert len({tracks[1].track_id for tracks in output[4:]} & set(ids)) == 0  # the two never share an id
    noisy = run(DegradedTracker(Counting(), latency_s=0, identity_change_hz=0, velocity_sigma_mps=2.0), count=3000)
    vx = np.array([tracks[0].box3d.vx for tracks in noisy]) - 1.0
    assert abs(vx.mean()) < 4 * 2.0 / np.sqrt(3000) and vx.std() == pytest.approx(2.0, rel=0.06)
    assert [t.box3d.x for t in noisy[5]] == [5.0, -5.0]  # positions untouched


def test_one_degradation_switched_off_leaves_the_others_draws_as_they_were():
    both = run(DegradedTracker(Counting(), latency_s=0, identity_change_hz=0.3, velocity_sigma_mps=1.0))
    ids_only = run(DegradedTracker(Counting(), latency_s=0, identity_change_hz=0.3, velocity_sigma_mps=0.0))
    speed_only = run(DegradedTracker(Counting(), latency_s=0, identity_change_hz=0.0, velocity_sigma_mps=1.0))
    assert [[t.track_id for t in f] for f in both] == [[t.track_id for t in f] for f in ids_only]
    assert [[t.box3d.vx for t in f] for f in both] == [[t.box3d.vx for t in f] for f in speed_only]
    again = run(DegradedTracker(Counting(), latency_s=0, identity_change_hz=0.3, velocity_sigma_mps=1.0))
    assert repr(again) == repr(both)  # Track compares by identity


def test_degraded_refuses_what_it_cannot_do():
    from simrig.trackers import create

    with pytest.raises(ValueError, match="latency_s=-1.0 must be a number in"):
        create("degraded", latency_s=-1.0)
    with pytest.raises(ValueError, match="parameter tracker must name another tracker, not this one"):
        create("degraded", tracker="degraded")
    with pytest.raises(KeyError, match="unknown tracker 'nope'"):
        create("degraded", tracker="nope")


def test_the_bca_interval_agrees_with_scipys_on_a_skewed_mean():
    """BCa from the bootstrap and jackknife replicates, against scipy.stats.bootstrap(method="BCa") on the mean of
    a skewed sample (both with 20,000 resamples: they differ by Monte Carlo error only)."""
    from scipy.stats import bootstrap

    from simrig.report.metric_validity import bca_interval

    sample = np.random.default_rng(3).exponential(1.0, size=25)
    draws = np.random.default_rng(4).integers(0, len(sample), size=(20_000, len(sample)))
    jack = (sample.sum() - sample) / (len(sample) - 1)
    low, high = bca_interval(sample.mean(), sample[draws].mean(axis=1), jack)
    theirs = bootstrap((sample,), np.mean, method="BCa", n_resamples=20_000, rng=np.random.default_rng(5))
    width = theirs.confidence_interval.high - theirs.confidence_interval.low
    assert abs(low - theirs.confidence_interval.low) < 0.05 * width
    assert abs(high - theirs.confidence_interval.high) < 0.05 * width
    plain = np.percentile(sample[draws].mean(axis=1), [2.5, 97.5])
    assert high > plain[1]  # skewed to the right: BCa moves the interval up, as it should
