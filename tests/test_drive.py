"""Closed loop: the ego driven by its planner on a tracker's output, inside the simulation."""

from __future__ import annotations

import math
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest
from bench_engines import assert_same_bench_bytes
from simrig.scenarios import load_scenario
from simrig.scenarios.overrides import with_setting

from simrig.classes import CLASS_SPECS
from simrig.dataset import Dataset
from simrig.pipeline.drive import DriveError, drive
from simrig.pipeline.guard import TrackerFault
from simrig.scoring.drive_outcome import drive_outcome
from simrig.types import ActorClass, Box3D, EgoPose, Track

FRAMES = 60


@pytest.fixture(scope="module")
def scenario():
    """``cut_in`` without rendered visibility (the drive's logic does not depend on it; it is faster)."""
    return with_setting(load_scenario("cut_in"), "render.visibility", False)


@pytest.fixture(scope="module")
def reference(scenario, tmp_path_factory):
    out = tmp_path_factory.mktemp("drive") / "reference"
    return drive(scenario, seed=4, out=out, frames=FRAMES)


class _Replay:
    """A "tracker" that reports the ground truth of a recorded dataset at each frame: perfect 3D tracks."""

    def __init__(self, dataset: Dataset):
        self.truth = dataset.ground_truth

    def reset(self, *, rig, seed=None):
        pass

    def step(self, frame):
        rows = np.flatnonzero(self.truth.frame == frame.frame)
        return [Track(int(self.truth.actor_id[r]), ActorClass(self.truth.label[r]), 1.0,
                      Box3D(*self.truth.boxes[r].tolist())) for r in rows]


def _tables(folder) -> dict[str, bytes]:
    return {path.name: path.read_bytes() for path in sorted(folder.glob("*.parquet"))}


def test_perfect_tracks_drive_exactly_as_the_ground_truth(scenario, reference, tmp_path):
    """(c) A tracker reporting the reference drive's ground truth drives the same world: every table of the
    dataset is the same bytes (the manifests differ only in who perceived)."""
    replayed = drive(scenario, seed=4, out=tmp_path / "replay", frames=FRAMES,
                     tracker=_Replay(Dataset.open(reference.dataset)))
    assert _tables(replayed.dataset) == _tables(reference.dataset)
    assert replayed.outcome == reference.outcome
    assert Dataset.open(reference.dataset).manifest["drive"] == {"perception": "ground truth"}


@pytest.mark.slow
def test_a_tracker_drives_another_world_and_the_same_one_twice_in_another_process(scenario, reference, tmp_path):
    """A reference tracker changes the ego's drive (its world differs from the ground-truth drive's), and the
    same drive in a fresh process writes the same bytes, manifest included."""
    first = drive(scenario, seed=4, out=tmp_path / "one", frames=FRAMES, tracker="global_hungarian")
    assert _tables(first.dataset)["ground_truth.parquet"] != _tables(reference.dataset)["ground_truth.parquet"]
    code = (
        "from simrig.pipeline.drive import drive; from simrig.scenarios import load_scenario;"
        "from simrig.scenarios.overrides import with_setting;"
        "s = with_setting(load_scenario('cut_in'), 'render.visibility', False);"
        f"drive(s, seed=4, out={str(tmp_path / 'two')!r}, frames={FRAMES}, tracker='global_hungarian')"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
    for name in ("dataset", "tracks"):
        here = {p.relative_to(tmp_path / "one"): p.read_bytes() for p in sorted((tmp_path / "one" / name).rglob("*"))
                if p.is_file()}
        there = {p.relative_to(tmp_path / "two"): p.read_bytes() for p in sorted((tmp_path / "two" / name).rglob("*"))
                 if p.is_file()}
        assert here == there and here, name


def test_a_2d_tracker_or_a_timed_sensor_cannot_drive_and_says_why(scenario, tmp_path):
    with pytest.raises(DriveError, match=r"tracker 'sort': frame \d+: track \d+ has no 3D box.*2D tracker cannot"):
        drive(scenario, seed=4, out=tmp_path / "sort", frames=FRAMES, tracker="sort")
    assert not (tmp_path / "sort" / "dataset").exists()  # nothing half-written left
    timed = with_setting(scenario, "sensor.latency.fixed_s", 0.05)
    with pytest.raises(DriveError, match=r"\[sensor.latency\] is set"):
        drive(timed, seed=4, out=tmp_path / "timed", frames=FRAMES, tracker="saga")
    assert not (tmp_path / "timed").exists()


class _NanVelocity(_Replay):
    def step(self, frame):
        tracks = super().step(frame)
        if tracks:
            box = tracks[0].box3d
            tracks[0] = Track(tracks[0].track_id, tracks[0].label, 1.0, Box3D(*box.as_array()[:7], math.nan, 0.0))
        return tracks


def test_a_tracker_with_nan_velocity_gets_one_line_naming_the_frame_and_field(scenario, reference, tmp_path):
    with pytest.raises(TrackerFault, match=r"frame 0: .*box3d has a non-finite value"):
        drive(scenario, seed=4, out=tmp_path / "nan", frames=FRAMES,
              tracker=_NanVelocity(Dataset.open(reference.dataset)))


def test_outcome_by_hand():
    """Ego at 20 m/s, a car 30 m ahead (centres) at 10 m/s, in the same lane: bumper gap 30 − 4.6 = 25.4 m closing
    at 10 m/s, TTC 2.54 s; a frame later both moved 0.1 s and the ego braked to 19.5 m/s (5 m/s², hard); a truck
    beside the ego (4 m across, overlapping no footprint) is not in its path."""
    car, truck = CLASS_SPECS[ActorClass.CAR], CLASS_SPECS[ActorClass.TRUCK]

    def box(x, y, spec, speed):
        return [x, y, spec.height / 2, spec.length, spec.width, spec.height, 0.0, speed, 0.0]

    truth = SimpleNamespace(
        frames=np.array([0, 1]), timestamps=np.array([0.0, 0.1]), events=((), ()), collisions=(),
        egos=(EgoPose(0.0, 0.0, 0.0, 0.0, 20.0, 0.0), EgoPose(2.0, 0.0, 0.0, 0.0, 19.5, 0.0)),
        frame=np.array([0, 0, 1]),
        boxes=np.array([box(30.0, 0.0, car, 10.0), box(0.0, 4.0, truck, 0.0), box(31.0, 0.0, car, 10.0)]),
    )
    outcome = drive_outcome(truth)
    gap1 = 31.0 - 2.0 - car.length
    assert outcome.min_ttc_s == pytest.approx(min(25.4 / 10.0, gap1 / 9.5))
    assert outcome.hard_brakes == (0,) and outcome.near_misses == () and outcome.collisions == 0
    assert outcome.progress_m == pytest.approx(2.0)


CLOSED_SUITE = """
name = "closed_small"
scenarios = ["cut_in"]
seeds = [4]
frames = 60
closed_loop = true

[[trackers]]
tracker = "global_hungarian"
"""


@pytest.mark.slow  # the default pass stays under 10 minutes; CI runs the slow pass too
def test_a_closed_loop_bench_row_is_the_drive_scored(tmp_path):
    """A suite with ``closed_loop = true``: the row is the tracker's drive scored on the world it drove, with the
    drive's outcome against the ground-truth drive."""
    from simrig.benchmark import run_bench
    from simrig.pipeline.drive import drive
    from simrig.scoring import score

    suite = tmp_path / "closed.toml"
    suite.write_text(CLOSED_SUITE)
    local = run_bench(suite, out=tmp_path / "local", workers=1)
    row = pq_rows(local.results)[0]
    scenario = load_scenario("cut_in")
    reference = drive(scenario, seed=4, out=tmp_path / "ref", frames=FRAMES)
    mine = drive(scenario, seed=4, out=tmp_path / "mine", frames=FRAMES, tracker="global_hungarian")
    direct = score(Dataset.open(mine.dataset), mine.tracks).metrics3d["overall"]
    assert row["3d_AMOTA"] == direct["AMOTA"] and row["3d_PKL"] == direct["PKL"]
    assert row["drive_progress_m"] == mine.outcome.progress_m
    assert row["drive_progress_lost_m"] == reference.outcome.progress_m - mine.outcome.progress_m
    assert row["drive_hard_brakes"] == len(mine.outcome.hard_brakes)


@pytest.mark.slow
def test_a_closed_loop_bench_scored_on_the_reference_is_the_tracker_open_loop_on_the_ground_truth_drive(tmp_path):
    """``scores_on = "reference"``: the metrics are the tracker run open loop on the ground-truth drive's world
    and scored there; the drive columns are still its own drive's."""
    from simrig.benchmark import run_bench
    from simrig.pipeline.track import run_tracker
    from simrig.scoring import score

    suite = tmp_path / "closed.toml"
    suite.write_text(CLOSED_SUITE.replace("closed_loop = true", 'closed_loop = true\nscores_on = "reference"'))
    row = pq_rows(run_bench(suite, out=tmp_path / "bench", workers=1).results)[0]
    scenario = load_scenario("cut_in")
    reference = drive(scenario, seed=4, out=tmp_path / "ref", frames=FRAMES)
    mine = drive(scenario, seed=4, out=tmp_path / "mine", frames=FRAMES, tracker="global_hungarian")
    logged = Dataset.open(reference.dataset)
    direct = score(logged, run_tracker(logged, "global_hungarian", seed=4).tracks).metrics3d["overall"]
    assert row["3d_AMOTA"] == direct["AMOTA"] and row["3d_PKL"] == direct["PKL"]
    assert row["drive_progress_m"] == mine.outcome.progress_m


def test_scores_on_needs_a_closed_loop_suite(tmp_path):
    from simrig.benchmark.suite import SuiteError, load_suite

    suite = tmp_path / "open.toml"
    suite.write_text(CLOSED_SUITE.replace("closed_loop = true", 'scores_on = "reference"'))
    with pytest.raises(SuiteError, match="scores_on: only a closed-loop suite"):
        load_suite(suite)
    suite.write_text(CLOSED_SUITE.replace("closed_loop = true", 'closed_loop = true\nscores_on = "log"'))
    with pytest.raises(SuiteError, match="scores_on"):
        load_suite(suite)


@pytest.mark.slow
def test_a_closed_loop_bench_writes_the_same_bytes_on_the_local_pool_and_ray(tmp_path):
    assert_same_bench_bytes(CLOSED_SUITE, tmp_path)


def test_a_closed_loop_suite_refuses_what_cannot_drive(tmp_path):
    from simrig.benchmark import run_bench
    from simrig.benchmark.suite import SuiteError

    suite = tmp_path / "closed.toml"
    suite.write_text(CLOSED_SUITE.replace('tracker = "global_hungarian"', 'tracker = "sort"\ncamera = "CAM_FRONT"'))
    with pytest.raises(SuiteError, match=r"trackers.0.camera: a closed-loop suite drives on 3D tracks"):
        run_bench(suite, out=tmp_path / "a")
    suite.write_text(CLOSED_SUITE.replace('"cut_in"', '"sweep_surround6"'))
    with pytest.raises(SuiteError, match=r"closed_loop = true: sweep_surround6: \[sensor.capture\] is set"):
        run_bench(suite, out=tmp_path / "b")
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def pq_rows(path) -> list[dict]:
    import pyarrow.parquet as pq

    return pq.read_table(path).to_pylist()
