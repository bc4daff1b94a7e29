"""Benchmark: a detector-only change made from a recorded world (``generate(world_from=...)``) against a full
generation of the same dataset, side by side in one run; and the start-up cost of the front door.

Run explicitly (not part of the test suite)::

    python tests/perf/world_reuse.py [--scenario highway_surround6] [--frames 200] [--repeats 3]
                                      [--out reports/perf/world_reuse.md]

The two sides alternate within each repeat and produce byte-identical folders (checked every time); medians
are reported, and their ratio is what a miss-probability sweep cell of ``simrig bench`` saves. Start-up:
``python -c "import simrig"`` and ``simrig --help`` in fresh interpreters, medians of 5.
"""

from __future__ import annotations

import argparse
import filecmp
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from published import command_line, machine, publish  # tests/perf helpers
from simrig.scenarios import load_scenario
from simrig.scenarios.overrides import with_setting

from simrig.dataset import Dataset
from simrig.pipeline.generate import generate


def _same_files(a: Path, b: Path) -> bool:
    names = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file())
    return names == sorted(p.relative_to(b) for p in b.rglob("*") if p.is_file()) and all(
        filecmp.cmp(a / name, b / name, shallow=False) for name in names)


def _startup(command: list[str], repeats: int = 5) -> float:
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True)
        times.append(time.perf_counter() - started)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="highway_surround6")
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=Path("reports/perf/world_reuse.md"))
    args = parser.parse_args()
    base = load_scenario(args.scenario)
    swept = with_setting(base, "sensor.detection.probability", 0.65)  # a miss-probability sweep value of 0.35
    full_s, reused_s = [], []
    with tempfile.TemporaryDirectory(prefix="simrig-world-reuse-") as scratch:
        scratch = Path(scratch)
        source = Dataset.open(generate(base, seed=0, out=scratch / "source", frames=args.frames).path)
        for _ in range(args.repeats):
            for side in ("full", "reused"):
                out = scratch / side
                shutil.rmtree(out, ignore_errors=True)
                started = time.perf_counter()
                generate(swept, seed=0, out=out, frames=args.frames,
                         world_from=source if side == "reused" else None)
                (full_s if side == "full" else reused_s).append(time.perf_counter() - started)
            if not _same_files(scratch / "full", scratch / "reused"):
                raise SystemExit("the reused-world dataset differs from the full generation")
    full, reused = statistics.median(full_s), statistics.median(reused_s)
    python = sys.executable
    simrig_cli = str(Path(python).with_name("simrig"))
    import_s = _startup([python, "-c", "import simrig"])
    help_s = _startup([simrig_cli, "--help"])
    lines = [
        "# Detector sweeps on a recorded world; start-up of the front door",
        "",
        f"`{command_line()}` — {machine()}. {args.scenario}, {args.frames} frames, seed 0, "
        f"{args.repeats} repeats, sides alternating, medians; the two datasets are byte-identical.",
        "",
        "| dataset of a miss-probability sweep cell (p = 0.65) | wall [s] | ms/frame |",
        "|---|---:|---:|",
        f"| full generation (traffic, projection, rendered visibility, sensor, writing) | {full:.2f} | "
        f"{1000 * full / args.frames:.1f} |",
        f"| from the recorded world (`generate(world_from=...)`: sensor and writing only) | {reused:.2f} | "
        f"{1000 * reused / args.frames:.1f} |",
        "",
        f"Ratio: **{full / reused:.1f}×** faster ({100 * (1 - reused / full):.0f}% of the generation saved).",
        "",
        "| start-up (fresh interpreter, median of 5) | wall [s] |",
        "|---|---:|",
        f"| `python -c \"import simrig\"` | {import_s:.3f} |",
        f"| `simrig --help` | {help_s:.3f} |",
        "",
    ]
    publish(lines, args.out)


if __name__ == "__main__":
    main()
