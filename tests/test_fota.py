"""FOTA (SAGA-Track Eq. 6–15) against POT: the Sinkhorn plan iterate for iterate, the exact partial-OT plan
as γ → 0, and the one-to-many decoding."""

import numpy as np
import ot
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from simrig.trackers.fota import augmented_problem, fota, sinkhorn


def _problem(seed, n=6, m=9, high=11.0):
    rng = np.random.default_rng(seed)
    cost = rng.uniform(0.0, high, (n, m))
    augmented, a, b = augmented_problem(cost, np.full(n, 2.0), np.ones(m), s=min(m, 2 * n) - 0.01, bound=high)
    return cost, augmented, a, b


def test_augmented_masses_balance_and_the_corner_is_two_bounds_plus_the_largest_cost():
    cost, augmented, a, b = _problem(0)
    assert a.sum() == pytest.approx(b.sum())
    assert augmented[-1, -1] == pytest.approx(2 * 11.0 + cost.max())
    assert np.all(augmented[:-1, -1] == 11.0) and np.all(augmented[-1, :-1] == 11.0)


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("gamma, iterations", [(0.1, 50), (0.1, 100), (0.5, 7)])
def test_plan_equals_pots_log_domain_sinkhorn(seed, gamma, iterations):
    _, augmented, a, b = _problem(seed)
    expected = ot.sinkhorn(a, b, augmented, gamma, method="sinkhorn_log", numItermax=iterations, stopThr=0,
                           warn=False)
    np.testing.assert_allclose(sinkhorn(a, b, augmented, gamma, iterations), expected, rtol=0, atol=1e-9)


def test_plan_equals_pot_where_exp_underflows_and_the_log_domain_path_is_taken():
    _, augmented, a, b = _problem(3, high=200.0)  # range/γ = 6000: exp(−C/γ) underflows in float64
    expected = ot.sinkhorn(a, b, augmented, 0.1, method="sinkhorn_log", numItermax=50, stopThr=0, warn=False)
    assert np.isfinite(expected).all()
    np.testing.assert_allclose(sinkhorn(a, b, augmented, 0.1, 50), expected, rtol=0, atol=1e-9)


def test_small_gamma_approaches_pots_exact_partial_wasserstein():
    cost, augmented, a, b = _problem(4, n=4, m=6)
    s = min(6, 8) - 0.01
    exact = ot.partial.partial_wasserstein(np.full(4, 2.0), np.ones(6), cost, m=s)
    gaps = []
    for gamma in (0.5, 0.1, 0.02):
        plan = sinkhorn(a, b, augmented, gamma, 5000)[:-1, :-1]
        gaps.append(np.abs(plan - exact).sum())
    assert gaps[0] > gaps[1] > gaps[2]
    assert gaps[2] < 0.02 * s
    assert np.sum(exact * cost) == pytest.approx(np.sum(sinkhorn(a, b, augmented, 0.02, 5000)[:-1, :-1] * cost),
                                                 rel=1e-3)


def test_a_track_seen_by_two_cameras_receives_both_detections():
    # Track 0 is seen by two cameras (detections 0 and 1), track 1 by one (detection 2); detection 3 is clutter.
    cost = np.array([
        [0.5, 0.8, 9.0, 30.0],
        [8.0, 9.5, 0.3, 30.0],
    ])
    result = fota(cost, gate=5.0)
    assert result.owner.tolist() == [0, 0, 1, -1]
    # With one-to-one Hungarian, the second view of track 0 would be left over (and start a duplicate).
    from simrig.trackers.assignment import hungarian
    assert hungarian(cost, gate=5.0).tolist().count(0) == 1


def test_a_detection_between_two_tracks_goes_to_the_nearer_one_only():
    result = fota(np.array([[1.0], [1.2]]), gate=5.0)
    assert result.owner.tolist() == [0]
    assert result.plan[0, 0] > 4 * result.plan[1, 0]  # entropic: a 0.2 cost gap is e² ≈ 7 at γ = 0.1


def test_nothing_within_the_gate_means_nothing_matched():
    assert fota(np.full((3, 4), 9.0), gate=5.0).owner.tolist() == [-1] * 4
    assert fota(np.zeros((0, 4)), gate=5.0).owner.tolist() == [-1] * 4
    assert fota(np.zeros((3, 0)), gate=5.0).owner.tolist() == []


def test_bad_settings_are_named():
    with pytest.raises(ValueError, match="gamma"):
        fota(np.ones((1, 1)), gate=5.0, gamma=0.0)


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(0, 6),
    m=st.integers(0, 8),
    seed=st.integers(0, 2**31),
    gate=st.floats(0.5, 8.0),
)
def test_every_detection_goes_to_at_most_one_track_and_only_within_the_gate(n, m, seed, gate):
    rng = np.random.default_rng(seed)
    cost = rng.uniform(0.0, 10.0, (n, m))
    cost[rng.random((n, m)) < 0.1] = np.inf  # e.g. a class mismatch
    owner = fota(cost, gate=gate).owner
    assert owner.shape == (m,)
    assert np.all((owner >= -1) & (owner < max(n, 1)))
    for j, i in enumerate(owner.tolist()):
        if i >= 0:
            assert cost[i, j] <= gate


# -- the physical constraint: one detection per camera per track -----------------------------------------------
def _two_views_of_three_cars(seed):
    """3 tracks, 2 cameras: cars 1 and 2 seen by both cameras, car 0 by camera 0 only, which also reports a
    second, slightly worse detection next to it (a ghost, or a neighbour the track has not met): 6 detections."""
    rng = np.random.default_rng(seed)
    cost = rng.uniform(3.0, 9.0, (3, 6))
    cameras = np.array([0, 0, 0, 1, 1, 0])
    cost[0, 0] = rng.uniform(0.1, 0.5)
    for car in (1, 2):
        cost[car, car] = cost[car, 2 + car] = rng.uniform(0.1, 0.5)
    cost[0, 5] = 0.8
    return cost, cameras


@pytest.mark.parametrize("seed", range(5))
def test_with_the_constraint_no_track_takes_two_detections_of_one_camera(seed):
    cost, cameras = _two_views_of_three_cars(seed)
    free = fota(cost, gate=5.0).owner
    assert free.tolist() == [0, 1, 2, 1, 2, 0]  # unconstrained, track 0 fuses both of camera 0's detections
    owner = fota(cost, gate=5.0, cameras=cameras).owner
    assert owner.tolist() == [0, 1, 2, 1, 2, -1]  # the worse one is left over (it may start a track)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(n=st.integers(1, 6), m=st.integers(1, 10), cameras=st.integers(1, 3), seed=st.integers(0, 2**31))
def test_the_constraint_holds_on_any_problem_and_only_removes_matches_that_break_it(n, m, cameras, seed):
    rng = np.random.default_rng(seed)
    cost = rng.uniform(0.0, 6.0, (n, m))
    camera = rng.integers(0, cameras, m)
    free = fota(cost, gate=4.0).owner
    owner = fota(cost, gate=4.0, cameras=camera).owner
    for track in range(n):
        seen = camera[owner == track]
        assert len(seen) == len(set(seen.tolist()))
    for j in np.nonzero(owner >= 0)[0]:
        assert cost[owner[j], j] <= 4.0
    pairs = {(int(i), int(camera[j])) for j, i in enumerate(free.tolist()) if i >= 0}
    if len(pairs) == int(np.sum(free >= 0)):  # no conflict: the constraint changes nothing
        assert owner.tolist() == free.tolist()
