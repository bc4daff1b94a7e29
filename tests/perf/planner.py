"""Benchmark: what the planner-aware scores cost (issue 31, check 5).

    python tests/perf/planner.py

1. **Open loop, per frame**: :func:`simrig.scoring.planner.planner_scores` on ``highway_surround6`` (40 vehicles,
   200 frames) and ``cut_in`` with ``saga``'s tracks — two planner queries a frame plus the weighing of the misses
   the ground-truth plan reads — against the same scores with highway-env's own neighbour search (its Python loop
   over every vehicle, the peer the numpy search replaces), side by side in one run, 3 alternating repeats each;
   target ≤ 1 ms per frame. Also the whole ``score`` with and without the planner.
2. **Closed loop**: ``simrig drive`` (one tracker drive) against generating the same scenario and tracking it
   separately, 3 alternating repeats; target ≤ 1.5×.

Writes ``reports/perf/planner.md``.
"""

from __future__ import annotations

import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from highway_env.road.road import Road
from published import command_line, machine, publish
from simrig.scenarios import load_scenario

from simrig.dataset import Dataset
from simrig.pipeline.drive import drive
from simrig.pipeline.generate import generate
from simrig.pipeline.track import run_tracker
from simrig.scoring import api as scoring_api
from simrig.scoring import score
from simrig.scoring.planner import planner_road_of, planner_scores
from simrig.world.phantoms import PhantomRoad

OUT = Path(__file__).resolve().parents[2] / "reports" / "perf" / "planner.md"
REPEATS = 3
SCENES = ("highway_surround6", "cut_in")


def _misses(report) -> np.ndarray:
    errors = report.errors.to_pandas()
    fn = errors[(errors.dimension == "3d") & (errors.kind == "FN")]
    return fn[["frame", "actor_id"]].to_numpy()


def _loop_neighbours(self, vehicle, lane_index=None):
    """highway-env's own neighbour search, recording what it returned as the numpy search does."""
    front, rear = Road.neighbour_vehicles(self, vehicle, lane_index)
    self.read.extend(v for v in (front, rear) if v is not None)
    return front, rear


def open_loop(work: Path) -> list[str]:
    lines = ["## Open loop: the planner per frame", "",
             "| scene | frames | numpy search [ms/frame] | highway-env's loop [ms/frame] | loop / numpy | score() "
             "without planner [s] | with [s] |", "|---|---|---|---|---|---|---|"]
    numpy_search = PhantomRoad.neighbour_vehicles
    for name in SCENES:
        dataset_path = work / name
        generate(load_scenario(name), seed=0, out=dataset_path)
        dataset = Dataset.open(dataset_path)
        tracks = run_tracker(dataset, "saga").tracks
        report = score(dataset, tracks)
        truth, road, misses = dataset.ground_truth, planner_road_of(dataset), _misses(report)
        timings = {"numpy": [], "loop": [], "score": [], "score_without": []}
        for _ in range(REPEATS):
            for kind, search in (("numpy", numpy_search), ("loop", _loop_neighbours)):
                PhantomRoad.neighbour_vehicles = search
                start = time.perf_counter()
                planner_scores(road, truth, tracks.tracks3d, misses)
                timings[kind].append(time.perf_counter() - start)
            PhantomRoad.neighbour_vehicles = numpy_search
            start = time.perf_counter()
            score(dataset, tracks)
            timings["score"].append(time.perf_counter() - start)
            original = scoring_api.planner_road_of
            scoring_api.planner_road_of = lambda dataset: None
            start = time.perf_counter()
            score(dataset, tracks)
            timings["score_without"].append(time.perf_counter() - start)
            scoring_api.planner_road_of = original
        frames = len(truth.frames)
        per_frame = {kind: statistics.median(values) / frames * 1e3 for kind, values in timings.items()}
        lines.append(f"| {name} | {frames} | {per_frame['numpy']:.2f} | {per_frame['loop']:.2f} | "
                     f"{per_frame['loop'] / per_frame['numpy']:.2f}× | "
                     f"{statistics.median(timings['score_without']):.2f} | {statistics.median(timings['score']):.2f} |")
    return lines


def closed_loop(work: Path) -> list[str]:
    scenario = load_scenario("cut_in")
    lines = ["## Closed loop: `simrig drive` against generate + track", "",
             "| scene | tracker | generate + track [s] | drive [s] | drive / (generate + track) |",
             "|---|---|---|---|---|"]
    separate, together = [], []
    for repeat in range(REPEATS):
        folder = work / f"separate{repeat}"
        start = time.perf_counter()
        generate(scenario, seed=0, out=folder)
        run_tracker(Dataset.open(folder), "saga")
        separate.append(time.perf_counter() - start)
        start = time.perf_counter()
        drive(scenario, seed=0, out=work / f"drive{repeat}", tracker="saga")
        together.append(time.perf_counter() - start)
    a, b = statistics.median(separate), statistics.median(together)
    lines.append(f"| cut_in (150 frames) | saga | {a:.1f} | {b:.1f} | {b / a:.2f}× |")
    return lines


def main() -> int:
    work = Path(tempfile.mkdtemp(prefix="planner-perf-"))
    try:
        lines = ["# Planner-aware scores: cost", "",
                 f"Produced by `{command_line()}` ({machine()}); medians of {REPEATS} alternating repeats. "
                 "Targets (issue 31): the open-loop planner ≤ 1 ms per frame; a drive ≤ 1.5× generate + track.", "",
                 *open_loop(work), "", *closed_loop(work), ""]
        publish(lines, OUT)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
