"""The evaluation region: which 2D ground truth is ignored and by which rule, how an ignored box is treated
(TrackEval's MotChallenge2DBox preprocessing), class-agnostic scoring, and the settings' validation."""

import numpy as np
import pyarrow as pa
import pyarrow.compute  # noqa: F401  (pa.compute)
import pytest
from simrig.scenarios import ScenarioError, load_scenario
from simrig.scenarios.evaluation_schema import EvaluationConfig
from simrig.scenarios.schema import RigConfig

from simrig.cli import main
from simrig.dataset.ground_truth import GroundTruth
from simrig.dataset.tracks_file import TrackRows
from simrig.formats.evaluation import EvaluationError, IgnoreRule, evaluation_of, ignore_rules, ignored_counts
from simrig.rig import build_rig
from simrig.scoring.api import UNITS_2D
from simrig.scoring.counts import combine
from simrig.scoring.inputs import camera_sequences
from simrig.types import EgoPose


def hand_built_truth(rows):
    """One frame of a stereo rig (ego at the origin); rows: (label, x [m], box in camera 0, truncation,
    occlusion), each actor in view of camera 0 only."""
    rig = build_rig(RigConfig(preset="stereo"))
    n = len(rows)
    boxes = np.zeros((n, 9))
    boxes[:, 0] = [r[1] for r in rows]
    boxes2d = np.full((n, 2, 4), np.nan)
    boxes2d[:, 0] = [r[2] for r in rows]
    in_view = np.zeros((n, 2), dtype=bool)
    in_view[:, 0] = True
    truncation = np.full((n, 2), np.nan)
    truncation[:, 0] = [r[3] for r in rows]
    occlusion = np.full((n, 2), np.nan)
    occlusion[:, 0] = [r[4] for r in rows]
    return GroundTruth(
        rig=rig, frames=np.array([0]), timestamps=np.array([0.0]), egos=(EgoPose(0, 0, 0, 0),), events=((),),
        frame=np.zeros(n, np.int64), actor_id=np.arange(n), label=np.array([r[0] for r in rows], dtype=object),
        boxes=boxes, in_view=in_view, view_boxes2d=boxes2d[in_view], view_truncation=truncation[in_view],
        view_occlusion=occlusion[in_view], causes=np.zeros((n, 2), np.int32), detected=np.zeros((n, 2), bool))


TALL = [0.0, 0.0, 50.0, 30.0]  # 30 px high


def test_each_rule_at_its_boundary():
    """Defaults: class range (car 50 m, motorcycle 40 m; in range strictly closer), height ≥ 25 px, visible
    fraction above 0, truncation up to 0.5. Each row sits just inside or just outside one rule."""
    truth = hand_built_truth([
        ("car", 49.9, TALL, 0.0, 0.0),                    # scored
        ("car", 50.0, TALL, 0.0, 0.0),                    # range
        ("motorcycle", 40.0, TALL, 0.0, 0.0),             # range (motorcycle: 40 m)
        ("motorcycle", 39.9, TALL, 0.0, 0.0),             # scored
        ("car", 10.0, [0.0, 0.0, 50.0, 25.0], 0.0, 0.0),  # scored: exactly 25 px
        ("car", 10.0, [0.0, 0.0, 50.0, 24.9], 0.0, 0.0),  # height
        ("car", 10.0, TALL, 0.0, 1.0),                    # visibility: nothing visible
        ("car", 10.0, TALL, 0.0, 0.99),                   # scored: 1% visible
        ("car", 10.0, TALL, 0.0, np.nan),                 # scored: not rendered, so no visibility rule
        ("car", 10.0, TALL, 0.5, 0.0),                    # scored: truncation exactly 0.5
        ("car", 10.0, TALL, 0.51, 0.0),                   # truncation
        ("car", 60.0, [0.0, 0.0, 50.0, 10.0], 0.7, 1.0),  # all four
    ])
    rules = ignore_rules(truth, EvaluationConfig())
    R, H, V, T = (int(r) for r in list(IgnoreRule)[:4])
    assert rules[:, 0].tolist() == [0, R, R, 0, 0, H, V, 0, 0, 0, T, R | H | V | T]
    assert not rules[:, 1].any()  # not in view of camera 1
    assert ignored_counts(rules) == {"ignored": 6, "range": 3, "height": 2, "visibility": 2, "truncation": 2,
                                    "source": 0, "unevaluated": 0}
    assert not ignore_rules(truth, EvaluationConfig(ignore=False)).any()
    wider = ignore_rules(truth, EvaluationConfig(range_m={"motorcycle": 45.0}, min_height_px=0, max_truncation=1))
    assert wider[:, 0].tolist() == [0, R, 0, 0, 0, 0, V, 0, 0, 0, 0, R | V]


def test_a_tracker_box_on_an_ignored_box_is_removed_not_a_false_positive():
    """Ground truth A (scored), B and C (ignored); tracker boxes on A, on B and on nothing: TP 1, FP 1, FN 0,
    MOTA (1 − 1) / 1 = 0, and C, which nobody tracks, is listed as an ignored miss, not counted as FN. With
    nothing ignored: TP 2, FP 1, FN 1 (C), MOTA (2 − 1) / 3."""
    a, b = [100.0, 100.0, 200.0, 200.0], [300.0, 100.0, 400.0, 200.0]
    truth = hand_built_truth([("car", 10.0, a, 0.0, 0.0), ("car", 10.0, b, 0.0, 0.0),
                              ("car", 10.0, [600.0, 100.0, 700.0, 200.0], 0.0, 0.0)])
    tracks = TrackRows(np.zeros(3, np.int64), np.array([7, 8, 9]), np.array(["car"] * 3, dtype=object),
                       np.ones(3), np.array([a, b, [450.0, 100.0, 550.0, 200.0]]),
                       np.array(["left"] * 3, dtype=object))
    ignored = np.zeros((3, 2), bool)
    ignored[1:, 0] = True
    (seq,) = camera_sequences(truth, tracks, ignored=ignored)
    values = combine(UNITS_2D, [{unit.name: unit.count(seq) for unit in UNITS_2D}])
    assert (values["CLR_TP"], values["CLR_FP"], values["CLR_FN"], values["MOTA"]) == (1, 1, 0, 0.0)
    assert seq.ignored_misses.tolist() == [[0, 2]]
    (seq,) = camera_sequences(truth, tracks)
    values = combine(UNITS_2D, [{unit.name: unit.count(seq) for unit in UNITS_2D}])
    assert (values["CLR_TP"], values["CLR_FP"], values["CLR_FN"], values["MOTA"]) == (2, 1, 1, pytest.approx(1 / 3))


def test_class_agnostic_scoring_matches_across_classes():
    """A truck tracked as a car: a miss and a false positive per class, a match class-agnostic."""
    box = [100.0, 100.0, 200.0, 200.0]
    truth = hand_built_truth([("truck", 10.0, box, 0.0, 0.0)])
    tracks = TrackRows(np.zeros(1, np.int64), np.array([3]), np.array(["car"], dtype=object), np.ones(1),
                       np.array([box]), np.array(["left"], dtype=object))
    per_class = camera_sequences(truth, tracks)
    assert sorted(s.label for s in per_class) == ["car", "truck"]
    assert sum(s.num_gt_dets for s in per_class) == 1 and not any(len(s.pair_gt) for s in per_class)
    (agnostic,) = camera_sequences(truth, tracks, classes="any")
    assert agnostic.label == "any" and len(agnostic.pair_gt) == 1 and agnostic.pair_similarity[0] == 1.0


def test_score_reports_ignored_boxes_per_camera_and_an_ignored_causes_line(small_dataset, tmp_path):
    from simrig.pipeline.track import run_tracker
    from simrig.scoring import score

    run = run_tracker(small_dataset, "sort", tmp_path / "sort")
    report = score(small_dataset, run.out)
    ignored = report.metrics2d["ground_truth"]
    truth = small_dataset.ground_truth
    rules = ignore_rules(truth, EvaluationConfig())
    for c, camera in enumerate(truth.rig.camera_names):
        delivered = int(np.sum(truth.in_view[:, c] & truth.detected[:, c] & (rules[:, c] == 0)))
        assert ignored["per_camera"][camera] == {"boxes": int(truth.in_view[:, c].sum()),
                                                 **ignored_counts(rules[:, c]), "delivered": delivered}
    assert ignored["overall"]["ignored"] == sum(v["ignored"] for v in ignored["per_camera"].values()) > 0
    kinds = report.errors.column("kind").to_pylist()
    causes = report.errors.column("causes").to_pylist()
    ign = [c for k, c in zip(kinds, causes, strict=True) if k == "IGN"]
    assert ign and all(any(tag.startswith("ignored_") for tag in tags) for tags in ign)
    text = report.table()
    assert "2D ground truth: boxes in view; ignored" in text and "ignored (not errors)" in text
    assert report.settings["evaluation"]["min_height_px"] == 25.0
    everything = score(small_dataset, run.out, evaluation={"ignore": False})
    assert everything.metrics2d["ground_truth"]["overall"]["ignored"] == 0
    assert "IGN" not in everything.errors.column("kind").to_pylist()


def test_bad_evaluation_settings_are_one_line_naming_the_key_and_file(tmp_path, small_dataset, capsys):
    for body, key in (("colour = 1", "evaluation.colour: unknown key"),
                      ("min_height_px = -1", "evaluation.min_height_px"),
                      ("min_visible_fraction = 1.5", "evaluation.min_visible_fraction")):
        path = tmp_path / "bad.toml"
        path.write_text(f'extends = "highway_surround6"\n[evaluation]\n{body}\n')
        with pytest.raises(ScenarioError) as error:
            load_scenario(path)
        assert str(path) in str(error.value) and key in str(error.value) and "\n" not in str(error.value)
    with pytest.raises(EvaluationError, match="max_truncation"):
        evaluation_of({"name": "x"}, {"max_truncation": 2})
    tracks = tmp_path / "none"
    tracks.mkdir()
    code = main(["score", str(small_dataset.path), str(tracks), "--evaluation", "min_height_px=-3"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.startswith("simrig: error:") and "min_height_px" in err and "\n" not in err


def test_ground_truth_is_read_once_per_dataset_for_several_trackers(small_dataset, tmp_path, monkeypatch):
    """Scoring two trackers on one opened dataset reads its ground truth once; a caller holding it passes it."""
    from simrig.dataset import Dataset
    from simrig.dataset import ground_truth as module
    from simrig.pipeline.track import run_tracker
    from simrig.scoring import score

    runs = [run_tracker(small_dataset, name, tmp_path / name).out for name in ("sort", "saga")]
    reads = []
    real = module.load_ground_truth
    monkeypatch.setattr(module, "load_ground_truth", lambda dataset: reads.append(dataset) or real(dataset))
    dataset = Dataset.open(small_dataset.path)
    first, second = (score(dataset, out) for out in runs)
    assert len(reads) == 1
    held = score(Dataset.open(small_dataset.path), runs[1], truth=dataset.ground_truth)
    assert len(reads) == 1 and held.metrics2d["overall"] == second.metrics2d["overall"]
    assert first.metrics2d["overall"] != second.metrics2d["overall"]


def test_a_3d_trackers_boxes_beyond_the_class_range_are_dropped_before_2d_scoring():
    """The devkit drops predictions at or beyond the class range (``filter_eval_boxes``); the 2D evaluation
    region ignores ground truth there. So a 3D tracker's far boxes are dropped before they are projected, not
    counted as 2D false positives: car at 49.9 m kept, 50.0 m dropped; motorcycle at 39.9 m kept, 40.0 m dropped
    (ego at the origin, the stereo pair facing +x, every box straight ahead and in view)."""
    from simrig.dataset.ground_truth import project_tracks
    from simrig.formats.evaluation import projected_in_range

    truth = hand_built_truth([("car", 10.0, TALL, 0.0, 0.0)])
    xs, labels = [49.9, 50.0, 39.9, 40.0, 10.0], ["car", "car", "motorcycle", "motorcycle", "truck"]
    boxes = np.zeros((5, 9))
    boxes[:, 0], boxes[:, 2], boxes[:, 3:6] = xs, 0.8, (4.0, 1.8, 1.6)
    tracks3d = TrackRows(np.zeros(5, np.int64), np.arange(5), np.array(labels, dtype=object), np.ones(5), boxes)
    everything = project_tracks(truth, tracks3d)
    assert sorted(set(everything.track_id.tolist())) == [0, 1, 2, 3, 4]  # all in view
    kept = projected_in_range(truth, tracks3d, EvaluationConfig())
    assert sorted(set(kept.track_id.tolist())) == [0, 2, 4]
    same = np.isin(everything.track_id, [0, 2, 4])
    np.testing.assert_array_equal(kept.boxes, everything.boxes[same])  # the kept ones projected as before
    assert len(projected_in_range(truth, tracks3d, EvaluationConfig(ignore=False))) == len(everything)
    wider = projected_in_range(truth, tracks3d, EvaluationConfig(range_m=60.0))
    assert len(wider) == len(everything)


def test_a_3d_trackers_far_boxes_are_no_2d_false_positives_in_score(small_dataset, tmp_path):
    """End to end: a 3D tracker's boxes moved beyond the class range add nothing to its 2D false positives."""
    import pyarrow.parquet as pq

    from simrig.pipeline.track import run_tracker
    from simrig.scoring import score

    run = run_tracker(small_dataset, "saga", tmp_path / "saga")
    before = score(small_dataset, run.out).metrics2d["overall"]
    table = pq.read_table(run.out / "tracks3d.parquet")
    far = table.set_column(table.schema.get_field_index("x"), "x",
                           pa.compute.add(table.column("x"), 500.0))  # every box far ahead of its place
    moved = tmp_path / "moved"
    moved.mkdir()
    pq.write_table(pa.concat_tables([table, far.set_column(
        far.schema.get_field_index("track_id"), "track_id", pa.compute.add(far.column("track_id"), 10_000))]),
        moved / "tracks3d.parquet")
    after = score(small_dataset, moved).metrics2d["overall"]
    assert after["CLR_FP"] == before["CLR_FP"] and after["HOTA"] == before["HOTA"]
