"""The tracks file format: round trip, clear errors for bad input, and ``simrig score`` end to end."""

import json

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from simrig.cli import main
from simrig.dataset.ground_truth import load_ground_truth
from simrig.dataset.tracks_file import TRACKS2D_SCHEMA, TRACKS3D_SCHEMA
from simrig.errors import TracksError
from simrig.formats.evaluation import IgnoreRule, evaluation_of, ignore_rules
from simrig.scoring import read_tracks, score, write_tracks
from simrig.types import ActorClass, Box2D, Box3D, Track

CAMERAS = ("CAM_A", "CAM_B")


def table3d(**overrides):
    columns = {"frame": [0, 0, 1], "track_id": [1, 2, 1], "class": ["car", "truck", "car"],
               "score": [0.9, 0.5, 0.8], "x": [1.0, 2.0, 3.0], "y": [0.0, 0.0, 0.0], "z": [0.8, 0.8, 0.8],
               "length": [4.6] * 3, "width": [1.9] * 3, "height": [1.6] * 3, "yaw": [0.0] * 3,
               "vx": [1.0] * 3, "vy": [0.0] * 3}
    columns.update(overrides)
    return pa.table({k: v for k, v in columns.items() if v is not None})


def write(tmp_path, table, name="tracks.parquet"):
    path = tmp_path / name
    pq.write_table(table, path)
    return path


def test_round_trip(tmp_path):
    frames = [(0, [Track(3, ActorClass.CAR, 0.7, Box3D(1, 2, 0.8, 4.6, 1.9, 1.6, 0.1, 5, 0),
                         {"CAM_A": Box2D(1, 2, 30, 40)})]),
              (1, [Track(3, ActorClass.CAR, 0.6, Box3D(1.5, 2, 0.8, 4.6, 1.9, 1.6, 0.1, 5, 0))])]
    write_tracks(tmp_path / "out", frames)
    assert pq.read_schema(tmp_path / "out" / "tracks3d.parquet").equals(TRACKS3D_SCHEMA, check_metadata=False)
    assert pq.read_schema(tmp_path / "out" / "tracks2d.parquet").equals(TRACKS2D_SCHEMA, check_metadata=False)
    tracks = read_tracks(tmp_path / "out", frame_count=2, cameras=CAMERAS)
    assert tracks.tracks3d.frame.tolist() == [0, 1] and tracks.tracks3d.boxes[1, 0] == 1.5
    assert tracks.tracks2d.camera.tolist() == ["CAM_A"] and tracks.tracks2d.boxes.tolist() == [[1, 2, 30, 40]]


def test_rows_in_any_order_come_back_sorted_by_frame_then_as_written(tmp_path):
    """Rows are read a column at a time; a file in several row groups, rows out of frame order: sorted by
    frame, ties in file order, every column moved with its row."""
    table = table3d(frame=[1, 0, 1, 0, 2], track_id=[5, 6, 7, 8, 9], **{"class": ["car"] * 5},
                    score=[0.1, 0.2, 0.3, 0.4, 0.5], x=[1.0, 2.0, 3.0, 4.0, 5.0], y=[0.0] * 5, z=[0.8] * 5,
                    length=[4.6] * 5, width=[1.9] * 5, height=[1.6] * 5, yaw=[0.0] * 5, vx=[1.0] * 5, vy=[0.0] * 5)
    path = tmp_path / "tracks.parquet"
    pq.write_table(table, path, row_group_size=2)
    assert pq.ParquetFile(path).num_row_groups == 3
    rows = read_tracks(path, frame_count=3, cameras=CAMERAS).tracks3d
    assert rows.frame.tolist() == [0, 0, 1, 1, 2] and rows.track_id.tolist() == [6, 8, 5, 7, 9]
    assert rows.score.tolist() == [0.2, 0.4, 0.1, 0.3, 0.5] and rows.boxes[:, 0].tolist() == [2, 4, 1, 3, 5]
    assert rows.frame.dtype == np.int64 and rows.boxes.flags.writeable


@pytest.mark.parametrize(("table", "message"), [
    (table3d(x=[1.0, float("nan"), 3.0]), "row 1 (frame 0, track 2): column 'x' is nan"),
    (table3d(track_id=[1, 1, 1]), "row 1 (frame 0, track 1): track id 1 appears twice in this frame (also row 0)"),
    (table3d(frame=[0, 0, 7]), "row 2 (frame 7, track 1): frame 7 is not in the dataset (frames 0…2)"),
    (table3d(score=None), "missing column(s) score"),
    (table3d(extra=[1, 2, 3]), "unknown column(s) extra"),
    (table3d(**{"class": ["car", "tank", "car"]}), "row 1 (frame 0, track 2): unknown class 'tank'"),
    (table3d(length=[4.6, 0.0, 4.6]), "row 1 (frame 0, track 2): box size [0.0, 1.9, 1.6] must be positive"),
    (table3d(frame=[0.0, 0.0, 1.0]), "column 'frame' must hold integers"),
    (table3d(y=pa.array([0.0, None, 0.0])), "row 1: column 'y' is null"),
])
def test_bad_3d_input_names_the_row_or_column(tmp_path, table, message):
    path = write(tmp_path, table)
    with pytest.raises(TracksError) as error:
        read_tracks(path, frame_count=3, cameras=CAMERAS)
    assert message in str(error.value) and str(path) in str(error.value)


def test_bad_2d_input(tmp_path):
    base = {"frame": [0, 0], "camera": ["CAM_A", "CAM_B"], "track_id": [1, 1], "class": ["car", "car"],
            "score": [0.5, 0.5], "x1": [0.0, 0.0], "y1": [0.0, 0.0], "x2": [10.0, 10.0], "y2": [10.0, 10.0]}
    read_tracks(write(tmp_path, pa.table(base)), frame_count=1, cameras=CAMERAS)  # one id in two cameras: fine
    for change, message in [({"camera": ["CAM_A", "CAM_Z"]}, "row 1 (frame 0, track 1, camera 'CAM_Z'): unknown "
                                                             "camera 'CAM_Z'"),
                            ({"camera": ["CAM_B", "CAM_B"]}, "track id 1 appears twice in this frame (also row 0)"),
                            ({"x2": [10.0, -1.0]}, "row 1 (frame 0, track 1, camera 'CAM_B'): empty box")]:
        path = write(tmp_path, pa.table({**base, **change}), "bad.parquet")
        with pytest.raises(TracksError, match=None) as error:
            read_tracks(path, frame_count=1, cameras=CAMERAS)
        assert message in str(error.value)


def test_missing_tracks_are_errors(tmp_path):
    with pytest.raises(TracksError, match="does not exist"):
        read_tracks(tmp_path / "nope", frame_count=1, cameras=CAMERAS)
    (tmp_path / "empty").mkdir()
    with pytest.raises(TracksError, match="holds neither"):
        read_tracks(tmp_path / "empty", frame_count=1, cameras=CAMERAS)


def ground_truth_tracks(truth, jitter_rng=None):
    frames = []
    for frame in truth.frames:
        rows = np.nonzero(truth.frame == frame)[0]
        frames.append((int(frame), [Track(int(truth.actor_id[r]) + 5, ActorClass(truth.label[r]), 0.8,
                                          Box3D(*truth.boxes[r].tolist())) for r in rows]))
    return frames


def test_perfect_tracker_scores_one_and_nothing_is_dropped(small_dataset, tmp_path):
    """Exact boxes under renamed ids: AMOTA 1, MOTA 1, IDS 0, HOTA 1 and no error. The boxes beyond the class
    range are dropped before projection (as the devkit drops far predictions), so the ground truth ignored for
    its range is left untracked — listed as ignored, never an error — and every other projected 2D box is a TP,
    an FP or removed because it sits on an ignored box (none silently dropped); with the evaluation region off,
    every one is a TP."""
    truth = load_ground_truth(small_dataset)
    write_tracks(tmp_path / "perfect", ground_truth_tracks(truth))
    report = score(small_dataset, tmp_path / "perfect")
    overall3d, overall2d = report.metrics3d["overall"], report.metrics2d["overall"]
    assert (overall3d["AMOTA"], overall3d["MOTA"], overall3d["IDS"], overall3d["AMOTP"]) == (1.0, 1.0, 0, 0.0)
    assert (overall2d["HOTA"], overall2d["MOTA"], overall2d["IDF1"], overall2d["IDSW"]) == (1.0, 1.0, 1.0, 0)
    assert set(report.errors.column("kind").to_pylist()) <= {"IGN"}  # no error
    far = ignore_rules(truth, evaluation_of(small_dataset.scenario)) & int(IgnoreRule.RANGE) != 0
    assert report.errors.num_rows == int(far.sum()) > 0  # untracked: exactly the ground truth beyond range
    assert all("ignored_range" in causes for causes in report.errors.column("causes").to_pylist())
    ignored = report.metrics2d["ground_truth"]["overall"]
    assert 0 < ignored["ignored"] < ignored["boxes"] == int(truth.in_view.sum())
    assert overall2d["CLR_TP"] + overall2d["CLR_FP"] + ignored["ignored"] == int(truth.in_view.sum())
    everything = score(small_dataset, tmp_path / "perfect", evaluation={"ignore": False}).metrics2d["overall"]
    assert everything["CLR_TP"] == int(truth.in_view.sum()) and everything["CLR_FP"] == 0


def test_cli_score_prints_a_table_and_writes_json(small_dataset, tmp_path, capsys):
    truth = load_ground_truth(small_dataset)
    frames = [(f, tracks[::2]) for f, tracks in ground_truth_tracks(truth)]  # every other actor missing
    write_tracks(tmp_path / "half", frames)
    out = tmp_path / "scores.json"
    assert main(["score", str(small_dataset.path), str(tmp_path / "half"), "--json", str(out),
                 "--errors", str(tmp_path / "errors.parquet")]) == 0
    printed = capsys.readouterr().out
    assert "AMOTA" in printed and "HOTA" in printed and "errors by cause" in printed
    data = json.loads(out.read_text())
    for name in ("AMOTA", "AMOTP", "MOTAR", "MOTA", "MOTP", "RECALL", "IDS", "FRAG", "MT", "ML", "TP", "FP", "FN",
                 "ATVE", "TVE"):
        assert name in data["3d"]["overall"] and all(name in v for v in data["3d"]["per_class"].values())
    for name in ("HOTA", "DetA", "AssA", "LocA", "MOTA", "MOTP", "IDSW", "Frag", "MT", "PT", "ML", "IDF1", "IDP",
                 "IDR"):
        assert name in data["2d"]["overall"] and set(data["2d"]["per_camera"]) == set(truth.rig.camera_names)
    assert 0.0 < data["3d"]["overall"]["RECALL"] < 1.0
    assert data["errors_by_cause"]["3d"]["total"]["FN"] == data["3d"]["overall"]["FN"]
    assert pq.read_table(tmp_path / "errors.parquet").num_rows > 0


def test_cli_bad_tracks_is_one_line(small_dataset, tmp_path, capsys):
    path = write(tmp_path, table3d(frame=[0, 0, 9999]))
    assert main(["score", str(small_dataset.path), str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "frame 9999 is not in the dataset" in err
