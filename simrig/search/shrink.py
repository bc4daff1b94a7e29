"""Shrinking a failing scenario: delta debugging over its settings, one seed, the failure kept.

Greedy reduction to a fixed point, in the spirit of "Simplifying and Isolating Failure-Inducing Input"
(Andreas Zeller and Ralf Hildebrandt, 2002): each round tries, in order, to drop a scheduled perturbation,
to lower the number of vehicles, to cut frames after the last window, to move every perturbation window
earlier, to shorten it, and to make the perturbation weaker (fewer actors hidden, a lower miss probability);
for each setting the smallest candidate value first. A change is kept when the scenario still fails on the
same seed (``still_fails``), and rounds repeat until none is kept or the evaluation budget is spent. A
reduction that did not keep the failure is not tried again in a later round (it rarely does after a further
reduction, and the budget is better spent elsewhere) until a round keeps nothing; then one last round tries
every reduction again, so with budget enough the result is 1-minimal: no single reduction keeps the failure.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

from simrig.scenarios import Scenario, ScenarioError
from simrig.scenarios.overrides import with_setting
from simrig.scenarios.perturbation_schema import WORLD_KINDS


@dataclass
class Shrunk:
    """The smallest failing scenario found, the changes kept (``path = value``) and evaluations spent."""

    scenario: Scenario
    kept: list[str] = field(default_factory=list)
    evaluations: int = 0


def actor_count(scenario: Scenario) -> int:
    """[-] vehicles other than the ego: the traffic's plus the scripted ones (occluders, cut-ins)."""
    return scenario.traffic.vehicles + sum(p.kind in WORLD_KINDS for p in scenario.perturbations)


def smaller_ints(current: int, floor: int) -> list[int]:
    """Candidate values below ``current`` down to ``floor``, smallest first (halving towards ``current``).

    >>> smaller_ints(10, 0)
    [0, 5, 8, 9]
    >>> smaller_ints(2, 2)
    []
    """
    values, low = [], floor
    while low < current:
        values.append(low)
        low = max(low + 1, (low + current + 1) // 2) if low < current - 1 else current
    return sorted(set(values))


def _last_window_frame(scenario: Scenario) -> int:
    rate = scenario.frame_rate_hz
    return max((p.frame_window(rate)[1] for p in scenario.perturbations), default=0)


def _reductions(scenario: Scenario) -> Iterator[tuple[str, Callable[[], Scenario]]]:
    """(description, make the smaller scenario) for every reduction of ``scenario``, in the order tried."""
    raw = scenario.model_dump(mode="json", exclude_unset=True)
    for index in range(len(scenario.perturbations)):
        def drop(index=index):
            changed = dict(raw, name=scenario.name)
            changed["perturbations"] = [p for i, p in enumerate(raw.get("perturbations", [])) if i != index]
            return Scenario.model_validate(changed)
        yield f"perturbations.{index} removed", drop
    for value in smaller_ints(scenario.traffic.vehicles, 0):
        yield f"traffic.vehicles = {value}", lambda value=value: with_setting(scenario, "traffic.vehicles", value)
    for frames in smaller_ints(scenario.frames, _last_window_frame(scenario) + 1):
        yield f"frames = {frames}", lambda frames=frames: with_setting(scenario, "frames", frames)
    for index, perturbation in enumerate(scenario.perturbations):
        if perturbation.frames is None:
            continue
        first, last = perturbation.frames
        for start in smaller_ints(first, 0):
            window = [start, last - first + start]
            yield (f"perturbations.{index}.frames = {window}",
                   lambda window=window, index=index: with_setting(scenario, f"perturbations.{index}.frames", window))
        for end in smaller_ints(last, first):
            yield (f"perturbations.{index}.frames = {[first, end]}",
                   lambda end=end, index=index, first=first: with_setting(
                       scenario, f"perturbations.{index}.frames", [first, end]))
        if perturbation.kind not in WORLD_KINDS and getattr(perturbation, "nearest", None):
            for k in smaller_ints(perturbation.nearest, 1):
                yield (f"perturbations.{index}.nearest = {k}",
                       lambda k=k, index=index: with_setting(scenario, f"perturbations.{index}.nearest", k))
        probability = getattr(perturbation, "probability", None)
        if probability is not None and probability > 0:
            for value in (0.0, round(probability / 2, 6)):
                yield (f"perturbations.{index}.probability = {value}",
                       lambda value=value, index=index: with_setting(
                           scenario, f"perturbations.{index}.probability", value))


def shrink(scenario: Scenario, still_fails: Callable[[Scenario], bool], *, budget: int = 60,
           on_step: Callable[[str, bool], None] | None = None) -> Shrunk:
    """The smallest scenario reachable from a failing ``scenario`` by kept reductions, with at most ``budget``
    calls of ``still_fails``. ``on_step(description, kept)`` is told about every candidate tried."""
    result = Shrunk(scenario)
    rejected: set[str] = set()
    seen: set[str] = set()
    retried = False
    while result.evaluations < budget:
        if _step(result, still_fails, rejected, seen, budget, on_step):
            retried = False
        elif rejected and not retried:  # a last pass that tries everything again: nothing left to keep
            rejected.clear()
            retried = True
        else:
            break
    return result


def _step(result: Shrunk, still_fails, rejected: set[str], seen: set[str], budget: int, on_step) -> bool:
    """Try the reductions of ``result.scenario`` in order; keep the first that still fails (True). A candidate
    equal to one tried before (``seen``: the same scenario, so the same verdict on the same seed — the last
    pass meets the reductions rejected since the last kept change again) is not evaluated twice."""
    for description, make in _reductions(result.scenario):
        if result.evaluations >= budget:
            return False
        if description in rejected:
            continue
        try:
            candidate = make()
        except ScenarioError:
            continue
        if candidate.frames < _last_window_frame(candidate) + 1:
            continue
        key = candidate.model_dump_json()
        if key in seen:
            continue
        seen.add(key)
        result.evaluations += 1
        kept = still_fails(candidate)
        if on_step is not None:
            on_step(description, kept)
        if kept:  # every kept change makes the scenario strictly smaller, so shrinking ends
            result.scenario = candidate
            result.kept.append(description)
            return True
        rejected.add(description)
    return False
