"""The command line: summaries, and one-line errors that name the problem."""

import json

import pytest

from simrig.cli import main


def _error_line(capsys):
    err = capsys.readouterr().err.strip()
    assert err.startswith("simrig: error:")
    assert "\n" not in err and "Traceback" not in err
    return err


def test_generate_prints_a_summary_then_info_reads_it(tmp_path, capsys):
    out = tmp_path / "d"
    assert main(["generate", "highway_stereo", "--seed", "4", "--frames", "8", "--out", str(out), "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert "highway_stereo" in printed and "seed 4" in printed and "left, right" in printed
    assert main(["info", str(out), "--verify"]) == 0
    assert "verified" in capsys.readouterr().out


def test_scenarios_lists_the_catalog_one_line_each(capsys):
    assert main(["scenarios"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert any(line.startswith("* highway_surround6") for line in lines)
    assert any("highway_stereo" in line for line in lines)


def test_unknown_scenario_key_is_one_line(tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text('extends = "highway_surround6"\n[traffic]\nlane_count = 3\n')
    assert main(["generate", str(path), "--out", str(tmp_path / "d")]) == 2
    err = _error_line(capsys)
    assert "traffic.lane_count: unknown key" in err and str(path) in err


def test_unknown_preset_is_one_line(tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text('extends = "highway_surround6"\n[rig]\npreset = "octopus"\n')
    assert main(["generate", str(path), "--out", str(tmp_path / "d")]) == 2
    assert "rig.preset" in _error_line(capsys)


def test_negative_frame_count_is_one_line(tmp_path, capsys):
    with pytest.raises(SystemExit) as raised:
        main(["generate", "highway_surround6", "--frames", "-3", "--out", str(tmp_path / "d")])
    assert raised.value.code == 2
    err = _error_line(capsys)
    assert "simrig: error: --frames: must be at least 1, got -3" in err


def test_complete_output_folder_is_one_line(tmp_path, capsys):
    out = tmp_path / "d"
    assert main(["generate", "highway_stereo", "--frames", "3", "--out", str(out), "--quiet"]) == 0
    capsys.readouterr()
    assert main(["generate", "highway_stereo", "--frames", "3", "--out", str(out), "--quiet"]) == 2
    err = _error_line(capsys)
    assert "already holds a complete dataset" in err and "--overwrite" in err


def test_info_on_a_folder_without_dataset_is_one_line(tmp_path, capsys):
    assert main(["info", str(tmp_path)]) == 2
    assert "no complete simrig dataset" in _error_line(capsys)


def test_render_writes_a_mosaic_and_rejects_a_frame_outside_the_dataset(tmp_path, capsys):
    out = tmp_path / "d"
    assert main(["generate", "highway_stereo", "--frames", "3", "--out", str(out), "--quiet"]) == 0
    capsys.readouterr()
    assert main(["render", str(out), "--frame", "2", "--out", str(tmp_path / "m.png")]) == 0
    png = (tmp_path / "m.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
    assert main(["render", str(out), "--frame", "3"]) == 2
    assert "--frame: 3 is outside the dataset's frames 0 … 2" in _error_line(capsys)


def test_images_are_written_per_camera_and_covered_by_the_manifest(tmp_path, capsys):
    out = tmp_path / "d"
    assert main(["generate", "highway_stereo", "--frames", "2", "--out", str(out), "--quiet", "--images"]) == 0
    assert sorted(p.relative_to(out).as_posix() for p in (out / "images").rglob("*.png")) == [
        "images/left/000000.png", "images/left/000001.png", "images/right/000000.png", "images/right/000001.png"
    ]
    assert main(["info", str(out), "--verify"]) == 0
    (out / "images" / "left" / "000001.png").write_bytes(b"tampered")
    assert main(["info", str(out), "--verify"]) == 2
    assert "images" in _error_line(capsys)


def test_track_then_score_a_dataset(small_dataset, tmp_path, capsys):
    out = tmp_path / "tracks"
    assert main(["track", str(small_dataset.path), "--tracker", "global_hungarian", "--param", "gate=4.5",
                 "--out", str(out)]) == 0
    assert "tracked   30 frames with global_hungarian" in capsys.readouterr().out
    assert (out / "tracks3d.parquet").exists()
    assert main(["score", str(small_dataset.path), str(out), "--json", str(tmp_path / "asked.json")]) == 0
    printed = capsys.readouterr().out
    assert "AMOTA" in printed and "Planner-aware" in printed
    assert main(["score", str(small_dataset.path), str(out), "--no-planner",
                 "--json", str(tmp_path / "not.json")]) == 0
    assert "Planner-aware: not asked" in capsys.readouterr().out
    asked, not_asked = (json.loads((tmp_path / name).read_text()) for name in ("asked.json", "not.json"))
    assert asked["3d"]["planner"] == {"scored": True} and asked["3d"]["overall"]["PKL"] >= 0
    assert not_asked["3d"]["planner"] == {"scored": False, "note": "not asked"}


def test_track_with_a_bad_tracker_or_parameter_is_one_line(small_dataset, tmp_path, capsys):
    assert main(["track", str(small_dataset.path), "--tracker", "nope", "--out", str(tmp_path / "t")]) == 2
    assert "unknown tracker 'nope'; known:" in _error_line(capsys)
    assert main(["track", str(small_dataset.path), "--param", "gamm=0.2", "--out", str(tmp_path / "t")]) == 2
    assert "'saga' has no parameter 'gamm'" in _error_line(capsys)
    with pytest.raises(SystemExit) as exit_:
        main(["track", str(small_dataset.path), "--param", "gamma", "--out", str(tmp_path / "t")])
    assert exit_.value.code == 2 and "expected key=value" in _error_line(capsys)


def test_run_generates_tracks_scores_and_reports_with_the_command(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", "highway_stereo", "--frames", "12", "--tracker", "simpletrack", "--out", str(out),
                 "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert "AMOTA" in printed and "reusing" not in printed
    report = (out / "report.md").read_text()
    assert "simrig run highway_stereo --seed 0 --tracker simpletrack --frames 12 --out THIS_FOLDER" in report
    assert str(tmp_path) not in report  # no absolute path in a results file
    scores = out / "scores" / "simpletrack"
    assert (scores / "score.json").exists() and (scores / "errors.parquet").exists()
    assert (out / "tracks" / "simpletrack" / "tracks3d.parquet").exists()
    assert main(["run", "highway_stereo", "--frames", "12", "--seed", "1", "--out", str(out), "--quiet"]) == 2
    assert "holds a dataset of another scenario, seed or frame count" in _error_line(capsys)


def test_a_second_tracker_reuses_the_matching_dataset_and_writes_its_own_tracks_and_score(tmp_path, capsys):
    """``run … --tracker saga --out R`` then ``… --tracker sort --out R``: the second reuses the
    dataset (and says so), writes its own tracks and score, and leaves the first run's files as they were."""
    out = tmp_path / "R"
    common = ["run", "highway_stereo", "--frames", "12", "--seed", "0", "--out", str(out), "--quiet"]
    assert main([*common, "--tracker", "saga"]) == 0
    capsys.readouterr()
    dataset_before = {p.name: p.stat().st_mtime_ns for p in (out / "dataset").iterdir()}
    saga_score = (out / "scores" / "saga" / "score.json").read_bytes()
    assert main([*common, "--tracker", "sort"]) == 0
    printed = capsys.readouterr().out
    assert f"dataset   reusing the complete dataset in {out / 'dataset'} (highway_stereo, seed 0, 12 frames" in printed
    assert {p.name: p.stat().st_mtime_ns for p in (out / "dataset").iterdir()} == dataset_before
    assert (out / "scores" / "saga" / "score.json").read_bytes() == saga_score
    sort_score = json.loads((out / "scores" / "sort" / "score.json").read_text())
    assert sort_score["tracks"] == "tracks/sort" and sort_score["dataset"] == "dataset"
    assert (out / "tracks" / "sort" / "tracks2d.parquet").exists()
    index = (out / "report.md").read_text()
    assert "tracker saga" in index and "tracker sort" in index
    timings = json.loads((out / "scores" / "sort" / "timings.json").read_text())
    assert timings["dataset_reused"] is True and timings["generation_s"] is None




def test_a_reader_that_leaves_early_is_not_a_traceback(tmp_path):
    # New-user trial: `simrig scenarios | head -3` ended in a BrokenPipeError traceback.
    import subprocess
    import sys

    for command in ("scenarios", "trackers"):
        run = subprocess.run(f"{sys.executable} -m simrig.cli {command} | head -c 5", shell=True, capture_output=True,
                             text=True, timeout=120, cwd=tmp_path)
        assert len(run.stdout) == 5 and "Traceback" not in run.stderr and "BrokenPipe" not in run.stderr, run.stderr
        assert "Broken pipe" not in run.stderr, run.stderr  # `simrig scenarios | grep -q X` printed an error line


def test_a_file_given_as_a_dataset_is_called_a_file(tmp_path, capsys):
    (tmp_path / "manifest.json").write_text("{}")
    assert main(["info", str(tmp_path / "manifest.json")]) == 2
    assert capsys.readouterr().err == (f"simrig: error: {str(tmp_path / 'manifest.json')!r} is a file, not a dataset "
                                       "folder (a dataset is the folder holding manifest.json)\n")
