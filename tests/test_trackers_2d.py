"""The per-camera 2D trackers (SORT, DeepSORT) and their box geometry, on hand-built frames."""

import numpy as np
import pytest
from simrig.trackers.boxes2d import iou, occlusion_ratios
from simrig.trackers.errors import TrackerInputError

from simrig import trackers as tracker
from simrig.types import ActorClass, Box2D, Camera, Detection, EgoPose, Rig, SensorFrame

STEREO = Rig("stereo", tuple(
    Camera(name, 1242, 375, 721.5, 721.5, 621.0, 187.5, (0.0, y, 1.65), 0.0)
    for name, y in (("left", 0.27), ("right", -0.27))
))


def unit(index, dimension=16):
    vector = np.zeros(dimension, dtype=np.float32)
    vector[index] = 1.0
    return vector


def detection(x1, y1=150.0, *, w=80.0, h=50.0, score=0.9, identity=None, label=ActorClass.CAR):
    return Detection(Box2D(x1, y1, x1 + w, y1 + h), score, label,
                     embedding=None if identity is None else unit(identity))


def frame(index, views, rig=STEREO):
    return SensorFrame(index, index * 0.1, EgoPose(0, 0, 0, 0), rig,
                       {name: tuple(views.get(name, ())) for name in rig.camera_names})


def run(name, frames, **params):
    t = tracker.create(name, **params)
    t.reset(rig=STEREO, seed=0)
    return [t.step(f) for f in frames]


def ids_in(outputs, camera="left"):
    return [[track.track_id for track in tracks if camera in track.boxes2d] for tracks in outputs]


def test_iou_and_occlusion_ratio_match_a_pixel_count():
    """Eq. 4 (union of the overlaps over the box's area) against counting pixels of a rasterised scene."""
    rng = np.random.default_rng(3)
    corners = rng.integers(0, 60, size=(6, 2))
    boxes = np.column_stack([corners, corners + rng.integers(5, 40, size=(6, 2))]).astype(float)
    yy, xx = np.mgrid[0:120, 0:120] + 0.5
    masks = [(box[0] <= xx) & (xx < box[2]) & (box[1] <= yy) & (yy < box[3]) for box in boxes]
    for i, mask in enumerate(masks):
        others = np.any([m for k, m in enumerate(masks) if k != i], axis=0)
        assert occlusion_ratios(boxes)[i] == pytest.approx((mask & others).sum() / mask.sum())
        for j, other in enumerate(masks):
            assert iou(boxes[i], boxes[j])[0, 0] == pytest.approx((mask & other).sum() / (mask | other).sum())


def test_sort_keeps_one_id_on_a_moving_box_and_reports_after_min_hits():
    frames = [frame(k, {"left": [detection(100 + 8 * k)]}) for k in range(12)]
    ids = ids_in(run("sort", frames, min_hits=3))
    assert ids[0] == ids[1] == ids[2] == [1]  # the first min_hits frames of a sequence are reported
    assert all(row == [1] for row in ids)


def test_sort_loses_a_box_missed_for_two_frames_and_starts_a_new_track_after_min_hits():
    frames = [frame(k, {"left": [] if k in (6, 7) else [detection(100 + 8 * k)]}) for k in range(14)]
    ids = ids_in(run("sort", frames, max_age=1, min_hits=3))
    assert ids[5] == [1] and ids[6] == ids[7] == []
    assert ids[8] == ids[9] == []  # the new track needs 3 hits
    assert ids[10] == [2] and ids[13] == [2]


def test_sort_never_matches_across_classes():
    frames = [frame(k, {"left": [detection(100, label=ActorClass.CAR if k < 5 else ActorClass.TRUCK)]})
              for k in range(10)]
    ids = ids_in(run("sort", frames, min_hits=1))
    assert ids[4] == [1] and ids[5] == [2]


def test_deepsort_re_identifies_by_appearance_after_a_gap_sort_cannot_bridge():
    """Missed for 5 frames then seen again nearby with the same embedding: DeepSORT's cascade gives it its
    old id back; SORT (max_age 1) starts a new one."""
    def views(k):
        return {"left": [] if 6 <= k <= 10 else [detection(100 + 4 * k, identity=0), detection(600, identity=1)]}
    frames = [frame(k, views(k)) for k in range(16)]
    deep = ids_in(run("deepsort", frames))
    assert deep[5] == deep[15]  # both objects keep their ids
    plain = ids_in(run("sort", frames, min_hits=1))
    assert plain[5] != plain[15]


def test_deepsort_cascade_prefers_the_same_appearance_over_the_closer_box():
    """At frame 5 a stranger appears exactly where the track is predicted and the tracked object slightly
    off: appearance decides (the matching cascade runs before IoU)."""
    frames = [frame(k, {"left": [detection(100, identity=0)]}) for k in range(5)]
    frames.append(frame(5, {"left": [detection(100, identity=1), detection(112, identity=0)]}))
    out = run("deepsort", frames)
    assert len(out[5]) == 2
    kept = [track for track in out[5] if track.track_id == out[4][0].track_id]
    assert len(kept) == 1 and kept[0].boxes2d["left"].x1 > 106  # the filter moved towards 112, not 100


def test_each_camera_is_tracked_on_its_own_with_ids_unique_across_cameras():
    frames = [frame(k, {"left": [detection(100)], "right": [detection(90)]}) for k in range(5)]
    for name in ("sort", "deepsort"):
        out = run(name, frames, min_hits=1) if name == "sort" else run(name, frames)
        left, right = ids_in(out, "left"), ids_in(out, "right")
        assert left[-1] and right[-1] and set(left[-1]).isdisjoint(right[-1])


def test_cameras_parameter_limits_tracking_and_names_an_unknown_camera():
    frames = [frame(k, {"left": [detection(100)], "right": [detection(90)]}) for k in range(3)]
    out = run("sort", frames, cameras="left")
    assert all(set(track.boxes2d) == {"left"} for tracks in out for track in tracks)
    t = tracker.create("sort", cameras="front")
    with pytest.raises(ValueError, match="'front'"):
        t.reset(rig=STEREO)


def test_bad_embedding_is_named():
    bad = Detection(Box2D(0, 0, 10, 10), 0.9, ActorClass.CAR, embedding=np.array([np.nan, 1.0], dtype=np.float32))
    t = tracker.create("deepsort")
    t.reset(rig=STEREO)
    with pytest.raises(TrackerInputError, match="frame 0, camera 'left', detection 0: embedding"):
        t.step(frame(0, {"left": [bad]}))


# -- ByteTrack ---------------------------------------------------------------------------------------------------
def test_bytetrack_keeps_a_track_through_low_score_boxes_that_sort_drops():
    # A car whose score falls to 0.3 (partly occluded) for frames 5-9: ByteTrack's second stage keeps the id;
    # SORT (score threshold 0.5) loses it and starts anew.
    frames = [frame(k, {"left": [detection(100 + 8 * k, score=0.3 if 5 <= k < 10 else 0.9)]}) for k in range(15)]
    byte = ids_in(run("bytetrack", frames))
    assert all(row == [1] for row in byte)
    sort = ids_in(run("sort", frames, min_hits=1))
    assert sort[5] == [] and sort[12] != sort[2]


def test_bytetrack_never_starts_a_track_from_a_low_or_borderline_box_and_confirms_on_the_second_frame():
    low = [frame(k, {"left": [detection(100 + 8 * k, score=0.55)]}) for k in range(5)]  # < track_thresh + 0.1
    assert ids_in(run("bytetrack", low)) == [[]] * 5
    late = [frame(k, {"left": [detection(100 + 8 * k)] if k >= 2 else []}) for k in range(6)]
    assert ids_in(run("bytetrack", late)) == [[], [], [], [1], [1], [1]]  # born at 2, confirmed at 3
    first = [frame(k, {"left": [detection(100 + 8 * k)]}) for k in range(3)]
    assert ids_in(run("bytetrack", first)) == [[1], [1], [1]]  # activated at once on the first frame


def test_bytetrack_finds_a_lost_track_again_within_its_buffer():
    frames = [frame(k, {"left": [] if 4 <= k < 8 else [detection(100 + 8 * k)]}) for k in range(12)]
    ids = ids_in(run("bytetrack", frames))
    assert ids[3] == [1] and ids[5] == [] and ids[8] == [1]
    assert ids_in(run("bytetrack", frames, track_buffer=2))[9] == [2]  # lost for too long: a new track


@pytest.mark.parametrize("name", ["deepsort", "bytetrack", "botsort"])
def test_a_box_shrinking_to_nothing_never_gives_an_empty_box(name):
    # A box at the image border shrinking fast (a car leaving the view): the filter's height velocity would
    # carry the predicted height below zero on the first missed frame. A counterfactual bench run once
    # stopped there, the tracker output refused as an empty box; like SORT's area, the height and aspect
    # stop shrinking at zero instead.
    heights = [60.0, 40.0, 20.0, 8.0, 2.0]
    frames = [frame(k, {"left": [detection(100.0, 150.0, w=h * 1.5, h=h, identity=0)]}) for k, h in enumerate(heights)]
    frames += [frame(len(heights) + k, {"left": []}) for k in range(3)]
    for tracks in run(name, frames):
        for track in tracks:
            x1, y1, x2, y2 = track.boxes2d["left"].as_array()
            assert x2 > x1 and y2 > y1, (track, tracks)


# -- BoT-SORT-style ----------------------------------------------------------------------------------------------
def test_botsort_appearance_decides_between_two_overlapping_boxes_where_bytetrack_takes_the_closer():
    """At frame 5 a stranger appears 4 px from where the track is predicted (IoU distance 1 − 76/84 = 0.095) and
    the tracked object 12 px off (0.26): BoT-SORT's fused cost min(d_iou, d̂_cos) is 0 for the same appearance
    (d = 0 < 0.25 and IoU distance < 0.5) and 0.095 for the stranger (d = 0.5: appearance not used), so it keeps
    the object; ByteTrack on IoU alone takes the stranger's box. (With the stranger exactly on the prediction
    both costs would be 0: the minimum lets appearance only lower a cost.)"""
    frames = [frame(k, {"left": [detection(100, identity=0)]}) for k in range(5)]
    frames.append(frame(5, {"left": [detection(104, identity=1), detection(112, identity=0)]}))
    for name, towards_object in (("botsort", True), ("bytetrack", False)):
        out = run(name, frames)
        kept = [track for track in out[5] if track.track_id == out[4][0].track_id]
        assert len(kept) == 1 and (kept[0].boxes2d["left"].x1 > 104) == towards_object, (name, kept)


def test_botsort_compensates_the_ego_turning_from_the_known_ego_motion():
    """A far object straight ahead while the ego yaws left by ψ: it stays at bearing 0 in the world, so the left
    camera (yaw 0, fx 721.5 px) sees it at u = cx + fx·tan ψ (pinhole, a point at infinity). A sudden 0.12 rad
    turn moves its box 87 px, beyond any overlap with the last box: with the motion compensation the track keeps
    its id; without it the track is lost and a new one starts."""
    camera = STEREO.cameras[0]
    yaws = [0.0, 0.0, 0.0, 0.0, 0.12, 0.12, 0.12, 0.12]

    def view(k):
        u = camera.cx + camera.fx * np.tan(yaws[k])
        box = Detection(Box2D(u - 20.0, 160.0, u + 20.0, 190.0), 0.9, ActorClass.CAR)
        return SensorFrame(k, k * 0.1, EgoPose(0.0, 0.0, 0.0, yaws[k]), STEREO, {"left": (box,), "right": ()})

    frames = [view(k) for k in range(len(yaws))]
    assert ids_in(run("botsort", frames)) == [[1]] * len(yaws)
    plain = ids_in(run("botsort", frames, motion_compensation=False))
    assert plain[3] == [1] and plain[-1] not in ([], [1])


@pytest.mark.parametrize(("params", "message"), [({"motion_compensation": "maybe"}, "motion_compensation"),
                                                  ({"track_buffer": 2.5}, "track_buffer"),
                                                  ({"appearance_thresh": 2.0}, "appearance_thresh")])
def test_botsort_refuses_settings_it_cannot_use(params, message):
    with pytest.raises(ValueError, match=message):
        tracker.create("botsort", **params).reset(rig=STEREO)
