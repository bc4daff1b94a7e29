"""Defects a new user hit in the first hour (each test failed on main before its fix): a read-only working
folder, a stray PYOPENGL_PLATFORM, tracks scored on a dataset they were not made on, and the rest of the list."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from simrig.cli import main

# ------------------------------------------------------------------------------- 1. a read-only working folder


@pytest.fixture
def read_only(tmp_path, monkeypatch):
    """A folder the process may not write in (``os.access`` says so, as it does on a read-only mount; a real
    one needs privileges the tests do not have)."""
    folder = tmp_path / "ro"
    folder.mkdir()
    real = os.access

    def access(path, mode, *args, **kwargs):
        if mode & os.W_OK and Path(path).resolve() == folder.resolve():
            return False
        return real(path, mode, *args, **kwargs)

    monkeypatch.setattr("simrig.dataset.outputs.os.access", access)
    return folder


@pytest.mark.parametrize("command", [
    ["generate", "highway_stereo", "--frames", "2", "--out", "{ro}/data"],
    ["run", "highway_stereo", "--frames", "2", "--out", "{ro}/run"],
    ["bench", "smoke", "--out", "{ro}/bench"],
    ["search", "{space}", "--out", "{ro}/search"],
])
def test_a_read_only_folder_is_refused_before_any_work(command, read_only, tmp_path, capsys):
    from test_search_run import TINY

    space = tmp_path / "tiny.toml"
    space.write_text(TINY)
    args = [part.format(ro=read_only, space=space) for part in command]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("simrig: error: ") and f"cannot write in {str(read_only)!r}" in err
    assert err.count("\n") == 1 and list(read_only.iterdir()) == []


def test_score_json_into_a_read_only_folder_is_refused_before_scoring(read_only, small_dataset, sort_tracks,
                                                                     capsys, monkeypatch):
    def never(*args, **kwargs):
        raise AssertionError("scored before the output was checked")

    monkeypatch.setattr("simrig.scoring.score", never)
    assert main(["score", str(small_dataset.path), str(sort_tracks), "--json", str(read_only / "s.json")]) == 2
    assert f"--json {str(read_only / 's.json')!r}: cannot write in" in capsys.readouterr().err


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes in a folder without write permission")
def test_a_folder_without_write_permission_is_refused(tmp_path, capsys):
    folder = tmp_path / "locked"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        assert main(["generate", "highway_stereo", "--frames", "2", "--out", str(folder / "data")]) == 2
        assert "cannot write in" in capsys.readouterr().err
    finally:
        folder.chmod(0o755)


# ----------------------------------------------------------------------------------- 2. PYOPENGL_PLATFORM


def _generate_with_platform(platform: str, tmp_path: Path) -> subprocess.CompletedProcess:
    env = os.environ | {"PYOPENGL_PLATFORM": platform}
    return subprocess.run([sys.executable, "-m", "simrig.cli", "generate", "highway_stereo", "--frames", "2",
                           "--out", str(tmp_path / "data"), "--quiet"], env=env, capture_output=True, text=True,
                          timeout=300)


@pytest.mark.parametrize("platform", ["osmesa", "glx"])
def test_a_platform_that_cannot_render_offscreen_is_one_line_naming_it(platform, tmp_path):
    if platform == "osmesa":
        import ctypes.util

        if ctypes.util.find_library("OSMesa"):
            pytest.skip("this machine has OSMesa: the osmesa platform renders")
    done = _generate_with_platform(platform, tmp_path)
    assert done.returncode == 2, done.stderr[-2000:]
    assert "Traceback" not in done.stderr
    (line,) = done.stderr.strip().splitlines()
    assert line.startswith(f"simrig: error: cannot render offscreen with PYOPENGL_PLATFORM={platform!r}")
    assert "unset PYOPENGL_PLATFORM or set it to egl" in line
    assert not (tmp_path / "data").exists()  # nothing that looks like a dataset


# ------------------------------------------------------------------------- 3. tracks from another dataset


@pytest.fixture(scope="module")
def other_seed(small_scenario, tmp_path_factory):
    from simrig.dataset import Dataset
    from simrig.pipeline.generate import generate

    out = tmp_path_factory.mktemp("datasets") / "small-seed1"
    generate(small_scenario, seed=1, out=out, progress=False)
    return Dataset.open(out)


def test_tracks_made_on_one_seed_are_refused_on_another(small_dataset, other_seed, saga_tracks, capsys):
    import simrig

    with pytest.raises(simrig.SimrigError, match="made on a dataset of scenario 'small', seed 0, not on"):
        simrig.score(other_seed, saga_tracks)
    assert main(["score", str(other_seed.path), str(saga_tracks)]) == 2
    err = capsys.readouterr().err
    assert "seed 0" in err and "seed 1" in err and "score them on the dataset they were made on" in err
    assert simrig.score(small_dataset, saga_tracks).metrics3d is not None  # its own dataset: scored


def test_tracks_of_a_surround_run_are_refused_on_a_stereo_dataset(tmp_path, saga_tracks, capsys):
    from simrig.scenarios import load_scenario

    from simrig.pipeline.generate import generate

    generate(load_scenario("highway_stereo"), seed=0, out=tmp_path / "stereo", frames=30, progress=False)
    assert main(["score", str(tmp_path / "stereo"), str(saga_tracks)]) == 2
    assert "made on a dataset of scenario 'small'" in capsys.readouterr().err


def test_tracks_in_memory_carry_their_dataset_too(small_dataset, other_seed):
    import simrig

    run = simrig.track(small_dataset, "sort")
    assert run.tracks.made_on == small_dataset.identity
    with pytest.raises(simrig.SimrigError, match="made on a dataset"):
        simrig.score(other_seed, run.tracks)


# ------------------------------------------------------------------- 5. simrig.register() and the bench's workers

USER_TRACKER = '''
from simrig import trackers


class Echo:
    """Reports SAGA's tracks: a stand-in for a user's own tracker."""

    def __init__(self):
        self.inner = trackers.create("saga")

    def reset(self, *, rig, seed=None):
        self.inner.reset(rig=rig, seed=seed)

    def step(self, frame):
        return self.inner.step(frame)
'''
TINY_SCENARIO = ('extends = "highway_surround6"\nframes = 8\n[traffic]\nvehicles = 6\nwindow_radius_m = 100.0\n'
                 "spawn_min_distance_m = 70.0\n[render]\nvisibility = false\n")
ONE_CELL_SUITE = 'name = "mine"\nscenarios = ["tiny.toml"]\nseeds = [0, 1]\n[[trackers]]\ntracker = "my-echo"\n'


def _bench_script(project: Path, tracker_in_script: bool) -> subprocess.CompletedProcess:
    """A user's script that registers its tracker inside ``if __name__ == "__main__":`` and runs a bench with
    two worker processes (which do not run that block)."""
    (project / "tiny.toml").write_text(TINY_SCENARIO)
    (project / "suite.toml").write_text(ONE_CELL_SUITE)
    if tracker_in_script:
        head = "import simrig\n\nif __name__ == '__main__':\n" + textwrap.indent(USER_TRACKER, "    ")
    else:
        (project / "my_tracker.py").write_text(USER_TRACKER)
        head = "import simrig\nfrom my_tracker import Echo\n\nif __name__ == '__main__':\n"
    script = head + ("    simrig.register('my-echo', Echo)\n"
                     "    run = simrig.bench('suite.toml', workers=2, out='bench')\n"
                     "    import pyarrow.parquet as pq\n"
                     "    print(sorted(set(pq.read_table('bench/results.parquet').column('tracker').to_pylist())))\n")
    (project / "drive.py").write_text(script)
    env = os.environ | {"PYTHONPATH": str(project)}
    return subprocess.run([sys.executable, "drive.py"], cwd=project, env=env, capture_output=True, text=True,
                          timeout=600)


def test_a_tracker_registered_in_a_users_module_runs_in_the_bench_workers(tmp_path):
    done = _bench_script(tmp_path, tracker_in_script=False)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.strip().splitlines()[-1] == "['my-echo']"


def test_a_tracker_the_workers_cannot_import_is_one_error_with_the_way_out(tmp_path):
    done = _bench_script(tmp_path, tracker_in_script=True)
    assert done.returncode == 1 and not (tmp_path / "bench" / "results.parquet").exists()
    assert "tracker 'my-echo', registered with simrig.register() as __main__:Echo, cannot be imported" in done.stderr
    assert "register it by entry point, or name it module:attribute" in done.stderr


def test_an_unknown_tracker_name_says_how_to_make_ones_own_known(capsys):
    assert main(["run", "highway_stereo", "--tracker", "my-echo", "--frames", "2", "--out", "x"]) == 2
    err = capsys.readouterr().err
    assert "unknown tracker 'my-echo'" in err and "entry point, group 'simrig.trackers'" in err
    assert "module:attribute" in err


# ------------------------------------------------------------------------ 6, 7: simrig.score and simrig.run


def test_the_front_door_score_takes_what_the_scorer_takes(small_dataset, saga_tracks):
    import simrig

    truth = small_dataset.ground_truth
    everything = simrig.score(small_dataset, saga_tracks, truth=truth, evaluation={"ignore": False})
    assert everything.metrics2d["ground_truth"]["overall"]["ignored"] == 0
    as_given = simrig.score(small_dataset, saga_tracks, interpolation="none", fmt="simrig")
    assert as_given.settings["interpolation"] == "none"
    assert simrig.score(small_dataset, saga_tracks).settings["interpolation"] == "devkit"


def test_the_front_door_score_loads_no_tracker(small_dataset, saga_tracks):
    code = ("import sys, simrig\n"
            f"simrig.score({str(small_dataset.path)!r}, {str(saga_tracks)!r})\n"
            "print(sorted(m for m in sys.modules if m.startswith(('simrig.trackers', 'simrig.pipeline', "
            "'filterpy'))))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip() == "[]"


def test_opening_a_dataset_and_reading_its_truth_loads_no_scenario_schema(small_dataset):
    """The dataset records its rig as data: reading it needs no scenario validation (pydantic, ~0.1 s)."""
    code = ("import sys, simrig\n"
            f"d = simrig.open_dataset({str(small_dataset.path)!r})\n"
            "d.rig, d.ground_truth\n"
            "print(sorted(m for m in sys.modules\n"
            "             if m.split('.')[0] == 'pydantic' or m.startswith('simrig.') and m.endswith('schema')))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip() == "[]"


class Still:
    """A tracker class that reports nothing."""

    def reset(self, *, rig, seed=None):
        pass

    def step(self, frame):
        return []


def test_run_takes_a_tracker_class_as_track_does(tmp_path):
    import simrig

    result = simrig.run("highway_stereo", tracker=Still, frames=5, out=tmp_path / "run")
    label = f"{__name__}_Still"  # module:qualname, the ':' made safe for a folder name
    assert result.label == label and (tmp_path / "run" / "tracks" / label).is_dir()
    text = (tmp_path / "run" / "scores" / label / "report.md").read_text()
    assert f"--tracker {__name__}:Still" in text  # the command that reproduces it


# ----------------------------------------------------------------- 8: a camera the rig lacks, before any work


def test_run_refuses_a_camera_the_rig_lacks_before_generating(tmp_path, capsys):
    assert main(["run", "stereo_occluder", "--camera", "CAM_FRONT", "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert "--camera 'CAM_FRONT': scenario 'stereo_occluder'" in err and "left, right" in err
    assert not (tmp_path / "run" / "dataset").exists()


# ------------------------------------------------------------------------------------------ 10: the rest


def test_a_parameter_of_the_wrong_kind_is_named(capsys):
    assert main(["run", "highway_stereo", "--tracker", "saga", "--param", "max_age_s=abc", "--frames", "2",
                 "--out", "never"]) == 2
    assert "tracker 'saga': parameter max_age_s='abc' must be a number (its default is 1.0)" in capsys.readouterr().err
    assert not Path("never").exists()


def test_track_does_not_overwrite_tracks_unasked(small_dataset, tmp_path, capsys):
    out = tmp_path / "tracks"
    assert main(["track", str(small_dataset.path), "--tracker", "sort", "--out", str(out)]) == 0
    before = (out / "tracks2d.parquet").read_bytes()
    assert main(["track", str(small_dataset.path), "--tracker", "saga", "--out", str(out)]) == 2
    assert "already holds tracks (tracks2d.parquet); pass --overwrite" in capsys.readouterr().err
    assert (out / "tracks2d.parquet").read_bytes() == before
    assert main(["track", str(small_dataset.path), "--tracker", "saga", "--out", str(out), "--overwrite"]) == 0
    assert (out / "tracks3d.parquet").is_file()


def test_a_parameterised_run_label_reads_as_its_parameters(tmp_path):
    import simrig

    result = simrig.run("highway_stereo", tracker="sort", params={"max_age": 3}, frames=3, out=tmp_path / "run")
    assert result.label.startswith("sort-max_age=3-") and len(result.label) == len("sort-max_age=3-") + 8


def test_report_writes_into_the_bench_folder_by_default(tmp_path, monkeypatch):
    from test_bench import TINY_SCENARIO

    from simrig.report import write_report

    monkeypatch.chdir(tmp_path)
    (tmp_path / "tiny.toml").write_text(TINY_SCENARIO.replace("frames = 25", "frames = 5"))
    (tmp_path / "suite.toml").write_text('name = "mini"\nscenarios = ["tiny.toml"]\nseeds = [0]\n'
                                         '[[trackers]]\ntracker = "saga"\n')
    assert main(["bench", "suite.toml", "--out", "bench", "--workers", "1", "--quiet"]) == 0
    written = write_report(tmp_path / "bench")
    assert written == tmp_path / "bench" / "report" / "index.md" and not (tmp_path / "reports").exists()


def test_explain_and_view_choose_a_run_with_the_same_option():
    from simrig.cli import build_parser

    parser = build_parser()
    assert parser.parse_args(["explain", "R", "--tracker", "saga"]).label == "saga"
    assert parser.parse_args(["explain", "R", "--label", "saga"]).label == "saga"  # the older spelling
    assert parser.parse_args(["view", "R", "--tracker", "saga"]).tracker == "saga"


# ------------------------------------------------------------ generate's printed time is the process's own


def test_generate_prints_the_whole_process_time(tmp_path):
    import re
    import time

    started = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "simrig.cli", "generate", "highway_stereo", "--frames", "5",
                           "--out", str(tmp_path / "data"), "--quiet"], capture_output=True, text=True, timeout=300)
    wall = time.perf_counter() - started
    assert done.returncode == 0, done.stderr[-2000:]
    found = re.search(r"time +(\S+) s in all: start-up \(imports, scenario\) (\S+) s, generation (\S+) s", done.stdout)
    assert found, done.stdout
    total, start_up, generation = map(float, found.groups())
    assert total <= wall and wall - total < 1.0  # the interpreter's own start and exit are all it leaves out
    # the imports are counted; three values printed to 0.1 s each differ from their exact sum by at most 0.15
    assert abs(total - start_up - generation) <= 0.15 + 1e-9 and start_up > 0.2


def test_the_scorers_hungarian_is_scipys_without_its_package_import():
    """The solver loaded alone (``simrig.scoring.hungarian``) gives scipy's public function's answer, ties
    included, on 300 small matrices full of ties; and scoring a dataset does not import ``scipy.optimize``."""
    import numpy as np
    from scipy.optimize import linear_sum_assignment as public

    from simrig.scoring.hungarian import linear_sum_assignment

    rng = np.random.default_rng(0)
    for _ in range(300):
        cost = rng.integers(0, 4, size=(rng.integers(1, 8), rng.integers(1, 8))).astype(float)
        for ours, theirs in zip(linear_sum_assignment(cost), public(cost), strict=True):
            np.testing.assert_array_equal(ours, theirs)
    code = ("import sys\nfrom simrig.scoring.hungarian import linear_sum_assignment\nimport numpy as np\n"
            "linear_sum_assignment(np.eye(3))\nprint('scipy.optimize' in sys.modules)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.stdout.strip() == "False", done.stderr[-2000:]


@pytest.mark.parametrize("layout", ["module", "package", "namespace package"])
def test_the_replay_lines_pythonpath_is_the_folder_the_tracker_was_imported_from(layout, tmp_path, monkeypatch):
    """``mypkg/tracker.py`` without ``__init__.py`` (a namespace package, as the docs' example has it), with one,
    and a plain module: the folder to put on PYTHONPATH is the one holding ``mypkg`` (or the module)."""
    import importlib

    from simrig.testing.plugin import _import_root

    if layout == "module":
        (tmp_path / "solo_tracker.py").write_text("class T:\n    pass\n")
        name = "solo_tracker"
    else:
        package = tmp_path / f"pkg_{layout.replace(' ', '_')}"
        package.mkdir()
        if layout == "package":
            (package / "__init__.py").write_text("")
        (package / "tracker.py").write_text("class T:\n    pass\n")
        name = f"{package.name}.tracker"
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.import_module(name)
    assert _import_root(f"{name}:T") == tmp_path.resolve()
    assert _import_root("simrig.trackers.saga:saga") is None  # installed (or the checkout): no PYTHONPATH


def test_a_run_folder_given_for_a_dataset_is_named_as_such(small_dataset, tmp_path, capsys):
    import shutil

    from simrig.cli import main

    run = tmp_path / "run"
    shutil.copytree(Path(small_dataset.path), run / "dataset")
    assert main(["info", str(run)]) == 2
    error = capsys.readouterr().err.strip()
    assert error.endswith(f"it looks like a 'simrig run' folder: its dataset is {str(run / 'dataset')!r}")
    assert len(error.splitlines()) == 1


def test_the_help_of_simrig_and_of_every_command_imports_nothing_heavy():
    """``simrig --help`` and ``simrig COMMAND --help`` build the parser without numpy, pyarrow, pydantic, pandas,
    scipy, matplotlib or a tracker (the parser of ``detector`` imported the dataset reader, and ``generate``'s the
    search-space schema: 0.5 s for the help; ~0.05 s without them)."""
    code = ("import contextlib, io, sys\nfrom simrig.cli import build_parser\nparser = build_parser()\n"
            "names = [a for a in parser._subparsers._group_actions[0].choices]\n"
            "for argv in [['--help']] + [[name, '--help'] for name in names]:\n"
            "    with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit):\n"
            "        parser.parse_args(argv)\n"
            "heavy = ('numpy', 'pyarrow', 'pydantic', 'pandas', 'scipy', 'matplotlib', 'filterpy', 'simrig.trackers')\n"
            "print(len(names), sorted({m.split('.')[0] if not m.startswith('simrig') else m for m in sys.modules\n"
            "                          if m.startswith(heavy)}))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    count, loaded = done.stdout.strip().split(" ", 1)
    assert int(count) >= 15 and loaded == "[]"
