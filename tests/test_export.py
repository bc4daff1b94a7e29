"""``simrig export``: TrackEval run on the MOTChallenge export agrees with ``simrig score``; the KITTI and
nuScenes files hold what the dataset holds; an export is all or nothing."""

import json

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq
import pytest
import trackeval

from simrig.cli import main
from simrig.dataset.ground_truth import load_ground_truth
from simrig.formats import export as export_api
from simrig.formats.export import export
from simrig.pipeline.track import run_tracker
from simrig.scoring import score

COMPARED = ("HOTA", "DetA", "AssA", "MOTA", "IDSW", "IDF1")


def trackeval_on(out, tracker_name):
    """TrackEval's MotChallenge2DBox on an export: (combined values, values per camera), each camera's
    sequences combined by TrackEval's own ``combine_sequences``."""
    config = trackeval.Evaluator.get_default_eval_config()
    config.update(PRINT_RESULTS=False, PRINT_CONFIG=False, OUTPUT_SUMMARY=False, OUTPUT_DETAILED=False,
                  PLOT_CURVES=False, TIME_PROGRESS=False, DISPLAY_LESS_PROGRESS=True, USE_PARALLEL=False)
    dataset = trackeval.datasets.MotChallenge2DBox({
        "GT_FOLDER": str(out / "gt" / "mot_challenge"), "TRACKERS_FOLDER": str(out / "trackers" / "mot_challenge"),
        "BENCHMARK": "SIMRIG", "SPLIT_TO_EVAL": "test", "TRACKERS_TO_EVAL": [tracker_name], "PRINT_CONFIG": False})
    metrics = [trackeval.metrics.HOTA(), trackeval.metrics.CLEAR({"PRINT_CONFIG": False}),
               trackeval.metrics.Identity({"PRINT_CONFIG": False})]
    results, _ = trackeval.Evaluator(config).evaluate([dataset], metrics)
    per_sequence = results["MotChallenge2DBox"][tracker_name]

    def values(result):
        return {"HOTA": float(np.mean(result["HOTA"]["HOTA"])), "DetA": float(np.mean(result["HOTA"]["DetA"])),
                "AssA": float(np.mean(result["HOTA"]["AssA"])), "MOTA": float(result["CLEAR"]["MOTA"]),
                "IDSW": float(result["CLEAR"]["IDSW"]), "IDF1": float(result["Identity"]["IDF1"])}

    cameras = {}
    for name in per_sequence:
        if name != "COMBINED_SEQ":
            cameras.setdefault(name.rsplit("-", 1)[0], []).append(name)
    per_camera = {}
    for camera, names in cameras.items():
        combined = {metric.get_name(): metric.combine_sequences({n: per_sequence[n]["pedestrian"][metric.get_name()]
                                                                 for n in names}) for metric in metrics}
        per_camera[camera] = values(combined)
    return values(per_sequence["COMBINED_SEQ"]["pedestrian"]), per_camera


def assert_equal_to_trackeval(report, theirs):
    combined, per_camera = theirs
    for name in COMPARED:
        assert report.metrics2d["overall"][name] == pytest.approx(combined[name], abs=1e-9), name
    for camera, values in per_camera.items():
        for name in COMPARED:
            assert report.metrics2d["per_camera"][camera][name] == pytest.approx(values[name], abs=1e-9), \
                (camera, name)


@pytest.mark.parametrize("tracker_name", ["sort", "saga"])
def test_trackeval_on_the_motchallenge_export_equals_simrig_score(small_dataset, tmp_path, tracker_name):
    """2D tracks as written, and 3D tracks projected through the rig as the scorer projects them; ignored ground
    truth written as MOTChallenge distractors, so TrackEval's preprocessing ignores what simrig ignores."""
    run = run_tracker(small_dataset, tracker_name, tmp_path / tracker_name)
    out = export(small_dataset, "motchallenge", tmp_path / "mot", tracks=run.out)
    report = score(small_dataset, run.out)
    assert report.metrics2d["ground_truth"]["overall"]["ignored"] > 0
    assert_equal_to_trackeval(report, trackeval_on(out, tracker_name))


@pytest.mark.parametrize("settings", [{}, {"classes": "any", "min_height_px": 40}])
def test_trackeval_equals_simrig_with_tracker_boxes_on_ignored_boxes(small_dataset, tmp_path, settings):
    """Hand-built 2D tracks on a generated dataset: every scored box tracked with jitter and an id swap, a box
    exactly on every other ignored box and one shifted to IoU 0.6 on the rest (where boxes overlap, the
    preprocessing's Hungarian decides which ground truth a tracker box belongs to)."""
    truth = load_ground_truth(small_dataset)
    from simrig.dataset.tracks_file import TRACKS2D_FILE, TRACKS2D_SCHEMA
    from simrig.formats.evaluation import evaluation_of, ignore_rules

    rules = ignore_rules(truth, evaluation_of(small_dataset.scenario, settings))
    rng = np.random.default_rng(5)
    rows, cams = np.nonzero(truth.in_view)
    boxes = truth.boxes2d[rows, cams].copy()
    on_ignored = rules[rows, cams] != 0
    jitter = rng.normal(0, 1.5, size=boxes.shape) * ~on_ignored[:, None]
    boxes += jitter
    width = boxes[:, 2] - boxes[:, 0]
    shifted = on_ignored & (np.arange(len(rows)) % 2 == 1)
    boxes[shifted, 0] += 0.25 * width[shifted]
    boxes[shifted, 2] += 0.25 * width[shifted]
    boxes[:, 2:] = np.maximum(boxes[:, 2:], boxes[:, :2] + 1.0)
    ids = truth.actor_id[rows] + 1000 * (truth.frame[rows] > 15) * (truth.actor_id[rows] % 2)
    assert on_ignored.any() and (~on_ignored).any()
    names = np.array(truth.rig.camera_names, dtype=object)
    order = np.lexsort((cams, truth.frame[rows]))
    folder = tmp_path / "hand"
    folder.mkdir()
    b = boxes[order]
    pq.write_table(pa.table({
        "frame": truth.frame[rows][order].astype(np.int32), "camera": names[cams][order].tolist(),
        "track_id": ids[order].astype(np.int64), "class": truth.label[rows][order].tolist(),
        "score": np.ones(len(rows)), "x1": b[:, 0], "y1": b[:, 1], "x2": b[:, 2], "y2": b[:, 3]},
        schema=TRACKS2D_SCHEMA), folder / TRACKS2D_FILE)
    out = export(small_dataset, "motchallenge", tmp_path / "mot", tracks=folder, evaluation=settings)
    report = score(small_dataset, folder, evaluation=settings)
    assert_equal_to_trackeval(report, trackeval_on(out, "hand"))


def test_kitti_labels_hold_every_box_in_view_with_the_projected_depth_and_dont_care(small_dataset, tmp_path):
    out = export(small_dataset, "kitti", tmp_path / "kitti")
    truth = load_ground_truth(small_dataset)
    projections = small_dataset.table("projections").to_pylist()
    depth = {(p["frame"], p["actor_id"], p["camera"]): p["depth"] for p in projections}
    from simrig.formats.evaluation import evaluation_of, ignore_rules

    rules = ignore_rules(truth, evaluation_of(small_dataset.scenario))
    truncation = {(p["frame"], p["actor_id"], p["camera"]): p["truncation"] for p in projections}
    for c, camera in enumerate(truth.rig.camera_names):
        lines = (out / camera / "label_02" / "0000.txt").read_text().splitlines()
        assert len(lines) == int(truth.in_view[:, c].sum())
        dont_care = [line.split() for line in lines if line.split()[2] == "DontCare"]
        assert len(dont_care) == int(np.count_nonzero(rules[:, c]))  # ignored ground truth: KITTI's DontCare
        assert all(f[1] == "-1" for f in dont_care)
        for line in [line for line in lines if "DontCare" not in line][:20]:
            f = line.split()
            frame, actor = int(f[0]), int(f[1])
            row = np.nonzero((truth.frame == frame) & (truth.actor_id == actor))[0][0]
            fraction = truncation[(frame, actor, camera)]
            assert int(f[3]) == (0 if fraction <= 1e-9 else 1 if fraction <= 0.5 else 2)
            assert [float(v) for v in f[6:10]] == pytest.approx(truth.boxes2d_in([row], c)[0], abs=1e-3)
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


@pytest.fixture(scope="module")
def drifting_dataset(small_scenario, tmp_path_factory):
    """``small_dataset``'s scenario with an ego-pose error: the tracker is given a drifting, noisy pose."""
    from simrig.scenarios.overrides import with_setting

    from simrig.dataset import Dataset
    from simrig.pipeline.generate import generate

    scenario = with_setting(with_setting(small_scenario, "sensor.ego_pose.noise_m", 0.3),
                            "sensor.ego_pose.drift_m_per_sqrt_s", 0.5)
    out = tmp_path_factory.mktemp("drift") / "ds"
    generate(scenario, seed=0, out=out)
    return Dataset.open(out)


def test_an_export_under_ego_pose_error_scores_in_trackeval_as_in_simrig(drifting_dataset, tmp_path):
    """simrig scores 3D tracks relative to the ego (moved from the pose the tracker was given to the true one);
    the export writes them moved the same way, so TrackEval on its projected boxes agrees with simrig score
    (written as reported, TrackEval counted the pose error as well)."""
    run = run_tracker(drifting_dataset, "global_hungarian", tmp_path / "gh")
    tracks = pq.read_table(run.out / "tracks3d.parquet")
    assert tracks.num_rows and not (run.out / "tracks2d.parquet").exists()  # 3D only: the export projects it
    out = export(drifting_dataset, "motchallenge", tmp_path / "mot", tracks=run.out)
    assert_equal_to_trackeval(score(drifting_dataset, run.out), trackeval_on(out, "gh"))


# ------------------------------------------------------------------------------------------ capture timing
@pytest.fixture(scope="module")
def timed_dataset(tmp_path_factory):
    """A small dataset whose cameras fire one after another (sweep, 50 ms spread) and whose CAM_BACK takes an image
    every 2nd frame and CAM_FRONT every 4th."""
    from simrig.scenarios import load_scenario

    from simrig.dataset import Dataset
    from simrig.pipeline.generate import generate

    folder = tmp_path_factory.mktemp("timed")
    (folder / "timed.toml").write_text(
        'extends = "highway_surround6"\nframes = 24\n[traffic]\nvehicles = 12\nwindow_radius_m = 90.0\n'
        "spawn_min_distance_m = 60.0\n[render]\nvisibility = false\n"
        '[sensor.capture]\ntrigger = "sweep"\nspread_s = 0.05\nrate_hz = { CAM_BACK = 5.0, CAM_FRONT = 2.5 }\n')
    generate(load_scenario(folder / "timed.toml"), seed=3, out=folder / "ds", progress=False)
    return Dataset.open(folder / "ds")


def _rotate(quaternion, vector):
    """``vector`` rotated by the unit quaternion (w, x, y, z): v + 2w(q×v) + 2q×(q×v)."""
    w, q = quaternion[0], np.asarray(quaternion[1:])
    return vector + 2 * w * np.cross(q, vector) + 2 * np.cross(q, np.cross(q, vector))


def test_the_nuscenes_export_stamps_each_camera_image_with_its_capture_time(timed_dataset, tmp_path):
    out = export(timed_dataset, "nuscenes", tmp_path / "nu")
    tables = {name: json.loads((out / "v1.0-simrig" / f"{name}.json").read_text())
              for name in ("sample", "sample_data", "calibrated_sensor", "sensor", "ego_pose")}
    captures = pq.read_table(timed_dataset.path / "captures.parquet").to_pylist()
    egos = pq.read_table(timed_dataset.path / "ego_poses.parquet").to_pylist()
    sensors = {s["token"]: s["channel"] for s in tables["sensor"]}
    calibration = {c["token"]: c for c in tables["calibrated_sensor"]}
    poses = {p["token"]: p for p in tables["ego_pose"]}
    samples = {s["token"]: s for s in tables["sample"]}
    images = {}
    for record in tables["sample_data"]:
        channel = sensors[calibration[record["calibrated_sensor_token"]]["sensor_token"]]
        if channel != "LIDAR_TOP":
            images[channel, int(record["sample_token"].rsplit("-", 1)[1])] = record
    fired = [c for c in captures if c["fired"]]
    assert len(images) == len(fired) and len(fired) < len(captures)  # the slow cameras skip frames
    for capture in fired:
        record = images[capture["camera"], capture["frame"]]  # the surround rig's names are nuScenes channels
        assert record["timestamp"] == round(capture["capture_time"] * 1e6)
        offset = capture["capture_time"] - samples[record["sample_token"]]["timestamp"] * 1e-6
        ego, pose = egos[capture["frame"]], poses[record["ego_pose_token"]]
        moved = [ego["x"] + ego["vx"] * offset, ego["y"] + ego["vy"] * offset]
        assert pose["translation"][:2] == pytest.approx(moved)
    front = sorted(frame for channel, frame in images if channel == "CAM_FRONT")
    assert front == list(range(0, 24, 4))
    chain = [images["CAM_FRONT", frame] for frame in front]
    assert [r["next"] for r in chain[:-1]] == [r["token"] for r in chain[1:]] and chain[-1]["next"] == ""
    for camera in timed_dataset.rig.camera_names:  # the mount: the optical axis (camera z) along the camera's yaw
        mounted = calibration[f"calibrated-{camera}"]
        spec = timed_dataset.rig.camera(camera)
        axis = _rotate(mounted["rotation"], np.array([0.0, 0.0, 1.0]))
        assert axis == pytest.approx([np.cos(spec.yaw), np.sin(spec.yaw), 0.0], abs=1e-9)
        assert mounted["camera_intrinsic"] == [[spec.fx, 0.0, spec.cx], [0.0, spec.fy, spec.cy], [0.0, 0.0, 1.0]]


def test_a_slow_camera_s_motchallenge_sequence_scores_in_trackeval_as_in_simrig(timed_dataset, tmp_path):
    run = run_tracker(timed_dataset, "sort", tmp_path / "sort")
    before = score(timed_dataset, run.out).metrics2d["per_camera"]["CAM_FRONT"]["CLR_FP"]
    table = pq.read_table(run.out / "tracks2d.parquet")  # one more box, in CAM_FRONT at frame 1: it took no image
    front = table.filter(pc.equal(table.column("camera"), "CAM_FRONT")).slice(0, 1).to_pylist()[0]
    front.update(frame=1, track_id=999_999)
    pq.write_table(pa.concat_tables([table, pa.Table.from_pylist([front], schema=table.schema)]),
                   run.out / "tracks2d.parquet")
    report = score(timed_dataset, run.out)
    assert report.metrics2d["per_camera"]["CAM_FRONT"]["CLR_FP"] == before + 1
    out = export(timed_dataset, "motchallenge", tmp_path / "mot", tracks=run.out)
    assert_equal_to_trackeval(report, trackeval_on(out, "sort"))
    front = (out / "gt" / "mot_challenge" / "SIMRIG-test" / "CAM_FRONT-car" / "seqinfo.ini").read_text()
    assert "frameRate=10\n" in front and "cameraRate=2.5\n" in front and "seqLength=24\n" in front
