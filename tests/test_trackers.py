"""The reference trackers on hand-built frames: one car seen by two cameras, silent cameras, empty frames,
floods of detections and bad numbers."""

from dataclasses import replace

import numpy as np
import pytest
from simrig.trackers.errors import TrackerInputError
from simrig.trackers.life import QueryLife, TrackLife

from simrig import trackers as tracker
from simrig.geometry import project_boxes
from simrig.types import ActorClass, Box2D, Box3D, Camera, Detection, EgoPose, Rig, SensorFrame

NAMES = ("saga", "global_hungarian", "percam_merge", "simpletrack", "mutr3d", "polymot")
RIG = Rig("pair", tuple(
    Camera(name, 1600, 900, 1000.0, 1000.0, 800.0, 450.0, (0.0, 0.0, 1.5), yaw)
    for name, yaw in (("A", 0.3), ("B", -0.3))
))
DT = 0.1  # [s]


def _detection(x, y, *, score=0.9, yaw=0.0, vx=10.0, label=ActorClass.CAR):
    return Detection(Box2D(0, 0, 10, 10), score, label, Box3D(x, y, 0.8, 4.6, 1.9, 1.6, yaw, vx, 0.0))


def _frame(index, per_camera):
    """A frame of RIG with the ego at the origin; each detection's pixel box is its 3D box projected into its
    camera (kept as given where the box is out of that camera's view)."""
    ego = EgoPose(0, 0, 0, 0)
    views = {}
    for camera, name in enumerate(RIG.camera_names):
        detections = tuple(per_camera.get(name, ()))
        with_3d = [d for d in detections if d.box3d is not None]
        if with_3d:
            boxes = np.array([[d.box3d.x, d.box3d.y, d.box3d.z, d.box3d.length, d.box3d.width, d.box3d.height,
                               d.box3d.yaw] for d in with_3d])
            pixels = iter(project_boxes(boxes, RIG, ego).boxes[camera])
            detections = tuple(
                d if d.box3d is None else (lambda p, d=d: replace(d, box=Box2D(*map(float, p)))
                                           if np.isfinite(p).all() else d)(next(pixels))
                for d in detections)
        views[name] = detections
    return SensorFrame(index, index * DT, ego, RIG, views)


def _car_seen_twice(frames=30, silent=()):
    """A car at 10 m/s along x, 20 m ahead, seen by both cameras with 0.3 m of disagreement; cameras in
    ``silent`` report nothing in frames 10–59."""
    out = []
    for k in range(frames):
        x = 20.0 + 10.0 * k * DT
        views = {"A": [_detection(x + 0.15, 0.1)], "B": [_detection(x - 0.15, -0.1)]}
        for name in silent:
            if 10 <= k < 60:
                views[name] = []
        out.append(_frame(k, views))
    return out


def _run(name, frames, **params):
    t = tracker.create(name, **params)
    t.reset(rig=RIG, seed=0)
    return [t.step(frame) for frame in frames]


@pytest.mark.parametrize("name", ["saga", "percam_merge", "simpletrack", "mutr3d", "polymot"])
def test_a_car_seen_by_two_cameras_is_one_track_with_one_id(name):
    outputs = _run(name, _car_seen_twice())
    assert all(len(tracks) == 1 for tracks in outputs)
    assert len({tracks[0].track_id for tracks in outputs}) == 1


def test_one_to_one_pooling_keeps_a_duplicate_of_a_car_seen_twice():
    outputs = _run("global_hungarian", _car_seen_twice())
    assert all(len(tracks) == 2 for tracks in outputs)  # the second view has nowhere to go but a new track


def test_saga_fuses_both_views_and_learns_the_velocity():
    outputs = _run("saga", _car_seen_twice())
    box = outputs[-1][0].box3d
    assert box.x == pytest.approx(20.0 + 10.0 * 29 * DT, abs=0.3)
    assert box.vx == pytest.approx(10.0, abs=0.5) and box.vy == pytest.approx(0.0, abs=0.5)


@pytest.mark.parametrize("name", NAMES)
def test_a_camera_silent_for_50_frames_changes_nothing_while_the_other_sees_the_car(name):
    outputs = _run(name, _car_seen_twice(frames=80, silent=("A",)))
    assert all(tracks for tracks in outputs)
    ids = {t.track_id for tracks in outputs for t in tracks}
    # global_hungarian keeps a duplicate while both cameras see the car: it dies when camera A falls silent
    # and a new one is born when A speaks again.
    assert len(ids) == (3 if name == "global_hungarian" else 1)
    assert len(outputs[-1]) == (2 if name == "global_hungarian" else 1)


@pytest.mark.parametrize("name", NAMES)
def test_empty_frames_give_no_tracks_and_existing_tracks_die_after_their_age(name):
    frames = _car_seen_twice(frames=5) + [_frame(k, {}) for k in range(5, 40)]
    outputs = _run(name, frames)
    assert outputs[4] and not outputs[-1]
    assert _run(name, [_frame(k, {}) for k in range(3)]) == [[], [], []]


@pytest.mark.parametrize("name", NAMES)
def test_no_tracks_and_500_detections_in_one_frame(name):
    rng = np.random.default_rng(0)
    xy = rng.uniform(-150, 150, (500, 2))
    views = {"A": [_detection(x, y, score=0.6) for x, y in xy[:250]],
             "B": [_detection(x, y, score=0.6) for x, y in xy[250:]]}
    outputs = _run(name, [_frame(0, views), _frame(1, views)])
    assert 0 < len(outputs[0]) <= 500 and 0 < len(outputs[1]) <= 500
    assert len({t.track_id for t in outputs[1]}) == len(outputs[1])


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("field", ["x", "yaw", "score"])
def test_a_nan_in_a_detection_names_the_camera_and_the_frame(name, field):
    frames = _car_seen_twice(frames=3)
    bad = _detection(20.0, 0.0, score=np.nan) if field == "score" else Detection(
        Box2D(0, 0, 10, 10), 0.9, ActorClass.CAR,
        Box3D(**{**dict(x=20.0, y=0.0, z=0.8, length=4.6, width=1.9, height=1.6, yaw=0.0), field: np.nan}))
    frames[2] = _frame(2, {"A": [_detection(21, 0)], "B": [_detection(21, 0), bad]})
    t = tracker.create(name)
    t.reset(rig=RIG)
    t.step(frames[0]), t.step(frames[1])
    with pytest.raises(TrackerInputError, match=rf"frame 2, camera 'B', detection 1: \S*{field} is nan"):
        t.step(frames[2])


@pytest.mark.parametrize("name", NAMES)
def test_time_must_move_forward(name):
    t = tracker.create(name)
    t.reset(rig=RIG)
    t.step(_frame(3, {}))
    with pytest.raises(TrackerInputError, match="frame 2: timestamp 0.2 s is not after"):
        t.step(_frame(2, {}))


def test_a_3d_tracker_needs_3d_boxes():
    t = tracker.create("saga")
    t.reset(rig=RIG)
    with pytest.raises(TrackerInputError, match="camera 'A', detection 0: no box3d"):
        t.step(_frame(0, {"A": [Detection(Box2D(0, 0, 1, 1), 0.9, ActorClass.CAR)]}))


def test_unknown_parameters_and_values_are_named():
    with pytest.raises(ValueError, match="'saga' has no parameter 'gamm'.*gamma"):
        tracker.create("saga", gamm=0.1)
    with pytest.raises(ValueError, match="unknown cost 'l2'"):
        tracker.create("saga", cost="l2")
    with pytest.raises(ValueError, match="unknown life rule"):
        tracker.create("global_hungarian", life="forever")


@pytest.mark.parametrize("name", [name for name in NAMES if name != "polymot"])  # polymot: one cost, one life
def test_every_cost_and_the_mutr3d_life_rule_run(name):
    params = ({"life": "mutr3d"} if name == "simpletrack" else {"cost2d": "centre", "life": "mutr3d_code"}
              if name == "mutr3d" else {"cost": "giou_bev", "life": "mutr3d"})
    outputs = _run(name, _car_seen_twice(frames=10), **params)
    assert all(len(tracks) >= 1 for tracks in outputs)


def test_the_public_codes_mutr3d_rule_counts_misses_below_tau_old_and_resets_only_at_tau_new():
    rule, life = QueryLife(reset="tau_new"), TrackLife(score=0.9)
    assert not rule.may_start(0.39) and rule.may_start(0.4)
    for score in (0.2, 0.3, 0.37, None):  # 0.37 is between τ_old and τ_new: neither a miss nor a reset
        rule.observe(life, score, DT)
    assert life.misses == 3 and not rule.is_dead(life) and not rule.is_reported(life)


def _mutr3d_scores(life_name, scores):
    """Feed ``scores`` (one per frame) to the life rule ``life_name`` builds; the frame index (1-based) at
    which the track is dead, or None."""
    from simrig.trackers.settings import build_life
    rule, life = build_life(life_name, min_hits=1, max_age_s=1.0), TrackLife(score=0.9)
    for frame, score in enumerate(scores, start=1):
        rule.observe(life, score, DT)
        if rule.is_dead(life):
            return frame
    return None


@pytest.mark.parametrize("recovery", [0.37, 0.9])  # between τ_old and τ_new; above τ_new
def test_mutr3d_life_as_the_paper_says_t_successive_frames_below_tau_old(recovery):
    low = [0.2, None, 0.3, 0.1]  # 4 frames below τ_old = 0.35 (None: nothing assigned, score 0)
    assert _mutr3d_scores("mutr3d", low + [recovery] + low + [recovery] * 3) is None  # 4, recover, 4: survives
    assert _mutr3d_scores("mutr3d", [0.9] + low + [0.34] + [0.9]) == 6  # 5 consecutive: dies at the 5th
    # The public code's variant needs no succession: a recovery below τ_new does not reset its count.
    died = _mutr3d_scores("mutr3d_code", low + [recovery] + low + [recovery] * 3)
    assert died == (6 if recovery < 0.4 else None)


def test_same_frames_same_tracks():
    first = _run("saga", _car_seen_twice())
    second = _run("saga", _car_seen_twice())
    assert [[(t.track_id, t.box3d) for t in ts] for ts in first] == [[(t.track_id, t.box3d) for t in ts]
                                                                    for ts in second]


def test_saga_drops_a_duplicate_track_but_never_a_neighbour_in_the_next_lane():
    twin_births = _car_seen_twice(frames=3)
    assert [len(ts) for ts in _run("saga", twin_births, birth_merge_m=0, duplicate_iou=0)] == [2, 2, 2]
    assert [len(ts) for ts in _run("saga", twin_births, birth_merge_m=0)] == [1, 1, 1]
    side_by_side = [_frame(k, {"A": [_detection(20 + k, 1.75)], "B": [_detection(20 + k, -1.75)]}) for k in range(5)]
    assert all(len(ts) == 2 for ts in _run("saga", side_by_side))


def _side_by_side_in_one_camera(frames=25, lateral=2.0):
    """Car 1 alone in camera A for 10 frames; then car 2 appears right beside it (``lateral`` m, 0.1 m of road
    between two 1.9 m wide cars), both at 10 m/s."""
    out = []
    for k in range(frames):
        x = 20.0 + 1.0 * k
        views = [_detection(x, 0.0)] + ([_detection(x, lateral)] if k >= 10 else [])
        out.append(_frame(k, {"A": views}))
    return out


def _recording_updates(t):
    """Wrap ``t.update`` to record, per frame, the camera of every detection each track was updated with."""
    fused = []
    original = t.update

    def update(detections, owner):
        per_track = {}
        for j, i in enumerate(owner.tolist()):
            if i >= 0:
                per_track.setdefault(i, []).append(int(detections.cameras[j]))
        fused.append(per_track)
        return original(detections, owner)

    t.update = update
    return fused


@pytest.mark.parametrize("one_per_camera", [True, False])
def test_fota_fuses_two_detections_of_one_camera_only_without_the_physical_constraint(one_per_camera):
    fused = []
    for frames in (_side_by_side_in_one_camera(), _car_seen_twice(frames=30)):
        t = tracker.create("saga", one_per_camera=one_per_camera)
        record = _recording_updates(t)
        t.reset(rig=RIG)
        for frame in frames:
            t.step(frame)
        fused += record
    doubled = sum(len(cams) != len(set(cams)) for per_track in fused for cams in per_track.values())
    assert (doubled == 0) if one_per_camera else (doubled > 0)
    both = sum(sorted(cams) == [0, 1] for per_track in fused for cams in per_track.values())
    assert both >= 28  # one detection of each camera per track is still fused (the car seen twice)


def test_two_cars_side_by_side_in_one_camera_each_keep_their_own_track():
    outputs = _run("saga", _side_by_side_in_one_camera())
    assert [len(ts) for ts in outputs] == [1] * 10 + [2] * 15
    lanes = {t.track_id: [] for ts in outputs for t in ts}
    for ts in outputs[10:]:
        for t in ts:
            lanes[t.track_id].append(t.box3d.y)
    assert len(lanes) == 2  # car 1's track never changed id; car 2 got one track of its own
    near = sorted(lanes.values(), key=lambda ys: np.mean(ys))
    assert np.allclose(near[0], 0.0, atol=0.2) and np.allclose(near[1][2:], 2.0, atol=0.3)
    free = _run("saga", _side_by_side_in_one_camera(), one_per_camera=False)
    assert [len(ts) for ts in free][10:] == [1] * 15  # unconstrained: car 1's track swallows car 2


def test_mutr3d_associates_in_the_image_and_updates_in_3d_from_every_camera_that_matched():
    # Monocular depth error: each camera's 3D box is off by up to 3 m along its own viewing ray, opposite
    # ways; the projected boxes still overlap the track's projection, so one track takes both and the fused
    # 3D position lies between the two.
    frames = []
    for k in range(20):
        x = 25.0 + 1.0 * k
        error = 0.0 if k == 0 else 3.0 if k % 2 else -3.0  # both cameras agree at birth
        frames.append(_frame(k, {"A": [_detection(x + error, 0.0)], "B": [_detection(x - error, 0.0)]}))
    outputs = _run("mutr3d", frames)
    assert all(len(ts) == 1 for ts in outputs) and len({ts[0].track_id for ts in outputs}) == 1
    assert abs(outputs[-1][0].box3d.x - (25.0 + 19)) < 1.5
    near_in_3d = replace(_detection(26.0, 0.0), box=Box2D(0, 0, 40, 30))  # 1 m off in 3D, elsewhere in pixels
    far = SensorFrame(1, DT, EgoPose(0, 0, 0, 0), RIG, {"A": (near_in_3d,), "B": ()})
    for cost2d, expected in (("iou", [2]), ("mahalanobis", [1])):  # the image gate: a new query; in 3D: matched
        t = tracker.create("mutr3d", cost2d=cost2d)
        t.reset(rig=RIG)
        t.step(frames[0])
        assert [track.track_id for track in t.step(far)] == expected, cost2d


# -- the constant-velocity filter: AB3DMOT's noise, and the lag theory predicts --------------------------------
def test_a_10_hz_step_uses_ab3dmot_process_noise_in_si_units():
    # AB3DMOT's KF (its code): Q = I, velocity block × 0.01, per 0.1 s KITTI frame, velocity in metres per frame.
    # In metres per second the velocity variance is 0.01 / 0.1² = 1 (m/s)² a step; positions stay 1 m².
    from simrig.trackers.motion import KalmanConfig, new_filter, predict
    kf = new_filter(np.array([0.0, 0.0, 0.0, 4.5, 1.9, 1.6, 0.0, 10.0, 0.0]), KalmanConfig())
    kf.P = np.zeros((10, 10))
    predict(kf, 0.1, KalmanConfig())
    assert np.allclose(np.diag(kf.P), [1.0] * 7 + [1.0] * 3)


def test_constant_velocity_filter_lags_a_braking_car_as_the_alpha_beta_filter_predicts():
    # A car braking at a constant a, measured exactly every T: a steady-state Kalman filter of a constant-velocity
    # model is an α-β filter, whose velocity error settles at a·T·(α/β − 1/2) (the innovation r = aT²/β is constant
    # and the update adds α·r to the position). α and β come from the steady-state gain of scipy's Riccati solver.
    from scipy.linalg import solve_discrete_are
    from simrig.trackers.motion import KalmanConfig, new_filter, predict, update
    config, T, a, v0 = KalmanConfig(), 0.1, 1.0, 40.0
    F = np.array([[1.0, T], [0.0, 1.0]])
    Q = np.diag([config.process_variance, config.process_velocity_variance]) * T
    P = solve_discrete_are(F.T, np.array([[1.0], [0.0]]), Q, np.array([[config.measurement_variance]]))
    alpha, beta = P[0, 0] / (P[0, 0] + 1.0), P[1, 0] / (P[0, 0] + 1.0) * T
    expected = a * T * (alpha / beta - 0.5)

    def box(k):
        t = k * T
        return np.array([v0 * t - a * t * t / 2, 0.0, 0.0, 4.5, 1.9, 1.6, 0.0, v0 - a * t, 0.0])

    kf = new_filter(box(0), config)
    for k in range(1, 300):
        predict(kf, T, config)
        update(kf, box(k)[:7])
    assert kf.x[7, 0] - box(299)[7] == pytest.approx(expected, rel=1e-3)
    assert 0.5 < expected < 1.5  # 1 m/s² → a lag of about 0.85 m/s with AB3DMOT's noise


# -- polymot: the modern filter baseline -------------------------------------------------------------------------
@pytest.mark.parametrize("model_name", ["CTRA", "BICYCLE"])
def test_turning_models_jacobian_matches_finite_differences(model_name):
    from filterpy.kalman import KalmanFilter
    from simrig.trackers import turning_motion
    from simrig.trackers.motion import KalmanConfig
    model = getattr(turning_motion, model_name)
    x0 = np.array([3.0, -2.0, 0.8, 4.6, 1.9, 1.6, 0.7, 12.0, 1.5, 0.3 if model_name == "CTRA" else 0.02])

    def moved(x, dt=0.1):
        kf = KalmanFilter(dim_x=10, dim_z=7)
        kf.x, kf.P = x[:, None].copy(), np.zeros((10, 10))
        model.predict(kf, dt, KalmanConfig())
        return kf.x[:, 0]

    numeric = np.column_stack([(moved(x0 + e) - moved(x0 - e)) / 2e-6 for e in np.eye(10) * 1e-6])
    kf = KalmanFilter(dim_x=10, dim_z=7)
    kf.x, kf.P = x0[:, None].copy(), np.eye(10)
    model.predict(kf, 0.1, KalmanConfig())
    analytic_P = kf.P - np.diag(model.process) * 0.1  # F I Fᵀ
    assert np.allclose(analytic_P, numeric @ numeric.T, atol=1e-6)


@pytest.mark.parametrize("model_name", ["CTRA", "BICYCLE"])
def test_turning_models_follow_a_circle(model_name):
    # 10 m/s on a 50 m circle: ω = 0.2 rad/s, κ = 0.02 /m; one second in ten steps ends on the circle.
    from filterpy.kalman import KalmanFilter
    from simrig.trackers import turning_motion
    from simrig.trackers.motion import KalmanConfig
    model = getattr(turning_motion, model_name)
    kf = KalmanFilter(dim_x=10, dim_z=7)
    kf.x = np.array([0.0, -50.0, 0.0, 4.6, 1.9, 1.6, 0.0, 10.0, 0.0, 0.2 if model_name == "CTRA" else 0.02])[:, None]
    for _ in range(10):
        model.predict(kf, 0.1, KalmanConfig())
    x, y, heading = kf.x[0, 0], kf.x[1, 0], kf.x[6, 0]
    assert (x, y) == pytest.approx((50 * np.sin(0.2), -50 * np.cos(0.2)), abs=0.01)
    assert heading == pytest.approx(0.2)


def test_polymot_reports_a_missed_frame_on_its_prediction_with_a_decayed_score():
    frames = [_frame(k, {} if k == 6 else {"A": [_detection(20.0 + k, 0.0)]}) for k in range(10)]
    outputs = _run("polymot", frames)
    assert [len(ts) for ts in outputs] == [1] * 10 and len({ts[0].track_id for ts in outputs}) == 1
    assert outputs[6][0].score == pytest.approx(0.9 * 0.5)
    assert outputs[6][0].box3d.x == pytest.approx(26.0, abs=0.3)  # predicted, 1 m per frame
    assert outputs[7][0].score == pytest.approx(0.9)


def test_polymot_second_stage_updates_a_track_with_a_low_score_detection_but_never_starts_one():
    frames = [_frame(k, {"A": [_detection(20.0 + k, 0.0, score=0.9 if k < 5 else 0.3)]}) for k in range(10)]
    outputs = _run("polymot", frames)
    assert all(len(ts) == 1 for ts in outputs) and len({ts[0].track_id for ts in outputs}) == 1
    assert outputs[9][0].box3d.x == pytest.approx(29.0, abs=0.3) and outputs[9][0].score == pytest.approx(0.3)
    assert _run("polymot", [_frame(k, {"A": [_detection(20.0 + k, 0.0, score=0.3)]}) for k in range(3)]) == [
        [], [], []]


def test_mutr3d_tracker_keeps_a_query_through_4_low_frames_twice_and_drops_it_at_the_5th_in_a_row():
    def scores_run(scores):
        frames = [_frame(k, {"A": [_detection(20.0 + k, 0.0, score=s)]}) for k, s in enumerate(scores)]
        t = tracker.create("mutr3d")
        t.reset(rig=RIG)
        alive = []
        for frame in frames:
            t.step(frame)
            alive.append([track.track_id for track in t.tracks])
        return alive

    low = [0.2] * 4  # matched every frame, but below τ_old = 0.35
    survived = scores_run([0.9] + low + [0.9] + low + [0.9] * 2)
    assert all(ids == [1] for ids in survived)
    died = scores_run([0.9] + low + [0.2] + [0.9])
    assert died[4] == [1] and died[5] == [] and died[6] == [2]  # gone at the 5th low frame; a new query after


def test_mutr3d_keeps_a_far_car_whose_3d_estimate_projects_beside_its_2d_box():
    """A car 60 m ahead of camera A (yaw 0.3 rad, so along its axis at bearing 0.3) with an accurate pixel box
    and a monocular 3D estimate steadily 2.5 m to the side: the track, fed by the 3D boxes, projects ~40 px beside
    the car's ~33 px wide box (IoU < 0.1 every frame, checked below on the projections). Under the image IoU gate no
    detection ever matches the track and new tracks keep being born; under the 3D Mahalanobis cost (the default)
    the estimates agree with each other and one track holds."""
    bearing, distance, offset = 0.3, 60.0, 2.5
    truth = np.array([distance * np.cos(bearing), distance * np.sin(bearing)])
    side = np.array([-np.sin(bearing), np.cos(bearing)]) * offset
    true_box = project_boxes(np.array([[*truth, 0.8, 4.6, 1.9, 1.6, bearing]]), RIG, EgoPose(0, 0, 0, 0)).boxes[0, 0]
    estimate_box = project_boxes(np.array([[*(truth + side), 0.8, 4.6, 1.9, 1.6, bearing]]), RIG,
                                 EgoPose(0, 0, 0, 0)).boxes[0, 0]
    overlap = max(0.0, min(true_box[2], estimate_box[2]) - max(true_box[0], estimate_box[0]))
    widths = true_box[2] - true_box[0], estimate_box[2] - estimate_box[0]
    assert overlap / (sum(widths) - overlap) < 0.1  # the two boxes (same height) overlap by IoU < 0.1
    frames = []
    for k in range(12):
        x, y = truth + side
        detection = Detection(Box2D(*map(float, true_box)), 0.9, ActorClass.CAR,
                              Box3D(float(x), float(y), 0.8, 4.6, 1.9, 1.6, bearing, 0.0, 0.0))
        frames.append(SensorFrame(k, k * DT, EgoPose(0, 0, 0, 0), RIG, {"A": (detection,), "B": ()}))
    default = {track.track_id for tracks in _run("mutr3d", frames) for track in tracks}
    image_gate = {track.track_id for tracks in _run("mutr3d", frames, cost2d="iou") for track in tracks}
    assert default == {1}
    assert len(image_gate) > 1


def _braking_car(frames=30, deceleration=8.0):
    """A car 20 m ahead at 20 m/s that brakes at ``deceleration`` [m/s²] from frame 5, seen by camera A with its
    exact position and velocity (what the ``perfect`` detector preset reports)."""
    out, x, v = [], 20.0, 20.0
    for k in range(frames):
        out.append((_frame(k, {"A": [_detection(x, 0.0, vx=v)]}), v))
        if k >= 5:
            v = max(v - deceleration * DT, 0.0)
        x += v * DT
    return out


def test_mutr3d_moves_its_track_with_the_detections_velocity_as_its_paper_moves_a_query():
    """MUTR3D's reference point moves with the velocity predicted from the image (Eq. 7); with exact velocities the
    track's speed is the car's at every frame, while a constant-velocity filter fed positions (global_hungarian)
    lags behind the braking car."""
    frames = _braking_car()
    for name, worst in (("mutr3d", 1e-9), ("global_hungarian", None)):
        t = tracker.create(name)
        t.reset(rig=RIG, seed=0)
        errors = []
        for frame, true_speed in frames:
            tracks = t.step(frame)
            if tracks:
                errors.append(tracks[0].box3d.vx - true_speed)
        if worst is not None:
            assert max(abs(e) for e in errors) <= worst, name
        else:
            assert max(errors) > 2.0, name  # lags by more than 2 m/s while braking
