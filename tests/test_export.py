"""``simrig export``: TrackEval run on the MOTChallenge export agrees with ``simrig score``; the KITTI and
nuScenes files hold what the dataset holds; an export is all or nothing."""

import json

import numpy as np
import pytest
import trackeval

from simrig.cli import main
from simrig.dataset.ground_truth import load_ground_truth
from simrig.export import api as export_api
from simrig.export import export
from simrig.pipeline.track import run_tracker
from simrig.score import score


def trackeval_on(out, tracker_name):
    config = trackeval.Evaluator.get_default_eval_config()
    config.update(PRINT_RESULTS=False, PRINT_CONFIG=False, OUTPUT_SUMMARY=False, OUTPUT_DETAILED=False,
                  PLOT_CURVES=False, TIME_PROGRESS=False, DISPLAY_LESS_PROGRESS=True, USE_PARALLEL=False)
    dataset = trackeval.datasets.MotChallenge2DBox({
        "GT_FOLDER": str(out / "gt" / "mot_challenge"), "TRACKERS_FOLDER": str(out / "trackers" / "mot_challenge"),
        "BENCHMARK": "SIMRIG", "SPLIT_TO_EVAL": "test", "TRACKERS_TO_EVAL": [tracker_name], "PRINT_CONFIG": False})
    metrics = [trackeval.metrics.HOTA(), trackeval.metrics.CLEAR({"PRINT_CONFIG": False}),
               trackeval.metrics.Identity({"PRINT_CONFIG": False})]
    results, _ = trackeval.Evaluator(config).evaluate([dataset], metrics)
    combined = results["MotChallenge2DBox"][tracker_name]["COMBINED_SEQ"]["pedestrian"]
    return {"HOTA": float(np.mean(combined["HOTA"]["HOTA"])), "MOTA": float(combined["CLEAR"]["MOTA"]),
            "IDF1": float(combined["Identity"]["IDF1"]), "IDSW": float(combined["CLEAR"]["IDSW"])}


@pytest.mark.parametrize("tracker_name", ["sort", "saga"])
def test_trackeval_on_the_motchallenge_export_equals_simrig_score(small_dataset, tmp_path, tracker_name):
    """2D tracks as written, and 3D tracks projected through the rig as the scorer projects them."""
    run = run_tracker(small_dataset, tracker_name, tmp_path / tracker_name)
    out = export(small_dataset, "motchallenge", tmp_path / "mot", tracks=run.out)
    theirs = trackeval_on(out, tracker_name)
    ours = score(small_dataset, run.out).metrics2d["overall"]
    for name in ("HOTA", "MOTA", "IDF1", "IDSW"):
        assert ours[name] == pytest.approx(theirs[name], abs=1e-9), name


def test_kitti_labels_hold_every_box_in_view_with_the_projected_depth(small_dataset, tmp_path):
    out = export(small_dataset, "kitti", tmp_path / "kitti")
    truth = load_ground_truth(small_dataset)
    projections = small_dataset.table("projections").to_pylist()
    depth = {(p["frame"], p["actor_id"], p["camera"]): p["depth"] for p in projections}
    for c, camera in enumerate(truth.rig.camera_names):
        lines = (out / camera / "label_02" / "0000.txt").read_text().splitlines()
        assert len(lines) == int(truth.in_view[:, c].sum())
        for line in lines[:20]:
            f = line.split()
            frame, actor = int(f[0]), int(f[1])
            row = np.nonzero((truth.frame == frame) & (truth.actor_id == actor))[0][0]
            assert [float(v) for v in f[6:10]] == pytest.approx(truth.boxes2d[row, c], abs=1e-3)
            assert float(f[15]) == pytest.approx(depth[(frame, actor, camera)], abs=1e-3)  # level cameras: z of centre
            assert [float(v) for v in f[10:13]] == pytest.approx(truth.boxes[row, [5, 4, 3]], abs=1e-3)  # h, w, l


def test_nuscenes_json_has_every_frame_and_one_class_per_track(small_dataset, tmp_path):
    run = run_tracker(small_dataset, "saga", tmp_path / "saga")
    out = export(small_dataset, "nuscenes", tmp_path / "nu", tracks=run.out)
    truth = load_ground_truth(small_dataset)
    gt = json.loads((out / "ground_truth.json").read_text())
    assert len(gt["results"]) == len(truth.frames) and sum(map(len, gt["results"].values())) == len(truth.frame)
    box = gt["results"][f"{small_dataset.scenario['name']}-seed0-000000"][0]
    assert set(box) == {"sample_token", "translation", "size", "rotation", "velocity", "tracking_id",
                        "tracking_name", "tracking_score"}
    assert np.linalg.norm(box["rotation"]) == pytest.approx(1.0)
    row = np.nonzero((truth.frame == 0) & (truth.actor_id == int(box["tracking_id"])))[0][0]
    assert 2 * np.arctan2(box["rotation"][3], box["rotation"][0]) == pytest.approx(truth.boxes[row, 6])
    assert box["size"] == pytest.approx(truth.boxes[row, [4, 3, 5]].tolist())
    tracks = json.loads((out / "saga.json").read_text())["results"]
    names: dict[str, set] = {}
    for boxes in tracks.values():
        for b in boxes:
            names.setdefault(b["tracking_id"], set()).add(b["tracking_name"])
            assert isinstance(b["tracking_score"], float) and not np.isnan(b["tracking_score"])
    assert names and all(len(v) == 1 for v in names.values())


def test_an_export_is_all_or_nothing(small_dataset, tmp_path, monkeypatch, capsys):
    def broken(data, out):
        (out / "half.txt").write_text("x")
        raise RuntimeError("disk full")
    monkeypatch.setattr(export_api, "_formats", lambda: {"kitti": broken})
    with pytest.raises(RuntimeError):
        export(small_dataset, "kitti", tmp_path / "out")
    assert not (tmp_path / "out").exists() and not list(tmp_path.glob(".out*"))
    monkeypatch.undo()
    (tmp_path / "taken").mkdir()
    assert main(["export", str(small_dataset.path), "--format", "kitti", "--out", str(tmp_path / "taken")]) == 2
    assert "--out" in capsys.readouterr().err
