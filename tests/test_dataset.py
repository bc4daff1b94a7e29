"""The dataset on disk: round trip, determinism, and atomic writing."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from simrig.dataset import Dataset, DatasetWriter
from simrig.errors import DatasetError, DatasetExistsError
from simrig.geometry import project_boxes
from simrig.pipeline.generate import generate


def _hashes(path):
    manifest = json.loads((path / "manifest.json").read_text())
    return {name: entry["sha256"] for name, entry in manifest["files"].items()}


def test_manifest_describes_the_run_and_ends_with_complete(tmp_path, small_scenario):
    result = generate(small_scenario, seed=1, out=tmp_path / "d", frames=12)
    text = (tmp_path / "d" / "manifest.json").read_text()
    manifest = json.loads(text)
    assert list(manifest)[-1] == "complete" and manifest["complete"] is True
    assert manifest["seed"] == 1 and manifest["frames"] == 12
    assert manifest["scenario"]["traffic"]["vehicles"] == 15
    assert {"highway-env", "numpy", "pyarrow", "python"} <= set(manifest["versions"])
    assert set(manifest["files"]) == {
        "ego_poses", "ground_truth", "projections", "visibility", "detections", "sensor_truth", "frames", "rig", "road",
        "truth_plans", "collisions",
    }
    dataset = Dataset.open(result.path, verify=True)
    assert dataset.table("ego_poses").num_rows == 12
    rows = manifest["files"]["ground_truth"]["rows"]
    assert dataset.table("projections").num_rows == rows * 6


def test_reader_gives_back_the_records_that_were_generated(tmp_path, small_scenario):
    generate(small_scenario, seed=2, out=tmp_path / "d", frames=15)
    dataset = Dataset.open(tmp_path / "d")
    frames = list(dataset.ground_truth_frames())
    assert [f.frame for f in frames] == list(range(15))
    assert dataset.rig.camera_names[0] == "CAM_FRONT"
    for frame in frames:
        # The stored projections are exactly what projecting the stored boxes gives.
        projection = project_boxes(frame.boxes, dataset.rig, frame.ego)
        for index, name in enumerate(dataset.rig.camera_names):
            stored = frame.cameras[name]
            np.testing.assert_array_equal(stored.in_view, projection.in_view[index])
            np.testing.assert_array_equal(stored.boxes, projection.boxes[index])
    assert frames[3].timestamp == pytest.approx(0.3)


def test_same_seed_same_bytes_other_seed_other_bytes(tmp_path, small_scenario):
    generate(small_scenario, seed=7, out=tmp_path / "a", frames=30)
    generate(small_scenario, seed=7, out=tmp_path / "b", frames=30)
    generate(small_scenario, seed=8, out=tmp_path / "c", frames=30)
    a, b, c = (_hashes(tmp_path / name) for name in "abc")
    assert a == b
    assert set(a) >= {"visibility", "detections", "sensor_truth", "frames"}  # rendering on: visibility measured
    for table in ("ego_poses", "ground_truth", "projections", "visibility", "detections", "sensor_truth"):
        assert a[table] != c[table]
    assert a["rig"] == c["rig"]  # same rig, same bytes


def test_a_complete_dataset_is_not_overwritten_unless_asked(tmp_path, small_scenario):
    generate(small_scenario, seed=1, out=tmp_path / "d", frames=5)
    with pytest.raises(DatasetExistsError, match="already holds a complete dataset.*--overwrite"):
        generate(small_scenario, seed=2, out=tmp_path / "d", frames=5)
    assert Dataset.open(tmp_path / "d").seed == 1
    generate(small_scenario, seed=2, out=tmp_path / "d", frames=5, overwrite=True)
    assert Dataset.open(tmp_path / "d").seed == 2
    assert [p.name for p in tmp_path.iterdir()] == ["d"]  # no leftovers


def test_a_folder_of_other_files_is_not_overwritten(tmp_path, small_scenario):
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "notes.txt").write_text("mine")
    with pytest.raises(DatasetError, match="not empty and holds no simrig dataset"):
        generate(small_scenario, seed=1, out=tmp_path / "d", frames=5)


def test_an_exception_midway_leaves_nothing_behind(tmp_path, small_scenario):
    with pytest.raises(KeyboardInterrupt), DatasetWriter(tmp_path / "d") as writer:
        writer.write_json("rig.json", {"name": "x"})
        raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []


def test_incomplete_or_tampered_folders_are_not_read_as_datasets(tmp_path, small_scenario):
    generate(small_scenario, seed=1, out=tmp_path / "d", frames=5)
    manifest_path = tmp_path / "d" / "manifest.json"
    manifest = json.loads(manifest_path.read_text())
    with (tmp_path / "d" / "ego_poses.parquet").open("ab") as handle:
        handle.write(b"x")
    with pytest.raises(DatasetError, match="ego_poses.parquet.*SHA-256"):
        Dataset.open(tmp_path / "d", verify=True)
    manifest["complete"] = False
    manifest_path.write_text(json.dumps(manifest))
    with pytest.raises(DatasetError, match="no complete simrig dataset"):
        Dataset.open(tmp_path / "d")


@pytest.mark.slow  # the default pass stays under 10 minutes; CI runs the slow pass too
def test_a_generation_killed_halfway_leaves_no_complete_dataset_and_a_rerun_succeeds(tmp_path):
    out = tmp_path / "d"
    command = [sys.executable, "-m", "simrig.cli", "generate", "highway_surround6", "--seed", "3",
               "--frames", "100000", "--out", str(out), "--quiet"]
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 60
    partials = []
    while time.monotonic() < deadline:  # wait until tables are being written
        partials = [p for p in tmp_path.glob(".d.partial-*") if any(p.glob("*.parquet"))]
        if partials:
            break
        time.sleep(0.1)
    assert partials, process.stderr.read().decode() if process.poll() is not None else "no partial folder appeared"
    os.kill(process.pid, signal.SIGKILL)
    process.wait()
    assert not out.exists()
    assert not any((p / "manifest.json").exists() for p in tmp_path.iterdir())
    with pytest.raises(DatasetError):
        Dataset.open(out)
    rerun = subprocess.run([*command[:-5], "--frames", "10", "--out", str(out), "--quiet"],
                           capture_output=True, text=True, check=False)
    assert rerun.returncode == 0, rerun.stderr
    assert Dataset.open(out, verify=True).frame_count == 10
    assert [p.name for p in tmp_path.iterdir()] == ["d"]  # the killed run's partial folder is gone


def test_a_road_without_traffic_reads_back_as_empty_frames(tmp_path):
    from simrig.scenarios import load_scenario

    path = tmp_path / "empty.toml"
    path.write_text('extends = "highway_surround6"\n[traffic]\nvehicles = 0\n')
    generate(load_scenario(path), seed=0, out=tmp_path / "d", frames=4)
    dataset = Dataset.open(tmp_path / "d", verify=True)
    frames = list(dataset.ground_truth_frames())
    assert len(frames) == 4
    assert frames[0].boxes.shape == (0, 9)
    assert frames[0].cameras["CAM_FRONT"].boxes.shape == (0, 4)
    assert "; 0 per frame, mean 0.0" in dataset.summary()


def test_sensor_frames_carry_arrays_and_the_object_view_flattens_back_to_the_same_arrays(small_dataset):
    import pyarrow.compute as pc
    from simrig.trackers.detections import detection_arrays

    table = small_dataset.table("detections")
    frames = list(small_dataset.sensor_frames())
    assert sum(len(frame.arrays) for frame in frames) == table.num_rows  # nothing dropped in this scenario
    for frame in frames:
        rows = table.filter(pc.equal(table.column("frame"), frame.frame))
        assert [frame.rig.camera_names[c] for c in frame.arrays.cameras] == rows.column("camera").to_pylist()
        np.testing.assert_array_equal(frame.arrays.scores, rows.column("score").to_numpy())
        rebuilt = detection_arrays(frame.replace(detections=frame.detections), require_3d=False)
        for name in ("boxes3d", "boxes2d", "scores", "labels", "cameras", "embeddings"):
            np.testing.assert_array_equal(getattr(rebuilt, name), getattr(frame.arrays, name), err_msg=name)
        assert sum(len(d) for d in frame.detections.values()) == len(frame.arrays)
    with pytest.raises(ValueError):
        frames[0].arrays.scores[:] = 0.0  # what one tracker sees, the next one sees too
