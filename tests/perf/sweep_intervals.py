"""The sweep claims of a bench with intervals: for each tracker and sweep, a metric at the sweep's last value minus
at its first, paired per sequence (scenario × seed) with its 95 % BCa interval (``simrig.report.paired``).

Run explicitly (not part of the test suite)::

    python tests/perf/sweep_intervals.py reports/standard [--metric 2d_HOTA --metric 3d_IDS]
                                         [--out reports/standard/sweep_intervals.md]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd
from published import command_line, publish  # tests/perf helpers

from simrig.report.paired import paired_difference


def sweep_rows(results: pd.DataFrame, metric: str) -> list[str]:
    """One markdown row per (sweep, tracker): mean at the first and last value and the paired difference."""
    rows = []
    for sweep in sorted(s for s in results["sweep"].unique() if s):
        swept = results[results["sweep"] == sweep]
        first, last = swept["value"].min(), swept["value"].max()
        for tracker in swept["tracker"].unique():
            ends = swept[swept["tracker"] == tracker].pivot_table(index=["scenario", "seed"], columns="value",
                                                                 values=metric)
            if first not in ends or last not in ends:
                continue
            ends = ends[[first, last]].dropna()
            d = paired_difference(ends[last].to_numpy(), ends[first].to_numpy())
            mark = "" if d.significant else " n.s."
            rows.append(f"| {sweep} {first:g} → {last:g} | `{tracker}` | {len(ends)} | {ends[first].mean():.3f} | "
                        f"{ends[last].mean():.3f} | {d.mean:+.3f} [{d.low:+.3f}, {d.high:+.3f}]{mark} |")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("report", type=Path, help="a bench or report folder with results.parquet")
    parser.add_argument("--metric", action="append", default=None)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    results = pd.read_parquet(args.report / "results.parquet")
    lines = ["# Sweep ends, paired per sequence", "", f"Produced by `{command_line()}` from "
             f"`{args.report}/results.parquet`: per tracker, the metric at the sweep's last value minus at its first, "
             "over the sequences (scenario × seed) that have both, with the 95 % BCa interval (n.s.: it holds 0).", ""]
    for metric in args.metric or ["2d_HOTA", "3d_IDS", "2d_IDSW"]:
        if metric not in results:
            continue
        lines += [f"## {metric}", "", "| sweep | tracker | sequences | first | last | last − first |",
                  "| --- | --- | ---: | ---: | ---: | ---: |", *sweep_rows(results, metric), ""]
    publish(lines, args.out or args.report / "sweep_intervals.md")


if __name__ == "__main__":
    main()
