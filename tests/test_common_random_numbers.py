"""Removing one cause group from the detector leaves every other cause's draws bit-identical (common random
numbers): compared row by row, outside the rows the removed cause touches, against the dataset with every
cause on. What the counterfactual explainer (``simrig explain``) relies on."""

from __future__ import annotations

import numpy as np
import pytest
from simrig.scenarios import load_scenario

from simrig.dataset import Dataset
from simrig.pipeline.generate import generate
from simrig.sensor.capture import TIMING_GROUPS
from simrig.sensor.groups import all_groups, present_groups

SCENARIO = """extends = "highway_surround6"
frames = 16
[traffic]
vehicles = 14
window_radius_m = 90.0
spawn_min_distance_m = 60.0
[rig]
overlap_deg = 30.0
[sensor.detection]
burst_fraction = 0.1
[sensor.clutter]
rate_per_frame = 1.0
[sensor.ghosts]
birth_rate_hz = 3.0
[sensor.duplicates]
probability = 0.2
[sensor.confusion.matrix]
car = {car = 0.8, truck = 0.2}
[sensor.box3d]
shared_fraction = 0.3
yaw_flip_duration_s = 0.5
correlation_time_s = 0.5
[[perturbations]]
kind = "occlude"
nearest = 2
frames = [2, 8]
[[perturbations]]
kind = "drop_frames"
probability = 0.4
frames = [4, 12]
[[perturbations]]
kind = "calibration"
yaw_offset_deg = 2.0
cameras = ["CAM_FRONT"]
frames = [6, 14]
[[perturbations]]
kind = "miss_burst"
probability = 0.6
nearest = 3
frames = [5, 11]
[[perturbations]]
kind = "noise"
factor = 3.0
frames = [0, 7]
"""

OWN_TAGS = {"calibration": {"calibration"}, "noise": {"noise"}}
"""Cause tags a window puts on rows whose detection it does not change."""
OUTPUTS = ("x1", "y1", "x2", "y2", "score", "label", "x", "y", "z", "length", "width", "height", "yaw", "vx", "vy",
           "embedding")
BOXES = ("x1", "y1", "x2", "y2", "x", "y", "z", "length", "width", "height", "yaw", "vx", "vy")


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    folder = tmp_path_factory.mktemp("crn")
    (folder / "all.toml").write_text(SCENARIO)
    scenario = load_scenario(folder / "all.toml")
    return scenario, Dataset.open(generate(scenario, seed=3, out=folder / "all").path), folder


def _rows(dataset: Dataset) -> tuple[dict, dict]:
    """Actor rows ``{(frame, camera, actor): {probability, causes, detected, outputs...}}`` and false
    positives ``{(frame, camera, cause): sorted list of their outputs}``."""
    truth = dataset.table("sensor_truth").to_pylist()
    detections = {(row["frame"], row["camera"], row["index"]): row for row in dataset.table("detections").to_pylist()}
    actors, false_positives = {}, {}
    for row in truth:
        output = detections.get((row["frame"], row["camera"], row["detection"]))
        values = tuple(_value(output[name]) for name in OUTPUTS) if output else None
        if row["actor_id"] >= 0:
            actors[(row["frame"], row["camera"], row["actor_id"])] = {
                "probability": row["probability"], "causes": tuple(row["causes"]), "detected": output is not None,
                **({name: _value(output[name]) for name in OUTPUTS} if output else {})}
        else:
            false_positives.setdefault((row["frame"], row["camera"], row["causes"][0]), []).append(values)
    return actors, {key: sorted(value, key=repr) for key, value in false_positives.items()}


def _value(value):
    """Bit-exact comparable form (NaN equal to NaN)."""
    if isinstance(value, list):
        return np.asarray(value, dtype=np.float32).tobytes()
    if isinstance(value, float):
        return np.float64(value).tobytes()
    return value


def _touched(group: str, dataset: Dataset) -> tuple[set, set, set]:
    """Actor rows whose detection (probability, causes, detected) and whose outputs the group may change, and
    the outputs it may change there — from the all-on dataset's own records."""
    truth = dataset.table("sensor_truth").to_pylist()
    occlusion = {(r["frame"], r["camera"], r["actor_id"]): r["occlusion"]
                 for r in dataset.table("visibility").to_pylist()}
    truncation = {(r["frame"], r["camera"], r["actor_id"]): r["truncation"]
                  for r in dataset.table("projections").to_pylist()}
    dropped = {r["frame"] for r in dataset.table("frames").to_pylist() if r["dropped"]}
    rows = {(r["frame"], r["camera"], r["actor_id"]): set(r["causes"]) for r in truth if r["actor_id"] >= 0}
    in_view = {key for key, causes in rows.items() if "out_of_view" not in causes}

    def having(cause: str) -> set:
        return {key for key, causes in rows.items() if cause in causes}

    def hindered(values: dict) -> set:
        return {key for key in in_view if not values.get(key, 0.0) == 0.0}  # NaN or > 0

    everything = set(OUTPUTS)
    kind = group.partition("#")[0]
    table = {
        "occlusion": (hindered(occlusion), hindered(occlusion), everything),
        "truncation": (hindered(truncation), hindered(truncation), everything),
        "far_range": (having("far"), set(), set()),
        "random_misses": (in_view, set(), set()),
        "localisation": (set(), set(rows), set(BOXES) | {"score"}),  # a score falls with the box's error
        "false_positives": (set(), set(), set()),
        "confusion": (having("confused"), set(rows), {"label"}),
        "reid": (set(), set(rows), {"embedding"}),
        "duplicates": (set(), set(), set()),
        "cross_camera": (in_view, set(), set()),
        "occlude": (having("scheduled_occlusion"), having("scheduled_occlusion"), everything),
        "drop_frames": ({k for k in rows if k[0] in dropped}, set(), set()),
        "calibration": (set(), having("calibration"), {"x", "y", "yaw", "vx", "vy", "score"}),
        "miss_burst": (having("scheduled_miss"), set(), set()),
        "noise": (set(), having("noise"), everything - {"label"}),
    }
    return table[kind]


def test_every_group_of_the_scenario_is_present(world):
    scenario, dataset, _ = world
    # every detector group (the capture-timing groups, trigger, latency and ego_pose, are not set in this world:
    # their own common-random-numbers tests are in tests/test_capture_timing.py)
    assert set(present_groups(scenario, 6)) == set(all_groups(scenario))
    assert not set(TIMING_GROUPS) & set(all_groups(scenario))


@pytest.mark.parametrize("group", ["occlusion", "truncation", "far_range", "random_misses", "localisation",
                                   "false_positives", "confusion", "reid", "duplicates", "cross_camera",
                                   "occlude#0", "drop_frames#1", "calibration#2", "miss_burst#3", "noise#4"])
def test_removing_one_group_leaves_every_other_draw_bit_identical(world, group):
    scenario, dataset, folder = world
    removed = Dataset.open(generate(scenario, seed=3, out=folder / group, world_from=dataset,
                                    removed=frozenset({group})).path)
    before, before_fp = _rows(dataset)
    after, after_fp = _rows(removed)
    assert before.keys() == after.keys()
    detection_touched, output_touched, outputs = _touched(group, dataset)
    changed = 0
    for key, row in before.items():
        other = after[key]
        if key not in detection_touched:  # the window's own tag goes with it
            own = OWN_TAGS.get(group.partition("#")[0], set())
            assert (other["probability"], other["causes"], other["detected"]) == (
                row["probability"], tuple(c for c in row["causes"] if c not in own), row["detected"]), (group, key)
        if row["detected"] and other["detected"]:
            kept = [name for name in OUTPUTS if key not in output_touched or name not in outputs]
            assert [other[name] for name in kept] == [row[name] for name in kept], (group, key)
        changed += other != row
    # clutter and ghosts are drawn from their own streams: identical unless removed (or their frame dropped)
    for cause in ("clutter", "ghost"):
        for key in {k for k in before_fp.keys() | after_fp.keys() if k[2] == cause}:
            if group == "drop_frames#1" and key[0] in _dropped(dataset):
                continue  # silenced there with the window on
            if group == "false_positives":
                assert key not in after_fp
                continue
            assert after_fp.get(key) == before_fp.get(key), (group, key)
    if group in ("false_positives", "duplicates"):
        cause = "duplicate" if group == "duplicates" else "clutter"
        assert any(k[2] == cause for k in before_fp) and not any(k[2] == cause for k in after_fp)
        assert any(k[2] == "duplicate" for k in after_fp) == (group != "duplicates")
        if group == "false_positives":  # duplicates derive from actor detections, which did not change
            assert {k: v for k, v in after_fp.items() if k[2] == "duplicate"} == {
                k: v for k, v in before_fp.items() if k[2] == "duplicate"}
    elif group == "cross_camera":
        assert any(n > 1 for n in _detections_per_actor(before).values())  # the rig's overlap does duplicate
        assert changed == sum(n - 1 for n in _detections_per_actor(before).values() if n > 1)  # all but the best
        assert all(n <= 1 for n in _detections_per_actor(after).values())
    else:
        assert changed > 0  # the removal did change something
    assert removed.manifest["removed_causes"] == [group]


def _detections_per_actor(rows: dict) -> dict:
    seen = {}
    for (frame, _, actor), row in rows.items():
        seen[(frame, actor)] = seen.get((frame, actor), 0) + row["detected"]
    return seen


def _dropped(dataset: Dataset) -> set[int]:
    return {r["frame"] for r in dataset.table("frames").to_pylist() if r["dropped"]}
