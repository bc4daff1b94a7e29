"""Benchmark: what a user waits for at the command line, each beside a peer in the same run.

Run explicitly (not part of the test suite)::

    python tests/perf/users_wait.py [--repeats 5] [--frames 200] [--stone-soup .cache/stonesoup-venv/bin/python]

1. Start-up: ``simrig --help`` against ``python -c pass`` (wall time of a fresh process, median; target ≤ 0.1 s).
2. Simulate → track → score, ``--frames`` frames: ``simrig run highway_surround6 --tracker global_hungarian``
   (generation with visibility, the Kalman/Hungarian tracker, every score) against Stone Soup 1.9.1 doing the same
   job its own way (``tests/perf/stone_soup_side.py``: a 2D multi-target simulation sized like the scene, its
   Kalman/GNN multi-target tracker, OSPA and SIAP), in the interpreter of a venv that has it. CPU seconds of the
   whole child process (user + system, interpreter start-up included), median; target: Stone Soup ÷ simrig ≥ 3.

The sides alternate, so a busy moment of the machine hits both. The table is printed and written to
``reports/perf/users_wait.md``; the other figures users wait for have their own scripts (the report lists them).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from published import command_line, publish  # tests/perf helpers

HERE = Path(__file__).resolve().parent
REPORT = HERE.parents[1] / "reports" / "perf" / "users_wait.md"
SIMRIG = str(Path(sys.executable).parent / "simrig")


def child_cost(command: list[str], cwd: Path) -> tuple[float, float, str]:
    """(wall [s], CPU [s] user + system, stdout) of one child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=1800)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode:
        raise SystemExit(f"{' '.join(command)} failed:\n{done.stderr[-2000:]}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), done.stdout


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--stone-soup", type=Path, default=HERE.parents[1] / ".cache" / "stonesoup-venv" / "bin" /
                        "python", help="a Python interpreter with stonesoup 1.9.1 installed")
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="users-wait-"))
    starts = {"python -c pass": [sys.executable, "-c", "pass"], "simrig --help": [SIMRIG, "--help"]}
    start_wall: dict[str, list[float]] = {name: [] for name in starts}
    for _ in range(2 * args.repeats + 1):
        for name, command in starts.items():
            start_wall[name].append(child_cost(command, work)[0])
    pipelines = {
        "simrig run": [SIMRIG, "run", "highway_surround6", "--seed", "0", "--frames", str(args.frames), "--tracker",
                       "global_hungarian", "--out", str(work / "run"), "--overwrite", "--quiet"],
        "Stone Soup": [str(args.stone_soup), str(HERE / "stone_soup_side.py"), "--frames", str(args.frames)],
    }
    pipeline_cpu: dict[str, list[float]] = {name: [] for name in pipelines}
    stone_soup_out = ""
    for _ in range(args.repeats):
        for name, command in pipelines.items():
            _, cpu, out = child_cost(command, work)
            pipeline_cpu[name].append(cpu)
            stone_soup_out = out if name == "Stone Soup" else stone_soup_out
    stages = json.loads(stone_soup_out.strip().splitlines()[-1])
    help_s, pass_s = (statistics.median(start_wall[k]) for k in ("simrig --help", "python -c pass"))
    ours, theirs = (statistics.median(pipeline_cpu[k]) for k in ("simrig run", "Stone Soup"))
    load = os.getloadavg()[0]
    lines = [
        "# What users wait for: start-up and the whole job, beside a peer", "",
        f"Produced by `{command_line()}` on {platform.machine()}, Python {platform.python_version()}, "
        f"{os.cpu_count()} cores (1-minute load {load:.1f} at the end). The sides alternate; medians.", "",
        "| figure | peer | simrig | ratio | target | |", "|---|---:|---:|---:|---|---|",
        f"| start-up, wall of a fresh process ({2 * args.repeats + 1} runs) | `python -c pass` {pass_s:.3f} s | "
        f"`simrig --help` {help_s:.3f} s | {help_s / pass_s:.1f}× the bare interpreter | ≤ 0.1 s | "
        f"{'met' if help_s <= 0.1 else 'missed'} |",
        f"| simulate → track → score, {args.frames} frames, CPU of the process ({args.repeats} runs) | Stone Soup "
        f"1.9.1 {theirs:.1f} CPU-s | {ours:.1f} CPU-s | {theirs / ours:.2f}× (peer ÷ simrig) | ≥ 3× | "
        f"{'met' if theirs / ours >= 3 else 'missed'} |", "",
        f"Stone Soup's last run by stage (CPU s inside the process, after the interpreter started): imports "
        f"{stages['import_s']:.1f}, simulation and tracking {stages['simulate_and_track_s']:.1f}, OSPA and SIAP "
        f"{stages['score_s']:.1f}; {stages['truths']} true paths, {stages['tracks']} tracks. simrig's run does more "
        "per frame — six cameras, rendered visibility, the detector model, the planner's plans, 2D and 3D scores — "
        "so the ratio is of the two tools doing their whole job, not of equal work.", "",
        "Every run: " + ", ".join(f"{name} {', '.join(f'{v:.1f}' for v in values)}"
                                  for name, values in pipeline_cpu.items()) + " CPU-s.", "",
        "The other figures users wait for, each beside its peer in its own script: scoring a MOTChallenge import "
        "against TrackEval (`python tests/perf/score_first_call.py`, `score_first_call.md`), generation against bare "
        "highway-env stepping (`python tests/perf/generate.py`, `generate.md`), visibility "
        "(`python tests/perf/visibility.py`, `visibility.md`), `simrig explain` (`python tests/perf/explain.py`, "
        "`explain.md`).", "",
    ]
    publish(lines, REPORT)


if __name__ == "__main__":
    main()
