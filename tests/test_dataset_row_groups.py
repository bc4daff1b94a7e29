"""Long datasets are read a Parquet row group at a time (bounded memory). The records must not
depend on where the row groups split: a dataset written in groups of 5 frames reads back exactly as the same
dataset written in one group, and each sensor frame holds exactly the detection rows of its frame."""

from __future__ import annotations

import numpy as np
import pyarrow.parquet as pq
import pytest

import simrig.dataset.writer as writer_module
from simrig.causes import CAUSE_BITS, Cause
from simrig.dataset import Dataset
from simrig.dataset.ground_truth import CAUSE_DTYPE, load_depth
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
                 "occlusion", "causes", "detected"):
        a, b = getattr(split, name), getattr(whole, name)
        assert a.dtype == b.dtype and a.shape == b.shape, name
        assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), name
    assert split.egos == whole.egos and split.events == whole.events
    assert np.array_equal(load_depth(split_and_whole[0]), load_depth(split_and_whole[1]))


def test_ground_truth_holds_the_tables_values(split_and_whole):
    """Every per-camera array is the table's column (read whole here, by pyarrow), in rig order per row."""
    dataset = split_and_whole[0]
    truth = dataset.ground_truth
    n, c = len(truth.frame), len(dataset.rig.camera_names)
    projections = pq.read_table(dataset.path / "projections.parquet").to_pydict()
    visibility = pq.read_table(dataset.path / "visibility.parquet").to_pydict()
    boxes = np.array([projections[k] for k in ("x1", "y1", "x2", "y2")], dtype=float).T.reshape(n, c, 4)
    assert np.array_equal(truth.boxes2d, boxes, equal_nan=True)
    for camera in range(c):  # only the boxes in view are held; picked by (row, camera)
        seen = np.nonzero(truth.in_view[:, camera])[0]
        assert np.array_equal(truth.boxes2d_in(seen[::-1], camera), boxes[seen[::-1], camera])
        assert not np.isnan(truth.boxes2d_in(seen, camera)).any()
    with pytest.raises(KeyError, match="not in view of camera 0"):
        truth.boxes2d_in(np.nonzero(~truth.in_view[:, 0])[0][:1], 0)
    for name, column in (("truncation", projections["truncation"]), ("occlusion", visibility["occlusion"])):
        assert np.array_equal(getattr(truth, name), np.array(column, dtype=float).reshape(n, c), equal_nan=True)
    assert np.array_equal(load_depth(dataset), np.array(projections["depth"], dtype=float).reshape(n, c))
    assert truth.in_view.tolist() == np.array(projections["in_view"]).reshape(n, c).tolist()
    sensor = pq.read_table(dataset.path / "sensor_truth.parquet").to_pydict()
    for frame, camera, actor, detection, causes in zip(sensor["frame"], sensor["camera"], sensor["actor_id"],
                                                        sensor["detection"], sensor["causes"], strict=True):
        if actor < 0:
            continue
        row, column = truth.rows_of(np.array([frame]), np.array([actor]))[0], dataset.rig.camera_names.index(camera)
        assert truth.detected[row, column] == (detection >= 0)
        assert truth.causes[row, column] == sum(int(Cause[name.upper()]) for name in causes)
    assert truth.in_view.any() and not truth.in_view.all() and truth.causes.any() and truth.detected.any()


def test_cause_masks_fit_their_type():
    assert int(CAUSE_BITS.max()) <= np.iinfo(CAUSE_DTYPE).max


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
