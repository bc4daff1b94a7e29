"""Data files are data: a suite or replay file naming ``os:system`` never runs a shell command, with or
without ``--trust-file``; a real ``module:attribute`` tracker runs once the user allows it."""

import subprocess
import sys
import textwrap
import tomllib

import pytest
import tomli_w

from simrig.pipeline.track import TrackingError, build_tracker
from simrig.pipeline.trust import is_tracker_factory
from simrig.testing import write_replay


def _simrig(*args, cwd, env=None):
    return subprocess.run([sys.executable, "-m", "simrig.cli", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=600, env=env)


def _hostile_suite(folder, target):
    path = folder / "hostile.toml"
    path.write_text(textwrap.dedent(f"""\
        name = "hostile"
        scenarios = ["highway_surround6"]
        seeds = [0]
        frames = 2
        [[trackers]]
        tracker = "os:system"
        params = {{ command = "echo pwned > {target}" }}
        """))
    return path


@pytest.mark.parametrize("trust", [False, True])
def test_hostile_suite_is_refused_and_its_command_never_runs(tmp_path, trust):
    target = tmp_path / "pwned.txt"
    suite = _hostile_suite(tmp_path, target)
    run = _simrig("bench", suite, "--out", tmp_path / "out", *(["--trust-file"] if trust else []), cwd=tmp_path)
    assert run.returncode == 2, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("simrig: error: ") and "os:system" in lines[0]
    assert ("not a tracker factory" in lines[0]) if trust else ("--trust-file" in lines[0])
    assert "--tracker" not in lines[0]  # bench has no --tracker option to suggest
    assert not target.exists()


def _with_scores(path):
    """A replay file as an attacker would send it: with recorded scores, so that only the tracker is at issue."""
    document = tomllib.loads(path.read_text())
    document["scores"] = {"2d": {"HOTA": 0.5}}
    path.write_text(tomli_w.dumps(document))
    return path


@pytest.mark.parametrize("trust", [False, True])
def test_hostile_replay_file_is_refused_and_its_command_never_runs(tmp_path, small_scenario, trust):
    target = tmp_path / "pwned.txt"
    replay_file = _with_scores(write_replay(tmp_path / "bug.toml", small_scenario, 0, tracker="os:system",
                                            params={"command": f"echo pwned > {target}"}))
    run = _simrig("replay", replay_file, *(["--trust-file"] if trust else []), cwd=tmp_path)
    assert run.returncode == 2, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and "os:system" in lines[0]
    assert ("not a tracker factory" in lines[0]) if trust else ("--trust-file" in lines[0] and
                                                                "on the command line with --tracker" in lines[0])
    assert not target.exists()
    assert not (tmp_path / "dataset").exists()  # refused before any generation


def test_a_command_line_reference_is_still_checked_before_it_is_called(tmp_path):
    target = tmp_path / "gone"
    target.mkdir()
    with pytest.raises(TrackingError, match="'shutil:rmtree' is a function, not a tracker factory"):
        build_tracker("shutil:rmtree", {"path": str(target)})
    assert target.is_dir()


MY_TRACKERS = '''
import simrig.trackers as registry
from simrig.trackers import Tracker


class Wrapped:
    """saga under another name: a user's tracker class."""

    def __init__(self, gate=None):
        self.inner = registry.create("saga", gate=gate)

    def reset(self, *, rig, seed=None):
        self.inner.reset(rig=rig, seed=seed)

    def step(self, frame):
        return self.inner.step(frame)


def make(gate=None) -> Tracker:
    return Wrapped(gate)


def unannotated(gate=None):
    return Wrapped(gate)
'''


def test_factory_check_accepts_classes_and_annotated_functions(tmp_path, monkeypatch):
    (tmp_path / "my_trackers.py").write_text(MY_TRACKERS)
    monkeypatch.syspath_prepend(str(tmp_path))
    import my_trackers

    assert is_tracker_factory(my_trackers.Wrapped) and is_tracker_factory(my_trackers.make)
    assert not is_tracker_factory(my_trackers.unannotated)  # nothing says what it returns
    assert not is_tracker_factory(print) and not is_tracker_factory(subprocess.run)
    assert type(build_tracker("my_trackers:make", {"gate": 4.0})).__name__ == "Wrapped"


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_with_trust_file_a_real_module_attribute_tracker_runs(tmp_path, small_scenario, monkeypatch):
    import simrig

    (tmp_path / "my_trackers.py").write_text(MY_TRACKERS)
    monkeypatch.syspath_prepend(str(tmp_path))
    short = small_scenario.model_copy(update={"frames": 5})
    dataset = simrig.generate(short, out=tmp_path / "recorded", seed=0)
    scores = simrig.score(dataset, simrig.track(dataset, "my_trackers:Wrapped"))  # what the failing test saw
    replay_file = write_replay(tmp_path / "mine.toml", short, 0, tracker="my_trackers:Wrapped", scores=scores)
    env = {**__import__("os").environ, "PYTHONPATH": str(tmp_path)}
    refused = _simrig("replay", replay_file, cwd=tmp_path, env=env)
    assert refused.returncode == 2 and "--trust-file" in refused.stderr
    trusted = _simrig("replay", replay_file, "--trust-file", "--out", tmp_path / "kept", cwd=tmp_path, env=env)
    assert trusted.returncode == 0, trusted.stderr
    assert (tmp_path / "kept" / "tracks" / "tracks3d.parquet").is_file()
    named = _simrig("replay", replay_file, "--tracker", "my_trackers:Wrapped", cwd=tmp_path, env=env)
    assert named.returncode == 0, named.stderr
