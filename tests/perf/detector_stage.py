"""Benchmark: the detector stage's milliseconds per frame, this code side by side with another commit's.

Run explicitly (not part of the test suite)::

    python tests/perf/detector_stage.py --before COMMIT [--frames 300] [--repeats 3]

Both versions run ``simrig generate`` on ``highway_surround6`` (40 vehicles, six cameras, the catalog's detector
``bevformer_small``) with visibility rendering off, alternating (now, before, now, before, …) so that machine
noise hits both; the sensor stage's seconds are read from each run's ``time`` line and divided by the frame
count. Target: at most 4 ms per frame. The table is printed and written to
``reports/perf/detector_stage.md``.
"""

from __future__ import annotations

import argparse
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from memory import ROOT, cli_at, commit  # tests/perf helpers
from published import command_line, machine, publish

SCENARIO = 'extends = "highway_surround6"\n[render]\nvisibility = false\n'
TARGET_MS = 4.0


def sensor_seconds(cli: list[str], scenario: Path, frames: int, out: Path) -> float:
    """The sensor stage's seconds of one ``simrig generate`` run."""
    result = subprocess.run([*cli, "generate", str(scenario), "--frames", str(frames), "--out", str(out),
                             "--overwrite", "--quiet"], capture_output=True, text=True, check=True, cwd=ROOT)
    found = re.search(r"sensor ([0-9.]+) s", result.stdout)
    if found is None:
        raise RuntimeError(f"no sensor time in: {result.stdout}")
    return float(found.group(1))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", required=True, help="the commit to compare with")
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        scratch = Path(scratch)
        scenario = scratch / "scenario.toml"
        scenario.write_text(SCENARIO)
        now = [sys.executable, "-c", "import sys; from simrig.cli import console; sys.exit(console())"]
        versions = {f"now ({commit()})": now, f"before ({args.before})": cli_at(args.before, scratch)}
        seconds: dict[str, list[float]] = {name: [] for name in versions}
        for repeat in range(args.repeats):
            for name, cli in versions.items():
                seconds[name].append(sensor_seconds(cli, scenario, args.frames, scratch / f"ds-{repeat}"))
                print(f"{name}: {1000 * seconds[name][-1] / args.frames:.2f} ms/frame", flush=True)
    medians = {name: 1000 * statistics.median(values) / args.frames for name, values in seconds.items()}
    first, second = medians.values()
    lines = [
        "# The detector stage, side by side", "",
        f"Produced by `{command_line()}` ({machine()}). `simrig generate` of `highway_surround6` (40 vehicles, six "
        f"cameras, `bevformer_small`), {args.frames} frames, visibility rendering off; the sensor stage's time from "
        f"each run's `time` line, runs alternating, median of {args.repeats}.", "",
        "| code | sensor stage [ms/frame] | runs [ms/frame] |", "|---|---:|---|",
        *(f"| {name} | {medians[name]:.2f} | {', '.join(f'{1000 * v / args.frames:.2f}' for v in values)} |"
          for name, values in seconds.items()),
        "", f"Ratio now / before: {first / second:.2f}. Target ≤ {TARGET_MS:g} ms per frame: "
        f"**{'met' if first <= TARGET_MS else 'missed'}** ({first:.2f} ms).", "",
    ]
    publish(lines, ROOT / "reports" / "perf" / "detector_stage.md")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
