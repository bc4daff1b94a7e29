"""``simrig import``: ground truth made elsewhere scores as the peers score it (TrackEval on MOTChallenge, the
nuScenes devkit on nuScenes), a generated dataset survives export → import with the same score, what the source
lacks is marked unknown, and bad input gets one line naming the file and line."""

import importlib.util
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from simrig.cli import main
from simrig.dataset import Dataset
from simrig.formats.export import export
from simrig.formats.importing import import_dataset
from simrig.formats.nuscenes.samples import sample_tokens, scene_of_frame
from simrig.scoring import score
from simrig.scoring.planner import PLANNER_METRICS
from simrig.scoring.results import METRICS_3D

sys.path.insert(0, str(Path(__file__).parent))
from motchallenge_case import write_case as write_mot_case  # noqa: E402
from nuscenes_case import SPLIT, VERSION  # noqa: E402
from nuscenes_case import write_case as write_nuscenes_case  # noqa: E402

COMPARED_2D = ("HOTA", "DetA", "AssA", "MOTA", "IDSW", "IDF1")
COMPARED_3D = ("AMOTA", "AMOTP", "MOTAR", "MOTA", "MOTP", "RECALL", "IDS", "FRAG", "MT", "ML", "TP", "FP", "FN")
CACHED_VENV = Path(__file__).resolve().parents[1] / ".cache" / "nuscenes-venv"
DEVKIT_PYTHON = Path(os.environ.get("SIMRIG_NUSCENES_PYTHON", CACHED_VENV / "bin" / "python"))
"""A Python with ``nuscenes-devkit`` (it pins numpy < 2, so it lives beside simrig's environment, not in it)::

    python3 -m venv .cache/nuscenes-venv
    .cache/nuscenes-venv/bin/pip install 'numpy<2' nuscenes-devkit==1.2.0 'pandas<2' motmetrics==1.4.0
"""


# ----------------------------------------------------------------------------------------------- MOTChallenge
def test_motchallenge_import_scores_as_trackeval(tmp_path, capsys):
    pytest.importorskip("trackeval")
    from motchallenge_case import trackeval_scores

    _, data = write_mot_case(tmp_path / "mot")
    expected = trackeval_scores(tmp_path / "mot")
    assert main(["import", "--format", "motchallenge", str(tmp_path / "mot"), "--out", str(tmp_path / "ds")]) == 0
    assert "2D only ground truth" in capsys.readouterr().out
    assert main(["score", str(tmp_path / "ds"), str(data), "--json", str(tmp_path / "score.json")]) == 0
    printed = capsys.readouterr().out
    ours = json.loads((tmp_path / "score.json").read_text())
    for name in COMPARED_2D:
        assert ours["2d"]["overall"][name] == pytest.approx(expected[name], abs=1e-9), name
    assert 0.3 < expected["HOTA"] < 0.9 and expected["IDSW"] >= 2  # a case where the numbers say something
    # 2D only: no 3D numbers anywhere, and no cause is invented
    assert ours["3d"] is None and "AMOTA" not in printed and "3D: not scored" in printed
    assert set(ours["errors_by_cause"]["2d"]) <= {"unknown", "total", "ignored"}
    assert ours["errors_by_cause"]["2d"]["unknown"] == ours["errors_by_cause"]["2d"]["total"]
    # the source's marks: distractors (a static person and a reflection every third frame, a static person every
    # fifth) and rows not evaluated (a car every third frame, a car and a pedestrian with consider 0.4 every fifth)
    gt = ours["2d"]["ground_truth"]["overall"]
    thirds, fifths = (sum(len(range(first, n + 1, step)) for n in (40, 30, 25)) for first, step in ((1, 3), (2, 5)))
    assert (gt["source"], gt["unevaluated"]) == (2 * thirds + fifths, thirds + 2 * fifths)
    assert gt["ignored"] == gt["source"] + gt["unevaluated"]
    # had the rows not evaluated been left out, the tracker boxes on the car and static person would be removed
    assert ours["2d"]["overall"]["CLR_FP"] >= 2 * fifths


def test_motchallenge_import_keeps_sequences_and_conventions(tmp_path):
    write_mot_case(tmp_path / "mot")
    import_dataset("motchallenge", tmp_path / "mot", tmp_path / "ds")
    dataset = Dataset.open(tmp_path / "ds")
    assert dataset.rig.camera_names == ("MOT17-02", "MOT17-04", "MOT17-09")
    assert [(c.width, c.height) for c in dataset.rig.cameras] == [(1920, 1080)] * 3
    assert dataset.frame_count == 40 and dataset.scenario["frame_rate_hz"] == 30
    assert not dataset.has_3d and dataset.source["calibrated_rig"] is False
    truth = dataset.ground_truth
    gt_lines = (tmp_path / "mot/gt/mot_challenge/MOT17-train/MOT17-04/gt/gt.txt").read_text().split()
    first = min((line.split(",") for line in gt_lines if line.split(",")[7] == "1"), key=lambda f: int(f[0]))
    row = np.nonzero((truth.frame == int(first[0]) - 1) & (truth.actor_id == 1_000_000_000 + int(first[1])))[0][0]
    left, top, width, height = map(float, first[2:6])
    assert truth.boxes2d[row, 1].tolist() == [left, top, left + width, top + height]  # 1-based frame → 0-based
    assert truth.label[row] == "pedestrian" and np.isnan(truth.boxes[row]).all()
    marks = Dataset.open(tmp_path / "ds").source_ignored_table().to_pydict()
    car = marks["reason"].index("class 3 (car), consider 0")
    assert marks["kind"][car] == "unevaluated" and "class 7 (static_person)" in marks["reason"]
    assert marks["kind"][marks["reason"].index("class 1 (pedestrian), consider 0.4")] == "unevaluated"


# ----------------------------------------------------------------------------------------------- nuScenes
def test_nuscenes_import_scores_as_the_devkit(tmp_path):
    """The devkit's TrackingEval on its own tables and results file against ``simrig import`` + ``simrig
    score`` on the same files. Skipped without a Python that has the devkit (see :data:`DEVKIT_PYTHON`)."""
    if not DEVKIT_PYTHON.exists():
        pytest.skip(f"no nuscenes-devkit environment at {DEVKIT_PYTHON} (set SIMRIG_NUSCENES_PYTHON)")
    results = write_nuscenes_case(tmp_path / "nu")
    run = subprocess.run([str(DEVKIT_PYTHON), str(Path(__file__).parent / "nuscenes_devkit_eval.py"),
                          str(tmp_path / "nu"), VERSION, SPLIT, str(results), str(tmp_path / "devkit")],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    devkit = json.loads(run.stdout.strip().splitlines()[-1])
    import_dataset("nuscenes", tmp_path / "nu", tmp_path / "ds")
    ours = score(tmp_path / "ds", results)
    assert ours.metrics2d is None
    for name in COMPARED_3D:
        assert ours.metrics3d["overall"][name] == pytest.approx(devkit[name.lower()], abs=1e-9), name
        for label, value in devkit["label_metrics"][name.lower()].items():
            if value is not None and not np.isnan(value):
                assert ours.metrics3d["per_class"][label][name] == pytest.approx(value, abs=1e-9), (label, name)
    assert set(ours.metrics3d["per_class"]) == {"car", "truck", "pedestrian", "bicycle"}
    assert 0.3 < devkit["amota"] < 0.95 and devkit["ids"] >= 2


def test_nuscenes_import_reads_the_devkit_tables(tmp_path):
    """Without the devkit: scenes follow each other, the ego pose is LIDAR_TOP's, a box with no point is left out,
    and a tracking id names one track per scene."""
    results = write_nuscenes_case(tmp_path / "nu")
    import_dataset("nuscenes", tmp_path / "nu", tmp_path / "ds")
    dataset = Dataset.open(tmp_path / "ds")
    assert dataset.frame_count == 24 + 18 and dataset.scenario["frame_rate_hz"] == pytest.approx(2.0)
    assert dataset.rig.cameras == () and dataset.has_3d and not dataset.has_2d
    assert dataset.source["left_out_boxes"]["no_points"] == 2  # one per scene
    tokens = sample_tokens(dataset)
    assert tokens["scene-a-sample-000"] == 0 and tokens["scene-b-sample-000"] == 24
    poses = json.loads((tmp_path / "nu" / VERSION / "ego_pose.json").read_text())
    truth = dataset.ground_truth
    assert (truth.egos[24].x, truth.egos[24].y) == tuple(poses[24]["translation"][:2])
    assert np.all(np.diff(truth.timestamps) > 0)
    tracks = json.loads(results.read_text())["results"]
    ids = {(k >= 24, box["tracking_id"]) for k, boxes in enumerate(tracks.values()) for box in boxes}
    report = score(dataset, results)
    assert report.metrics3d["overall"]["TP"] > 0 and report.metrics2d is None
    from simrig.formats.tracks import read_tracks_as

    read = read_tracks_as(results, "nuscenes", frame_count=dataset.frame_count, cameras=(), tokens=tokens,
                          scenes=scene_of_frame(dataset))
    assert len(np.unique(read.tracks3d.track_id)) == len(ids)


# ----------------------------------------------------------------------------------------------- round trips
def assert_same(ours: dict, theirs: dict, names=None):
    assert ours.keys() == theirs.keys()
    for name in names or ours:
        assert ours[name] == pytest.approx(theirs[name], abs=1e-9, nan_ok=True), name


@pytest.mark.parametrize("fmt", ["motchallenge", "kitti"])
def test_export_import_round_trip_2d(small_dataset, sort_tracks, tmp_path, fmt):
    original = score(small_dataset, sort_tracks)
    out = export(small_dataset, fmt, tmp_path / "export", tracks=sort_tracks)
    import_dataset(fmt, out, tmp_path / "ds")
    imported = Dataset.open(tmp_path / "ds")
    again = score(imported, out)
    assert 0 < original.metrics2d["overall"]["HOTA"] < 1 and original.metrics2d["overall"]["CLR_FN"] > 0
    assert again.metrics3d is None
    assert_same(again.metrics2d["overall"], original.metrics2d["overall"])
    # a camera that saw nothing and was given no track has no file to come back from
    assert set(imported.rig.camera_names) <= set(small_dataset.rig.camera_names)
    for camera, values in original.metrics2d["per_camera"].items():
        if camera in imported.rig.camera_names:
            assert_same(again.metrics2d["per_camera"][camera], values)
        else:
            assert original.metrics2d["ground_truth"]["per_camera"][camera]["boxes"] == 0 and values["CLR_FP"] == 0
    for label, values in original.metrics2d["per_class"].items():
        if label in again.metrics2d["per_class"] or fmt == "motchallenge":
            assert_same(again.metrics2d["per_class"][label], values)
        else:  # KITTI's DontCare has no class: a class whose every box was ignored does not come back
            assert values["CLR_TP"] == values["CLR_FN"] == values["CLR_FP"] == 0, label
    # what the evaluation region ignored comes back as the source's marks
    assert (again.metrics2d["ground_truth"]["overall"]["source"]
            >= original.metrics2d["ground_truth"]["overall"]["ignored"] > 0)


def test_export_import_round_trip_nuscenes(small_dataset, saga_tracks, tmp_path):
    out = export(small_dataset, "nuscenes", tmp_path / "export", tracks=saga_tracks)
    original = score(small_dataset, out / "saga.json")
    import_dataset("nuscenes", out, tmp_path / "ds")
    imported = Dataset.open(tmp_path / "ds")
    again = score(imported, out / "saga.json")
    assert original.metrics3d["overall"]["AMOTA"] > 0
    assert_same(again.metrics3d["overall"], original.metrics3d["overall"], names=METRICS_3D)
    # an imported dataset has no ego planner to ask: its planner-aware scores are NaN, and the report says why
    assert all(math.isnan(again.metrics3d["overall"][name]) for name in PLANNER_METRICS)
    assert again.metrics3d["planner"]["note"].startswith("not scored: the dataset was not simulated by simrig")
    assert original.metrics3d["planner"] == {"scored": True}
    for label, values in original.metrics3d["per_class"].items():
        assert_same(again.metrics3d["per_class"][label], values)
    assert imported.frame_count == small_dataset.frame_count
    assert imported.scenario["frame_rate_hz"] == pytest.approx(small_dataset.scenario["frame_rate_hz"])


def test_nuscenes_export_loads_in_the_devkit(small_dataset, saga_tracks, tmp_path):
    """The export's tables and split run through the devkit's own TrackingEval, with simrig's AMOTA family."""
    if not DEVKIT_PYTHON.exists():
        pytest.skip(f"no nuscenes-devkit environment at {DEVKIT_PYTHON} (set SIMRIG_NUSCENES_PYTHON)")
    from simrig.formats.nuscenes.writer import SPLIT as EXPORT_SPLIT
    from simrig.formats.nuscenes.writer import VERSION as EXPORT_VERSION

    out = export(small_dataset, "nuscenes", tmp_path / "export", tracks=saga_tracks)

    def devkit(results: Path) -> dict:
        run = subprocess.run([str(DEVKIT_PYTHON), str(Path(__file__).parent / "nuscenes_devkit_eval.py"), str(out),
                              EXPORT_VERSION, EXPORT_SPLIT, str(results), str(tmp_path / results.stem)],
                             capture_output=True, text=True, timeout=300)
        assert run.returncode == 0, run.stderr[-2000:]
        return json.loads(run.stdout.strip().splitlines()[-1])

    # the ground truth as a tracker's results: no gap anywhere, so every number is the same
    theirs, ours = devkit(out / "ground_truth.json"), score(small_dataset, out / "ground_truth.json").metrics3d
    for name in COMPARED_3D:
        assert ours["overall"][name] == pytest.approx(theirs[name.lower()], abs=1e-9), name
    assert theirs["tp"] > 50
    # saga loses a car for a frame or two and finds it again: the devkit fills such a gap by interpolation (its
    # inverted weights included), and so does simrig by default: every number is the same
    theirs, shipped = devkit(out / "saga.json"), score(small_dataset, out / "saga.json").metrics3d["overall"]
    for name in COMPARED_3D:
        assert shipped[name] == pytest.approx(theirs[name.lower()], abs=1e-9), name
    # without the gap filling the frames are scored as given, and the best-MOTA threshold each side picks may
    # differ: only the ground truth in range is the same
    ours = score(small_dataset, out / "saga.json", interpolation="none").metrics3d["overall"]
    assert theirs["tp"] + theirs["fn"] == ours["TP"] + ours["FN"] and ours["AMOTA"] != shipped["AMOTA"]


# ----------------------------------------------------------------------------------------------- unknowns
def test_imported_dataset_renders_and_summarises(tmp_path, capsys):
    _, data = write_mot_case(tmp_path / "mot")
    import_dataset("motchallenge", tmp_path / "mot", tmp_path / "ds")
    assert main(["render", str(tmp_path / "ds"), "--frame", "3", "--tracks", str(data),
                 "--out", str(tmp_path / "m.png")]) == 0
    assert (tmp_path / "m.png").stat().st_size > 1000
    assert main(["info", str(tmp_path / "ds"), "--verify"]) == 0
    out = capsys.readouterr().out
    assert "imported from motchallenge" in out and "error causes unknown" in out
    assert "sensor    none (an imported dataset holds ground truth only)" in out and "missed" not in out
    if importlib.util.find_spec("rerun") is not None:  # the viewer is an optional extra
        assert main(["view", str(tmp_path / "ds"), "--save", str(tmp_path / "v.rrd")]) == 0
        assert (tmp_path / "v.rrd").stat().st_size > 1000


# ----------------------------------------------------------------------------------------------- bad input
def _error(capsys, argv) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("simrig: error: "), err
    return err


def test_bad_input_one_line_naming_file_and_line(tmp_path, capsys):
    # a MOT file with 9 columns where 10 are expected
    write_mot_case(tmp_path / "mot")
    gt = tmp_path / "mot/gt/mot_challenge/MOT17-train/MOT17-04/gt/gt.txt"
    lines = gt.read_text().splitlines()
    lines = [line + ",-1" for line in lines]
    lines[2] = lines[2].rsplit(",", 1)[0]
    gt.write_text("\n".join(lines) + "\n")
    err = _error(capsys, ["import", "--format", "motchallenge", str(tmp_path / "mot"), "--out", str(tmp_path / "a")])
    assert f"{gt}:3: 9 columns where 10 are expected" in err
    assert not (tmp_path / "a").exists() and not list(tmp_path.glob(".a*"))  # nothing half-written

    # a KITTI file with a non-numeric field
    labels = tmp_path / "kitti" / "label_02"
    labels.mkdir(parents=True)
    (labels / "0000.txt").write_text("0 1 Car 0 0 -10 10 20 110 90 -1 -1 -1 -1000 -1000 -1000 -10\n"
                                     "1 1 Car 0 0 -10 1x 20 110 90 -1 -1 -1 -1000 -1000 -1000 -10\n")
    err = _error(capsys, ["import", "--format", "kitti", str(tmp_path / "kitti"), "--out", str(tmp_path / "b")])
    assert f"{labels / '0000.txt'}:2: column 7 (left) is '1x'" in err

    # a nuScenes results JSON with an unknown sample token, and an annotation of an unknown sample
    results = write_nuscenes_case(tmp_path / "nu")
    import_dataset("nuscenes", tmp_path / "nu", tmp_path / "nu-ds")
    document = json.loads(results.read_text())
    document["results"]["no-such-sample"] = []
    results.write_text(json.dumps(document, indent=1))
    line = next(k for k, text in enumerate(results.read_text().splitlines(), 1) if "no-such-sample" in text)
    err = _error(capsys, ["score", str(tmp_path / "nu-ds"), str(results)])
    assert f"{results}:{line}: unknown sample token 'no-such-sample'" in err
    annotations = tmp_path / "nu" / VERSION / "sample_annotation.json"
    table = json.loads(annotations.read_text())
    table[5]["sample_token"] = "no-such-sample"
    annotations.write_text(json.dumps(table, indent=1))
    line = next(k for k, text in enumerate(annotations.read_text().splitlines(), 1) if table[5]["token"] in text)
    err = _error(capsys, ["import", "--format", "nuscenes", str(tmp_path / "nu"), "--out", str(tmp_path / "c")])
    assert f"{annotations}:{line}: unknown sample token 'no-such-sample'" in err

    # an import into a folder that holds a dataset: refused, the dataset untouched
    manifest = (tmp_path / "nu-ds" / "manifest.json").read_bytes()
    err = _error(capsys, ["import", "--format", "motchallenge", str(tmp_path / "mot2"), "--out",
                          str(tmp_path / "nu-ds")])
    assert "does not exist" in err
    write_mot_case(tmp_path / "mot2")
    err = _error(capsys, ["import", "--format", "motchallenge", str(tmp_path / "mot2"), "--out",
                          str(tmp_path / "nu-ds")])
    assert f"{str(tmp_path / 'nu-ds')!r} already holds a complete dataset" in err and "--overwrite" in err
    assert (tmp_path / "nu-ds" / "manifest.json").read_bytes() == manifest


def test_tracks_of_the_missing_dimension_are_refused(tmp_path, capsys):
    """3D tracks on 2D-only ground truth, or 2D tracks on ground truth without cameras: one line, no number."""
    results = write_nuscenes_case(tmp_path / "nu")
    _, data = write_mot_case(tmp_path / "mot")
    import_dataset("nuscenes", tmp_path / "nu", tmp_path / "nu-ds")
    import_dataset("motchallenge", tmp_path / "mot", tmp_path / "mot-ds")
    mot_ds = Dataset.open(tmp_path / "mot-ds")
    tokens = {f"{mot_ds.scenario['name']}-seed0-{f:06d}": f for f in range(3)}
    assert set(tokens) <= set(sample_tokens(mot_ds))
    document = json.loads(results.read_text())
    boxes = next(iter(document["results"].values()))
    (tmp_path / "r3d.json").write_text(json.dumps({"results": {token: boxes for token in tokens}}))
    err = _error(capsys, ["score", str(tmp_path / "mot-ds"), str(tmp_path / "r3d.json")])
    assert "2D ground truth only" in err
    camera_file = tmp_path / "cam" / "CAM.txt"
    camera_file.parent.mkdir()
    camera_file.write_text("1,1,10,10,20,20,0.9,-1,-1,-1\n")
    err = _error(capsys, ["score", str(tmp_path / "nu-ds"), str(camera_file)])
    assert "CAM" in err  # the dataset has no camera of that name (it has none)
