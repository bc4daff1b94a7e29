"""AMOTA family on hand-built scenes whose values are worked out in the comments, and the 3D matcher against
py-motmetrics (the accumulator the nuScenes devkit runs)."""

import numpy as np
import pytest
from peer_scorers import motmetrics_module

from simrig.scoring.amota import RECALL_LEVELS, amota_family
from simrig.scoring.bev import bev_sequence
from simrig.scoring.clear3d import accumulate, clear_counts


def sequence(gt, tracks, frames=None):
    """gt: (frame, id, x, y, vx, vy); tracks: (frame, id, x, y, vx, vy, score)."""
    gt = np.array(sorted(gt, key=lambda r: r[0]), float).reshape(-1, 6)
    tracks = np.array(sorted(tracks, key=lambda r: r[0]), float).reshape(-1, 7)
    frames = np.arange(int(max(gt[:, 0].max(), tracks[:, 0].max(initial=0))) + 1) if frames is None else frames
    return bev_sequence("car", frames, gt[:, 0].astype(int), gt[:, 1].astype(int), gt[:, 2:4], gt[:, 4:6],
                        tracks[:, 0].astype(int), tracks[:, 1].astype(int), tracks[:, 2:4], tracks[:, 4:6],
                        tracks[:, 6])


def test_recall_levels():
    assert len(RECALL_LEVELS) == 40 and RECALL_LEVELS[0] == 0.1 and RECALL_LEVELS[-1] == 1.0


def test_perfect_tracker():
    gt = [(f, o, 10.0 * o, 0.0, 1.0, 0.0) for f in range(10) for o in range(3)]
    tracks = [(f, 50 + o, 10.0 * o, 0.0, 1.0, 0.0, 0.9) for f, o, *_ in gt]
    m = amota_family(sequence(gt, tracks)).metrics
    assert (m["AMOTA"], m["MOTA"], m["IDS"], m["AMOTP"], m["RECALL"], m["ATVE"]) == (1.0, 1.0, 0, 0.0, 1.0, 0.0)


def test_worked_example():
    """P = 20 ground-truth boxes: objects 1 and 2 over frames 0-9.
    Track A follows object 1 in all 10 frames, 0.5 m off, velocity error 1 m/s, score 0.8.
    Track B follows object 2 in frames 0-4, 1.0 m off, velocity error 2 m/s, score 0.6.
    Track C: 3 false boxes far away, score 0.7.
    Matched scores: ten 0.8, five 0.6 → recall k/20 up to 0.75. Levels r_i = 0.1 + 0.9 i / 39:
      i = 0..17 (r ≤ 0.5): threshold 0.8 → A only: TP 10, FP 0, FN 10; MOTAR = 1, MOTA 0.5, MOTP 0.5
      i = 18 (r = 0.515): threshold 0.8 − 0.2·(0.0154/0.05) = 0.738 → the same counts: MOTAR 1
      i = 19 (r = 0.538): threshold 0.646 → C kept: TP 10, FP 3, FN 10; MOTAR = 1 − (3+10−10)/10 = 0.7
      i = 20..28 (r ≤ 0.75): threshold 0.6 → TP 15, FP 3, FN 5; MOTAR = 1 − (3+5−5)/15 = 0.8, MOTA 0.6,
        MOTP (10·0.5 + 5·1)/15 = 2/3, velocity error (10·1 + 5·2)/15 = 4/3
      i = 29..39: not reached → MOTAR 0, MOTP 2
    AMOTA = (19 + 0.7 + 9·0.8)/40 = 0.6725; AMOTP = (20·0.5 + 9·2/3 + 11·2)/40 = 0.95;
    best MOTA 0.6 at threshold 0.6; ATVE = (20·1 + 9·4/3)/29 = 32/29."""
    gt = [(f, o, 10.0 * o, 0.0, 1.0, 0.0) for f in range(10) for o in (1, 2)]
    tracks = [(f, 100, 10.5, 0.0, 2.0, 0.0, 0.8) for f in range(10)]
    tracks += [(f, 200, 21.0, 0.0, 3.0, 0.0, 0.6) for f in range(5)]
    tracks += [(f, 300, 90.0, 0.0, 0.0, 0.0, 0.7) for f in range(3)]
    result = amota_family(sequence(gt, tracks))
    m = result.metrics
    assert m["AMOTA"] == pytest.approx(0.6725, abs=1e-12)
    assert m["AMOTP"] == pytest.approx(0.95, abs=1e-12)
    assert m["ATVE"] == pytest.approx(32 / 29, abs=1e-12)
    assert (m["MOTA"], m["TP"], m["FP"], m["FN"], m["IDS"]) == (pytest.approx(0.6), 15, 3, 5, 0)
    assert (m["MOTAR"], m["RECALL"]) == (pytest.approx(0.8), pytest.approx(0.75))
    assert m["MOTP"] == pytest.approx(2 / 3) and m["TVE"] == pytest.approx(4 / 3)
    assert result.best_threshold == pytest.approx(0.6)
    assert sum(level.counts is None for level in result.levels) == 11


def test_identity_switch_counts_as_matched_but_not_tp():
    """One object over 10 frames; track 1 in frames 0-4, track 2 in frames 5-9 (score 0.9 both). Frame 5 is a
    SWITCH: matched, but not a TP (devkit). Matched TP scores: 9 → recall reaches 0.9 → levels with
    0.1 + 0.9 i / 39 ≤ 0.9, i ≤ 34 (35 levels), reached. At 0.9: TP 9, IDS 1, FN 0, FP 0, r = 0.9 →
    MOTAR = 1 − (1 + 0 + 0 − 0.1·10)/9 = 1.
    AMOTA = 35/40 = 0.875; MOTA = 1 − 1/10 = 0.9; RECALL (matches incl. switches) = 1."""
    gt = [(f, 1, 0.0, 0.0, 0.0, 0.0) for f in range(10)]
    tracks = [(f, 1 if f < 5 else 2, 0.0, 0.0, 0.0, 0.0, 0.9) for f in range(10)]
    m = amota_family(sequence(gt, tracks)).metrics
    assert m["AMOTA"] == pytest.approx(0.875)
    assert (m["MOTA"], m["IDS"], m["TP"], m["RECALL"]) == (pytest.approx(0.9), 1, 9, 1.0)


def test_best_mota_ties_go_to_the_highest_recall():
    """A (score 0.8) follows object 1, B (0.6) object 2, C (0.6) 10 false boxes; P = 20.
    At 0.8: TP 10, FN 10, FP 0 → MOTA 0.5. At 0.6: TP 20, FN 0, FP 10 → MOTA 0.5. The tie goes to 0.6."""
    gt = [(f, o, 10.0 * o, 0.0, 0.0, 0.0) for f in range(10) for o in (1, 2)]
    tracks = [(f, 100, 10.0, 0.0, 0.0, 0.0, 0.8) for f in range(10)]
    tracks += [(f, 200, 20.0, 0.0, 0.0, 0.0, 0.6) for f in range(10)]
    tracks += [(f, 300, 80.0, 0.0, 0.0, 0.0, 0.6) for f in range(10)]
    m = amota_family(sequence(gt, tracks)).metrics
    assert (m["MOTA"], m["RECALL"], m["FP"]) == (pytest.approx(0.5), 1.0, 10)


def test_no_match_at_all_scores_the_worst_values():
    gt = [(f, 1, 0.0, 0.0, 0.0, 0.0) for f in range(5)]
    tracks = [(f, 9, 50.0, 0.0, 0.0, 0.0, 0.9) for f in range(5)]
    m = amota_family(sequence(gt, tracks)).metrics
    assert (m["AMOTA"], m["AMOTP"], m["MOTA"], m["FN"], m["ML"]) == (0.0, 2.0, 0.0, 5, 1)


def random_3d_scene(rng, frames, objects, crowded):
    spread = 12 if crowded else 80
    gt, tracks, next_id = [], [], 1000
    track_of = {o: o + 1 for o in range(objects)}
    score_of = {}
    start, velocity = rng.uniform(0, spread, (objects, 2)), rng.normal(0, 1, (objects, 2))
    for f in range(frames):
        if rng.random() < 0.05:
            a, b = rng.choice(objects, 2, replace=False)
            track_of[a], track_of[b] = track_of[b], track_of[a]
        for o in range(objects):
            xy = start[o] + velocity[o] * 0.1 * f
            gt.append((f, 100 + o, *xy, *velocity[o]))
            if rng.random() < 0.03:
                track_of[o], next_id = next_id, next_id + 1
            if rng.random() < 0.15:
                continue
            t = track_of[o]
            score = score_of.setdefault(t, rng.uniform(0.2, 1.0))
            tracks.append((f, t, *(xy + rng.normal(0, 0.7, 2)), *(velocity[o] + rng.normal(0, 0.3, 2)), score))
        for _ in range(rng.poisson(0.7)):
            tracks.append((f, next_id, *rng.uniform(0, spread, 2), 0.0, 0.0, rng.uniform(0, 0.6)))
            next_id += 1
    seen = set()
    tracks = [r for r in tracks if (r[0], r[1]) not in seen and not seen.add((r[0], r[1]))]
    return gt, tracks


@pytest.mark.parametrize("seed", range(8))
def test_3d_matching_equals_motmetrics(seed):
    """At several thresholds, TP (MATCH), IDS (SWITCH), FN, FP, MT, ML, FRAG, MOTP and recall equal
    py-motmetrics' accumulator fed the devkit's gated distance matrices (NaN at ≥ 2 m)."""
    mm = motmetrics_module()
    rng = np.random.default_rng(seed)
    gt, tracks = random_3d_scene(rng, 40, 8, crowded=seed % 2 == 0)
    seq = sequence(gt, tracks, np.arange(40))
    g, t = np.array(gt), np.array(tracks)
    for threshold in (0.0, 0.45, 0.7):
        acc = mm.MOTAccumulator()
        frame_id = 0
        for f in range(40):
            a, b = g[g[:, 0] == f], t[(t[:, 0] == f) & (t[:, 6] >= threshold)]
            if len(a) == 0 and len(b) == 0:
                continue
            d = np.sqrt(((a[:, None, 2:4] - b[None, :, 2:4]) ** 2).sum(-1)).reshape(len(a), len(b))
            d[d >= 2.0] = np.nan
            acc.update(a[:, 1].astype(int).tolist(), b[:, 1].astype(int).tolist(), d, frameid=frame_id)
            frame_id += 1
        names = ["num_matches", "num_switches", "num_misses", "num_false_positives", "mostly_tracked",
                 "mostly_lost", "num_fragmentations", "motp", "recall"]
        theirs = mm.metrics.create().compute(acc, metrics=names, name="x").iloc[0]
        c = clear_counts(seq, accumulate(seq, threshold))
        mine = [c.tp, c.ids, c.fn, c.fp, c.mt, c.ml, c.frag, c.distance_sum / (c.tp + c.ids), (c.tp + c.ids) / c.gt]
        assert mine == pytest.approx([theirs[name] for name in names], abs=1e-9), f"threshold {threshold}"


def test_renaming_track_ids_changes_nothing():
    rng = np.random.default_rng(11)
    gt, tracks = random_3d_scene(rng, 30, 6, crowded=True)
    ids = sorted({r[1] for r in tracks})
    renamed = dict(zip(ids, rng.permutation(100000)[: len(ids)].tolist(), strict=True))
    tracks2 = [(r[0], renamed[r[1]], *r[2:]) for r in tracks]
    a = amota_family(sequence(gt, tracks, np.arange(30))).metrics
    b = amota_family(sequence(gt, tracks2, np.arange(30))).metrics
    assert a == pytest.approx(b, abs=1e-12, nan_ok=True)


def test_generated_dataset_3d_matching_equals_motmetrics(small_dataset):
    """The class sequences of a generated dataset (class ranges applied), scored against its ground truth moved
    by 0.8 m noise with misses and an id change, equal py-motmetrics' accumulator on the same rows."""
    from simrig.dataset.ground_truth import load_ground_truth
    from simrig.dataset.tracks_file import TrackRows
    from simrig.scoring.inputs import class_sequences

    mm = motmetrics_module()
    truth = load_ground_truth(small_dataset)
    rng = np.random.default_rng(5)
    keep = np.nonzero(rng.random(len(truth.frame)) > 0.15)[0]
    boxes = truth.boxes[keep].copy()
    boxes[:, :2] += rng.normal(0, 0.8, size=(len(keep), 2))
    ids = truth.actor_id[keep] + 500 * (truth.frame[keep] > 20)
    tracks = TrackRows(truth.frame[keep], ids, truth.label[keep], rng.uniform(0.3, 1.0, len(keep)), boxes)
    sequences = class_sequences(truth, tracks)
    assert sequences
    for seq in sequences:
        acc = mm.MOTAccumulator()
        frame_id = 0
        for position in range(len(seq.frames)):
            (g0, g1), (k0, k1) = seq.gt_slices[position], seq.tracker_slices[position]
            if g1 == g0 and k1 == k0:
                continue
            distance = np.full((g1 - g0, k1 - k0), np.nan)
            in_frame = seq.pair_frame == position
            distance[seq.pair_gt[in_frame] - g0, seq.pair_tracker[in_frame] - k0] = seq.pair_distance[in_frame]
            acc.update(seq.gt_labels[seq.gt_id[g0:g1]].tolist(), seq.tracker_labels[seq.tracker_id[k0:k1]].tolist(),
                       distance, frameid=frame_id)
            frame_id += 1
        names = ["num_matches", "num_switches", "num_misses", "num_false_positives", "num_fragmentations"]
        theirs = mm.metrics.create().compute(acc, metrics=names, name="x").iloc[0]
        c = clear_counts(seq, accumulate(seq, None))
        assert [c.tp, c.ids, c.fn, c.fp, c.frag] == [theirs[name] for name in names], seq.label


def test_a_class_that_reaches_no_recall_level_counts_motar_zero_overall():
    """One car tracked perfectly, one truck never matched: the devkit gives the truck its metric_worst MOTAR 0
    and averages the classes with ground truth, overall MOTAR (1 + 0) / 2 = 0.5 (and AMOTA 0.5)."""
    from simrig.scoring.amota import combine_classes
    from simrig.scoring.results import METRICS_3D

    car = [(f, 1, 0.0, 0.0, 0.0, 0.0) for f in range(5)]
    truck = [(f, 2, 20.0, 0.0, 0.0, 0.0) for f in range(5)]
    per_class = {
        "car": amota_family(sequence(car, [(f, 7, 0.0, 0.0, 0.0, 0.0, 0.9) for f in range(5)])).metrics,
        "truck": amota_family(sequence(truck, [(f, 8, 40.0, 0.0, 0.0, 0.0, 0.9) for f in range(5)])).metrics,
    }
    assert per_class["car"]["MOTAR"] == 1.0 and per_class["truck"]["MOTAR"] == 0.0
    overall = combine_classes(per_class, METRICS_3D)
    assert (overall["MOTAR"], overall["AMOTA"], overall["MOTA"]) == (0.5, 0.5, 0.5)
    assert (overall["TP"], overall["FN"], overall["ML"]) == (5, 5, 1)
