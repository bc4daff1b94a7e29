"""The learned association: pair features by hand arithmetic, the model file safe and strict, the
learned gate deciding as its probability says, the training loader's labels against the dataset's own truth, and a
model trained on a small collection separating true pairs from false ones on sequences it never saw."""

import json
import math
import os

import numpy as np
import pytest
from simrig.scenarios.schema import RigConfig
from simrig.trackers.assignment import hungarian
from simrig.trackers.association_features import TRACK_FEATURES, track_pair_features
from simrig.trackers.costs import mahalanobis
from simrig.trackers.detections import DetectionArrays
from simrig.trackers.learned import AssociationModel, LearnedCost, LearnedTracker, ModelError, learned
from simrig.trackers.settings import kalman_tracker_parts

from simrig.collection import generate_collection
from simrig.collection.loader import CollectionPairs, concatenated
from simrig.collection.pairs import detection_actor_ids, sequence_pairs
from simrig.detector.measure import linked_errors
from simrig.errors import DatasetError
from simrig.rig import build_rig
from simrig.types import EgoPose, SensorFrame

F = len(TRACK_FEATURES)


def test_pair_features_by_hand():
    predicted = np.array([[10.0, 0.0, 0.5, 4.0, 2.0, 1.5, 0.0]])
    innovation = np.eye(7)[None] * 4.0  # σ = 2 in every coordinate
    boxes = np.array([[13.0, 4.0, 0.5, 4.0, 2.0, 3.0, math.pi, 0, 0]])  # 5 m away, facing back, twice as tall
    a = np.array([[1.0, 0.0]])
    b = np.array([[0.6, 0.8]])
    features = track_pair_features(predicted, innovation, a, np.array([0.3]), np.array([4]), boxes,
                                   np.array([0.7]), b, np.array([13.6]))[0, 0]
    expected = dict(zip(TRACK_FEATURES, features, strict=True))
    assert expected["distance_m"] == pytest.approx(5.0)
    # Mahalanobis with S = 4 I: √(3² + 4² + 1.5² + (heading folded: π → 0)²) / 2
    assert expected["mahalanobis"] == pytest.approx(math.sqrt(9 + 16 + 2.25) / 2)
    assert expected["mahalanobis"] == pytest.approx(mahalanobis(predicted, innovation, boxes)[0, 0])
    assert expected["heading"] == pytest.approx(0.0, abs=1e-12)  # 1 − |cos π|
    assert expected["log_volume_ratio"] == pytest.approx(math.log(2.0))
    assert expected["appearance"] == pytest.approx(0.4)  # 1 − 0.6
    assert expected["has_appearance"] == 1.0
    assert expected["since_update_s"] == pytest.approx(0.3)
    assert expected["score"] == pytest.approx(0.7)
    assert expected["log_hits"] == pytest.approx(math.log(5))
    assert expected["range_m"] == pytest.approx(13.6)
    none = track_pair_features(predicted, innovation, np.full((1, 2), np.nan), [0.0], [1], boxes, [0.7], b, [1.0])
    assert none[0, 0, TRACK_FEATURES.index("appearance")] == 1.0
    assert none[0, 0, TRACK_FEATURES.index("has_appearance")] == 0.0


def _distance_model(metres: float = 2.0, steepness: float = 10.0) -> AssociationModel:
    """A hand-set model: P = σ(steepness · (metres − distance)) — the distance gate, learned by no one."""
    coef = [0.0] * (2 * F)
    coef[TRACK_FEATURES.index("distance_m")] = -steepness
    return AssociationModel(mean=(0.0,) * (2 * F), scale=(1.0,) * (2 * F), coef=tuple(coef),
                            intercept=steepness * metres)


def test_the_model_file_round_trips_and_its_probability_is_the_logistic_of_its_terms(tmp_path):
    model = _distance_model()
    path = tmp_path / "model.json"
    path.write_text(model.to_json())
    loaded = AssociationModel.load(path)
    assert loaded == model
    features = np.zeros((3, F))
    features[:, TRACK_FEATURES.index("distance_m")] = [1.0, 2.0, 3.0]
    assert loaded.probability(features) == pytest.approx(1 / (1 + np.exp(-10 * (2 - np.array([1.0, 2.0, 3.0])))))


@pytest.mark.parametrize("change, message", [
    (lambda d: d.update(format="something else"), "not a simrig association model"),
    (lambda d: d.update(features=["distance_m"]), "features: "),
    (lambda d: d["coef"].__setitem__(0, float("nan")), r"coef\[0\]: a number in \[-1e\+06, 1e\+06\], got nan"),
    (lambda d: d.update(scale=[0.0] * 20), r"scale\[0\]: a number in \[1e-09, 1e\+09\], got 0.0"),
    (lambda d: d["coef"].__setitem__(3, 1e308), r"coef\[3\]: .*got 1e\+308"),  # made inf and NaN log-odds
    (lambda d: d["scale"].__setitem__(2, 1e-308), r"scale\[2\]: .*got 1e-308"),
    (lambda d: d.update(coef=list(range(20_000))), "coef: 20 numbers .*got 20000$"),  # not a 376 KB line
    (lambda d: d.update(trained_on="ab"), "trained_on: a table of what the model was trained on, got 'ab'"),
    (lambda d: d.update(threshold=1.5), r"threshold: in \(0, 1\)"),
    (lambda d: d.pop("intercept"), "intercept: missing"),
])
def test_a_bad_model_file_is_one_error_naming_the_file_and_key(change, message, tmp_path):
    document = json.loads(_distance_model().to_json())
    change(document)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(document))
    with pytest.raises(ModelError, match=rf"model file '{path}': .*{message}"):
        AssociationModel.load(path)


def test_a_model_path_that_is_not_a_json_file_is_refused_without_reading(tmp_path):
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    with pytest.raises(ModelError, match="not a regular file"):
        learned(model=str(fifo))  # a FIFO would block a reader for ever
    (tmp_path / "model.txt").write_text(_distance_model().to_json())
    with pytest.raises(ModelError, match=r"a \.json file"):
        learned(model=str(tmp_path / "model.txt"))


def _frame(index: int, xs: list[float], rig) -> SensorFrame:
    boxes = np.array([[x, 0.0, 0.8, 4.5, 1.9, 1.6, 0.0, 0.0, 0.0] for x in xs]).reshape(-1, 9)
    m = len(xs)
    arrays = DetectionArrays(boxes, np.tile([100.0, 100.0, 200.0, 200.0], (m, 1)), np.full(m, 0.9),
                             np.zeros(m, dtype=np.int64), np.zeros(m, dtype=np.int64))
    return SensorFrame(index, 0.1 * index, EgoPose(0.0, 0.0, 0.0, 0.0), rig, arrays=arrays)


def test_the_learned_gate_matches_a_near_detection_and_starts_a_track_for_a_far_one():
    rig = build_rig(RigConfig(preset="surround6"))
    parts = kalman_tracker_parts(cost="mahalanobis", gate=None, life="hits", min_hits=1, max_age_s=1.0,
                                 measurement_variance=1.0, score_threshold=0.0)
    parts["cost"] = LearnedCost(_distance_model(metres=2.0))
    tracker = LearnedTracker(**parts, assign=hungarian)
    tracker.reset(rig=rig)
    first = tracker.step(_frame(0, [20.0], rig))
    near = tracker.step(_frame(1, [21.0], rig))  # 1 m from the track: P = σ(10) → the same track
    assert [t.track_id for t in first] == [t.track_id for t in near] == [1]
    far = tracker.step(_frame(2, [25.0], rig))  # ~4 m from the prediction: P ≈ σ(−20) → a new track
    assert [t.track_id for t in far] == [2]
    assert tracker.cost_matrix(_frame(3, [200.0], rig).arrays)[0, 0] == np.inf  # beyond the prefilter


def test_detection_actor_ids_agree_with_the_detector_measurements_join(small_dataset):
    actors = detection_actor_ids(small_dataset)
    linked = linked_errors(small_dataset)  # an independent join: (frame, camera, actor) → the detection's row
    assert np.array_equal(actors[linked["row"]], linked["actor"])
    clutter = np.setdiff1d(np.arange(len(actors)), linked["row"])
    assert np.all(actors[clutter] == -1) and small_dataset.num_rows("detections") == len(actors)


def test_the_loader_labels_a_pair_same_exactly_when_global_hungarian_s_track_last_saw_that_actor(small_dataset):
    """An independent derivation of the labels: global_hungarian (the teacher's settings) from the registry, its
    assignments recorded as it makes them; a track takes the actor of the detection assigned to it, and — births
    being one per unmatched detection, best score first (birth_merge_m = 0) — of the detection it was born from."""
    from simrig.trackers import create

    frames = list(sequence_pairs(small_dataset))
    assert [f.frame for f in frames] == list(range(small_dataset.frame_count))
    tracker = create("global_hungarian")
    tracker.reset(rig=small_dataset.rig)
    assigned = {}
    original_update = tracker.update

    def recording_update(detections, owner):
        assigned["owner"] = owner.copy()
        return original_update(detections, owner)

    tracker.update = recording_update
    identity: dict[int, int] = {}
    checked = 0
    for frame, pairs in zip(small_dataset.sensor_frames(), frames, strict=True):
        ids_before = [track.track_id for track in tracker.tracks]
        assert set(pairs.track_ids.tolist()) <= set(ids_before)
        for track, detection, same in zip(pairs.track_ids, pairs.track_detections, pairs.track_same, strict=True):
            actor = int(pairs.actor_ids[detection])
            assert same == (actor >= 0 and identity[int(track)] == actor)
            checked += 1
        tracks_before = list(tracker.tracks)
        tracker.step(frame)
        owner = assigned.pop("owner", np.full(len(frame.arrays.scores), -1))
        for j in np.flatnonzero(owner >= 0):
            identity[tracks_before[int(owner[j])].track_id] = int(pairs.actor_ids[j])
        born = sorted(track.track_id for track in tracker.tracks if track.track_id > max(ids_before, default=0))
        unmatched = sorted(np.flatnonzero(owner < 0).tolist(), key=lambda j: (-frame.arrays.scores[j], j))
        assert len(born) == len(unmatched)
        for track_id, detection in zip(born, unmatched, strict=True):
            identity[track_id] = int(pairs.actor_ids[detection])
    assert checked > 100
    share = np.mean(np.concatenate([f.track_same for f in frames]))
    assert 0.2 < share < 0.95
    window = concatenated(frames[:3])
    assert len(window["scores"]) == sum(len(f.scores) for f in frames[:3])
    assert np.all(window["actor_ids"][window["track_detections"]] ==
                  np.concatenate([f.actor_ids[f.track_detections] for f in frames[:3]]))


SPACE = """
name = "learn_small"
base = "highway_surround6"
frames = 12
[base_settings]
"render.visibility" = false
[[dimensions]]
path = "traffic.vehicles"
low = 10
high = 25
[[dimensions]]
path = "sensor.detection.probability"
low = 0.7
high = 0.95
"""


@pytest.fixture(scope="module")
def small_collection(tmp_path_factory):
    folder = tmp_path_factory.mktemp("learn")
    (folder / "space.toml").write_text(SPACE)
    return generate_collection(folder / "space.toml", count=8, out=folder / "collection", seed=2, workers=2).out


def test_a_model_trained_on_six_sequences_separates_the_pairs_of_two_it_never_saw(small_collection):
    pytest.importorskip("sklearn")
    from simrig.collection.train import fit_association, permutation_importances, roc_auc

    features, same, sequence = CollectionPairs(small_collection).track_pairs()
    train, test = sequence < 6, sequence >= 6
    model = fit_association(features[train], same[train], trained_on={"sequences": 6})
    assert roc_auc(model, features[test], same[test]) > 0.9
    importances = permutation_importances(model, features[test], same[test], repeats=2)
    assert set(importances) == set(TRACK_FEATURES)
    assert importances["distance_m"] > 0.01  # shuffling the distance costs separation: geometry is used


def test_the_loader_refuses_an_unfinished_collection_and_an_unknown_sequence(small_collection, tmp_path):
    with pytest.raises(DatasetError, match="no sequence 8"):
        CollectionPairs(small_collection, sequences=[8])
    (tmp_path / "collection.json").write_text(json.dumps({"complete": False}))
    with pytest.raises(DatasetError, match="not finished"):
        CollectionPairs(tmp_path)


def test_the_torch_adapter_gives_each_window_as_tensors(small_collection):
    torch = pytest.importorskip("torch")
    from simrig.collection.loader import torch_dataset

    pairs = CollectionPairs(small_collection, sequences=[0])
    data = torch_dataset(pairs, window=4)
    assert len(data) == 3  # 12 frames in windows of 4
    item = data[0]
    assert isinstance(item["track_features"], torch.Tensor) and item["track_features"].shape[1] == F
    assert torch.equal(item["track_same"], torch.as_tensor(next(pairs.windows(4))["track_same"]))
