"""CollabMOT (Ninh and Kim, IEEE Access 2024), step by step on hand-built tracklets, then end to end on a
hand-built stereo scene."""

import numpy as np
import pytest
from simrig.trackers.collabmot.affinity import affinity, box_side, position_cost, remote_side
from simrig.trackers.collabmot.association import associate, combine_ids, verify
from simrig.trackers.collabmot.interpolation import fill_gap
from simrig.trackers.collabmot.resurfacing import resurface
from simrig.trackers.collabmot.tracklets import NO_ID, Tracklet
from test_trackers_2d import STEREO, detection, frame

from simrig import trackers as tracker


def tracklet(camera, local_id, frames, *, global_id=NO_ID, min_cost=np.inf, feature=None, x=100.0, vx=0.0):
    """A tracklet with a 40×40 box at x + vx·frame for each of ``frames``."""
    t = Tracklet(camera, local_id, 0, global_id=global_id, min_cost=min_cost)
    for f in frames:
        t.boxes[f] = np.array([x + vx * f, 100.0, x + vx * f + 40.0, 140.0])
        t.scores[f] = 0.9
    t.feature = None if feature is None else np.asarray(feature, dtype=float)
    return t


def counter(start=100):
    values = iter(range(start, start + 1000))
    return lambda: next(values)


# -- Algorithm 2 -------------------------------------------------------------------------------------------
def linked_pair(old_cost):
    """Ego i linked (𝒢 5) with remote k at ``old_cost``; remote j coexists with k (another object)."""
    i = tracklet("ego", 1, range(0, 10), global_id=5, min_cost=old_cost)
    k = tracklet("remote", 1, range(0, 10), global_id=5, min_cost=old_cost)
    j = tracklet("remote", 2, range(5, 10))
    i.partner, k.partner = k, i
    return i, k, j


def test_algorithm_2_revokes_a_weaker_earlier_link():
    i, k, j = linked_pair(old_cost=0.08)
    check = verify(i, j, [k, j], cost=0.03)
    assert check.valid and check.global_id == NO_ID and check.revoked == [i, k]
    result = associate([i], [j], np.array([[0.03]]), ego_all=[i], remote_all=[k, j], limit=0.1, new_id=counter())
    assert result.restarts == 0 and k.global_id == NO_ID and k.partner is None
    assert i.global_id == j.global_id > 0 and i.partner is j and j.min_cost == pytest.approx(0.03)


def test_algorithm_2_rejects_a_weaker_new_link_and_algorithm_1_reruns_without_it():
    i, k, j = linked_pair(old_cost=0.02)
    assert not verify(i, j, [k, j], cost=0.05).valid
    result = associate([i], [j], np.array([[0.05]]), ego_all=[i], remote_all=[k, j], limit=0.1, new_id=counter())
    assert result.restarts == 1 and result.links == []
    assert i.global_id == k.global_id == 5 and j.global_id == NO_ID


def test_algorithm_2_keeps_an_existing_link_and_reconnects_a_lost_tracklet():
    i, k, _ = linked_pair(old_cost=0.05)
    assert verify(i, k, [k], cost=0.04).global_id == 5
    lost = tracklet("ego", 7, range(0, 5), global_id=9)
    remote = tracklet("remote", 3, range(0, 20), global_id=9)
    new = tracklet("ego", 8, range(8, 20))
    check = verify(remote, new, [lost, new], cost=0.04)
    assert check.global_id == 9 and check.reconnected == [lost]
    result = associate([new], [remote], np.array([[0.04]]), ego_all=[lost, new], remote_all=[remote], limit=0.1,
                       new_id=counter())
    assert new.global_id == 9 and result.reconnections == [(lost, new)]


def test_mutual_verification_checks_the_ego_side_too():
    """The remote tracklet's earlier ego partner coexists with the candidate and was the better match."""
    m = tracklet("ego", 1, range(0, 10), global_id=4, min_cost=0.01)
    r = tracklet("remote", 1, range(0, 10), global_id=4, min_cost=0.01)
    candidate = tracklet("ego", 2, range(3, 10))
    result = associate([candidate], [r], np.array([[0.05]]), ego_all=[m, candidate], remote_all=[r], limit=0.1,
                       new_id=counter())
    assert result.restarts == 1 and candidate.global_id == NO_ID and r.global_id == 4


# -- Eq. 6 -------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("g_ego", "g_remote", "expected"), [
    (4, -1, 4),   # only the ego side's verification found a global id
    (-1, 7, 7),   # only the remote side's
    (5, 5, 5),    # both the same
    (4, 7, -1),   # both, different: no link
    (-1, -1, 0),  # neither: a new id (0 stands for "new")
])
def test_every_case_of_eq_6(g_ego, g_remote, expected):
    assert combine_ids(g_ego, g_remote) == expected


def test_eq_6_through_a_round_new_id_and_conflict():
    a, b = tracklet("ego", 1, range(3)), tracklet("remote", 1, range(3))
    associate([a], [b], np.array([[0.02]]), ego_all=[a], remote_all=[b], limit=0.1, new_id=counter(100))
    assert a.global_id == b.global_id == 100
    # Two set, different global ids (each side linked to a lost tracklet of the other camera): no link.
    lost_remote = tracklet("remote", 5, range(0, 3), global_id=4)
    lost_ego = tracklet("ego", 5, range(0, 3), global_id=7)
    e = tracklet("ego", 6, range(5, 9), global_id=4)
    r = tracklet("remote", 6, range(5, 9), global_id=7)
    associate([e], [r], np.array([[0.02]]), ego_all=[lost_ego, e], remote_all=[lost_remote, r], limit=0.1,
              new_id=counter())
    assert e.global_id == r.global_id == NO_ID


# -- Sp (Appendix, Table 10) -------------------------------------------------------------------------------
def test_position_prior_rules_out_exactly_the_table_10_cases():
    for relp in (0, 1):
        sides = np.array([0, 1, 2])
        cost = position_cost(relp, sides, sides)
        for e in sides:
            for r in sides:
                ruled_out = (relp, e, r) in {(0, 1, 0), (1, 0, 1)}
                assert np.isinf(cost[e, r]) == ruled_out, (relp, e, r)


def test_relative_positions_of_the_stereo_pair_and_of_boxes():
    left, right = STEREO.cameras
    assert remote_side(left, right) == 1 and remote_side(right, left) == 0
    assert box_side(np.array([[500, 0, 600, 10], [640, 0, 700, 10], [600, 0, 640, 10]]), 621.0, 10.0).tolist() == [
        0, 1, 2]
    # The physics behind Table 10: a point ahead is further right in the left image than in the right one.
    point = np.array([20.0, 1.0, 1.0, 1.0])  # ego frame [m]
    u = [(c.intrinsics @ (np.linalg.inv(c.ego_from_camera()) @ point)[:3])[0] for c in (left, right)]
    assert u[0] > u[1]


def test_affinity_is_infinite_above_the_appearance_gate_or_without_a_feature():
    ego = [tracklet("ego", 1, [0], feature=[1, 0], x=650), tracklet("ego", 2, [0], feature=[0, 1], x=650),
           tracklet("ego", 3, [0], x=650)]
    remote = [tracklet("remote", 1, [0], feature=[1, 0.1], x=640)]
    cost = affinity(ego, remote, 0, relp=1, ego_camera=STEREO.cameras[0], remote_camera=STEREO.cameras[1],
                    appearance_limit=0.1, margin=10.0)
    assert cost[0, 0] == pytest.approx(1 - 1 / np.sqrt(1.01)) and np.isinf(cost[1, 0]) and np.isinf(cost[2, 0])


# -- interpolation (Eq. 7) ---------------------------------------------------------------------------------
def test_gap_is_filled_linearly_when_the_iou_gate_holds():
    lost = tracklet("ego", 1, range(0, 10), vx=5.0)
    current = tracklet("ego", 2, range(15, 25), vx=5.0)
    boxes = fill_gap(lost, current, depth=2, iou_limit=0.5, occlusion_limit=0.5, others_at=lambda f: np.zeros((0, 4)))
    assert sorted(boxes) == [10, 11, 12, 13, 14]
    assert np.allclose(boxes[12], [160, 100, 200, 140])


def test_gap_is_not_filled_when_the_interpolated_boxes_miss_the_tracklets_own():
    lost = tracklet("ego", 1, range(0, 10), vx=5.0)
    current = tracklet("ego", 2, range(15, 25), vx=5.0)
    current.boxes[17] = current.boxes[17] + [60, 0, 60, 0]  # t₂ = first + ω jumps away: IoU at 15, 16 fails
    boxes = fill_gap(lost, current, depth=2, iou_limit=0.5, occlusion_limit=0.5, others_at=lambda f: np.zeros((0, 4)))
    assert boxes == {}


def test_heavily_occluded_gap_boxes_are_dropped():
    lost = tracklet("ego", 1, range(0, 10), vx=5.0)
    current = tracklet("ego", 2, range(15, 25), vx=5.0)
    cover = np.array([[150.0, 90.0, 215.0, 150.0]])  # covers the boxes of frames 11-13 entirely
    boxes = fill_gap(lost, current, depth=2, iou_limit=0.5, occlusion_limit=0.5,
                     others_at=lambda f: cover if 11 <= f <= 13 else np.zeros((0, 4)))
    assert sorted(boxes) == [10, 14]


# -- local tracklet resurfacing ----------------------------------------------------------------------------
def test_a_briefly_overlapping_resurfaced_tracklet_is_kept_and_a_lasting_or_distant_one_revoked():
    lost, current = tracklet("ego", 1, list(range(0, 5)) + [20, 21], global_id=3), tracklet("ego", 2, range(8, 22),
                                                                                            global_id=3)
    assert resurface([lost, current], merged_iou=0.3, coappearance_limit=5) == []
    lost.boxes.update({f: current.boxes[f] for f in range(8, 13)})  # five overlapping co-appearances
    assert resurface([lost, current], merged_iou=0.3, coappearance_limit=5) == [current]
    assert current.global_id == NO_ID and lost.global_id == 3
    far = tracklet("ego", 3, [20, 21], global_id=3, x=600)
    assert resurface([lost, far], merged_iou=0.3, coappearance_limit=5) == [far]


# -- end to end ----------------------------------------------------------------------------------------------
def stereo_scene(frames=24, hidden=range(8, 11)):
    """Two cars seen by both cameras of the pair (disparity 15 px); car 0 is missed by the left camera in
    ``hidden``."""
    out = []
    for k in range(frames):
        left = [detection(200 + 6 * k, identity=1)]
        if k not in hidden:
            left.insert(0, detection(700 + 4 * k, identity=0))
        right = [detection(685 + 4 * k, identity=0), detection(185 + 6 * k, identity=1)]
        out.append(frame(k, {"left": left, "right": right}))
    return out


def left_ids(outputs):
    return {f: {round(t.boxes2d["left"].x1): t.track_id for t in tracks} for f, tracks in outputs}


def test_semi_online_collabmot_repairs_the_ego_cameras_identity_switch_and_fills_the_gap():
    scene = stereo_scene()
    sort = tracker.create("sort", cameras="left")
    sort.reset(rig=STEREO)
    plain = [(f.frame, sort.step(f)) for f in scene]
    car0 = lambda tracks: [t.track_id for t in tracks if t.boxes2d["left"].x1 > 500]  # noqa: E731
    assert car0(plain[5][1]) != car0(plain[20][1])  # SORT alone: a new id after the miss

    collab = tracker.create("collabmot", semi_online=True)
    collab.reset(rig=STEREO)
    for f in scene:
        collab.step(f)
    final = collab.finish()
    ids = [car0(tracks) for _, tracks in final]
    assert all(len(row) == 1 for row in ids) and len({row[0] for row in ids}) == 1  # one id, every frame
    gap = {f: [t for t in tracks if t.boxes2d["left"].x1 > 500][0].boxes2d["left"] for f, tracks in final}
    for f in range(8, 13):  # missed (8-10) and not yet reported by the new SORT track (11-12): interpolated
        assert gap[f].x1 == pytest.approx(700 + 4 * f, abs=2.0)
    other = {row for _, tracks in final for row in (t.track_id for t in tracks if t.boxes2d["left"].x1 < 500)}
    assert len(other) == 1 and other.isdisjoint({ids[0][0]})


def test_online_collabmot_repairs_the_switch_at_each_time_step_and_never_revises_the_past():
    scene = stereo_scene()
    collab = tracker.create("collabmot")
    assert not hasattr(collab, "finish")  # online: what step returned is the answer
    collab.reset(rig=STEREO)
    online = [(f.frame, collab.step(f)) for f in scene]
    car0 = {f: [t.track_id for t in tracks if t.boxes2d["left"].x1 > 500] for f, tracks in online}
    assert all(car0[f] == [] for f in range(8, 11))  # missed, and no interpolated box from the future
    assert car0[7] == car0[20] and len(car0[20]) == 1  # the new SORT track took the car's global id

    semi = tracker.create("collabmot", semi_online=True)
    semi.reset(rig=STEREO)
    stepped = [(f.frame, semi.step(f)) for f in scene]
    assert left_ids(stepped) == left_ids(online)  # the two differ only in what finish() revises


def test_a_pair_that_eq_6_gives_a_new_id_does_not_reuse_the_ego_tracklets_old_one():
    # The ego tracklet had global id 4 through a link that the round revokes (its old partner coexists with
    # the new one and cost more); neither side then has an id, so Eq. 6 says: a new one.
    old_partner = tracklet("remote", 1, range(0, 10), global_id=4, min_cost=0.08)
    e = tracklet("ego", 1, range(0, 10), global_id=4, min_cost=0.08)
    r = tracklet("remote", 2, range(0, 10))
    associate([e], [r], np.array([[0.02]]), ego_all=[e], remote_all=[old_partner, r], limit=0.1,
              new_id=counter(100))
    assert e.global_id == r.global_id == 100 and old_partner.global_id == NO_ID


def test_collabmot_without_interpolation_leaves_the_gap_and_keeps_the_repair():
    collab = tracker.create("collabmot", interpolate=False, semi_online=True)
    collab.reset(rig=STEREO)
    for f in stereo_scene():
        collab.step(f)
    final = dict(collab.finish())
    car0 = {f: [t.track_id for t in tracks if t.boxes2d["left"].x1 > 500] for f, tracks in final.items()}
    assert car0[9] == [] and car0[5] == car0[20]


def test_collabmot_needs_both_cameras_and_known_trackers():
    with pytest.raises(ValueError, match="ego_tracker must be one of sort, deepsort"):
        tracker.create("collabmot", ego_tracker="bytetrack")
    t = tracker.create("collabmot", ego_camera="CAM_FRONT")
    with pytest.raises(ValueError, match="camera 'CAM_FRONT' is not in rig 'stereo'"):
        t.reset(rig=STEREO)
