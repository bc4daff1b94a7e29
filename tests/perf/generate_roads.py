"""Benchmark: ``simrig generate`` on each road layout next to the highway.

    python tests/perf/generate_roads.py [--frames 200] [--repeats 2]

Each scenario is generated as a user would (visibility rendering on, the scenario's detector), seed 0, the
scenarios alternating within each repeat so that machine noise hits all of them; medians. Per scenario: frames/s
and ms per frame of the whole, and of its stages (traffic, projection, visibility, sensor, writing), and the ratio
of the whole to ``highway_surround6``'s. Writes ``reports/perf/generate_roads.md``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

from published import command_line, machine, publish
from simrig.scenarios import load_scenario

from simrig.pipeline.generate import generate

OUT = Path(__file__).resolve().parents[2] / "reports" / "perf" / "generate_roads.md"
SCENARIOS = ("highway_surround6", "merge_surround6", "exit_surround6", "two_way_surround6", "intersection_surround6",
             "highway_stereo", "two_way_stereo")
STAGES = ("traffic", "projection", "visibility", "sensor", "writing")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    times: dict[str, list] = {name: [] for name in SCENARIOS}
    with tempfile.TemporaryDirectory() as tmp:
        for repeat in range(args.repeats):
            for name in SCENARIOS:
                result = generate(load_scenario(name), seed=0, out=Path(tmp) / f"{name}-{repeat}", frames=args.frames)
                times[name].append(result.times)
    lines = ["# `simrig generate` on the road layouts, next to the highway", "",
             f"Produced by `{command_line()}` ({machine()}); {args.frames} frames, seed 0, visibility rendered, "
             f"medians of {args.repeats} repeats, the scenarios alternating.", "",
             "| scenario | frames/s | ms/frame | × highway's (same rig) | " + " | ".join(
                 f"{stage} [ms/frame]" for stage in STAGES) + " |",
             "|---|---|---|---|" + "---|" * len(STAGES)]
    per_frame = {name: 1000 * statistics.median(t.total for t in runs) / args.frames for name, runs in times.items()}
    for name, runs in times.items():
        base = "highway_stereo" if name.endswith("stereo") else "highway_surround6"
        stages = " | ".join(f"{1000 * statistics.median(getattr(t, stage) for t in runs) / args.frames:.1f}"
                            for stage in STAGES)
        lines.append(f"| {name} | {1000 / per_frame[name]:.1f} | {per_frame[name]:.1f} | "
                     f"{per_frame[name] / per_frame[base]:.2f}× | {stages} |")
    publish([*lines, ""], OUT)
    return 0


if __name__ == "__main__":
    sys.exit(main())
