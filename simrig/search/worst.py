"""``DIR/worst/``: the worst failing case of a search, shrunk, as a replay file and a pytest file.

* ``worst.toml`` — a replay file (:mod:`simrig.testing.replay`): ``simrig replay worst.toml`` reruns it;
* ``test_worst_case.py`` — a regression test a user drops into their suite: it fails while the tracker still
  fails the case (``SIMRIG_TRACKER`` / ``SIMRIG_TRACKER_PARAMS`` (JSON) run it on another tracker);
* ``shrink.json`` — where the case came from, every reduction kept, and the sizes before and after
  (written last: a folder without it is shrunk again by a rerun).
"""

from __future__ import annotations

import json
from pathlib import Path

from simrig.dataset.manifest import write_json_atomic
from simrig.dataset.outputs import write_text_atomic
from simrig.testing.replay import write_replay

from .evaluate import score_seed
from .fragments import Evaluation
from .ranking import best_candidates, fails
from .shrink import actor_count, shrink
from .space import SearchSpace

REPLAY = "worst.toml"
TEST = "test_worst_case.py"
LOG = "shrink.json"

_TEST_TEMPLATE = '''"""Regression test written by simrig search: the worst case found for {tracker!r}
in search space {space!r}, shrunk to {actors} actor(s) and {frames} frames (see shrink.json next to this file).

It fails while the tracker fails the case: {metric} {relation} {threshold} on seed {seed}.
Run it: pytest {test}
On another tracker: SIMRIG_TRACKER=saga SIMRIG_TRACKER_PARAMS='{{}}' pytest {test}
"""

import json
import os
from pathlib import Path

from simrig.benchmark.evaluate import metric_values
from simrig.testing import load_replay, run_tracker

REPLAY = Path(__file__).with_name({replay!r})
METRIC = {metric!r}
{threshold_name} = {threshold!r}


def test_worst_case_of_{slug}():
    replay = load_replay(REPLAY)
    tracker = os.environ.get("SIMRIG_TRACKER", replay.tracker)
    if "SIMRIG_TRACKER_PARAMS" in os.environ:
        params = json.loads(os.environ["SIMRIG_TRACKER_PARAMS"])
    else:
        params = replay.params if tracker == replay.tracker else {{}}
    value = metric_values(run_tracker(tracker, replay.scenario, seed=replay.seed, params=params))[METRIC]
    assert not value {operator} {threshold_name}, (
        f"{{tracker}} {{params}} still fails the shrunk worst case: {{METRIC}} = {{value}} "
        f"{relation} {{{threshold_name}}} (simrig replay {{REPLAY}})")
'''


def _worst_failing(space: SearchSpace, evaluations: dict[str, list[Evaluation]]) -> Evaluation | None:
    failing = [e for stream, items in evaluations.items() if stream != "confirm" for e in items if fails(space, e)]
    chosen = best_candidates(space, failing, 1)
    return chosen[0] if chosen else None


def write_worst(space: SearchSpace, evaluations: dict[str, list[Evaluation]], folder: Path, cache: Path,
                budget: int, progress: bool = False) -> Path | None:
    """Shrink the worst failing evaluation (on its first failing seed) and write ``folder``; None when no
    evaluation failed. Done once: a folder with ``shrink.json`` for the same case is kept as it is."""
    worst = _worst_failing(space, evaluations)
    if worst is None:
        return None
    failure = space.config.objective.failure
    metric = space.config.objective.failure_metric
    source = {"stream": worst.stream, "index": worst.index, "candidate": worst.candidate}
    log_path = folder / LOG
    if log_path.exists() and json.loads(log_path.read_text(encoding="utf-8")).get("source") == source:
        return folder
    seed = next(s for s, v in zip(worst.seeds, worst.values(metric), strict=True) if failure.fails(v))
    tracker, params = space.tracker, space.params

    def still_fails(scenario) -> bool:
        from simrig.benchmark.evaluate import metric_values

        return failure.fails(metric_values(score_seed(scenario, seed, tracker, params, str(cache)))[metric])

    def told(description: str, kept: bool) -> None:
        if progress:
            print(f"shrink    {'kept ' if kept else 'tried'} {description}", flush=True)

    start = space.scenario_for(worst.candidate)
    shrunk = shrink(start, still_fails, budget=budget, on_step=told)
    report = score_seed(shrunk.scenario, seed, tracker, params, str(cache))
    relation = ">=" if failure.at_least is not None else "<="
    threshold = failure.at_least if failure.at_least is not None else failure.at_most
    folder.mkdir(parents=True, exist_ok=True)
    write_replay(folder / REPLAY, shrunk.scenario, seed, tracker=tracker, params=params, scores=report,
                 failure=f"{metric} {relation} {threshold} (simrig search {space.config.name})")
    test = _TEST_TEMPLATE.format(
        tracker=tracker, space=space.config.name, actors=actor_count(shrunk.scenario),
        frames=shrunk.scenario.frames, metric=metric, relation=relation, threshold=threshold, seed=seed,
        test=TEST, replay=REPLAY, slug="".join(c if c.isalnum() else "_" for c in space.config.name),
        threshold_name="AT_LEAST" if relation == ">=" else "AT_MOST", operator=relation)
    write_text_atomic(folder / TEST, test)
    write_json_atomic(log_path, {
        "source": source, "seed": seed, "kept": shrunk.kept, "evaluations": shrunk.evaluations,
        "before": {"actors": actor_count(start), "frames": start.frames,
                   "perturbations": len(start.perturbations)},
        "after": {"actors": actor_count(shrunk.scenario), "frames": shrunk.scenario.frames,
                  "perturbations": len(shrunk.scenario.perturbations)},
    })
    return folder
