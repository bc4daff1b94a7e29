"""Report: the planner-aware scores next to HOTA and AMOTA for every 3D reference tracker.

Run explicitly, on the results of the ``planner`` suite (the surround catalog, ten fresh seeds)::

    simrig bench planner --out runs/bench/planner
    python tests/perf/planner_scores.py runs/bench/planner

1. Per tracker, pooled over every sequence (scenario × seed): the mean of HOTA (2D, the 3D tracks projected), AMOTA,
   PKL, dACC, HZ_MISS, HZ_FAKE and LANE, and the paired difference to the suite's first tracker with its BCa 95%
   interval (:func:`simrig.report.paired.paired_difference`; ``n.s.``: the interval holds 0).
2. How the rankings agree: per sequence, Spearman's ρ between the trackers' order by each classic metric (higher
   is better) and by PKL (lower is better), averaged over the sequences with a bootstrap 95% interval; and ρ between
   the orders of the pooled means.
3. The scenes where they disagree most: the sequences with the lowest ρ(AMOTA, −PKL), with the two trackers whose
   order flips most, and a mosaic of the frame where the AMOTA-better tracker's plan diverges most from the
   ground-truth plan (made by ``simrig run`` + ``simrig render`` into ``reports/planner/``).

Writes ``reports/planner/index.md``.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from published import command_line, machine, publish
from scipy.stats import bootstrap, spearmanr

from simrig.report.paired import paired_difference

OUT = Path(__file__).resolve().parents[2] / "reports" / "planner"
METRICS = {  # column: (name, digits, higher is better)
    "2d_HOTA": ("HOTA", 3, True), "3d_AMOTA": ("AMOTA", 3, True), "3d_PKL": ("PKL [nats/frame]", 3, False),
    "3d_dACC": ("dACC [m/s²]", 3, False), "3d_HZ_MISS": ("missed-hazard frames", 1, False),
    "3d_HZ_FAKE": ("invented-hazard frames", 1, False), "3d_LANE": ("lane-decision frames", 1, False),
}
CLASSIC = ("2d_HOTA", "3d_AMOTA")
WORST = 3


def paired_table(results: pd.DataFrame, trackers: list[str]) -> list[str]:
    """Section 1: means and paired differences to the first tracker."""
    base = trackers[0]
    table = results.pivot_table(index=["scenario", "seed"], columns="tracker", values=list(METRICS))
    lines = [f"| tracker | {' | '.join(name for name, _, _ in METRICS.values())} |",
             "|---|" + "---|" * len(METRICS)]
    for tracker in trackers:
        cells = []
        for column, (_, digits, _) in METRICS.items():
            mean = table[(column, tracker)].mean()
            if tracker == base:
                cells.append(f"{mean:.{digits}f}")
            else:
                diff = paired_difference(table[(column, tracker)].to_numpy(), table[(column, base)].to_numpy())
                cells.append(f"{mean:.{digits}f}<br>{diff.text(digits=digits)}")
        lines.append(f"| {tracker} | {' | '.join(cells)} |")
    return lines


def rank_agreement(results: pd.DataFrame) -> tuple[list[str], pd.DataFrame]:
    """Section 2: ρ per sequence between each classic metric's order and PKL's, and of the pooled means."""
    rows, lines = [], []
    for (scenario, seed), group in results.groupby(["scenario", "seed"]):
        row = {"scenario": scenario, "seed": seed}
        for column in CLASSIC:
            rho = spearmanr(group[column], -group["3d_PKL"]).statistic
            row[column] = rho
        rows.append(row)
    per_sequence = pd.DataFrame(rows)
    means = results.groupby("tracker")[[*CLASSIC, "3d_PKL"]].mean()
    lines += ["| classic metric | mean ρ over sequences [95% interval] | sequences with ρ < 0 "
              "| ρ of the pooled means |", "|---|---|---|---|"]
    for column in CLASSIC:
        values = per_sequence[column].dropna().to_numpy()
        interval = bootstrap((values,), np.mean, n_resamples=10_000, random_state=0, method="BCa").confidence_interval
        pooled = spearmanr(means[column], -means["3d_PKL"]).statistic
        lines.append(f"| {METRICS[column][0]} | {values.mean():+.2f} [{interval.low:+.2f}, {interval.high:+.2f}] "
                     f"| {int((values < 0).sum())} of {len(values)} | {pooled:+.2f} |")
    return lines, per_sequence


def disagreements(results: pd.DataFrame, per_sequence: pd.DataFrame, scratch: Path) -> list[str]:
    """Section 3: the sequences where AMOTA's and PKL's orders disagree most, with a mosaic each."""
    lines = []
    worst = per_sequence.sort_values("3d_AMOTA").head(WORST)
    for _, row in worst.iterrows():
        group = results[(results.scenario == row.scenario) & (results.seed == row.seed)].set_index("tracker")
        pairs = [(a, b) for a in group.index for b in group.index
                 if group.at[a, "3d_AMOTA"] > group.at[b, "3d_AMOTA"] and group.at[a, "3d_PKL"] > group.at[b, "3d_PKL"]]
        better, worse = max(pairs, key=lambda p: (group.at[p[0], "3d_PKL"] - group.at[p[1], "3d_PKL"]))
        run = scratch / f"{row.scenario}-seed{row.seed}"
        subprocess.run(["simrig", "run", row.scenario, "--seed", str(row.seed), "--tracker", better, "--out",
                        str(run), "--quiet"], check=True, capture_output=True)
        plan = pd.read_parquet(run / "scores" / better / "plan.parquet")
        frame = int(plan.sort_values("divergence", ascending=False).frame.iloc[0])
        picture = OUT / f"{row.scenario}-seed{row.seed}-{better}-frame{frame}.png"
        subprocess.run(["simrig", "render", str(run / "dataset"), "--frame", str(frame), "--tracks",
                        str(run / "tracks" / better), "--out", str(picture)], check=True, capture_output=True)
        at = plan[plan.frame == frame].iloc[0]
        lines += [f"### {row.scenario}, seed {row.seed}: ρ(AMOTA, −PKL) = {row['3d_AMOTA']:+.2f}", "",
                  f"`{better}` has the higher AMOTA ({group.at[better, '3d_AMOTA']:.3f} against "
                  f"{group.at[worse, '3d_AMOTA']:.3f}) but the higher PKL ({group.at[better, '3d_PKL']:.3f} against "
                  f"{group.at[worse, '3d_PKL']:.3f}); its plan diverges most at frame {frame}: "
                  f"{at.acceleration_tracks:+.2f} m/s² on its tracks against {at.acceleration_truth:+.2f} on the "
                  f"ground truth (lane decision {int(at.lane_change_tracks):+d} against {int(at.lane_change_truth):+d}"
                  f"{', an ' + at.hazard + ' hazard' if at.hazard else ''}).", "",
                  f"![{row.scenario} seed {row.seed}, {better}, frame {frame}]({picture.name})", "",
                  f"*`simrig run {row.scenario} --seed {row.seed} --tracker {better}` then `simrig render DATASET "
                  f"--frame {frame} --tracks TRACKS`.*", ""]
    return lines


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("bench", type=Path, help="the planner bench folder (results.parquet)")
    parser.add_argument("--scratch", type=Path, default=Path("runs/planner-report"),
                        help="where the disagreement scenes are run again for their mosaics")
    args = parser.parse_args()
    results = pd.read_parquet(args.bench / "results.parquet")
    trackers = list(dict.fromkeys(results["tracker"]))
    sequences = results.groupby(["scenario", "seed"]).ngroups
    agreement, per_sequence = rank_agreement(results)
    lines = [
        "# Planner-aware scores next to HOTA and AMOTA", "",
        f"Produced by `{command_line()}` on the results of `simrig bench planner` ({machine()}): "
        f"{len(trackers)} 3D reference trackers on {results.scenario.nunique()} surround scenarios × "
        f"{results.seed.nunique()} fresh seeds ({sequences} sequences). Definitions: docs/planner.md.", "",
        "## Every tracker against global_hungarian, paired per sequence", "",
        f"Mean over the sequences; under it the paired difference to `{trackers[0]}` with its BCa 95% interval "
        "(`n.s.`: the interval holds 0). HOTA and AMOTA: higher is better; the planner-aware scores: lower.", "",
        *paired_table(results, trackers), "",
        "## Do the rankings agree?", "",
        "Spearman's ρ between the order of the trackers by a classic metric and their order by PKL (lower PKL "
        "ranked better), per sequence; 1: the same order, −1: reversed.", "",
        *agreement, "",
        "## Where they disagree most", "",
        *disagreements(results, per_sequence, args.scratch),
    ]
    publish(lines, OUT / "index.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
