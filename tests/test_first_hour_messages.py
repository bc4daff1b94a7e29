"""Messages a tracker author met in the first hour that pointed the wrong way (each reproduced before its fix): a
score report or a folder of trackers given as tracks, a part of a run folder given to explain, a collection's index
file given as the collection, a crashing tracker with no place named, an empty scenario name."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from simrig.cli import main


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    """A ``simrig run`` folder with two trackers run into it (5 frames of ``highway_stereo``)."""
    folder = tmp_path_factory.mktemp("first-hour") / "run"
    for tracker in ("sort", "deepsort"):
        assert main(["run", "highway_stereo", "--frames", "5", "--tracker", tracker, "--out", str(folder),
                     "--quiet"]) == 0
    return folder


def _error(capsys, argv: list[str]) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("simrig: error: ") and err.count("\n") == 1, err
    return err


def test_a_score_report_given_as_tracks_says_so_and_where_the_tracks_are(run_folder, capsys):
    err = _error(capsys, ["score", str(run_folder / "dataset"), str(run_folder / "scores" / "sort" / "score.json")])
    assert "is a score report of a run folder, not tracks" in err and str(run_folder / "tracks" / "sort") in err
    assert "results" not in err  # not the nuScenes reader's complaint


def test_a_folder_of_several_trackers_lists_them(run_folder, capsys):
    err = _error(capsys, ["score", str(run_folder / "dataset"), str(run_folder / "tracks")])
    assert "holds the tracks of 2 trackers (deepsort, sort)" in err and "--format" not in err


def test_explain_points_from_a_part_of_the_run_folder_to_the_folder_and_names_the_option_it_shows(run_folder,
                                                                                                   capsys):
    err = _error(capsys, ["explain", str(run_folder / "dataset"), "--tracker", "sort"])
    assert f"give the run folder itself: simrig explain {run_folder}" in err and "dataset/dataset" not in err
    err = _error(capsys, ["explain", str(run_folder), "--tracker", "sortt"])
    assert "--tracker 'sortt'" in err and "deepsort, sort" in err and "--label" not in err


def test_a_collections_index_file_is_not_taken_for_the_collection(tmp_path):
    from simrig.collection.loader import CollectionPairs
    from simrig.collection.run import COLLECTION_FILE, INDEX_FILE
    from simrig.errors import DatasetError

    (tmp_path / COLLECTION_FILE).write_text("{}")
    (tmp_path / INDEX_FILE).write_bytes(b"")
    with pytest.raises(DatasetError, match=r"is a file, not a collection folder; the collection is its folder"):
        CollectionPairs(tmp_path / INDEX_FILE)


def test_a_crashing_tracker_names_the_file_and_line_and_shows_the_traceback_on_request(tmp_path):
    (tmp_path / "crashy.py").write_text(textwrap.dedent("""\
        class Crashy:
            def reset(self, *, rig, seed=None):
                self.count = 0

            def step(self, frame):
                return [1 / self.count]
        """))
    argv = [sys.executable, "-m", "simrig", "run", "highway_stereo", "--frames", "3", "--tracker", "crashy:Crashy",
            "--out", "run", "--quiet"]
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    env.pop("SIMRIG_TRACEBACK", None)
    done = subprocess.run(argv, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    where = f"{tmp_path / 'crashy.py'}:6 in step"
    assert done.returncode == 2 and f"ZeroDivisionError: division by zero (at {where};" in done.stderr
    assert "Traceback" not in done.stderr and "SIMRIG_TRACEBACK=1 shows the whole traceback" in done.stderr
    shown = subprocess.run([*argv[:-3], "--out", "run2", "--quiet"], cwd=tmp_path,
                           env={**env, "SIMRIG_TRACEBACK": "1"}, capture_output=True, text=True, timeout=300)
    assert "Traceback (most recent call last)" in shown.stderr and "return [1 / self.count]" in shown.stderr
    assert shown.stderr.rstrip().splitlines()[-1].startswith("simrig: error: ")
    assert f"(at {where})" in shown.stderr and "shows the whole traceback" not in shown.stderr  # no hint then


@pytest.mark.parametrize("command", ["generate", "run", "drive"])
def test_an_empty_scenario_name_is_an_error_not_the_default_scenario(command, tmp_path, capsys):
    assert not Path(tmp_path / "out").exists()
    with pytest.raises(SystemExit) as stop:
        main([command, "", "--out", str(tmp_path / "out")])
    assert stop.value.code == 2 and "an empty scenario name" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_valid_nuscenes_results_file_is_scored_under_a_3_gib_address_space_limit(small_dataset, saga_tracks,
                                                                                    tmp_path):
    """Containers and CI runners cap the address space: reading a results file asked the OS for the whole 2 GiB
    cap up front (``read(max + 1)``), a MemoryError for any file, valid ones included."""
    import resource

    assert main(["export", str(small_dataset.path), "--tracks", str(saga_tracks), "--format", "nuscenes", "--out",
                 str(tmp_path / "export")]) == 0
    results = next(path for path in (tmp_path / "export").glob("*.json") if path.stem == saga_tracks.name)

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (3 * 2**30, 3 * 2**30))

    done = subprocess.run([sys.executable, "-m", "simrig", "score", str(small_dataset.path), str(results)],
                          preexec_fn=limit, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "AMOTA" in done.stdout


def test_nan_in_a_manifest_or_a_tracker_record_is_named_in_one_line(run_folder, tmp_path, capsys):
    import shutil

    copy = shutil.copytree(run_folder, tmp_path / "run")
    record = copy / "tracks" / "sort" / "tracker.json"
    record.write_text(record.read_text().replace('"params": {}', '"params": {"max_age": NaN}'))
    err = _error(capsys, ["explain", str(copy), "--tracker", "sort"])
    assert f"{record}: tracker.json is not valid JSON (NaN is not a JSON number" in err
    manifest = copy / "dataset" / "manifest.json"
    manifest.write_text(manifest.read_text().replace('"frame_rate_hz": 10.0', '"frame_rate_hz": NaN'))
    err = _error(capsys, ["info", str(copy / "dataset")])
    assert f"{manifest}: manifest is not valid JSON (NaN is not a JSON number" in err


@pytest.mark.parametrize(("source", "said"), [
    ("def f(:\n", "importing bad_module raised SyntaxError: invalid syntax"),
    ("raise RuntimeError('boom')\n", "importing bad_module raised RuntimeError: boom"),
    ("import sys\nsys.exit(0)\n", "importing bad_module raised SystemExit: 0"),
])
def test_a_tracker_module_that_fails_on_import_is_one_line_naming_file_and_line(source, said, tmp_path):
    (tmp_path / "bad_module.py").write_text(source)
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    env.pop("SIMRIG_TRACEBACK", None)
    done = subprocess.run([sys.executable, "-m", "simrig", "run", "highway_stereo", "--frames", "2", "--tracker",
                           "bad_module:T", "--out", "run", "--quiet"], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr[-2000:]  # exit(0) on import: not 0
    assert said in done.stderr and f"(at {tmp_path / 'bad_module.py'}:" in done.stderr
    assert not (tmp_path / "run").exists()


def test_a_relative_module_name_and_a_closed_output_are_one_line_or_nothing(capsys, small_dataset):
    err = _error(capsys, ["run", "highway_stereo", "--frames", "2", "--tracker", "..x:Y", "--out", "unused"])
    assert "'..x' is a relative module name" in err
    done = subprocess.run(f"{sys.executable} -m simrig info {small_dataset.path} >&-", shell=True,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stderr == ""


def test_another_distribution_owning_files_of_the_simrig_package_is_said_in_one_line(tmp_path):
    """PyPI's unrelated ``simrig`` (what a plugin declaring ``dependencies = ["simrig"]`` pulls in) writes into the
    same package folder; ``--version``, ``simrig trackers`` and the pytest plugin's header say so."""
    info = tmp_path / "simrig-0.5.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: simrig\nVersion: 0.5.0\n")
    (info / "RECORD").write_text("simrig/__init__.py,,\nsimrig/cli.py,,\nsimrig-0.5.0.dist-info/RECORD,,\n")
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    for argv in (["--version"], ["trackers"]):
        done = subprocess.run([sys.executable, "-m", "simrig", *argv], env=env, capture_output=True, text=True,
                              timeout=120)
        assert done.returncode == 0
        assert done.stderr.count("\n") == 1 and "simrig 0.5.0 also installed files into the simrig package" in \
            done.stderr and "depends on 'simrig-mot'" in done.stderr
    clean = subprocess.run([sys.executable, "-m", "simrig", "--version"], capture_output=True, text=True, timeout=120)
    assert clean.stderr == ""
    from simrig.testing.plugin import pytest_report_header

    assert pytest_report_header(None) == []


@pytest.mark.parametrize("setting", ["sensor.ego_pose.noise_m", "traffic.ego_speed_mps", "sensor.latency.fixed_s"])
def test_an_absurd_number_in_a_scenario_is_refused_naming_the_key(setting, tmp_path, capsys):
    """Every real-valued setting is bounded (10⁶ in its unit at most): ``noise_m = 1e200`` was accepted."""
    table, _, key = setting.rpartition(".")
    scenario = tmp_path / "absurd.toml"
    scenario.write_text(f'extends = "highway_stereo"\nname = "absurd"\n[{table}]\n{key} = 1e200\n')
    err = _error(capsys, ["generate", str(scenario), "--out", str(tmp_path / "out")])
    assert f"{setting}: Input should be less than or equal to" in err and not (tmp_path / "out").exists()


def test_a_tracker_calling_os_exit_during_a_drive_is_reported_not_a_silent_exit(tmp_path):
    (tmp_path / "quits.py").write_text(textwrap.dedent("""\
        import os

        class Quits:
            def reset(self, *, rig, seed=None):
                pass

            def step(self, frame):
                os._exit(3)
        """))
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    done = subprocess.run([sys.executable, "-m", "simrig", "drive", "lead_brake", "--frames", "5", "--tracker",
                           "quits:Quits", "--out", "drive", "--quiet"], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 2 and "frame 0: step() raised _HardExit: os._exit(3) called" in done.stderr


def test_a_non_finite_parameter_is_refused_wherever_it_comes_from(tmp_path):
    from simrig.pipeline.track import TrackingError, build_tracker

    for value in (float("nan"), float("inf")):
        with pytest.raises(TrackingError, match=r"tracker 'saga': parameter gamma = (nan|inf): a parameter must be "
                                                r"a finite number"):
            build_tracker("saga", {"gamma": value})  # what a suite's or a tracker.json's params reach


def test_a_damaged_made_on_record_in_a_tracks_file_is_an_error_not_taken_as_none(small_dataset, sort_tracks,
                                                                                  tmp_path, capsys):
    import shutil

    import pyarrow.parquet as pq

    from simrig.dataset.tracks_file import MADE_ON_KEY

    tracks = shutil.copytree(sort_tracks, tmp_path / "tracks")
    for file in tracks.glob("*.parquet"):
        table = pq.read_table(file)
        pq.write_table(table.replace_schema_metadata({**(table.schema.metadata or {}), MADE_ON_KEY: b"{not json"}),
                       file)
    err = _error(capsys, ["score", str(small_dataset.path), str(tracks)])
    assert "simrig.made_on record is damaged" in err and str(tracks) in err


def test_a_symbolic_link_as_an_output_folder_is_refused_and_nothing_moves(tmp_path, capsys):
    real = tmp_path / "real"
    real.mkdir()
    (real / "notes.txt").write_text("mine")
    link = tmp_path / "link"
    link.symlink_to(real)
    for argv in (["generate", "highway_stereo", "--frames", "2", "--out", str(link), "--overwrite"],
                 ["run", "highway_stereo", "--frames", "2", "--out", str(link)]):
        err = _error(capsys, argv)
        assert f"{str(link)!r} is a symbolic link; simrig does not write through links" in err
    assert link.is_symlink() and sorted(p.name for p in real.iterdir()) == ["notes.txt"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link", "real"]


@pytest.mark.parametrize(("key", "value", "said"), [
    ("frames", 10**12, "manifest key 'frames' is 1000000000000, more than a sequence may have (1,000,000)"),
    ("frames", 31, "manifest says 31 frames but its ego_poses table holds 30 rows"),
    ("frame_rate_hz", 0.0, "manifest key 'frame_rate_hz' must be a number in (0, 1000], got 0.0"),
    ("frame_rate_hz", "10", "manifest key 'frame_rate_hz' must be a number in (0, 1000], got '10'"),
])
def test_a_rehashed_manifest_that_lies_is_refused_in_one_line(key, value, said, small_dataset, tmp_path, capsys):
    """Anyone can edit a manifest and compute its hash again: what it states is checked against its tables and
    limits (10¹² frames tried to allocate 7.28 TiB)."""
    copy = _rehashed(small_dataset, tmp_path, lambda manifest: manifest.__setitem__(key, value))
    err = _error(capsys, ["info", str(copy)])
    assert said in err


def _rehashed(dataset, tmp_path, edit):
    """A copy of ``dataset`` whose manifest ``edit`` changed, its hash computed again (as anyone can)."""
    import json
    import shutil

    from simrig.dataset.manifest import manifest_digest

    copy = shutil.copytree(dataset.path, tmp_path / "ds")
    manifest = json.loads((copy / "manifest.json").read_text())
    assert manifest["frames"] == 30
    edit(manifest)
    manifest.pop("manifest_sha256")
    manifest.pop("complete")
    manifest["manifest_sha256"] = manifest_digest(manifest)
    manifest["complete"] = True
    (copy / "manifest.json").write_text(json.dumps(manifest))
    return copy


def test_a_rehashed_manifest_that_lies_about_a_tables_rows_is_refused_when_the_table_is_read(small_dataset, sort_tracks,
                                                                                             tmp_path, capsys):
    copy = _rehashed(small_dataset, tmp_path, lambda manifest: manifest["files"]["detections"].update(rows=7))
    err = _error(capsys, ["track", str(copy), "--tracker", "sort", "--out", str(tmp_path / "t")])
    assert f"dataset {str(copy)!r}: manifest says detections holds 7 rows, its table holds" in err


def test_an_invalid_scenario_in_a_rehashed_manifest_is_one_line_naming_the_dataset_and_setting(
        small_dataset, saga_tracks, tmp_path, capsys):
    """``traffic.vehicles = "many"`` in a manifest's scenario printed a raw pydantic traceback where the scorer's
    planner rebuilds the scenario."""
    copy = _rehashed(small_dataset, tmp_path, lambda manifest: manifest["scenario"]["traffic"].update(vehicles="many"))
    err = _error(capsys, ["score", str(copy), str(saga_tracks)])
    assert f"dataset {copy}: its scenario is not valid" in err and "traffic.vehicles" in err


def test_measure_json_is_strict_json_and_a_one_degree_camera_is_the_narrowest(small_dataset, tmp_path, capsys):
    import json

    from simrig.scenarios.schema import Scenario

    assert main(["detector", "measure", str(small_dataset.path), "--json", str(tmp_path / "m.json")]) == 0

    def refuse(constant):
        raise ValueError(constant)

    json.loads((tmp_path / "m.json").read_text(), parse_constant=refuse)  # no NaN: empty bands are null
    with pytest.raises(ValueError, match=r"hfov_deg\s+Input should be greater than or equal to 1"):
        Scenario.model_validate({"name": "t", "rig": {"preset": "stereo", "hfov_deg": 1e-300}})


def test_a_tracker_that_ignores_the_alarm_is_still_stopped_with_one_line(small_dataset, tmp_path):
    """A tracker that sets SIGALRM to be ignored and then loops defeated --frame-time-limit: the command hung for
    good. The watchdog ends the process a little after the limit, saying why."""
    import time

    (tmp_path / "stubborn.py").write_text(textwrap.dedent("""\
        import signal

        class Stubborn:
            def reset(self, *, rig, seed=None):
                pass

            def step(self, frame):
                signal.signal(signal.SIGALRM, signal.SIG_IGN)
                while True:
                    pass
        """))
    started = time.monotonic()
    done = subprocess.run([sys.executable, "-m", "simrig", "track", str(small_dataset.path), "--tracker",
                           "stubborn:Stubborn", "--out", str(tmp_path / "t"), "--frame-time-limit", "0.5"],
                          cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(tmp_path)}, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 124 and time.monotonic() - started < 60
    assert done.stderr.strip().splitlines()[-1].startswith("simrig: error: tracker 'stubborn:Stubborn': frame 0")
    assert "could not be stopped (it ignores or replaced SIGALRM" in done.stderr
    assert not (tmp_path / "t").exists()


def test_a_tracker_that_reports_nothing_in_the_whole_run_is_warned_about(small_dataset, tmp_path, capsys):
    # a latency of 5 s on a 3 s dataset: every track would arrive after the run
    assert main(["track", str(small_dataset.path), "--tracker", "degraded", "--param", "latency_s=5",
                 "--out", str(tmp_path / "late")]) == 0
    err = capsys.readouterr().err
    assert f"warning: degraded reported no track in any of the {small_dataset.frame_count} frames" in err
    assert main(["track", str(small_dataset.path), "--tracker", "degraded", "--param", "latency_s=0.5",
                 "--out", str(tmp_path / "early")]) == 0
    assert "warning" not in capsys.readouterr().err


@pytest.mark.parametrize(("edit", "said"), [
    (lambda manifest: manifest.__setitem__("seed", 1), "scenario 'small' with seed 1 does not give its ego_poses"),
    (lambda manifest: manifest["scenario"]["traffic"].update(vehicles=14),
     "scenario 'small' with seed 0 does not give its"),
])
def test_info_verify_refuses_a_rehashed_manifest_whose_seed_or_scenario_did_not_make_the_dataset(
        edit, said, small_dataset, tmp_path, capsys):
    """A seed edited into the manifest and re-hashed passes every SHA-256; regenerating the opening frames from
    what the manifest says shows it did not make the tables. The true manifest passes."""
    assert main(["info", str(small_dataset.path), "--verify"]) == 0
    assert "reproduced its scenario and seed regenerate its opening frames" in capsys.readouterr().out
    copy = _rehashed(small_dataset, tmp_path, edit)
    err = _error(capsys, ["info", str(copy), "--verify"])
    assert said in err and "the manifest does not describe what made this dataset" in err


def test_a_plugin_tracker_that_fails_to_import_is_one_line_and_the_others_are_listed(monkeypatch, capsys):
    """An installed tracker whose module raises on import (a missing dependency) ended `simrig trackers` in a
    traceback after half the list."""
    from simrig.trackers import registry

    monkeypatch.setattr(registry, "_LAZY", {**registry._LAZY, "aaa_broken": "no_such_module_xyz:Tracker"})
    assert main(["trackers"]) == 1
    out, err = capsys.readouterr()
    assert "simrig: tracker 'aaa_broken' cannot be imported (ModuleNotFoundError: No module named " in err
    assert "Traceback" not in err and "saga: " in out and "sort: " in out


def test_a_dataset_folder_or_a_run_folder_given_as_another_commands_out_is_named_for_what_it_is(
        small_dataset, tmp_path, capsys):
    """`--out` at a dataset said the folder "holds no dataset"; `generate --out RUN` gave no hint of RUN/dataset."""
    import shutil

    copy = shutil.copytree(small_dataset.path, tmp_path / "ds")
    err = _error(capsys, ["run", "highway_surround6", "--frames", "5", "--out", str(copy)])
    assert f"run folder {str(copy)!r} is not empty and holds no dataset; it is a simrig dataset folder" in err
    (tmp_path / "run").mkdir()
    shutil.copytree(small_dataset.path, tmp_path / "run" / "dataset")
    err = _error(capsys, ["generate", "highway_surround6", "--frames", "5", "--out", str(tmp_path / "run")])
    assert f"it looks like a 'simrig run' folder: its dataset is {str(tmp_path / 'run' / 'dataset')!r}" in err
