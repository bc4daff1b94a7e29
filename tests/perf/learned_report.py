"""Report: the learned association against saga, polymot and global_hungarian.

Run explicitly, on the results of the ``learned`` suite::

    simrig bench learned --out runs/bench/learned
    python tests/perf/learned_report.py runs/bench/learned

Per group of roads — the four road types the packaged model was trained on (``traffic_mix``: highway, merge,
two-way, exit; 40 sequences) and the one held out of its training (the intersection; 10 sequences) — each
tracker's mean AMOTA and ID switches per sequence, and the paired difference of ``learned`` minus each other
tracker per sequence with its BCa 95% interval (:func:`simrig.report.paired.paired_difference`; ``n.s.``: the
interval holds 0). Writes ``reports/learned/index.md``, linking the training report for what the model learned.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd
from published import command_line, machine, publish

from simrig.report.paired import paired_difference

OUT = Path(__file__).resolve().parents[2] / "reports" / "learned" / "index.md"
HELD_OUT = "intersection_surround6"
METRICS = {"3d_AMOTA": ("AMOTA", 3), "3d_IDS": ("IDS per sequence", 1), "2d_HOTA": ("HOTA", 3)}
LEARNED = "learned"


def group_table(results: pd.DataFrame) -> list[str]:
    table = results.pivot_table(index=["scenario", "seed"], columns="tracker", values=list(METRICS))
    others = [name for name in dict.fromkeys(results.tracker) if name != LEARNED]
    lines = ["| tracker | " + " | ".join(f"{label} (mean)" for label, _ in METRICS.values()) + " | " +
             " | ".join(f"learned − tracker: {label}" for label, _ in METRICS.values()) + " |",
             "|---|" + "---|" * (2 * len(METRICS))]
    for tracker in [LEARNED, *others]:
        means = " | ".join(f"{table[(column, tracker)].mean():.{digits}f}" for column, (_, digits) in METRICS.items())
        if tracker == LEARNED:
            diffs = " | ".join("" for _ in METRICS)
        else:
            diffs = " | ".join(paired_difference(table[(column, LEARNED)].to_numpy(),
                                                 table[(column, tracker)].to_numpy()).text(digits=digits)
                               for column, (_, digits) in METRICS.items())
        lines.append(f"| {tracker} | {means} | {diffs} |")
    return lines


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("bench", type=Path)
    args = parser.parse_args()
    results = pd.read_parquet(args.bench / "results.parquet")
    trained = results[results.scenario != HELD_OUT]
    held = results[results.scenario == HELD_OUT]
    lines = ["# The learned association against the hand-set trackers", "",
             f"Produced by `{command_line()}` ({machine()}) on the `learned` suite (`simrig bench learned`): "
             f"seeds 100–109, no tracker tuned on them and none in the training collection (its seeds are "
             f"≥ 1,000,000). `learned` is `global_hungarian` with the packaged model "
             "(`tracker/models/association.json`) in place of the Mahalanobis gate; how it was trained and what it "
             "learned (permutation importances): [training.md](training.md). Paired differences per sequence "
             "(scenario × seed), BCa 95% intervals; `n.s.`: the interval holds 0.", "",
             f"## The road types it was trained on ({trained.groupby(['scenario', 'seed']).ngroups} sequences: "
             f"{', '.join(dict.fromkeys(trained.scenario))})", "", *group_table(trained), "",
             f"## The road type held out of training ({held.groupby(['scenario', 'seed']).ngroups} sequences: "
             f"{HELD_OUT})", "", *group_table(held), ""]
    publish(lines, OUT)
    return 0


if __name__ == "__main__":
    sys.exit(main())
