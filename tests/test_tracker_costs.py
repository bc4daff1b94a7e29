"""Association costs on boxes whose overlaps are written down by hand, and the one-to-one assigners
against brute force."""

import itertools

import numpy as np
import pytest
from simrig.trackers.assignment import greedy, hungarian
from simrig.trackers.costs import bev_distance, iou, mahalanobis, overlaps


def _box(x, y, z=1.0, length=2.0, width=2.0, height=2.0, yaw=0.0):
    return np.array([x, y, z, length, width, height, yaw, 0.0, 0.0])


def test_giou_of_unit_cubes_matches_the_arithmetic():
    a = np.stack([_box(0, 0)])
    b = np.stack([_box(1, 0), _box(4, 0), _box(0, 0, z=2.0)])
    iou, giou = overlaps(a, b)
    # Offset 1 m: intersection 1·2·2 = 4, union 12, hull 3·2·2 = 12.
    # Offset 4 m: no intersection, union 16, hull 6·2·2 = 24 → GIoU = 16/24 − 1.
    # Raised 1 m: intersection 2·2·1 = 4, union 12, hull 2·2·3 = 12.
    np.testing.assert_allclose(iou[0], [1 / 3, 0.0, 1 / 3])
    np.testing.assert_allclose(giou[0], [1 / 3, 16 / 24 - 1, 1 / 3])
    iou_bev, giou_bev = overlaps(a, b, bev=True)
    np.testing.assert_allclose(iou_bev[0], [1 / 3, 0.0, 1.0])
    np.testing.assert_allclose(giou_bev[0], [1 / 3, 8 / 12 - 1, 1.0])


def test_iou_alone_matches_the_arithmetic_and_overlaps():
    a = np.stack([_box(0, 0)])
    b = np.stack([_box(1, 0), _box(4, 0), _box(0, 0, z=2.0)])
    np.testing.assert_allclose(iou(a, b)[0], [1 / 3, 0.0, 1 / 3])
    np.testing.assert_allclose(iou(a, b, bev=True)[0], [1 / 3, 0.0, 1.0])
    # Boxes scattered so that some overlap, some touch circumcircles only, most are apart: the IoU-only path
    # (which skips pairs whose circumcircles are apart) gives overlaps()'s IoU bit for bit.
    rng = np.random.default_rng(3)
    many = np.stack([_box(*rng.uniform(-6, 6, 2), z=rng.uniform(0.5, 1.5), length=rng.uniform(1, 5),
                          width=rng.uniform(1, 2.5), height=rng.uniform(1, 3), yaw=rng.uniform(-3, 3))
                     for _ in range(40)])
    for bev in (False, True):
        expected, _ = overlaps(many, many[:25], bev=bev)
        assert (expected > 0).sum() > 40 and (expected == 0).sum() > 200
        np.testing.assert_array_equal(iou(many, many[:25], bev=bev), expected)
    assert iou(many[:0], many).shape == (0, 40)


def test_giou_is_unchanged_when_the_whole_scene_turns():
    rng = np.random.default_rng(0)
    a = np.stack([_box(*rng.uniform(-3, 3, 2), length=4.6, width=1.9, yaw=rng.uniform(-3, 3)) for _ in range(4)])
    b = np.stack([_box(*rng.uniform(-3, 3, 2), length=4.0, width=1.8, yaw=rng.uniform(-3, 3)) for _ in range(5)])
    angle = 0.7
    turn = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    a2, b2 = a.copy(), b.copy()
    for boxes in (a2, b2):
        boxes[:, :2] = boxes[:, :2] @ turn.T
        boxes[:, 6] += angle
    for bev in (False, True):
        np.testing.assert_allclose(overlaps(a, b, bev=bev)[1], overlaps(a2, b2, bev=bev)[1], atol=1e-9)


def test_a_box_turned_half_a_turn_is_the_same_box():
    a = np.stack([_box(0, 0, length=4.6, width=1.9, yaw=0.3)])
    b = np.stack([_box(0, 0, length=4.6, width=1.9, yaw=0.3 + np.pi)])
    iou, giou = overlaps(a, b)
    assert iou[0, 0] == pytest.approx(1.0) and giou[0, 0] == pytest.approx(1.0)


def test_the_floor_skips_only_pairs_provably_below_it():
    rng = np.random.default_rng(1)
    a = np.stack([_box(*rng.uniform(0, 40, 2), length=4.6, width=1.9, yaw=rng.uniform(-3, 3)) for _ in range(15)])
    b = np.stack([_box(*rng.uniform(0, 40, 2), length=4.6, width=1.9, yaw=rng.uniform(-3, 3)) for _ in range(20)])
    iou, giou = overlaps(a, b)
    iou_f, giou_f = overlaps(a, b, floor=-0.5)
    skipped = np.isneginf(giou_f)
    assert skipped.any() and not skipped.all()
    assert np.all(giou[skipped] < -0.5)
    np.testing.assert_allclose(giou_f[~skipped], giou[~skipped])
    np.testing.assert_allclose(iou_f, iou)


def test_mahalanobis_equals_the_textbook_formula_pair_by_pair():
    rng = np.random.default_rng(2)
    predicted = rng.normal(size=(3, 7))
    root = rng.normal(size=(3, 7, 7))
    innovation = root @ root.transpose(0, 2, 1) + 7 * np.eye(7)
    measured = rng.normal(size=(4, 9))
    got = mahalanobis(predicted, innovation, measured)
    for i, j in itertools.product(range(3), range(4)):
        diff = measured[j, :7] - predicted[i]
        diff[6] = (diff[6] + np.pi / 2) % np.pi - np.pi / 2  # heading difference, modulo a half turn
        assert got[i, j] == pytest.approx(np.sqrt(diff @ np.linalg.solve(innovation[i], diff)))


def test_bev_distance_ignores_height():
    assert bev_distance(np.stack([_box(0, 0, z=5)]), np.stack([_box(3, 4)]))[0, 0] == pytest.approx(5.0)


@pytest.mark.parametrize("seed", range(20))
def test_hungarian_finds_the_cheapest_matching_when_unmatched_costs_half_the_gate_each(seed):
    rng = np.random.default_rng(seed)
    cost = rng.uniform(0, 10, (3, 4))
    gate = 6.0

    def total(pairs):
        return sum(cost[i, j] for i, j in pairs) + gate / 2 * (3 + 4 - 2 * len(pairs))

    owner = hungarian(cost, gate)
    pairs = [(i, j) for j, i in enumerate(owner.tolist()) if i >= 0]
    assert len({i for i, _ in pairs}) == len(pairs) and all(cost[i, j] <= gate for i, j in pairs)
    best = min(
        total([(i, j) for i, j in zip(rows, cols, strict=False) if cost[i, j] <= gate])
        for k in range(4)
        for rows in itertools.permutations(range(3), min(k, 3))
        for cols in itertools.permutations(range(4), len(rows))
    )
    assert total(pairs) == pytest.approx(best)


def test_greedy_takes_the_cheapest_pair_first():
    cost = np.array([[1.0, 2.0], [1.5, 10.0]])
    assert greedy(cost, gate=5.0).tolist() == [0, -1]  # Hungarian would pair (0,1) and (1,0): 3.5 < 11
    assert hungarian(cost, gate=5.0).tolist() == [1, 0]
