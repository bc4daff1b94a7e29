"""Error attribution on a generated scenario: a scheduled 20-frame occlusion of the actor nearest the ego."""

import numpy as np
import pytest
from simrig.scenarios import load_scenario

from simrig.causes import Cause
from simrig.dataset import Dataset
from simrig.dataset.ground_truth import load_ground_truth
from simrig.pipeline.generate import generate
from simrig.scoring import score, write_tracks
from simrig.scoring.inputs import CLASS_RANGE_M
from simrig.types import ActorClass, Box3D, Track

OCCLUDED_FRAMES = range(10, 30)


@pytest.fixture(scope="module")
def occluded_dataset(tmp_path_factory):
    folder = tmp_path_factory.mktemp("occlusion")
    toml = folder / "occlusion.toml"
    toml.write_text(
        'extends = "highway_surround6"\nname = "occlusion_test"\nframes = 45\n'
        "[traffic]\nvehicles = 12\nwindow_radius_m = 100.0\nspawn_min_distance_m = 70.0\n"
        '[[perturbations]]\nkind = "occlude"\nnearest = 1\nframes = [10, 29]\n'
    )
    generate(load_scenario(toml), seed=1, out=folder / "data", progress=False)
    return Dataset.open(folder / "data")


def detection_oracle_tracks(truth, renamed_actor, after_frame):
    """A tracker that outputs the exact box of every actor some camera detected, under the actor's id — except
    that ``renamed_actor`` comes back under a new id after ``after_frame``."""
    frames = []
    detected = truth.detected.any(axis=1)
    for frame in truth.frames:
        rows = np.nonzero((truth.frame == frame) & detected)[0]
        tracks = []
        for r in rows:
            actor = int(truth.actor_id[r])
            track_id = actor + 10000 if actor == renamed_actor and frame > after_frame else actor
            tracks.append(Track(track_id, ActorClass(truth.label[r]), 0.9, Box3D(*truth.boxes[r].tolist())))
        frames.append((int(frame), tracks))
    return frames


def test_occlusion_misses_and_the_switch_after_it_are_tagged(occluded_dataset, tmp_path):
    truth = load_ground_truth(occluded_dataset)
    hidden = truth.causes & int(Cause.SCHEDULED_OCCLUSION) != 0
    actors = np.unique(truth.actor_id[hidden.any(axis=1)])
    assert len(actors) == 1
    actor = int(actors[0])
    assert sorted(np.unique(truth.frame[hidden.any(axis=1)]).tolist()) == list(OCCLUDED_FRAMES)

    write_tracks(tmp_path / "tracks", detection_oracle_tracks(truth, actor, after_frame=29))
    errors = score(occluded_dataset, tmp_path / "tracks").errors.to_pylist()
    mine = [e for e in errors if e["actor_id"] == actor]

    misses_3d = [e for e in mine if e["dimension"] == "3d" and e["kind"] == "FN" and e["frame"] in OCCLUDED_FRAMES]
    assert sorted(e["frame"] for e in misses_3d) == list(OCCLUDED_FRAMES)  # (random misses may add others)
    assert all({"occluded", "scheduled_occlusion"} <= set(e["causes"]) for e in misses_3d)

    switches_3d = [e for e in mine if e["dimension"] == "3d" and e["kind"] == "IDS"]
    assert len(switches_3d) == 1
    switch = switches_3d[0]
    assert switch["frame"] >= 30 and switch["track_id"] == actor + 10000 and switch["previous_track_id"] == actor
    assert "occluded" in switch["causes"]

    misses_2d = [e for e in mine if e["dimension"] == "2d" and e["kind"] == "FN" and e["frame"] in OCCLUDED_FRAMES]
    assert len(misses_2d) >= len(OCCLUDED_FRAMES)  # at least one camera sees it in every frame
    assert all("scheduled_occlusion" in e["causes"] for e in misses_2d)
    assert any(e["dimension"] == "2d" and e["kind"] == "IDS" and "occluded" in e["causes"] for e in mine)


def test_errors_the_detector_did_not_cause_are_tagged_none(occluded_dataset, tmp_path):
    """Drop one detected actor from the output for frames 0-4: its FNs carry no sensor cause."""
    truth = load_ground_truth(occluded_dataset)
    frames = detection_oracle_tracks(truth, renamed_actor=-1, after_frame=0)
    output = [{t.track_id for t in tracks} for _, tracks in frames[:5]]

    def scored_in_first_frames(actor):
        """Output by the oracle in frames 0-4 and inside its class range there (so the 3D score counts it)."""
        rows = np.nonzero((truth.actor_id == actor) & (truth.frame < 5))[0]
        egos = [truth.egos[int(np.searchsorted(truth.frames, frame))] for frame in truth.frame[rows]]
        distance = np.hypot(*(truth.boxes[rows, :2] - np.array([(e.x, e.y) for e in egos]).reshape(-1, 2)).T)
        limit = CLASS_RANGE_M[ActorClass(truth.label[rows[0]])] if len(rows) else 0.0
        return len(rows) == 5 and all(actor in ids for ids in output) and bool((distance < limit).all())

    dropped = next(t.track_id for t in frames[0][1] if scored_in_first_frames(t.track_id))  # depends on the traffic
    frames = [(f, [t for t in tracks if not (t.track_id == dropped and f < 5)]) for f, tracks in frames]
    write_tracks(tmp_path / "tracks", frames)
    errors = score(occluded_dataset, tmp_path / "tracks").errors.to_pylist()
    misses = [e for e in errors if e["dimension"] == "3d" and e["kind"] == "FN" and e["actor_id"] == dropped
              and e["frame"] < 5]
    assert sorted(e["frame"] for e in misses) == [0, 1, 2, 3, 4]
    assert all(e["causes"] == ["none"] for e in misses)
