"""Long datasets are read a Parquet row group at a time (issue 23, check 8: bounded memory). The records must not
depend on where the row groups split: a dataset written in groups of 5 frames reads back exactly as the same
dataset written in one group, and each sensor frame holds exactly the detection rows of its frame."""

from __future__ import annotations

import numpy as np
import pyarrow.parquet as pq
import pytest

import simrig.dataset.writer as writer_module
from simrig.dataset import Dataset
from simrig.pipeline.generate import generate
from simrig.types import LABELS

FRAMES = 12


@pytest.fixture(scope="module")
def split_and_whole(tmp_path_factory, small_scenario):
    """The same 12 frames written in row groups of 5 frames (3 groups) and in one group."""
    out = tmp_path_factory.mktemp("row_groups")
    datasets = []
    for name, frames_per_group in (("split", 5), ("whole", 1000)):
        patch = pytest.MonkeyPatch()
        patch.setattr(writer_module, "FRAMES_PER_ROW_GROUP", frames_per_group)
        try:
            generate(small_scenario, seed=3, out=out / name, frames=FRAMES)
        finally:
            patch.undo()
        datasets.append(Dataset.open(out / name))
    return datasets


def test_the_split_dataset_has_several_row_groups(split_and_whole):
    split, whole = split_and_whole
    assert pq.ParquetFile(split.path / "detections.parquet").num_row_groups == 3
    assert pq.ParquetFile(whole.path / "detections.parquet").num_row_groups == 1


def test_ground_truth_does_not_depend_on_row_groups(split_and_whole):
    split, whole = (dataset.ground_truth for dataset in split_and_whole)
    for name in ("frames", "timestamps", "frame", "actor_id", "label", "boxes", "boxes2d", "in_view", "truncation",
                 "depth", "occlusion", "causes", "detected", "probability"):
        a, b = getattr(split, name), getattr(whole, name)
        assert a.dtype == b.dtype and a.shape == b.shape, name
        assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), name
    assert split.egos == whole.egos and split.events == whole.events


def test_summary_does_not_depend_on_row_groups(split_and_whole):
    split, whole = split_and_whole
    assert split.summary().replace(str(split.path), "") == whole.summary().replace(str(whole.path), "")


def test_each_sensor_frame_holds_the_detection_rows_of_its_frame(split_and_whole):
    split, _ = split_and_whole
    table = pq.read_table(split.path / "detections.parquet").to_pydict()
    rows_of = {}
    for row, frame in enumerate(table["frame"]):
        rows_of.setdefault(frame, []).append(row)
    dropped = pq.read_table(split.path / "frames.parquet").column("dropped").to_pylist()
    cameras, labels = split.rig.camera_names, [label.value for label in LABELS]
    seen = []
    for frame in split.sensor_frames():
        seen.append(frame.frame)
        rows = rows_of.get(frame.frame, [])
        arrays = frame.arrays
        assert arrays.boxes2d.tolist() == [[table[k][r] for k in ("x1", "y1", "x2", "y2")] for r in rows]
        assert arrays.scores.tolist() == [table["score"][r] for r in rows]
        assert arrays.cameras.tolist() == [cameras.index(table["camera"][r]) for r in rows]
        assert arrays.labels.tolist() == [labels.index(table["label"][r]) for r in rows]
        assert np.array_equal(arrays.boxes3d[:, 0], np.array([table["x"][r] for r in rows]).reshape(-1))
        embeddings = [table["embedding"][r] for r in rows]
        assert arrays.embeddings.shape[0] == len(rows)
        for got, want in zip(arrays.embeddings, embeddings, strict=True):
            assert np.array_equal(got, np.float32(want)) if want else np.isnan(got).all()
    assert seen == [f for f in range(FRAMES) if not dropped[f]]
    assert sum(len(rows_of.get(f, [])) for f in seen) > 0


def test_sensor_frames_do_not_depend_on_row_groups(split_and_whole):
    split, whole = split_and_whole
    pairs = list(zip(split.sensor_frames(), whole.sensor_frames(), strict=True))
    assert len(pairs) > 0
    for a, b in pairs:
        assert (a.frame, a.timestamp, a.ego) == (b.frame, b.timestamp, b.ego)
        for name in ("boxes3d", "boxes2d", "scores", "labels", "cameras", "embeddings"):
            x, y = getattr(a.arrays, name), getattr(b.arrays, name)
            assert x.dtype == y.dtype and x.shape == y.shape, name
            assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), name
