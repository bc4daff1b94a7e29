"""Safe under abuse: what a hostile or careless input can and cannot make simrig do.

Each case runs the command line as a user would and checks the promise it tests (docs/safety.md, "Safe under abuse"):
nothing imported that was not trusted, nothing written outside the folder the user named, nothing written
through a link, no hang (every subprocess runs under a timeout), and the refusal is one line
``simrig: error: ...`` with exit status 2.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from simrig.cli import main

pytestmark = pytest.mark.timeout(180)  # no case may hang: a blocked read or write fails its test here
HERE = Path(__file__).resolve().parent
ZEN = "Beautiful is better than ugly"  # what `import this` prints: the proof that a module was imported


def _one_line(text: str) -> str:
    lines = text.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("simrig: error: "), text
    return lines[0]


def _simrig(*args, cwd: Path, timeout: float = 120, env: dict | None = None) -> subprocess.CompletedProcess:
    """The command line in a fresh interpreter under a timeout (a hang fails the test, it does not stall it)."""
    environment = {**os.environ, "PYTHONPATH": str(HERE), **(env or {})}
    return subprocess.run([sys.executable, "-m", "simrig.cli", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=timeout, env=environment)


def _refused(run: subprocess.CompletedProcess, expected: str) -> str:
    assert run.returncode == 2, run.stderr
    line = _one_line(run.stderr)
    assert expected in line, line
    return line


def _main_refuses(argv: list[str], capsys, expected: str) -> str:
    try:
        code = main([str(word) for word in argv])
    except SystemExit as exit_:
        code = exit_.code
    err = capsys.readouterr().err
    assert code == 2, err
    line = _one_line(err)
    assert expected in line, line
    return line


def _tree(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _files_outside(root: Path, allowed: Path) -> list[Path]:
    """Files under ``root`` that are not under ``allowed``."""
    return [p for p in root.rglob("*") if p.is_file() and allowed not in p.parents]


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory, small_scenario):
    """A `simrig run` folder of the small scenario (10 frames, sort)."""
    from simrig.pipeline.run import run_pipeline

    out = tmp_path_factory.mktemp("abuse") / "run"
    run_pipeline(small_scenario, seed=0, tracker="sort", out=out, frames=10)
    return out


def _copy_run(run_folder: Path, to: Path, tracker: str) -> Path:
    copy = shutil.copytree(run_folder, to)
    record = copy / "tracks" / "sort" / "tracker.json"
    document = json.loads(record.read_text())
    document["tracker"] = tracker
    record.write_text(json.dumps(document))
    return copy


# ---------------------------------------------------------------- a run folder is data
@pytest.mark.parametrize("tracker, trusted_error", [("this:x", "has no attribute 'x'"),
                                                     ("gymnasium:make", "not a tracker factory")])
def test_a_run_folder_naming_a_module_imports_nothing(run_folder, tmp_path, tracker, trusted_error):
    hostile = _copy_run(run_folder, tmp_path / "shared-run", tracker)
    run = _simrig("explain", hostile, cwd=tmp_path)
    line = _refused(run, "--trust-file")
    assert tracker in line and ZEN not in run.stdout + run.stderr
    # trusted, it is imported, and still never called unless it is a tracker factory
    trusted = _simrig("explain", hostile, "--trust-file", cwd=tmp_path)
    _refused(trusted, trusted_error)
    assert not (hostile / "explain").exists()


# ---------------------------------------------------------------- names from data never become paths unchecked
HOSTILE_NAMES = {
    "traversal": "../../victim",
    "bidi": "evil\u202ecod.exe",
    "nul": "cam\x00era",
    "long": "c" * 300,
    "dot-dot": "..",
    "newline": "two\nlines",
}


@pytest.mark.parametrize("kind", sorted(HOSTILE_NAMES))
def test_a_hostile_scenario_name_is_refused_before_anything_is_written(kind, tmp_path, capsys, monkeypatch):
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    scenario = work / "s.toml"
    scenario.write_text(f'extends = "highway_surround6"\nname = {json.dumps(HOSTILE_NAMES[kind])}\nframes = 2\n')
    _main_refuses(["run", scenario, "--tracker", "sort"], capsys, "name")
    assert _files_outside(tmp_path, work) == [] and not (work / "runs").exists()


@pytest.mark.parametrize("kind", sorted(HOSTILE_NAMES))
def test_a_hostile_camera_name_is_refused(kind, tmp_path, capsys):
    scenario = tmp_path / "rig.toml"
    name = json.dumps(HOSTILE_NAMES[kind])
    scenario.write_text(textwrap.dedent(f"""\
        extends = "highway_stereo"
        frames = 2
        [rig]
        preset = "custom"
        [[rig.cameras]]
        name = {name}
        """))
    out = tmp_path / "deep" / "dataset"
    _main_refuses(["generate", scenario, "--images", "--out", out, "--quiet"], capsys, "cameras.0.name")
    assert list(tmp_path.rglob("*.png")) == [] and not out.exists()


def test_a_hostile_search_space_name_is_refused(tmp_path, capsys, monkeypatch):
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    space = Path(__file__).resolve().parents[1] / "scenarios" / "spaces" / "occlusion_gaps.toml"
    text = space.read_text().replace('name = "occlusion_gaps"', 'name = "../../victim"')
    (work / "space.toml").write_text(text)
    _main_refuses(["search", work / "space.toml", "--budget", "1"], capsys, "name")
    assert _files_outside(tmp_path, work) == []


# ---------------------------------------------------------------- --out: not /, not home, not a user's folder
def _a_users_folder(tmp_path: Path) -> Path:
    folder = tmp_path / "my_files"
    folder.mkdir()
    (folder / "results.parquet").write_bytes(b"my own table")
    (folder / "report.md").write_text("my notes")
    (folder / "bench.json.bak").write_text("{}")
    return folder


def _commands(tmp_path: Path, run_folder: Path, out: Path) -> dict[str, list]:
    bench = tmp_path / "bench-input"
    if not bench.exists():
        shutil.copytree(Path(__file__).resolve().parents[1] / "reports" / "appearance", bench)
    dataset = run_folder / "dataset"
    return {
        "run": ["run", "--frames", "2", "--out", out],
        "generate": ["generate", "--frames", "2", "--out", out, "--quiet"],
        "bench": ["bench", "smoke", "--out", out, "--quiet"],
        "search": ["search", "occlusion_gaps", "--budget", "1", "--out", out],
        "report": ["report", bench, "--out", out],
        "export": ["export", dataset, "--format", "kitti", "--out", out, "--overwrite"],
        "track": ["track", dataset, "--tracker", "sort", "--out", out],
    }


WRITERS = ["run", "generate", "bench", "search", "report", "export", "track"]


@pytest.mark.parametrize("command", WRITERS)
def test_out_at_the_root_or_home_is_refused(command, tmp_path, run_folder, capsys, monkeypatch):
    home = tmp_path / "home"
    home.mkdir()
    (home / ".bashrc").write_text("mine")
    monkeypatch.setenv("HOME", str(home))
    for out, expected in ((Path("/"), "root of the file system"), (home, "home folder")):
        argv = _commands(tmp_path, run_folder, out)[command]
        _main_refuses(argv, capsys, expected)
    assert _tree(home) == {".bashrc": b"mine"}


@pytest.mark.parametrize("command", WRITERS)
def test_out_at_a_users_folder_is_refused_and_left_as_it_was(command, tmp_path, run_folder, capsys):
    folder = _a_users_folder(tmp_path)
    before = _tree(folder)
    argv = _commands(tmp_path, run_folder, folder)[command]
    _main_refuses(argv, capsys, str(folder))
    assert _tree(folder) == before


# ---------------------------------------------------------------- no write through a link
def test_render_replaces_a_planted_link_and_never_writes_through_it(run_folder, tmp_path, capsys):
    dataset = shutil.copytree(run_folder / "dataset", tmp_path / "dataset")
    victim = tmp_path / "thesis.tex"
    victim.write_text("years of work")
    (dataset / "mosaic_000000.png").symlink_to(victim)
    assert main(["render", str(dataset), "--frame", "0"]) == 0
    assert victim.read_text() == "years of work"
    mosaic = dataset / "mosaic_000000.png"
    assert not mosaic.is_symlink() and mosaic.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_score_json_replaces_a_planted_link(run_folder, tmp_path, capsys):
    victim = tmp_path / "victim.txt"
    victim.write_text("mine")
    link = tmp_path / "score.json"
    link.symlink_to(victim)
    assert main(["score", str(run_folder / "dataset"), str(run_folder / "tracks" / "sort"), "--json", str(link)]) == 0
    assert victim.read_text() == "mine" and not link.is_symlink() and json.loads(link.read_text())


# ---------------------------------------------------------------- special files: refused, never a hang
def _fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


@pytest.mark.parametrize("command", ["generate", "run", "bench", "search", "replay"])
def test_a_fifo_as_a_data_file_is_refused_without_hanging(command, tmp_path):
    fifo = _fifo(tmp_path / "file.toml")
    argv = {"generate": ["generate", fifo, "--out", tmp_path / "out"], "run": ["run", fifo],
            "bench": ["bench", fifo], "search": ["search", fifo], "replay": ["replay", fifo]}[command]
    _refused(_simrig(*argv, cwd=tmp_path, timeout=60), "is a FIFO, not a regular file")


@pytest.mark.parametrize("target", ["fifo", "/dev/zero"])
@pytest.mark.parametrize("command", ["info", "score"])
def test_a_dataset_file_replaced_by_a_fifo_or_a_device_is_refused(command, target, run_folder, tmp_path):
    dataset = shutil.copytree(run_folder / "dataset", tmp_path / "dataset")
    table = dataset / "ground_truth.parquet"
    table.unlink()
    if target == "fifo":
        _fifo(table)
    else:
        table.symlink_to(target)
    argv = (["info", dataset, "--verify"] if command == "info"
            else ["score", dataset, run_folder / "tracks" / "sort"])
    _refused(_simrig(*argv, cwd=tmp_path, timeout=60), "not a regular file")


DATASET_FILES = ("manifest.json", "rig.json", "road.json", "ego_poses.parquet", "frames.parquet",
                 "ground_truth.parquet", "projections.parquet", "visibility.parquet", "detections.parquet",
                 "sensor_truth.parquet", "truth_plans.parquet", "collisions.parquet")


@pytest.mark.parametrize("target", ["fifo", "/dev/zero"])
@pytest.mark.parametrize("name", DATASET_FILES)
def test_every_dataset_file_replaced_by_a_fifo_or_a_device_is_refused_by_verify(name, target, run_folder, tmp_path):
    dataset = shutil.copytree(run_folder / "dataset", tmp_path / "dataset")
    assert sorted(p.name for p in dataset.iterdir()) == sorted(DATASET_FILES)  # the list covers every file
    (dataset / name).unlink()
    if target == "fifo":
        _fifo(dataset / name)
    else:
        (dataset / name).symlink_to(target)
    _refused(_simrig("info", dataset, "--verify", cwd=tmp_path, timeout=60), "not a regular file")


def test_a_manifest_that_is_a_fifo_is_refused(run_folder, tmp_path):
    dataset = shutil.copytree(run_folder / "dataset", tmp_path / "dataset")
    (dataset / "manifest.json").unlink()
    _fifo(dataset / "manifest.json")
    _refused(_simrig("info", dataset, cwd=tmp_path, timeout=60), "not a regular file")


def test_a_huge_scenario_file_is_refused_before_it_is_parsed(tmp_path, capsys):
    scenario = tmp_path / "huge.toml"
    with scenario.open("w") as handle:
        handle.write('extends = "highway_surround6"\n')
        for index in range(600_000):
            handle.write(f"key_{index:07d} = {index}\n")
    _main_refuses(["generate", scenario, "--out", tmp_path / "out"], capsys, "larger than")


# ---------------------------------------------------------------- --overwrite deletes only what simrig wrote
def test_generate_overwrite_keeps_what_the_user_added(small_dataset, tmp_path, capsys):
    dataset = shutil.copytree(small_dataset.path, tmp_path / "dataset")
    (dataset / "notes.txt").write_text("mine")
    assert main(["generate", "--frames", "2", "--out", str(dataset), "--overwrite", "--quiet"]) == 0
    assert (dataset / "notes.txt").read_text() == "mine"
    assert json.loads((dataset / "manifest.json").read_text())["frames"] == 2


def test_a_planted_empty_export_marker_does_not_let_overwrite_delete_a_folder(run_folder, tmp_path, capsys):
    folder = _a_users_folder(tmp_path)
    (folder / "simrig-export.json").write_text("{}")
    before = _tree(folder)
    _main_refuses(["export", run_folder / "dataset", "--format", "kitti", "--out", folder, "--overwrite"], capsys,
                  "was not written by simrig export")
    assert _tree(folder) == before


def test_a_users_folder_named_like_a_dead_partial_is_kept(tmp_path, capsys):
    lookalike = tmp_path / ".dataset.partial-999999999"
    lookalike.mkdir()
    (lookalike / "mine.txt").write_text("mine")
    assert main(["generate", "--frames", "2", "--out", str(tmp_path / "dataset"), "--quiet"]) == 0
    assert (lookalike / "mine.txt").read_text() == "mine"


# ---------------------------------------------------------------- bounded work
def test_a_clutter_rate_that_would_fill_the_disk_is_refused(tmp_path, capsys):
    scenario = tmp_path / "clutter.toml"
    scenario.write_text('extends = "highway_surround6"\n[sensor.clutter]\nrate_per_frame = 2e5\n')
    _main_refuses(["generate", scenario, "--out", tmp_path / "out"], capsys, "sensor.clutter.rate_per_frame")


def test_a_suite_of_a_million_seeds_is_refused_at_once(tmp_path):
    suite = tmp_path / "huge.toml"
    suite.write_text('name = "huge"\nscenarios = ["highway_surround6"]\nframes = 2\n'
                     f"seeds = [{', '.join(map(str, range(1_000_000)))}]\n[[trackers]]\ntracker = \"sort\"\n")
    _refused(_simrig("bench", suite, "--out", tmp_path / "out", cwd=tmp_path, timeout=120), "seeds")
    assert not (tmp_path / "out").exists()


def test_a_sweep_value_nan_is_refused(tmp_path, capsys):
    suite = tmp_path / "nan.toml"
    suite.write_text('name = "nan"\nscenarios = ["highway_surround6"]\nseeds = [0]\nframes = 2\n'
                     '[[trackers]]\ntracker = "sort"\n[[sweeps]]\nparameter = "miss_probability"\nvalues = [nan]\n')
    _main_refuses(["bench", suite, "--out", tmp_path / "out"], capsys, "sweeps.0.values")


def test_explain_samples_beyond_the_bound_is_one_line(run_folder, capsys):
    _main_refuses(["explain", run_folder, "--samples", "99999999999"], capsys, "--samples: must be at most")


# ---------------------------------------------------------------- a tracker's own failures are its errors
@pytest.mark.parametrize("mode, expected", [
    ("exit", "raised SystemExit"),
    ("million", "1,000,000 tracks"),
    ("score_above_1", "outside 0 … 1"),
    ("negative_id", "outside 0 … 2⁶³ − 1"),
    ("huge_id", "outside 0 … 2⁶³ − 1"),
])
def test_a_misbehaving_tracker_is_one_line(mode, expected, small_dataset, tmp_path, capsys, monkeypatch):
    monkeypatch.syspath_prepend(str(HERE))
    _main_refuses(["track", small_dataset.path, "--tracker", "misbehaving_trackers:Misbehaving", "--param",
                   f"mode={mode}", "--out", tmp_path / "tracks"], capsys, expected)
    assert not (tmp_path / "tracks" / "tracks3d.parquet").exists()


def test_a_tracker_that_raises_when_built_is_one_line(small_dataset, tmp_path, capsys, monkeypatch):
    monkeypatch.syspath_prepend(str(HERE))
    _main_refuses(["track", small_dataset.path, "--tracker", "misbehaving_trackers:FailsWhenBuilt", "--out",
                   tmp_path / "tracks"], capsys, "building it raised FileNotFoundError")


# ---------------------------------------------------------------- tracks outside their formats' ranges
def _tracks_with(run_folder: Path, to: Path, column: str, value, type_=None) -> Path:
    table = pq.read_table(run_folder / "tracks" / "sort" / "tracks2d.parquet")
    values = table.column(column).to_pylist()
    values[0] = value
    index = table.schema.get_field_index(column)
    table = table.set_column(index, pa.field(column, type_ or table.schema.field(column).type),
                             pa.array(values, type=type_ or table.schema.field(column).type))
    to.mkdir()
    pq.write_table(table, to / "tracks2d.parquet")
    return to


@pytest.mark.parametrize("column, value, type_, expected", [
    ("score", 1.5, None, "score 1.5 is outside 0 … 1"),
    ("score", -0.1, None, "outside 0 … 1"),
    ("track_id", -3, None, "track id -3 is negative"),
    ("track_id", 2**64 - 1, pa.uint64(), "beyond 2⁶³ − 1"),
])
def test_tracks_outside_their_ranges_are_refused_naming_the_row(column, value, type_, expected, run_folder,
                                                                  tmp_path, capsys):
    tracks = _tracks_with(run_folder, tmp_path / "tracks", column, value, type_)
    line = _main_refuses(["score", run_folder / "dataset", tracks], capsys, expected)
    assert "row 0" in line


def test_a_nuscenes_box_with_a_zero_quaternion_is_refused(small_dataset, saga_tracks, tmp_path, capsys):
    from simrig.formats.export import export

    exported = export(small_dataset.path, "nuscenes", tmp_path / "export", tracks=saga_tracks)
    results = next(path for path in exported.rglob("*.json") if path.name == "saga.json")
    document = json.loads(results.read_text())
    token, boxes = next((token, boxes) for token, boxes in document["results"].items() if boxes)
    boxes[0]["rotation"] = [0.0, 0.0, 0.0, 0.0]
    results.write_text(json.dumps(document))
    _main_refuses(["score", small_dataset.path, results], capsys, "is not a unit quaternion")


# ---------------------------------------------------------------- Ctrl-C that a library swallows
def test_a_swallowed_ctrl_c_still_stops_the_next_frame():
    import signal

    from simrig.interrupts import noting_interrupts, stop_if_interrupted

    # Python's own Ctrl-C handler, as in the simrig command (an earlier test in the session, Ray's say, may have
    # put its own in place, and noting_interrupts leaves a handler it did not expect alone)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with noting_interrupts():
            try:  # a library's bare except around an optional import, say
                signal.raise_signal(signal.SIGINT)  # this thread, now: the handler runs before the next line
            except BaseException:  # noqa: BLE001 - what the library does
                pass
            with pytest.raises(KeyboardInterrupt):
                stop_if_interrupted()
        stop_if_interrupted()  # outside the block: nothing noted, nothing raised
    finally:
        signal.signal(signal.SIGINT, previous)


# ---------------------------------------------------------------- the probe's tracebacks, each one line now
@pytest.fixture
def hostile_files(tmp_path, run_folder):
    """A dataset with a manifest nested 100,000 deep, a scenario at 1e-300 Hz, a FIFO, a bench folder whose
    results table is empty, a replay file."""
    deep = shutil.copytree(run_folder / "dataset", tmp_path / "deep")
    (deep / "manifest.json").write_text("[" * 100_000 + "]" * 100_000)
    (tmp_path / "slow.toml").write_text('extends = "highway_surround6"\nframe_rate_hz = 1e-300\n')
    _fifo(tmp_path / "fifo.json")
    bench = shutil.copytree(Path(__file__).resolve().parents[1] / "reports" / "appearance", tmp_path / "bench")
    table = pq.read_table(bench / "results.parquet")
    pq.write_table(table.slice(0, 0), bench / "results.parquet")
    return tmp_path


PROBE_CASES = [
    ("long-path", ["info", "a" * 300], "File name too long"),
    ("long-out", ["generate", "--frames", "2", "--out", "b" * 300], "File name too long"),
    ("deep-manifest", ["info", "{tmp}/deep"], "nested too deeply"),
    ("tiny-frame-rate", ["generate", "{tmp}/slow.toml", "--out", "{tmp}/x"], "frame_rate_hz"),
    ("render-txt", ["render", "{run}/dataset", "--frame", "0", "--out", "{tmp}/m.txt"], "name a .png file"),
    ("lookback-huge", ["score", "{run}/dataset", "{run}/tracks/sort", "--lookback", "1e308"], "--lookback"),
    ("time-limit-tiny", ["track", "{run}/dataset", "--tracker", "sort", "--out", "{tmp}/t", "--frame-time-limit",
                         "1e-300"], "did not return within"),
    ("evaluation-twice", ["score", "{run}/dataset", "{run}/tracks/sort", "--evaluation", "min_height_px=1",
                          "--evaluation", "min_height_px=2"], "given twice"),
    ("explain-seeds-twice", ["bench", "smoke", "--out", "{tmp}/b", "--explain", "--explain-seeds", "0,0"],
     "listed twice"),
    ("view-save-not-rrd", ["view", "{run}", "--save", "{run}/report.md"], "an .rrd file"),
    ("json-to-a-fifo", ["score", "{run}/dataset", "{run}/tracks/sort", "--json", "{tmp}/fifo.json"], "a FIFO"),
    ("replay-into-a-dataset", ["replay", "{tmp}/bug.toml", "--out", "{run}/dataset"], "replay folder"),
    ("cache-in-a-dataset", ["bench", "smoke", "--out", "{tmp}/b2", "--cache", "{run}/dataset"], "--cache"),
    ("report-of-an-empty-table", ["report", "{tmp}/bench", "--out", "{tmp}/r"], "no row"),
    ("report-of-a-fifo", ["report", "{tmp}/fifo.json", "--out", "{tmp}/r2"], "Not a directory"),
]


@pytest.mark.parametrize("argv, expected", [case[1:] for case in PROBE_CASES], ids=[case[0] for case in PROBE_CASES])
def test_the_probes_bad_input_is_one_line(argv, expected, hostile_files, run_folder, small_scenario):
    from simrig.testing import write_replay

    replay_file = write_replay(hostile_files / "bug.toml", small_scenario, 0, tracker="sort", scores=None)
    replay_file.write_text(replay_file.read_text().replace("[scores]", "[scores.2d]\nHOTA = 0.5"))
    words = [word.format(tmp=hostile_files, run=run_folder) for word in argv]
    _refused(_simrig(*words, cwd=hostile_files, timeout=120), expected)


@pytest.mark.parametrize("command, marker", [("bench", "bench.json"), ("search", "search.json")])
def test_a_users_own_file_named_like_simrigs_marker_does_not_make_the_folder_simrigs(command, marker, tmp_path,
                                                                                       capsys):
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / marker).write_text("my own notes, not simrig's")
    (folder / "thesis.tex").write_text("years of work")
    before = _tree(folder)
    argv = (["bench", "smoke", "--out", folder, "--quiet"] if command == "bench"
            else ["search", "occlusion_gaps", "--budget", "1", "--out", folder])
    _main_refuses(argv, capsys, "holds no")
    assert _tree(folder) == before


def test_an_unreachable_ray_address_is_one_line_not_a_hang(run_folder, tmp_path):
    pytest.importorskip("ray")
    run = _simrig("explain", run_folder, "--workers", "1", "--samples", "2", "--engine", "ray", "--address",
                  "127.0.0.1:1", "--quiet", cwd=tmp_path, timeout=60)
    _refused(run, "no Ray cluster answers there")


def test_a_bench_of_more_than_an_hour_says_so_before_it_starts(capsys):
    from types import SimpleNamespace

    from simrig.benchmark.api import _warn_if_long
    from simrig.benchmark.plan import FRAME_SECONDS

    frames = int(3600 / FRAME_SECONDS) + 1  # just over an hour on one worker
    _warn_if_long([SimpleNamespace(frames=frames)], workers=1, engine="local")
    assert "roughly 1.0 h on 1 workers" in capsys.readouterr().err
    _warn_if_long([SimpleNamespace(frames=frames)], workers=2, engine="local")  # half an hour: nothing said
    assert capsys.readouterr().err == ""
