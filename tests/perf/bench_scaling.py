"""Benchmark: how the bench scales — cells per minute with 1 and 2 local workers, and what Ray adds per cell.

Run explicitly (not part of the test suite)::

    python tests/perf/bench_scaling.py [--suite smoke] [--repeats 2] [--out reports/perf/bench.md]

Every run starts from an empty folder and an empty dataset cache, so every cell is generated, tracked and
scored. Sides alternate within each repeat (local 1, local 2, Ray 2, Ray 1); medians are reported. The
in-process row runs the same cells one after another in this process (no pool, no Ray): the floor that
engines add to. Ray's own start-up (``ray.init`` of a local instance and its shutdown) is timed on its own,
and Ray's overhead per cell is (Ray wall − local wall at the same workers − start-up) / cells.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import tempfile
import time
from pathlib import Path

from published import command_line, machine, publish  # tests/perf helpers

from simrig.benchmark import load_suite, run_bench
from simrig.benchmark.evaluate import evaluate
from simrig.benchmark.plan import make_plan
from simrig.benchmark.results import finished

SIDES = (("local", 1), ("local", 2), ("ray", 2), ("ray", 1))


def timed_bench(suite: str, engine: str, workers: int, scratch: Path) -> tuple[float, int]:
    """Wall seconds of a cold ``run_bench`` and its cell count."""
    out = scratch / f"{engine}-{workers}"
    shutil.rmtree(out, ignore_errors=True)
    started = time.perf_counter()
    result = run_bench(suite, engine=engine, workers=workers, out=out)
    return time.perf_counter() - started, result.cells


def in_process(suite: str, scratch: Path) -> float:
    """Wall seconds of every cell evaluated serially in this process, cold cache."""
    loaded, scenarios = load_suite(suite)
    cache = scratch / "in-process"
    shutil.rmtree(cache, ignore_errors=True)
    started = time.perf_counter()
    for job in make_plan(loaded, scenarios).jobs(finished(scratch / "nothing"), cache):
        evaluate(job)
    return time.perf_counter() - started


def ray_startup() -> float:
    import ray

    started = time.perf_counter()
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    ray.shutdown()
    return time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", default="smoke")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--out", type=Path, default=Path("reports/perf/bench.md"))
    args = parser.parse_args()

    walls: dict[tuple[str, int], list[float]] = {side: [] for side in SIDES}
    serial, startups, cells = [], [], 0
    with tempfile.TemporaryDirectory(prefix="simrig-bench-scaling-") as folder:
        scratch = Path(folder)
        for repeat in range(args.repeats):
            serial.append(in_process(args.suite, scratch))
            for engine, workers in SIDES:
                wall, cells = timed_bench(args.suite, engine, workers, scratch)
                walls[(engine, workers)].append(wall)
                print(f"repeat {repeat}: {engine} × {workers}: {wall:.1f} s", flush=True)
            startups.append(ray_startup())
    startup = statistics.median(startups)
    floor = statistics.median(serial)
    median = {side: statistics.median(values) for side, values in walls.items()}
    lines = [
        f"# Bench scaling — suite `{args.suite}` ({cells} cells)", "",
        f"Command: `{command_line()}`  ",
        f"Machine: {machine()}, {len(__import__('os').sched_getaffinity(0))} processors; cold cache every run "
        f"(every cell generated, tracked, scored); medians of {args.repeats} repeats, sides alternating.", "",
        "| engine | workers | wall [s] | cells/min | speed-up vs local × 1 | engine overhead per cell [s] |",
        "|---|---:|---:|---:|---:|---:|",
        f"| in process, serial | 1 | {floor:.1f} | {60 * cells / floor:.1f} | "
        f"{median[('local', 1)] / floor:.2f}× | – |",
    ]
    for engine, workers in SIDES:
        wall = median[(engine, workers)]
        overhead = (wall - floor / workers) / cells if workers == 1 else float("nan")
        lines.append(f"| {engine} | {workers} | {wall:.1f} | {60 * cells / wall:.1f} | "
                     f"{median[('local', 1)] / wall:.2f}× | {'–' if overhead != overhead else f'{overhead:.2f}'} |")
    lines += [
        "",
        f"Ray start-up and shutdown of a local instance: {startup:.1f} s (median).",
        "",
        "Ray overhead per cell, start-up excluded: "
        + ", ".join(f"{workers} worker{'s' if workers > 1 else ''}: "
                    f"{(median[('ray', workers)] - median[('local', workers)] - startup) / cells:+.2f} s"
                    for workers in (1, 2))
        + " (Ray wall − local wall − start-up, divided by the cells).",
        "",
        "Engine overhead per cell (1 worker): (wall − in-process serial wall) / cells — process start-up, "
        "imports in the worker and passing results back.",
    ]
    publish(lines, args.out)


if __name__ == "__main__":
    main()
