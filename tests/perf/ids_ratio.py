"""Report: each 3D tracker's identity switches against a reference tracker's, pooled over a bench's sequences.

Run explicitly (not part of the test suite)::

    python tests/perf/ids_ratio.py BENCH_OR_REPORT_FOLDER [--reference global_hungarian] [--out FILE.md]

Reads the folder's ``results.parquet`` (the base points: each scenario at its own settings), pairs every tracker
with the reference on the same sequences (scenario × seed) and prints, per tracker: the pooled IDS ratio
``sum(IDS) / sum(reference IDS)`` with its 95 % BCa bootstrap interval over sequences resampled in pairs
(:func:`simrig.report.paired.paired_ratio`), the ratio per scenario, and how many sequences reach the SAGA-Track
paper's target (at most ⅓ of the reference's switches; a sequence where the reference has none reaches it only
with none). Written to ``--out`` (default ``FOLDER/ids_ratio.md``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd
from published import command_line, machine, publish  # tests/perf helpers

from simrig.report.paired import paired_ratio


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--reference", default="global_hungarian")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    results = pd.read_parquet(args.folder / "results.parquet")
    base = results[(results["sweep"] == "") & (results["scored"] == "3d")]
    table = base.pivot_table(index=["scenario", "seed"], columns="tracker", values="3d_IDS", aggfunc="first")
    reference = table[args.reference]
    scenarios = list(dict.fromkeys(base["scenario"]))
    lines = [f"# Identity switches against `{args.reference}`, pooled", "",
             f"Produced by `{command_line()}` ({machine()}) from `{args.folder / 'results.parquet'}`: "
             f"{len(table)} sequences ({', '.join(f'`{s}`' for s in scenarios)} × seeds "
             f"{', '.join(map(str, sorted(base['seed'].unique())))}). Pooled ratio: sum of the tracker's IDS over "
             "the sum of the reference's, with its 95 % BCa bootstrap interval over sequences resampled in pairs.",
             "", "| tracker | pooled IDS ratio | " + " | ".join(f"`{s}`" for s in scenarios)
             + " | sequences with ratio ≤ ⅓ |", "|---|---:|" + "---:|" * len(scenarios) + "---:|"]
    for tracker in [t for t in dict.fromkeys(base["tracker"]) if t != args.reference]:
        mine = table[tracker]
        ratio, low, high = paired_ratio(mine.to_numpy(), reference.to_numpy())
        per_scene = [mine.loc[s].sum() / reference.loc[s].sum() for s in scenarios]
        reached = int(((mine * 3 <= reference) & ~((reference == 0) & (mine > 0))).sum())
        lines.append(f"| `{tracker}` | {ratio:.2f} [{low:.2f}, {high:.2f}] | "
                     + " | ".join(f"{value:.2f}" for value in per_scene) + f" | {reached} / {len(mine)} |")
    publish(lines + [""], args.out or args.folder / "ids_ratio.md")


if __name__ == "__main__":
    main()
