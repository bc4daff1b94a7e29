"""Benchmark: wall time of ``simrig explain`` on the run ``simrig run highway_surround6 --seed 0 --tracker saga``
(200 frames, every cause group present in the scenario), cold: the counterfactual cache is emptied first.

Run explicitly (not part of the test suite)::

    python tests/perf/explain.py [--run-dir runs/highway_surround6-seed0] [--samples N] [--workers 2]
                                 [--out reports/perf/explain.md]

The run folder is made with ``simrig run`` (in Python) when it holds no saga run. Each configuration is timed
once (a cold explain is minutes long); the table gives wall time, counterfactual runs, seconds per run and the
machine's load average before and after, since the machine may be shared.
"""

from __future__ import annotations

import argparse
import os
import shutil
import time
from pathlib import Path

from published import command_line, machine, publish  # tests/perf helpers

from simrig.explain import explain
from simrig.explain.api import CACHE_DIR, EXPLAIN_DIR, explain_table
from simrig.pipeline.run import run_pipeline

TARGET_S = 120.0


def ensure_run(run_dir: Path) -> None:
    if not (run_dir / "tracks" / "saga" / "tracker.json").exists():
        run_pipeline("highway_surround6", seed=0, tracker="saga", out=run_dir)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--run-dir", type=Path, default=Path("runs/highway_surround6-seed0"))
    parser.add_argument("--samples", type=int, action="append", default=None,
                        help="permutations to sample (repeatable; default: the explainer's default mode)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=Path("reports/perf/explain.md"))
    args = parser.parse_args()
    ensure_run(args.run_dir)
    rows = []
    for samples in args.samples or [None]:
        shutil.rmtree(args.run_dir / EXPLAIN_DIR / CACHE_DIR, ignore_errors=True)
        load_before = os.getloadavg()[0]
        started = time.perf_counter()
        result = explain(args.run_dir, samples=samples, workers=args.workers)
        wall = time.perf_counter() - started
        document = result.document
        rows.append((document, result.coalitions, wall, load_before, os.getloadavg()[0]))
        print(result.table)
    lines = [
        "# `simrig explain` wall time", "",
        f"Produced by `{command_line()}` on {machine()}, {os.cpu_count()} cores. The machine is shared with other "
        "developers' jobs (load average given), so times are upper bounds of what an idle machine does.", "",
        f"Run: `simrig run highway_surround6 --seed 0 --tracker saga` (200 frames); target ≤ {TARGET_S:.0f} s, "
        "counterfactual cache emptied before each row (cold).", "",
        "| groups | mode | permutations | counterfactual runs | workers | wall [s] | s per run | load before / after "
        "| target |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for document, coalitions, wall, before, after in rows:
        lines.append(f"| {len(document['causes'])} | {document['mode']} | {document['samples'] or '-'} | "
                     f"{coalitions} | {args.workers} | {wall:.0f} | {wall / coalitions:.2f} | {before:.1f} / "
                     f"{after:.1f} | {'met' if wall <= TARGET_S else 'missed'} |")
    last = rows[-1][0]
    lines += ["", f"Groups: {', '.join(last['causes'])}.", "",
              "Shares of the last row (the explainer's table):", "", "```",
              explain_table(last), "```", ""]
    publish(lines, args.out)


if __name__ == "__main__":
    main()
