"""simrig inside other people's test suites: the strategies, properties of our own trackers, the pytest plugin
from a project outside this repository, and replay files."""

import os
import random
import re
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from simrig.scenarios.schema import Scenario

from simrig.testing import load_replay, run_tracker, write_replay
from simrig.testing.runs import dataset_for
from simrig.testing.strategies import scenarios, seeds

QUICK = settings(max_examples=6, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
TRACKERS_3D = ("saga", "global_hungarian", "percam_merge", "simpletrack", "mutr3d", "polymot")


@QUICK
@given(scenarios(perfect=True), seeds)
def test_with_a_perfect_detector_no_3d_tracker_switches_identities(scenario, seed):
    for name in TRACKERS_3D:
        report = run_tracker(name, scenario, seed=seed)
        ids = report.metrics3d["overall"]["IDS"]
        assert np.isnan(ids) or ids == 0, (name, ids)


@QUICK
@given(scenarios(max_perturbations=0))
def test_adding_an_occlusion_never_adds_ground_truth_or_detections(scenario):
    occluded = Scenario.model_validate({
        **scenario.model_dump(mode="json", exclude_none=True, exclude_unset=True),
        "perturbations": [{"kind": "occlude", "nearest": 1, "frames": [0, scenario.frames - 1]}],
    })
    before, after = dataset_for(scenario), dataset_for(occluded)
    assert after.table("ground_truth").num_rows == before.table("ground_truth").num_rows
    assert after.table("detections").num_rows <= before.table("detections").num_rows


class Shuffled:
    """Feeds ``inner`` every frame with each camera's detections in a shuffled order."""

    def __init__(self, inner, seed):
        self.inner, self.rng = inner, random.Random(seed)

    def reset(self, *, rig, seed=None):
        self.inner.reset(rig=rig, seed=seed)

    def step(self, frame):
        shuffled = {name: tuple(self.rng.sample(list(dets), len(dets))) for name, dets in frame.detections.items()}
        return self.inner.step(frame.replace(detections=shuffled))


@QUICK
@given(scenarios())
def test_tracking_does_not_depend_on_the_order_of_detections_within_a_frame(scenario):
    from simrig import trackers as tracker
    from simrig.dataset.tracks_file import read_tracks
    from simrig.pipeline.track import run_tracker as run_on_dataset

    dataset = dataset_for(scenario)
    for name in ("saga", "sort", "mutr3d", "polymot", "bytetrack"):
        rows = []
        for k, wrapped in enumerate((tracker.create(name), Shuffled(tracker.create(name), 7))):
            out = run_on_dataset(dataset, wrapped, dataset.path.parent / f"order-{name}-{k}")
            tracks = read_tracks(out.out, frame_count=dataset.frame_count, cameras=dataset.rig.camera_names)
            t = tracks.tracks3d if tracks.tracks3d is not None else tracks.tracks2d
            rows.append(canonical(t.frame, t.track_id, t.boxes))
        assert rows[0] == rows[1], name


def canonical(frame, track_id, boxes):
    """Rows with ids renamed by first appearance in (frame, box) order: the same tracking up to the names."""
    order = np.lexsort((*np.round(boxes, 6).T[::-1], frame))
    names: dict[int, int] = {}
    out = []
    for k in order:
        names.setdefault(int(track_id[k]), len(names))
        out.append((int(frame[k]), names[int(track_id[k])], *np.round(boxes[k], 6).tolist()))
    return out


def test_a_replay_file_round_trips(tmp_path):
    from simrig.scenarios import load_scenario

    scenario = load_scenario("stereo_one_sided")
    path = write_replay(tmp_path / "r.toml", scenario, 3, tracker="saga", params={"gate": 4.0}, failure="boom")
    loaded = load_replay(path)
    assert loaded.scenario == scenario and loaded.seed == 3 and loaded.tracker == "saga"
    assert loaded.params == {"gate": 4.0} and loaded.failure == "boom"


def test_a_replay_file_with_no_recorded_scores_is_refused(tmp_path, capsys):
    """A replay that could not check anything is an error (exit 2, one line), not 'reproduced'."""
    from simrig.scenarios import load_scenario

    from simrig.cli import main

    path = write_replay(tmp_path / "empty.toml", load_scenario("stereo_one_sided"), 0, tracker="saga")
    assert main(["replay", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("simrig: error:") and "records no scores" in err and str(path) in err and "\n" not in err


def test_an_empty_scene_scores_zero_counts_and_the_peers_ratios():
    """Nothing in view and no clutter: every 2D count is 0 and the ratios are TrackEval's on zero counts (HOTA,
    MOTA, IDF1 0; LocA 1); 3D counts 0 and 3D ratios undefined (NaN, as the nuScenes devkit without ground
    truth)."""
    scenario = Scenario.model_validate({"name": "empty", "frames": 3, "traffic": {"vehicles": 0},
                                        "rig": {"preset": "stereo"}, "render": {"visibility": False},
                                        "sensor": {"clutter": {"rate_per_frame": 0.0}}})
    report = run_tracker("saga", scenario)
    overall = report.metrics2d["overall"]
    assert {name: overall[name] for name in ("CLR_TP", "CLR_FN", "CLR_FP", "IDSW", "MT", "ML")} == dict.fromkeys(
        ("CLR_TP", "CLR_FN", "CLR_FP", "IDSW", "MT", "ML"), 0)
    assert (overall["HOTA"], overall["MOTA"], overall["IDF1"], overall["LocA"]) == (0.0, 0.0, 0.0, 1.0)
    overall3d = report.metrics3d["overall"]
    assert (overall3d["TP"], overall3d["FN"], overall3d["IDS"]) == (0, 0, 0) and np.isnan(overall3d["AMOTA"])


BROKEN = '''
"""A deliberately broken tracker: once fewer detections arrive than in the frame before (a miss, an
occlusion), it never reports anything again."""
from simrig import trackers as tracker


class DropsAfterOcclusion:
    def __init__(self):
        self.inner = tracker.create("saga")

    def reset(self, *, rig, seed=None):
        self.inner.reset(rig=rig, seed=seed)
        self.previous, self.broken = None, False

    def step(self, frame):
        count = sum(len(d) for d in frame.detections.values())
        self.broken = self.broken or (self.previous is not None and count < self.previous)
        self.previous = count
        tracks = self.inner.step(frame)
        return [] if self.broken else tracks
'''

PROPERTY = '''
from hypothesis import given, settings
from simrig.testing import run_tracker
from simrig.testing.strategies import scenarios, seeds
from broken_tracker import DropsAfterOcclusion


def keeps_recall(tracker, scenario):
    """The property of docs/test-your-tracker.md: the tracker matches at least half of the scored boxes its
    detector delivered."""
    report = run_tracker(tracker, scenario)
    overall, truth = report.metrics2d["overall"], report.metrics2d["ground_truth"]["overall"]
    assert overall["CLR_TP"] >= 0.5 * truth["delivered"], "recall below one half"


@settings(max_examples=15, deadline=None, derandomize=True)
@given(scenarios(rigs=("stereo",), max_frames=12, max_vehicles=4))
def test_the_tracker_keeps_tracking_through_misses(scenario):
    keeps_recall(DropsAfterOcclusion, scenario)


@settings(max_examples=20, deadline=None, derandomize=True)
@given(scenarios(rigs=("stereo",)))
def test_saga_keeps_tracking_through_misses(scenario):
    keeps_recall("saga", scenario)


def test_fixtures(simrig_dataset, simrig_scenario):
    assert simrig_dataset.frame_count == 12
    assert simrig_scenario("highway_stereo", frames=7, traffic={"vehicles": 3}).traffic.vehicles == 3
'''


def plugin_project(python: str, project, env: dict) -> None:
    """In ``project`` (outside this repository), run the failing property with ``python``'s pytest and check
    that the shrunk scenario is written, named in the report, and reproduced by ``simrig replay``."""
    (project / "broken_tracker.py").write_text(textwrap.dedent(BROKEN))
    (project / "test_property.py").write_text(textwrap.dedent(PROPERTY))
    # no PYTHONPATH: pytest finds broken_tracker beside the test file, the simrig command would not
    env = {key: value for key, value in env.items() if key != "PYTHONPATH"}
    env["PATH"] = f"{os.path.dirname(python)}{os.pathsep}{env.get('PATH', '')}"  # where `simrig` is installed
    run = subprocess.run([python, "-m", "pytest", "-q", "-p", "no:cacheprovider", "test_property.py"],
                         cwd=project, env=env, capture_output=True, text=True, timeout=600)
    output = run.stdout + run.stderr
    assert run.returncode == 1 and "1 failed, 2 passed" in output, output[-3000:]
    replay_file = project / "simrig-failures" / "test_the_tracker_keeps_tracking_through_misses.toml"
    command = f"simrig replay {replay_file} --tracker broken_tracker:DropsAfterOcclusion"
    assert replay_file.is_file() and command in output  # the tracker named on the command line, not imported
    printed = re.search(r"reproduce it with: (.*)", output).group(1)
    assert printed == f"PYTHONPATH={project} {command}"  # runs as printed, in the same folder
    again = subprocess.run(["bash", "-c", printed], cwd=project, env=env, capture_output=True, text=True,
                           timeout=300)
    assert again.returncode == 0 and "reproduced: all" in again.stdout, again.stdout[-2000:] + again.stderr[-2000:]
    env = {**env, "PYTHONPATH": str(project)}
    replay = load_replay(replay_file)
    assert replay.tracker == "broken_tracker:DropsAfterOcclusion" and "recall below one half" in replay.failure
    recorded = replay.scores["2d"]
    assert recorded["CLR_TP"] < recorded["CLR_TP"] + recorded["CLR_FN"]  # the failing run's own numbers
    assert replay.scenario.frames <= 6 and len(replay.scenario.perturbations) <= 1  # shrunk from up to 12 and 2
    refused = subprocess.run([python, "-m", "simrig.cli", "replay", str(replay_file)], cwd=project, env=env,
                             capture_output=True, text=True, timeout=300)
    assert refused.returncode == 2 and "--trust-file" in refused.stderr and refused.stderr.count("\n") == 1


@pytest.mark.slow  # the default run stays under 10 minutes on 2 cores; CI runs it in the slow pass
def test_plugin_from_a_project_outside_the_repository_writes_a_replay_that_reproduces_the_failure(tmp_path):
    """A project in a temporary folder, using this environment's installed simrig: its failing property shrinks,
    the plugin writes the shrunk scenario and names it in the failure report, ``simrig replay`` reproduces it."""
    plugin_project(sys.executable, tmp_path, dict(os.environ))


@pytest.mark.slow
def test_plugin_works_in_a_fresh_venv_that_only_pip_installs_simrig(tmp_path, venv_with_release):
    """The same, in a new virtual environment with nothing but ``pip install simrig[testing] pytest`` (this
    checkout's wheel, not editable)."""
    python = venv_with_release
    project = tmp_path / "project"
    project.mkdir()
    env = {key: value for key, value in os.environ.items() if key not in ("PYTHONPATH", "VIRTUAL_ENV")}
    plugin_project(python, project, env)
