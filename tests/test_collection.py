"""``simrig generate --space``: a collection sampled from a space — the same bytes however it is made
(workers, engines, interrupted and resumed), the declared shares met, bad spaces refused before any work."""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from scipy import stats

from simrig.cli import main
from simrig.collection import generate_collection, load_generation_space
from simrig.collection.sampling import FIRST_SEQUENCE_SEED, choice_shares, sample_candidates, sequence_seed
from simrig.errors import SimrigError
from simrig.search import SearchError, load_space

SMALL_SPACE = """
name = "small"
base = "highway_surround6"
frames = 3

[base_settings]
"render.visibility" = false
"traffic.vehicles" = 4

[[dimensions]]
path = "traffic.vehicles"
low = 2
high = 6

[[dimensions]]
path = "rig.overlap_deg"
low = 0.0
high = 30.0

[[dimensions]]
path = "sensor.clutter.rate_per_frame"
choices = [0.2, 3.0]
weights = [0.75, 0.25]

[[dimensions]]
path = "perturbations"
choices = [[], [{ kind = "blackout", cameras = ["CAM_FRONT"], frames = [1, 2] }]]
weights = [0.8, 0.2]
"""


def _space(tmp_path: Path, text: str = SMALL_SPACE, name: str = "space.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _files(folder: Path) -> dict[str, bytes]:
    """Every file of a collection by relative path (the lock file aside: it is empty and only held)."""
    return {str(path.relative_to(folder)): path.read_bytes() for path in sorted(folder.rglob("*"))
            if path.is_file() and path.name != ".lock"}


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_a_collection_is_the_same_bytes_with_one_worker_or_two_and_every_dataset_matches_its_index_row(tmp_path):
    space = _space(tmp_path)
    one = generate_collection(space, count=8, out=tmp_path / "one", seed=5, shard_size=3, workers=1)
    two = generate_collection(space, count=8, out=tmp_path / "two", seed=5, shard_size=3, workers=2)
    assert (one.made, two.made) == (8, 8)
    assert _files(one.out) == _files(two.out)
    index = pq.read_table(one.index).to_pylist()
    assert [row["sequence"] for row in index] == list(range(8))
    assert [row["shard"] for row in index] == [0, 0, 0, 1, 1, 1, 2, 2]  # 3 per shard
    from simrig.dataset import Dataset

    for row in index:
        dataset = Dataset.open(one.out / row["folder"])
        assert dataset.seed == row["seed"] == sequence_seed(5, row["sequence"])
        assert dataset.seed >= FIRST_SEQUENCE_SEED  # never a catalog, bench or docs seed
        scenario = dataset.scenario
        assert scenario["traffic"]["vehicles"] == row["traffic.vehicles"]
        assert scenario["rig"]["overlap_deg"] == pytest.approx(row["rig.overlap_deg"])
        assert scenario["sensor"]["clutter"]["rate_per_frame"] == row["sensor.clutter.rate_per_frame"]
        blackout = json.loads(row["perturbations"])
        assert [p["kind"] for p in scenario["perturbations"]] == [p["kind"] for p in blackout]
        assert row["frames"] == dataset.frame_count == 3
        assert row["detections"] == dataset.num_rows("detections")
    description = json.loads((one.out / "collection.json").read_text())
    assert description["complete"] is True and description["count"] == 8


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_a_rerun_keeps_every_finished_sequence_and_another_collection_in_the_folder_is_refused(tmp_path):
    space = _space(tmp_path)
    first = generate_collection(space, count=4, out=tmp_path / "c", seed=1, workers=1)
    before = _files(first.out)
    again = generate_collection(space, count=4, out=tmp_path / "c", seed=1, workers=1)
    assert (again.kept, again.made) == (4, 0)
    assert _files(again.out) == before
    with pytest.raises(SearchError, match=r"holds another collection \(its count differs\)"):
        generate_collection(space, count=5, out=tmp_path / "c", seed=1, workers=1)
    with pytest.raises(SearchError, match=r"its seed differs"):
        generate_collection(space, count=4, out=tmp_path / "c", seed=2, workers=1)


@pytest.mark.parametrize("planted", ["shards", "shards/0000", "shards/0000/000001"])
def test_a_link_planted_in_a_collection_folder_is_refused_and_nothing_is_written_through_it(planted, tmp_path):
    """A collection folder is data: a symbolic link planted in it (to a folder of the user's) must not carry a
    resumed run's writes elsewhere."""
    from simrig.dataset.outputs import OutputPathError

    space = _space(tmp_path)
    first = generate_collection(space, count=2, out=tmp_path / "c", seed=1, workers=1)
    elsewhere = tmp_path / "elsewhere"
    shutil.move(first.out / planted, elsewhere)
    shutil.rmtree(elsewhere / "0000" / "000001" if planted == "shards" else
                  elsewhere / "000001" if planted == "shards/0000" else elsewhere)
    elsewhere.mkdir(exist_ok=True)
    before = _files(elsewhere)
    (first.out / planted).symlink_to(elsewhere, target_is_directory=True)
    with pytest.raises(OutputPathError, match=rf"collection folder .*: {planted} is a symbolic link"):
        generate_collection(space, count=2, out=first.out, seed=1, workers=1)
    assert _files(elsewhere) == before


def _run_until_killed(command: list[str], out: Path, finished: int) -> None:
    """Start ``command``, kill it (SIGKILL) once ``finished`` datasets are in ``out``, and wait for it."""
    process = subprocess.Popen(command, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 240
    try:
        while time.monotonic() < deadline and process.poll() is None:
            if len(list(out.glob("shards/*/*/manifest.json"))) >= finished:
                break
            time.sleep(0.05)
    finally:
        os.killpg(process.pid, signal.SIGKILL)  # the driver and its workers, as a machine that goes down
        process.wait()


@pytest.mark.slow  # three collections and two killed runs (~1 min); CI's slow pass runs it
def test_a_collection_killed_twice_and_resumed_is_byte_identical_to_an_uninterrupted_one(tmp_path):
    space = _space(tmp_path)
    command = [sys.executable, "-m", "simrig.cli", "generate", "--space", str(space), "--count", "12", "--seed", "9",
               "--shard-size", "5", "--workers", "2", "--quiet", "--out"]
    whole = tmp_path / "whole"
    subprocess.run([*command, str(whole)], check=True, capture_output=True)
    killed = tmp_path / "killed"
    for finished in (2, 7):
        _run_until_killed([*command, str(killed)], killed, finished)
        assert not (killed / "index.parquet").exists()  # a killed collection never looks complete
        assert json.loads((killed / "collection.json").read_text())["complete"] is False
    done = subprocess.run([*command, str(killed)], check=True, capture_output=True, text=True)
    assert "finished earlier" in done.stdout
    assert not [path for path in killed.rglob("*") if ".partial" in path.name]  # partial folders cleaned up
    assert _files(killed) == _files(whole)


def test_the_sampled_settings_meet_the_declared_distribution(tmp_path):
    """Stratified sampling: each weighted choice is taken N·w times to within one, and every range's values are
    spread over it as the declared uniform (Kolmogorov–Smirnov and χ² tests, and the stratification bound)."""
    space = load_generation_space(_space(tmp_path))
    count = 2000
    candidates = sample_candidates(space.dimensions, count, 11)
    for dimension in space.dimensions:
        values = [candidate[dimension.path] for candidate in candidates]
        if dimension.kind == "choice":
            shares = choice_shares(dimension)
            observed = np.array([sum(value == choice for value in values) for choice in dimension.choices])
            assert np.all(np.abs(observed - count * shares) < 1.0 + 1e-9), (dimension.path, observed)
            assert stats.chisquare(observed, count * shares).pvalue > 0.99
        elif dimension.integer:
            levels = np.arange(dimension.low, dimension.high + 1)
            observed = np.array([values.count(level) for level in levels])
            assert np.all(np.abs(observed - count / len(levels)) <= 1.0), observed
        else:
            uniform = stats.uniform(dimension.low, dimension.high - dimension.low)
            test = stats.kstest(values, uniform.cdf)
            assert test.statistic <= 1.0 / count + 1e-12  # one draw per stratum of width 1/N
            assert test.pvalue > 0.99


@pytest.mark.slow  # a 40-sequence collection (~30 s); the sampling test above checks the shares in the default pass
def test_the_index_of_a_collection_meets_the_declared_shares(tmp_path):
    """The same on the index table a user reads: 40 sequences, the blackout in 8 (20 %), heavy clutter in 10."""
    run = generate_collection(_space(tmp_path), count=40, out=tmp_path / "c", seed=3, workers=2)
    index = pq.read_table(run.index).to_pandas()
    assert (index["perturbations"] != "[]").sum() == 8
    assert (index["sensor.clutter.rate_per_frame"] == 3.0).sum() == 10
    assert sorted(index["traffic.vehicles"].value_counts().tolist()) == [8, 8, 8, 8, 8]
    overlap = np.sort(index["rig.overlap_deg"].to_numpy()) / 30.0
    assert np.all((overlap >= np.arange(40) / 40) & (overlap < np.arange(1, 41) / 40))  # one per stratum
    # the rare settings reach the data: heavy clutter makes more false positives, the blackout drops detections
    assert index.groupby("sensor.clutter.rate_per_frame")["false_positives"].mean().is_monotonic_increasing


def test_a_choice_of_base_samples_road_types_and_checks_every_dimension_on_each(tmp_path):
    text = SMALL_SPACE.replace('[[dimensions]]\npath = "traffic.vehicles"', '[[dimensions]]\npath = "base"\n'
                               'choices = ["highway_surround6", "two_way_surround6"]\n\n[[dimensions]]\n'
                               'path = "traffic.vehicles"', 1)
    space = load_generation_space(_space(tmp_path, text))
    assert set(space.bases) == {"highway_surround6", "two_way_surround6"}
    run = generate_collection(space, count=4, out=tmp_path / "c", seed=0, workers=2)
    index = pq.read_table(run.index).to_pandas()
    assert sorted(index["scenario"]) == sorted(index["base"]) == ["highway_surround6"] * 2 + ["two_way_surround6"] * 2
    stereo = text.replace('"two_way_surround6"]', '"highway_stereo"]')
    with pytest.raises(SearchError, match=r"stereo\.toml': base 'highway_stereo': dimensions\.2\.path "
                                          r"\(rig\.overlap_deg\): .*not a setting of the 'stereo' preset"):
        load_generation_space(_space(tmp_path, stereo, "stereo.toml"))
    # a camera only the surround rig has is found when the sequences are sampled, still before any work
    stereo = stereo.replace('[[dimensions]]\npath = "rig.overlap_deg"\nlow = 0.0\nhigh = 30.0\n', "", 1)
    message = r"sequence \d+ samples .*'base': 'highway_stereo'.*has no camera 'CAM_FRONT'"
    with pytest.raises(SearchError, match=message):
        generate_collection(_space(tmp_path, stereo, "stereo.toml"), count=40, out=tmp_path / "stereo")
    assert not (tmp_path / "stereo").exists()


BAD_SPACES = {
    "an empty range": ("low = 2\nhigh = 6", "low = 6\nhigh = 6",
                       r"dimensions\.0 \(traffic\.vehicles\)\.high: .*range \[6, 6\] is empty"),
    "a setting that does not exist": ('path = "traffic.vehicles"', 'path = "traffic.vehicle_count"',
                                      r"dimensions\.0\.path \(traffic\.vehicle_count\)"),
    "weights that do not match the choices": ("weights = [0.75, 0.25]", "weights = [1.0]",
                                              r"weights: 1 weights for 2 choices"),
    "a negative weight": ("weights = [0.75, 0.25]", "weights = [0.75, -0.25]", r"weights\.1: .*greater than 0"),
    "weights on a range": ("high = 30.0", "high = 30.0\nweights = [1.0]", r"weights: only a list of choices"),
    "a base that does not exist": ('base = "highway_surround6"', 'base = "highway_surround7"',
                                   r"base: .*highway_surround7"),
    "a base chosen by number": ('path = "traffic.vehicles"\nlow = 2\nhigh = 6', 'path = "base"\nchoices = [1, 2]',
                                r"path: 'base' chooses the base scenario"),
}


@pytest.mark.parametrize("case", sorted(BAD_SPACES))
def test_a_bad_space_gets_one_clear_line_before_any_work(case, tmp_path, capsys):
    old, new, message = BAD_SPACES[case]
    assert old in SMALL_SPACE
    space = _space(tmp_path, SMALL_SPACE.replace(old, new, 1))
    out = tmp_path / "out"
    assert main(["generate", "--space", str(space), "--count", "3", "--out", str(out)]) == 2
    error = capsys.readouterr().err.strip()
    assert len(error.splitlines()) == 1 and error.startswith(f"simrig: error: space file '{space}'")
    assert __import__("re").search(message, error), error
    assert not out.exists()


@pytest.mark.parametrize("argv, message", [
    ([], "--space: give --count N"),
    (["--count", "2", "--frames", "4"], "--space: not with --frames"),
    (["--count", "2", "highway_surround6"], "--space: not with a scenario"),
    (["--count", "2", "--overwrite"], "--space: not with --overwrite"),
])
def test_bad_collection_options_get_one_line(argv, message, tmp_path, capsys):
    space = _space(tmp_path)
    assert main(["generate", "--space", str(space), "--out", str(tmp_path / "out"), *argv]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_no_sequences_is_refused_by_the_parser(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["generate", "--space", str(_space(tmp_path)), "--count", "0", "--out", str(tmp_path / "out")])
    assert stop.value.code == 2
    assert "simrig: error: --count: must be at least 1, got 0" in capsys.readouterr().err
    with pytest.raises(SearchError, match=r"--count 0: must be a whole number of sequences from 1"):
        generate_collection(_space(tmp_path), count=0, out=tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_collection_options_without_a_space_are_refused(tmp_path, capsys):
    assert main(["generate", "--count", "3", "--out", str(tmp_path / "d")]) == 2
    assert "--count: only with --space SPACE" in capsys.readouterr().err


def test_a_combination_no_scenario_allows_is_refused_naming_the_sequence_before_any_work(tmp_path):
    """Each extreme is valid alone, but a window smaller than the spawn distance is not: found when sampling."""
    text = SMALL_SPACE.replace('path = "rig.overlap_deg"\nlow = 0.0\nhigh = 30.0',
                               'path = "traffic.spawn_min_distance_m"\nlow = 50.0\nhigh = 150.0\n\n[[dimensions]]\n'
                               'path = "traffic.window_radius_m"\nlow = 110.0\nhigh = 200.0', 1)
    with pytest.raises(SearchError, match=r"sequence \d+ samples .* not a valid scenario: .*spawn_min_distance_m"):
        generate_collection(_space(tmp_path, text), count=200, out=tmp_path / "c")
    assert not (tmp_path / "c").exists()


def test_a_search_refuses_what_only_a_collection_samples_and_a_generation_space_without_objective(tmp_path):
    search_keys = 'tracker = "saga"\n[objective]\nmetric = "3d_HOTA"\ndirection = "minimize"\n'
    weighted = SMALL_SPACE.replace("[base_settings]", search_keys + "\n[base_settings]", 1)
    with pytest.raises(SearchError, match=r"dimensions\.2\.weights: a search explores choices evenly"):
        load_space(_space(tmp_path, weighted, "weighted.toml"))
    with pytest.raises(SearchError, match=r"no \[objective\]: a space for simrig generate --space"):
        load_space(_space(tmp_path))
    # a search space is a generation space: its search keys are ignored, and said so
    space = load_generation_space("occlusion_gaps")
    assert set(space.ignored) >= {"tracker", "objective", "budget", "seeds"}


def test_the_catalog_space_traffic_mix_samples_every_road_type_it_names(tmp_path):
    space = load_generation_space("traffic_mix")
    assert set(space.bases) == {"highway_surround6", "merge_surround6", "two_way_surround6", "exit_surround6"}
    bases = [candidate["base"] for candidate in sample_candidates(space.dimensions, 100, 0)]
    assert {name: bases.count(name) for name in space.bases} == dict.fromkeys(space.bases, 25)
    assert os.path.basename(space.path) == "traffic_mix.toml"


@pytest.mark.slow  # starts a local Ray instance (~30 s); CI's slow pass runs it
def test_the_local_pool_and_ray_make_the_same_collection(tmp_path):
    pytest.importorskip("ray")
    space = _space(tmp_path)
    local = generate_collection(space, count=6, out=tmp_path / "local", seed=4, workers=2)
    ray_run = generate_collection(space, count=6, out=tmp_path / "ray", seed=4, workers=2, engine="ray")
    assert _files(local.out) == _files(ray_run.out)


def test_the_ray_engine_without_ray_is_refused_before_the_folder_is_made(tmp_path, monkeypatch):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "ray" else real(name, *a))
    with pytest.raises(SimrigError, match=r"--engine ray needs Ray: pip install 'simrig-mot\[ray\]'"):
        generate_collection(_space(tmp_path), count=2, out=tmp_path / "ray", engine="ray")
    assert not (tmp_path / "ray").exists()
