"""Every bad input is one line: exit status 2, ``simrig: error: ...`` naming the file, key, row, frame or option,
no traceback, and nothing written that looks complete. One case per malformed input found when simrig was probed
as a hostile user would (binary and Latin-1 TOML, a folder named ``.toml``, deep nesting, huge and non-finite
numbers, silently converted types, damaged datasets and tracks, malformed suites and replay files)."""

from __future__ import annotations

import json
import shutil
import tomllib
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import tomli_w

from simrig.cli import main
from simrig.pipeline.track import run_tracker
from simrig.testing import write_replay

HERE = Path(__file__).parent
SCENARIO_HEAD = 'extends = "highway_surround6"\nframes = 3\n'
SUITE_HEAD = 'scenarios = ["highway_surround6"]\nseeds = [0]\nframes = 2\n'
SUITE_TRACKER = '[[trackers]]\ntracker = "saga"\n'


@pytest.fixture(scope="module")
def inputs(tmp_path_factory, small_dataset, small_scenario):
    """A folder of bad inputs, a good dataset and good tracks (read-only for the cases)."""
    root = tmp_path_factory.mktemp("bad-inputs")
    files = {
        "binary.toml": b"\x00\x01\xff\xfe\x80garbage",
        "latin1.toml": 'description = "café"\n'.encode("latin-1"),
        "deep.toml": ("a = " + "[" * 3000 + "]" * 3000 + "\n").encode(),
        "syntax.toml": b"frames = = 3\n",
    }
    for name, data in files.items():
        (root / name).write_bytes(data)
    (root / "folder.toml").mkdir()
    scenarios = {
        "huge_radius": "[traffic]\nwindow_radius_m = 1e308\n",
        "frames_true": "frames = true\n",
        "frames_float": "frames = 1.5\n",
        "frames_text": 'frames = "10"\n',
        "frames_zero": "frames = 0\n",
        "frames_date": "frames = 1979-05-27\n",
        "unknown_key": 'colour = "red"\n',
        "vehicles_negative": "[traffic]\nvehicles = -1\n",
        "vehicles_float": "[traffic]\nvehicles = 1e9\n",
        "visibility_no": '[render]\nvisibility = "no"\n',
        "visibility_tiny": "[render]\nvisibility_scale = 0.0001\n",
        "window_after_run": '[[perturbations]]\nkind = "miss_burst"\nframes = [50, 60]\n',
        "window_missing": '[[perturbations]]\nkind = "miss_burst"\n',
        "camera_unknown": '[[perturbations]]\nkind = "blackout"\ncameras = ["CAM_TOP"]\nframes = [0, 1]\n',
        "actor_float": '[[perturbations]]\nkind = "occlude"\nframes = [0, 1]\nactors = [1.7]\n',
        "rate_nan": "frame_rate_hz = nan\n",
        "rate_inf": "frame_rate_hz = inf\n",
        "speeds_reversed": "[traffic]\nspeed_range_mps = [30.0, 20.0]\n",
        "speed_huge": "[traffic]\nego_speed_mps = 1e6\n",
        "class_plane": "[traffic.class_mix]\nplane = 1.0\n",
        "preset_unknown": '[rig]\npreset = "octopus"\n',
        "probability_high": "[sensor.detection]\nprobability = 1.5\n",
    }
    for name, body in scenarios.items():
        head = SCENARIO_HEAD if not name.startswith("frames_") else 'extends = "highway_surround6"\n'
        (root / f"{name}.toml").write_text(head + body)
    (root / "extends_unknown.toml").write_text('extends = "nowhere"\n')
    (root / "cycle_a.toml").write_text('extends = "cycle_b"\n')  # catalog names only: a file cannot extend a file
    suites = {
        "suite_frames_true": SUITE_HEAD.replace("frames = 2", "frames = true") + SUITE_TRACKER,
        "suite_seed_negative": SUITE_HEAD.replace("[0]", "[-1]") + SUITE_TRACKER,
        "suite_seed_float": SUITE_HEAD.replace("[0]", "[1.5]") + SUITE_TRACKER,
        "suite_no_trackers": SUITE_HEAD + "trackers = []\n",
        "suite_unknown_key": SUITE_HEAD + "colour = 1\n" + SUITE_TRACKER,
        "suite_sweep_text": SUITE_HEAD + SUITE_TRACKER + '[[sweeps]]\nparameter = "rig.overlap_deg"\nvalues = ["a"]\n',
        "suite_sweep_unknown": SUITE_HEAD + SUITE_TRACKER + '[[sweeps]]\nparameter = "colour"\nvalues = [1]\n',
        "suite_bad_name": 'name = "../../escape"\n' + SUITE_HEAD + SUITE_TRACKER,
        "suite_scenario_missing": SUITE_HEAD.replace("highway_surround6", "nowhere") + SUITE_TRACKER,
        "suite_param_unknown": SUITE_HEAD + SUITE_TRACKER + "params = { colour = 1 }\n",
        "suite_camera_unknown": SUITE_HEAD + SUITE_TRACKER + 'camera = "nowhere"\n',
        "suite_import": SUITE_HEAD + '[[trackers]]\ntracker = "bench_trackers:Crashing"\n',
    }
    for name, body in suites.items():
        (root / f"{name}.toml").write_text(body)
    (root / "suite_binary.toml").write_bytes(b"\xff\xfe\x00")
    short = small_scenario.model_copy(update={"frames": 3})
    good = tomllib.loads(write_replay(root / "replay_good.toml", short, 0, tracker="saga").read_text())
    replays = {
        "replay_scores_5": {"scores": 5},
        "replay_hota_high": {"scores": {"2d": {"HOTA": "high"}}},
        "replay_seed_text": {"seed": "0"},
        "replay_seed_true": {"seed": True},
        "replay_no_scenario": {"scenario": None},
        "replay_params_3": {"params": 3},
        "replay_tracker_5": {"tracker": 5},
        "replay_frames_true": {"scenario": {**good["scenario"], "frames": True}},
        "replay_unknown_key": {"colour": 1},
    }
    for name, change in replays.items():
        document = {key: value for key, value in {**good, **change}.items() if value is not None}
        (root / f"{name}.toml").write_text(tomli_w.dumps(document))

    tracks = run_tracker(small_dataset, "saga", root / "tracks").out
    table = pq.read_table(tracks / "tracks3d.parquet")
    bad_tracks = {
        "ids_float": table.set_column(table.schema.get_field_index("track_id"), "track_id",
                                      pa.array([i + 0.7 for i in table.column("track_id").to_pylist()])),
        "box_nan": table.set_column(table.schema.get_field_index("x"), "x",
                                    pa.array([float("nan")] * table.num_rows)),
        "class_unknown": table.set_column(table.schema.get_field_index("class"), "class",
                                          pa.array(["plane"] * table.num_rows)),
    }
    for name, bad in bad_tracks.items():
        pq.write_table(bad, root / f"{name}.parquet")
    (root / "garbage.parquet").write_bytes(b"PAR1 not really")
    pq.write_table(table, root / "truncated.parquet")
    data = (root / "truncated.parquet").read_bytes()
    (root / "truncated.parquet").write_bytes(data[: len(data) // 2])

    damaged = {
        "ds_deleted_table": lambda d: (d / "ground_truth.parquet").unlink(),
        "ds_garbage_table": lambda d: (d / "detections.parquet").write_bytes(b"garbage"),
        "ds_truncated_table": lambda d: (d / "projections.parquet").write_bytes(
            (d / "projections.parquet").read_bytes()[:100]),
        "ds_missing_rig": lambda d: (d / "rig.json").unlink(),
        "ds_empty_rig": lambda d: (d / "rig.json").write_text(""),
        "ds_no_manifest": lambda d: (d / "manifest.json").unlink(),
        "ds_garbage_manifest": lambda d: (d / "manifest.json").write_text("{not json"),
        "ds_manifest_escape": lambda d: _edit(d, lambda m: m["files"]["rig"].update(file="../../etc/hostname")),
        "ds_manifest_frames": lambda d: _edit(d, lambda m: m.update(frames=m["frames"] + 1)),
    }
    for name, damage in damaged.items():
        damage(shutil.copytree(small_dataset.path, root / name))
    (root / "empty_folder").mkdir()
    (root / "bench_garbage").mkdir()
    (root / "bench_garbage" / "bench.json").write_text("{oops")
    return {"root": root, "ds": small_dataset.path, "tracks": tracks}


def _edit(folder, change):
    manifest = json.loads((folder / "manifest.json").read_text())
    change(manifest)
    (folder / "manifest.json").write_text(json.dumps(manifest))


# (case id, argv with {root} {ds} {tracks} {out} placeholders, text the error line must contain)
CASES = [
    # scenario files
    ("toml-binary", "generate {root}/binary.toml --out {out}", "binary.toml': not UTF-8"),
    ("toml-latin1", "generate {root}/latin1.toml --out {out}", "latin1.toml': not UTF-8"),
    ("toml-folder", "generate {root}/folder.toml --out {out}", "folder.toml' is a folder"),
    ("toml-deep", "generate {root}/deep.toml --out {out}", "deep.toml"),
    ("toml-syntax", "generate {root}/syntax.toml --out {out}", "syntax.toml': not valid TOML"),
    ("toml-missing", "generate {root}/nowhere.toml --out {out}", "nowhere.toml' does not exist"),
    ("scenario-unknown-name", "generate nowhere --out {out}", "unknown scenario 'nowhere'"),
    ("radius-1e308", "generate {root}/huge_radius.toml --out {out}", "traffic.window_radius_m"),
    ("frames-true", "generate {root}/frames_true.toml --out {out}", "frames: Input should be a valid integer"),
    ("frames-float", "generate {root}/frames_float.toml --out {out}", "frames:"),
    ("frames-text", "generate {root}/frames_text.toml --out {out}", "frames:"),
    ("frames-zero", "generate {root}/frames_zero.toml --out {out}", "frames:"),
    ("frames-date", "generate {root}/frames_date.toml --out {out}", "frames:"),
    ("unknown-key", "generate {root}/unknown_key.toml --out {out}", "colour: unknown key"),
    ("vehicles-negative", "generate {root}/vehicles_negative.toml --out {out}", "traffic.vehicles"),
    ("vehicles-float", "generate {root}/vehicles_float.toml --out {out}", "traffic.vehicles"),
    ("visibility-no", "generate {root}/visibility_no.toml --out {out}", "render.visibility: Input should be a valid "
                                                                        "boolean"),
    ("visibility-scale-tiny", "generate {root}/visibility_tiny.toml --out {out}", "render.visibility_scale"),
    ("window-after-run", "generate {root}/window_after_run.toml --out {out}", "window_after_run.toml': "
                                                                              "perturbations.0.frames: the window "
                                                                              "starts at frame 50"),
    # new-user trial: found when the rig is built, after the file was read: the message did not name the file
    ("camera-unknown", "generate {root}/camera_unknown.toml --out {out}", "camera_unknown.toml': "
                                                                          "perturbations.0.cameras: rig 'surround6' "
                                                                          "has no camera 'CAM_TOP'"),
    ("camera-unknown-run", "run {root}/camera_unknown.toml --out {out}", "camera_unknown.toml': "
                                                                         "perturbations.0.cameras: rig 'surround6' "
                                                                         "has no camera 'CAM_TOP'"),
    ("window-missing", "generate {root}/window_missing.toml --out {out}", "perturbations.0"),
    ("actor-id-float", "generate {root}/actor_float.toml --out {out}", "perturbations.0"),
    ("rate-nan", "generate {root}/rate_nan.toml --out {out}", "frame_rate_hz"),
    ("rate-inf", "generate {root}/rate_inf.toml --out {out}", "frame_rate_hz"),
    ("speeds-reversed", "generate {root}/speeds_reversed.toml --out {out}", "speed_range_mps"),
    ("speed-huge", "generate {root}/speed_huge.toml --out {out}", "traffic.ego_speed_mps"),
    ("class-unknown", "generate {root}/class_plane.toml --out {out}", "class_mix"),
    ("preset-unknown", "generate {root}/preset_unknown.toml --out {out}", "rig.preset"),
    ("probability-above-1", "generate {root}/probability_high.toml --out {out}", "sensor.detection.probability"),
    ("extends-unknown", "generate {root}/extends_unknown.toml --out {out}", "extends: unknown catalog scenario"),
    ("extends-a-file", "generate {root}/cycle_a.toml --out {out}", "extends: unknown catalog scenario 'cycle_b'"),
    # command-line values
    ("frames-20-digits", "generate --frames 99999999999999999999 --out {out}", "--frames: must be at most"),
    ("frames-0", "generate --frames 0 --out {out}", "--frames: must be at least 1"),
    ("frames-text-arg", "generate --frames ten --out {out}", "--frames: expected an integer"),
    ("seed-negative", "generate --seed -1 --out {out}", "--seed"),
    ("seed-huge", "generate --seed 99999999999999999999999 --out {out}", "--seed: must be at most"),
    ("lookback-inf", "score {ds} {tracks} --lookback inf", "--lookback: must be a finite number"),
    ("lookback-nan", "score {ds} {tracks} --lookback nan", "--lookback"),
    ("lookback-negative", "score {ds} {tracks} --lookback -1", "--lookback"),
    ("param-nan", "track {ds} --param gate=nan --out {out}", "gate=nan: a parameter must be a finite number"),
    ("param-inf", "track {ds} --param gate=inf --out {out}", "gate=inf"),
    ("param-no-value", "track {ds} --param gate --out {out}", "expected key=value"),
    ("param-twice", "track {ds} --param gate=1 --param gate=2 --out {out}", "--param gate given twice"),
    ("param-unknown", "track {ds} --param colour=1 --out {out}", "no parameter 'colour'"),
    ("tracker-unknown", "track {ds} --tracker nowhere --out {out}", "unknown tracker 'nowhere'"),
    ("tracker-not-factory", "track {ds} --tracker os:system --out {out}", "'os:system' is a builtin_function_or_"
                                                                          "method, not a tracker factory"),
    ("tracker-not-importable", "track {ds} --tracker no_such_module:X --out {out}", "cannot import it"),
    *[(f"tracker-{mode}", f"track {{ds}} --tracker misbehaving_trackers:Misbehaving --param mode={mode} --out {{out}}",
       expected) for mode, expected in (
        ("raise", "'misbehaving_trackers:Misbehaving': frame 2: step() raised ZeroDivisionError"),
        ("dict", "frame 2: step() returned a dict, not a list of Track"),
        ("none", "frame 2: step() returned a NoneType, not a list of Track"),
        ("string_ids", "frame 2: item 0: track_id 'a' is not an integer"),
        ("float_ids", "frame 2: item 0: track_id 1.7 is not an integer"),
        ("bool_ids", "frame 2: item 0: track_id True is not an integer"),
        ("duplicate_ids", "frame 2: track 1: track_id appears twice in this frame"),
        ("unknown_label", "frame 2: track 1: label 'plane' is not a known class"),
        ("nan_score", "frame 2: track 1: score nan is not a finite number"),
        ("nan_box", "frame 2: track 1: box3d has a non-finite value"),
        ("unknown_camera", "frame 2: track 1: boxes2d names camera 'NOWHERE'"),
        ("not_tracks", "frame 2: item 0 is a str, not a Track"),
    )],
    ("run-tracker-unknown", "run --frames 2 --tracker nowhere --out {out}", "unknown tracker 'nowhere'"),
    ("run-param-nan", "run --frames 2 --param gate=nan --out {out}", "gate=nan"),
    ("out-under-a-file", "track {ds} --out {root}/binary.toml/tracks", "which is a file"),
    ("out-in-proc", "track {ds} --out /proc/simrig", "system folder /proc"),
    # damaged datasets
    ("info-missing", "info {root}/nowhere", "does not exist"),
    ("info-a-file", "info {root}/binary.toml", "is a file, not a dataset folder"),
    ("info-empty-folder", "info {root}/empty_folder", "holds no complete simrig dataset"),
    ("render-frame-outside", "render {ds} --frame 100000", "--frame: 100000 is outside"),
    ("score-deleted-table", "score {root}/ds_deleted_table {tracks}", "ground_truth (ground_truth.parquet) is missing"),
    ("score-garbage-table", "track {root}/ds_garbage_table --out {out}", "detections (detections.parquet) does not"),
    ("score-truncated-table", "score {root}/ds_truncated_table {tracks}", "projections (projections.parquet) does "
                                                                          "not match"),
    ("score-missing-rig", "score {root}/ds_missing_rig {tracks}", "rig (rig.json) is missing"),
    ("score-empty-rig", "score {root}/ds_empty_rig {tracks}", "rig (rig.json) does not match"),
    ("score-no-manifest", "score {root}/ds_no_manifest {tracks}", "holds no complete simrig dataset"),
    ("score-garbage-manifest", "score {root}/ds_garbage_manifest {tracks}", "manifest is not valid JSON"),
    ("manifest-escape", "score {root}/ds_manifest_escape {tracks}", "files.rig.file must be a plain file name"),
    ("manifest-edited", "info {root}/ds_manifest_frames --verify", "manifest was edited"),
    # damaged tracks
    ("tracks-missing", "score {ds} {root}/nowhere", "nowhere"),
    ("tracks-id-1.7", "score {ds} {root}/ids_float.parquet", "column 'track_id' must hold integers"),
    ("tracks-nan-box", "score {ds} {root}/box_nan.parquet", "column 'x' is nan"),
    ("tracks-unknown-class", "score {ds} {root}/class_unknown.parquet", "unknown class 'plane'"),
    ("tracks-garbage", "score {ds} {root}/garbage.parquet", "garbage.parquet"),
    ("tracks-truncated", "score {ds} {root}/truncated.parquet", "truncated.parquet"),
    ("score-camera-unknown", "score {ds} {tracks} --camera nowhere", "nowhere"),
    ("export-dataset-missing", "export {root}/nowhere --format kitti --out {out}", "does not exist"),
    ("export-format-unknown", "export {ds} --format csv --out {out}", "--format: invalid choice"),
    # suites
    ("suite-binary", "bench {root}/suite_binary.toml --out {out}", "suite_binary.toml': not UTF-8"),
    ("suite-folder", "bench {root}/folder.toml --out {out}", "folder.toml' is a folder"),
    ("suite-frames-true", "bench {root}/suite_frames_true.toml --out {out}", "frames: Input should be a valid integer"),
    ("suite-seed-negative", "bench {root}/suite_seed_negative.toml --out {out}", "seeds.0"),
    ("suite-seed-float", "bench {root}/suite_seed_float.toml --out {out}", "seeds.0"),
    ("suite-no-trackers", "bench {root}/suite_no_trackers.toml --out {out}", "trackers"),
    ("suite-unknown-key", "bench {root}/suite_unknown_key.toml --out {out}", "colour: unknown key"),
    ("suite-sweep-text", "bench {root}/suite_sweep_text.toml --out {out}", "sweeps.0.values.0"),
    ("suite-sweep-unknown", "bench {root}/suite_sweep_unknown.toml --out {out}", "sweeps.0.parameter"),
    ("suite-name-escapes", "bench {root}/suite_bad_name.toml", "name: String should match pattern"),
    ("suite-scenario-missing", "bench {root}/suite_scenario_missing.toml --out {out}", "scenarios.0"),
    ("suite-param-unknown", "bench {root}/suite_param_unknown.toml --out {out}", "no parameter 'colour'"),
    ("suite-camera-unknown", "bench {root}/suite_camera_unknown.toml --out {out}", "camera 'nowhere'"),
    ("suite-import-untrusted", "bench {root}/suite_import.toml --out {out}", "--trust-file"),
    ("suite-unknown-name", "bench nowhere --out {out}", "unknown suite 'nowhere'"),
    ("bench-workers-0", "bench smoke --workers 0 --out {out}", "--workers: must be at least 1"),
    ("bench-engine-unknown", "bench smoke --engine slurm --out {out}", "--engine: invalid choice"),
    # replay files
    ("replay-scores-5", "replay {root}/replay_scores_5.toml", "scores: must be a table"),
    ("replay-hota-high", "replay {root}/replay_hota_high.toml", "scores.2d.HOTA: must be a finite number"),
    ("replay-seed-text", "replay {root}/replay_seed_text.toml", "needs an integer 'seed'"),
    ("replay-seed-true", "replay {root}/replay_seed_true.toml", "needs an integer 'seed'"),
    ("replay-no-scenario", "replay {root}/replay_no_scenario.toml", "[scenario] table"),
    ("replay-params-3", "replay {root}/replay_params_3.toml", "params: must be a table"),
    ("replay-tracker-5", "replay {root}/replay_tracker_5.toml", "tracker: must be non-empty text"),
    ("replay-frames-true", "replay {root}/replay_frames_true.toml", "scenario: frames: Input should be a valid "
                                                                     "integer"),
    ("replay-unknown-key", "replay {root}/replay_unknown_key.toml", "colour: unknown key"),
    ("replay-binary", "replay {root}/binary.toml", "binary.toml': not UTF-8"),
    ("replay-missing", "replay {root}/nowhere.toml", "nowhere.toml' does not exist"),
    # bench folders
    ("report-missing", "report {root}/nowhere", "nowhere"),
    ("report-no-bench-json", "report {root}/empty_folder", "has no bench.json"),
    ("report-garbage-bench-json", "report {root}/bench_garbage", "bench.json"),
]


@pytest.mark.parametrize(("argv", "expected"), [case[1:] for case in CASES], ids=[case[0] for case in CASES])
def test_bad_input_is_one_line_exit_2_and_writes_nothing_complete(argv, expected, inputs, tmp_path, capsys,
                                                                  monkeypatch):
    monkeypatch.syspath_prepend(str(HERE))  # bench_trackers and misbehaving_trackers
    monkeypatch.chdir(tmp_path)  # default output folders (runs/...) land here, where they are checked
    out = tmp_path / "out"
    words = [word.format(root=inputs["root"], ds=inputs["ds"], tracks=inputs["tracks"], out=out)
             for word in argv.split()]
    try:
        code = main(words)
    except SystemExit as exit_:  # argparse's usage errors exit from inside parse_args
        code = exit_.code
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1 and lines[0].startswith("simrig: error: "), err
    assert "Traceback" not in err
    assert expected in lines[0], lines[0]
    written = [path for path in tmp_path.rglob("*") if path.name in ("manifest.json", "score.json", "bench.json",
                                                                      "results.parquet", "tracks3d.parquet")]
    assert not written, written


def test_there_are_at_least_sixty_cases():
    assert len(CASES) >= 60 and len({case[0] for case in CASES}) == len(CASES)


def test_settings_that_cannot_take_effect_are_warned_about(tmp_path, capsys):
    """Valid but ineffective: an actor id that never appears, a density the window cannot hold, a window cut off
    by --frames — each a warning naming the key (the dataset is still what the simulation produced)."""
    scenario = tmp_path / "crowded.toml"
    scenario.write_text(
        'extends = "highway_surround6"\nframes = 4\n'
        "[traffic]\nvehicles = 40\nwindow_radius_m = 5.0\nspawn_min_distance_m = 0.0\ninitial_clearance_m = 0.0\n"
        "[render]\nvisibility = false\n"
        '[[perturbations]]\nkind = "occlude"\nframes = [0, 1]\nactors = [9999]\n'
        '[[perturbations]]\nkind = "drop_frames"\nframes = [3, 3]\n'
        '[[perturbations]]\nkind = "miss_burst"\nframes = [1, 5]\n'
    )
    assert main(["generate", str(scenario), "--frames", "3", "--out", str(tmp_path / "out"), "--quiet"]) == 0
    warnings = [line for line in capsys.readouterr().err.splitlines() if line.startswith("warning: ")]
    assert any("perturbations.0 (occlude): actor id(s) [9999] never appear" in line for line in warnings), warnings
    assert any("perturbations.1 (drop_frames) starts at frame 3, after the last of the 3 frames" in line
               for line in warnings), warnings
    # new-user trial: a window that starts inside the run but ends after it was cut off without a word
    assert any("perturbations.2 (miss_burst) covers frames 1–5, but only 3 frames were generated: it applies to "
               "frames 1–2 only" in line for line in warnings), warnings
    assert any("traffic.vehicles = 40, but only" in line and "unreachable" in line for line in warnings), warnings
