"""simrig's 2D metrics against TrackEval (and py-motmetrics where the two agree by definition), within 1e-9."""

import numpy as np
import pytest
from peer_scorers import flatten, motmetrics_module, random_scene, trackeval_data, trackeval_metrics

from simrig.dataset.ground_truth import load_ground_truth
from simrig.dataset.tracks_file import TrackRows
from simrig.scoring.clear import CLEAR
from simrig.scoring.counts import sum_counts
from simrig.scoring.hota import HOTA
from simrig.scoring.identity import Identity
from simrig.scoring.inputs import camera_sequences
from simrig.scoring.ratios import clear_ratios, hota_ratios, identity_ratios
from simrig.scoring.sequence import sequence_from_rows

COMPARED = ("HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr", "MOTA", "MOTP", "IDSW", "Frag",
            "MT", "PT", "ML", "CLR_TP", "CLR_FN", "CLR_FP", "IDF1", "IDP", "IDR")


def simrig_counts(seq):
    return {**HOTA().count(seq), **CLEAR().count(seq), **Identity().count(seq)}


def simrig_metrics(counts):
    return {**hota_ratios(counts), **clear_ratios(counts), **identity_ratios(counts)}


def assert_same(mine: dict, theirs: dict, where: str):
    for name in COMPARED:
        assert mine[name] == pytest.approx(theirs[name], abs=1e-9), f"{where}: {name}"


def compare(frames, rows, where):
    seq = sequence_from_rows("cam", "car", frames, *rows)
    theirs = flatten(trackeval_metrics({"s": trackeval_data(frames, *rows)})["s"])
    assert_same(simrig_metrics(simrig_counts(seq)), theirs, where)


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("crowded", [False, True])
def test_random_scenes_match_trackeval(seed, crowded):
    rows = random_scene(np.random.default_rng(seed), 50, 10, crowded=crowded)
    compare(np.arange(50), rows, f"seed {seed}")


def test_combining_sequences_matches_trackeval_combined_seq():
    """Cameras combine like TrackEval's sequences: counts summed, AssA and LocA weighted by TP."""
    sequences, data = [], {}
    for seed in range(4):
        rows = random_scene(np.random.default_rng(100 + seed), 40, 8, crowded=seed % 2 == 0)
        sequences.append(sequence_from_rows(f"cam{seed}", "car", np.arange(40), *rows))
        data[f"cam{seed}"] = trackeval_data(np.arange(40), *rows)
    theirs = flatten(trackeval_metrics(data)["COMBINED_SEQ"])
    mine = simrig_metrics(sum_counts(simrig_counts(seq) for seq in sequences))
    assert_same(mine, theirs, "combined")


def rows_of(gt, tr):
    """(frame, id, box) lists → the flat sorted arrays the scorer and the oracle take."""
    def columns(items):
        frame = np.array([i[0] for i in items], dtype=np.int64)
        return frame, np.array([i[1] for i in items], dtype=np.int64), np.array([i[2] for i in items], float)
    return (*columns(gt), *columns(tr))


def box(x, y=0.0, w=10.0, h=10.0):
    return [x, y, x + w, y + h]


def test_id_swap_between_two_objects():
    """Two objects side by side; the tracker swaps their ids at frame 3: two switches."""
    gt = [(f, o, box(20 * o)) for f in range(6) for o in (1, 2)]
    tr = [(f, (o if f < 3 else 3 - o) + 10, box(20 * o + 1)) for f in range(6) for o in (1, 2)]
    rows = rows_of(gt, tr)
    compare(np.arange(6), rows, "swap")
    mine = simrig_metrics(simrig_counts(sequence_from_rows("c", "car", np.arange(6), *rows)))
    assert mine["IDSW"] == 2 and mine["CLR_TP"] == 12
    assert mine["IDF1"] == pytest.approx(0.5)  # each id pair overlaps in 3 of 6 frames on each side


def test_fragmentation_and_a_frame_with_no_tracker_output():
    """A track lost for two frames then resumed under the same id (one Frag); a frame where the tracker output
    nothing at all does not break the segment (TrackEval's rule) — both checked against TrackEval."""
    gt = [(f, 1, box(0)) for f in range(10)]
    tr = [(f, 7, box(1)) for f in range(10) if f not in (3, 4, 8)]
    tr += [(3, 9, box(300)), (4, 9, box(300))]  # frames 3-4: output elsewhere only → misses, false positives
    tr = sorted(tr, key=lambda r: r[0])  # frame 8: no output at all → a miss, but not a time step
    rows = rows_of(gt, tr)
    compare(np.arange(10), rows, "fragments")
    mine = simrig_metrics(simrig_counts(sequence_from_rows("c", "car", np.arange(10), *rows)))
    assert (mine["Frag"], mine["IDSW"], mine["CLR_FN"], mine["CLR_FP"]) == (1, 0, 3, 2)


def test_crowded_scene_with_contested_boxes():
    """Heavily overlapping boxes (every box contests several others) — the Hungarian path, against TrackEval."""
    rng = np.random.default_rng(7)
    gt, tr = [], []
    for f in range(15):
        for o in range(6):
            x = 4.0 * o + 0.3 * f
            gt.append((f, o, box(x, w=12)))
            tr.append((f, 100 + (o + (f // 5)) % 6, box(x + rng.normal(0, 1.5), w=12)))
    rows = rows_of(gt, tr)
    compare(np.arange(15), rows, "crowded")


def test_where_motmetrics_differs_by_design():
    """One object tracked in exactly 8 of 10 frames (ratio 0.8): TrackEval's MT needs > 0.8, motmetrics' ≥ 0.8.
    MOTP: TrackEval reports the mean IoU of matches, motmetrics the mean 1 − IoU; they sum to 1."""
    mm = motmetrics_module()
    gt = [(f, 1, box(0)) for f in range(10)]
    tr = [(f, 5, box(2)) for f in range(10) if f < 8]
    rows = rows_of(gt, tr)
    mine = simrig_metrics(simrig_counts(sequence_from_rows("c", "car", np.arange(10), *rows)))
    acc = mm.MOTAccumulator(auto_id=True)
    for f in range(10):
        distance = mm.distances.iou_matrix([[0, 0, 10, 10]], [[2, 0, 10, 10]] if f < 8 else np.zeros((0, 4)),
                                           max_iou=0.5)
        acc.update([1], [5] if f < 8 else [], distance)
    theirs = mm.metrics.create().compute(acc, metrics=["mostly_tracked", "motp", "mota"], name="x").iloc[0]
    assert mine["MT"] == 0 and theirs["mostly_tracked"] == 1
    assert mine["MOTP"] + theirs["motp"] == pytest.approx(1.0, abs=1e-12)
    assert mine["MOTA"] == pytest.approx(theirs["mota"], abs=1e-12)


def test_generated_dataset_matches_trackeval(small_dataset):
    """Every (camera, class) sequence of a generated dataset, scored against a degraded copy of its own
    ground truth (jitter, misses, an id swap), equals TrackEval on the same rows."""
    truth = load_ground_truth(small_dataset)
    rng = np.random.default_rng(3)
    rows, cams = np.nonzero(truth.in_view)
    keep = rng.random(len(rows)) > 0.1
    rows, cams = rows[keep], cams[keep]
    boxes = truth.boxes2d[rows, cams] + rng.normal(0, 2.0, size=(len(rows), 4))
    boxes[:, 2:] = np.maximum(boxes[:, 2:], boxes[:, :2] + 1.0)
    ids = truth.actor_id[rows] + 1000 * (truth.frame[rows] > 15) * (truth.actor_id[rows] % 2)
    names = np.array(truth.rig.camera_names, dtype=object)
    order = np.lexsort((cams, truth.frame[rows]))
    tracks = TrackRows(truth.frame[rows][order], ids[order], truth.label[rows][order], np.ones(len(rows)),
                       boxes[order], names[cams][order])
    sequences = camera_sequences(truth, tracks)
    assert sequences
    for seq in sequences:
        c = truth.rig.camera_names.index(seq.camera)
        g = np.nonzero(truth.in_view[:, c] & (truth.label == seq.label))[0]
        t = np.nonzero((tracks.camera == seq.camera) & (tracks.label == seq.label))[0]
        data = trackeval_data(truth.frames, truth.frame[g], truth.actor_id[g], truth.boxes2d_in(g, c),
                              tracks.frame[t], tracks.track_id[t], tracks.boxes[t])
        theirs = flatten(trackeval_metrics({"s": data})["s"])
        assert_same(simrig_metrics(simrig_counts(seq)), theirs, seq.name)
