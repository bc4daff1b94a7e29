"""``simrig score`` on outside formats: each export of a tracker's output (MOTChallenge, KITTI, nuScenes) read back
scores as the tracks it was written from (with exactly what the format keeps of them), and bad files get one line
naming the file and line."""

import json
from collections import Counter

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq
import pytest

from simrig.cli import main
from simrig.dataset.tracks_file import TRACKS3D_FILE
from simrig.formats.export import export
from simrig.scoring import score


def assert_same(ours, theirs, part="metrics2d"):
    a, b = getattr(ours, part), getattr(theirs, part)
    assert a is not None and b is not None
    keys = ("overall", "per_camera", "per_class") if part == "metrics2d" else ("overall", "per_class")
    for key in keys:
        assert a[key].keys() == b[key].keys(), key
        for group in (a[key].values() if key != "overall" else [a[key]]):
            assert group
        for name, value in (a[key].items() if key == "overall" else []):
            assert value == pytest.approx(b[key][name], abs=1e-9, nan_ok=True), (key, name)
        if key != "overall":
            for sub, values in a[key].items():
                for name, value in values.items():
                    assert value == pytest.approx(b[key][sub][name], abs=1e-9, nan_ok=True), (key, sub, name)


@pytest.mark.parametrize("settings", [{}, {"classes": "any"}])
def test_motchallenge_export_scores_as_the_tracks(small_dataset, sort_tracks, tmp_path, settings):
    out = export(small_dataset, "motchallenge", tmp_path / "mot", tracks=sort_tracks, evaluation=settings)
    original = score(small_dataset, sort_tracks, evaluation=settings)
    assert original.metrics2d["overall"]["IDSW"] >= 0 and original.metrics2d["overall"]["HOTA"] > 0
    assert_same(score(small_dataset, out, evaluation=settings), original)
    # the tracker's folder of per-camera files, named as a format, gives the same
    data = out / "trackers" / "mot_challenge" / "SIMRIG-test" / "sort" / "data"
    assert_same(score(small_dataset, data, evaluation=settings, fmt="motchallenge"), original)


def test_kitti_export_scores_as_the_tracks(small_dataset, sort_tracks, tmp_path):
    """KITTI files keep pixel boxes at full precision: the export scores exactly as the tracks."""
    out = export(small_dataset, "kitti", tmp_path / "kitti", tracks=sort_tracks)
    assert_same(score(small_dataset, out), score(small_dataset, sort_tracks))


def test_nuscenes_export_scores_as_the_tracks(small_dataset, saga_tracks, tmp_path):
    """The results JSON holds 3D boxes with one class per track (its most frequent): the expected score is the
    original 3D tracks with that class, scored without their own 2D boxes (projected, as the JSON's are)."""
    out = export(small_dataset, "nuscenes", tmp_path / "nu", tracks=saga_tracks)
    table = pq.read_table(saga_tracks / TRACKS3D_FILE)
    ids, labels = table.column("track_id").to_pylist(), table.column("class").to_pylist()
    majority = {i: Counter(lab for j, lab in zip(ids, labels, strict=True) if j == i).most_common(1)[0][0]
                for i in set(ids)}
    table = table.set_column(table.schema.get_field_index("class"), "class",
                             pa.array([majority[i] for i in ids], pa.string()))
    expected_dir = tmp_path / "expected"
    expected_dir.mkdir()
    pq.write_table(table, expected_dir / TRACKS3D_FILE)
    expected = score(small_dataset, expected_dir)
    ours = score(small_dataset, out / "saga.json")
    assert expected.metrics3d["overall"]["AMOTA"] > 0
    assert_same(ours, expected, "metrics3d")
    assert_same(ours, expected, "metrics2d")
    assert pc.sum(table.column("score")).as_py() > 0


def _error_line(capsys, argv):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("simrig: error: ")
    return err


def test_bad_files_get_one_line_naming_file_and_line(small_dataset, tmp_path, capsys):
    camera = small_dataset.rig.camera_names[0]
    mot = tmp_path / f"{camera}-car.txt"
    mot.write_text("1,1,10,10,20,20,0.9,-1,-1,-1\n2,1,11,10,20,20,0.9,-1,-1,-1\n3,1,12,10,20,20,0.9,-1,-1\n")
    err = _error_line(capsys, ["score", str(small_dataset.path), str(mot)])
    assert f"{mot}:3: 9 columns where 10 are expected" in err

    kitti = tmp_path / f"{camera}.txt"
    kitti.write_text("0 1 Car 0 0 -10 10 10 30 30 -1 -1 -1 -1000 -1000 -1000 -10 0.9\n"
                     "1 1 Car 0 0 -10 10 10 3O 30 -1 -1 -1 -1000 -1000 -1000 -10 0.9\n")
    err = _error_line(capsys, ["score", str(small_dataset.path), str(kitti), "--format", "kitti"])
    assert f"{kitti}:2: column 9 (right) is '3O'" in err

    token = f"{small_dataset.scenario['name']}-seed{small_dataset.seed}-000000"
    box = {"translation": [10, 0, 1], "size": [2, 4.5, 1.5], "rotation": [1, 0, 0, 0], "velocity": [0, 0],
           "tracking_id": "1", "tracking_name": "car", "tracking_score": 0.5}
    nu = tmp_path / "results.json"
    nu.write_text(json.dumps({"meta": {}, "results": {token: [box], "not-a-sample": [box]}}, indent=1))
    err = _error_line(capsys, ["score", str(small_dataset.path), str(nu)])
    line = next(n for n, text in enumerate(nu.read_text().splitlines(), 1) if text.strip() == '"not-a-sample": [')
    assert f"{nu}:{line}: unknown sample token 'not-a-sample'" in err

    plain = tmp_path / "plain" / f"{camera}.txt"
    plain.parent.mkdir()
    plain.write_text("1,1,10,10,20,20,0.9,-1,-1,-1\n")
    err = _error_line(capsys, ["score", str(small_dataset.path), str(plain.parent)])
    assert "carry no class" in err and "classes=any" in err
    assert main(["score", str(small_dataset.path), str(plain.parent), "--evaluation", "classes=any"]) == 0


def test_layouts_and_ids_without_a_dataset(tmp_path):
    """Detection of each layout, KITTI types (pedestrians kept) and DontCare, nuScenes string ids and yaw (a
    class simrig has not, trailer, left out), on hand-written files."""
    from simrig.formats.tracks import detect_format, read_tracks_as

    cameras = ("left", "right")
    kitti = tmp_path / "kitti"
    kitti.mkdir()
    (kitti / "left.txt").write_text(
        "0 7 Van 0 0 -10 10 20 30 50 -1 -1 -1 -1000 -1000 -1000 -10 0.5\n"
        "0 -1 DontCare -1 -1 -10 0 0 5 5 -1 -1 -1 -1000 -1000 -1000 -10 1\n"
        "1 8 Pedestrian 0 0 -10 10 20 30 50 -1 -1 -1 -1000 -1000 -1000 -10 0.5\n")
    assert detect_format(kitti, cameras) == "kitti"
    rows = read_tracks_as(kitti, frame_count=2, cameras=cameras).tracks2d
    assert rows.track_id.tolist() == [7, 8] and rows.label.tolist() == ["car", "pedestrian"]
    assert rows.boxes.tolist() == [[10, 20, 30, 50]] * 2 and rows.score.tolist() == [0.5] * 2

    mot = tmp_path / "mot"
    mot.mkdir()
    (mot / "right-truck.txt").write_text("2,3,10.5,20,4,5,0.75,-1,-1,-1\n")
    assert detect_format(mot, cameras) == "motchallenge"
    rows = read_tracks_as(mot, frame_count=2, cameras=cameras).tracks2d
    assert (rows.frame.tolist(), rows.camera.tolist(), rows.label.tolist()) == ([1], ["right"], ["truck"])
    assert rows.boxes.tolist() == [[10.5, 20, 14.5, 25]]

    yaw = 2.0
    box = {"translation": [1, 2, 3], "size": [2, 5, 1.5], "rotation": [np.cos(yaw / 2), 0, 0, np.sin(yaw / 2)],
           "velocity": [1, 0], "tracking_name": "car", "tracking_score": 0.5}
    nu = tmp_path / "r.json"
    nu.write_text(json.dumps({"results": {"s0": [{**box, "tracking_id": "b"}, {**box, "tracking_id": "a"}],
                                          "s1": [{**box, "tracking_id": "x", "tracking_name": "trailer"}]}}))
    rows = read_tracks_as(nu, frame_count=2, cameras=cameras, tokens={"s0": 0, "s1": 1}).tracks3d
    assert sorted(rows.track_id.tolist()) == [0, 1]  # "a", "b" numbered in sorted order; the trailer left out
    assert rows.boxes[0, :7].tolist() == pytest.approx([1, 2, 3, 5, 2, 1.5, yaw])
