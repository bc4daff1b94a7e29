"""Benchmark: what the planner-aware scores cost.

    python tests/perf/planner.py

1. **Open loop, per frame**: :func:`simrig.scoring.planner.planner_scores` on ``highway_surround6`` (40 vehicles,
   200 frames) and ``cut_in`` with ``saga``'s tracks, the ground truth's plans read from the dataset's
   ``truth_plans`` table (one query a frame, on the tracks; target ≤ 1 ms per frame); beside it, a dataset without
   the table (its plans computed first: a query on the ground truth and one per vehicle it reads), what recording
   the table adds to ``generate`` and what ``generate`` costs in all, and the whole ``score`` with and without the
   planner; 3 repeats, each on a fresh generation.
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
from published import command_line, machine, publish
from simrig.scenarios import load_scenario

from simrig.dataset import Dataset
from simrig.pipeline.drive import drive
from simrig.pipeline.generate import generate
from simrig.pipeline.track import run_tracker
from simrig.scoring import score
from simrig.scoring.planner import planner_road_of, planner_scores
from simrig.scoring.truth_plans import computed_truth_side, truth_side_of

OUT = Path(__file__).resolve().parents[2] / "reports" / "perf" / "planner.md"
REPEATS = 3
SCENES = ("highway_surround6", "cut_in")


def _misses(report) -> np.ndarray:
    errors = report.errors.to_pandas()
    fn = errors[(errors.dimension == "3d") & (errors.kind == "FN")]
    return fn[["frame", "actor_id"]].to_numpy()


def open_loop(work: Path) -> list[str]:
    lines = ["## Open loop: the planner per frame", "",
             "| scene | frames | scoring a tracker, plans on the ground truth recorded [ms/frame] | a dataset without "
             "them, its first tracker [ms/frame] | recording them in `generate` [ms/frame] | `generate` in all "
             "[ms/frame] | score() without the planner [s] | with it [s] | with / without |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name in SCENES:
        timings = {"recorded": [], "computed": [], "record": [], "generate": [], "score": [], "score_without": []}
        for repeat in range(REPEATS):
            dataset_path = work / f"{name}{repeat}"
            result = generate(load_scenario(name), seed=0, out=dataset_path)
            timings["record"].append(result.times.planning)
            timings["generate"].append(result.times.total)
            dataset = Dataset.open(dataset_path)
            tracks = run_tracker(dataset, "saga").tracks
            misses = _misses(score(dataset, tracks, planner=False))
            truth, road = dataset.ground_truth, planner_road_of(dataset)
            start = time.perf_counter()
            planner_scores(road, truth, tracks.tracks3d, misses, truth_side_of(dataset, road, truth))
            timings["recorded"].append(time.perf_counter() - start)
            start = time.perf_counter()
            planner_scores(road, truth, tracks.tracks3d, misses, computed_truth_side(road, truth))
            timings["computed"].append(time.perf_counter() - start)
            start = time.perf_counter()
            score(dataset, tracks)
            timings["score"].append(time.perf_counter() - start)
            start = time.perf_counter()
            score(dataset, tracks, planner=False)
            timings["score_without"].append(time.perf_counter() - start)
        frames = len(truth.frames)
        median = {kind: statistics.median(values) for kind, values in timings.items()}
        per_frame = {kind: median[kind] / frames * 1e3 for kind in ("recorded", "computed", "record", "generate")}
        lines.append(f"| {name} | {frames} | {per_frame['recorded']:.2f} | {per_frame['computed']:.2f} | "
                     f"{per_frame['record']:.2f} | {per_frame['generate']:.1f} | {median['score_without']:.2f} | "
                     f"{median['score']:.2f} | {median['score'] / median['score_without']:.2f}× |")
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
                 "Targets: the open-loop planner ≤ 1 ms per frame; a drive ≤ 1.5× generate + track.", "",
                 *open_loop(work), "", *closed_loop(work), ""]
        publish(lines, OUT)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
