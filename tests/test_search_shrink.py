"""Shrinking by delta debugging, on a failure predicate whose minimal case is known: no simulation needed."""

from __future__ import annotations

from simrig.scenarios import Scenario

from simrig.search.shrink import actor_count, shrink, smaller_ints


def _scenario() -> Scenario:
    return Scenario.model_validate({
        "name": "big", "frames": 80, "traffic": {"vehicles": 12},
        "perturbations": [
            {"kind": "occlude", "nearest": 3, "frames": [20, 39]},
            {"kind": "miss_burst", "nearest": 2, "frames": [50, 59], "probability": 0.8},
            {"kind": "occluder", "frames": [0, 70], "lane_offset": 1},
        ],
    })


def _fails(scenario: Scenario) -> bool:
    """A made-up weakness: an occlusion of 6 frames or more, with at least 2 other vehicles in the traffic,
    and at least 5 frames after the occlusion for the actor to come back."""
    occlusions = [p for p in scenario.perturbations if p.kind == "occlude"]
    return (scenario.traffic.vehicles >= 2 and any(p.frames[1] - p.frames[0] + 1 >= 6 for p in occlusions)
            and any(scenario.frames - 1 - p.frames[1] >= 5 for p in occlusions))


def test_shrinking_reaches_the_known_minimal_case_and_every_kept_step_still_fails():
    start = _scenario()
    assert _fails(start)
    seen = []
    result = shrink(start, _fails, budget=500, on_step=lambda description, kept: seen.append((description, kept)))
    scenario = result.scenario
    assert _fails(scenario) and result.evaluations == len(seen) <= 500
    (occlusion,) = scenario.perturbations  # the miss burst and the scripted occluder are dropped
    assert occlusion.kind == "occlude" and occlusion.frames == (0, 5) and occlusion.nearest == 1
    assert scenario.traffic.vehicles == 2 and actor_count(scenario) == 2
    assert scenario.frames == 6 + 5  # frames 0-5 hidden, then 5 frames to come back
    assert [d for d, kept in seen if kept] == result.kept


def test_no_scenario_is_evaluated_twice():
    # The last pass meets again the reductions rejected since the last kept change: the same scenario on the
    # same seed gives the same verdict, so it is not evaluated again (a log once showed "frames = 9" twice).
    tried = []
    shrink(_scenario(), lambda s: tried.append(s.model_dump_json()) or _fails(s), budget=500)
    assert len(tried) == len(set(tried)) > 20


def test_the_budget_bounds_the_evaluations():
    calls = []
    result = shrink(_scenario(), lambda s: calls.append(s) or _fails(s), budget=7)
    assert len(calls) == result.evaluations == 7


def test_candidate_values_go_from_the_floor_up():
    assert smaller_ints(10, 0) == [0, 5, 8, 9]
    assert smaller_ints(3, 1) == [1, 2]
    assert smaller_ints(1, 1) == []
