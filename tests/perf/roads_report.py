"""Report: every reference tracker on the road layouts.

Run explicitly, on the results of the ``roads`` suite and of the ``planner`` suite (for the highway at the same
fresh seeds)::

    simrig bench roads --out runs/bench/roads
    simrig bench planner --out runs/bench/planner
    python tests/perf/roads_report.py runs/bench/roads --highway runs/bench/planner

1. Per road, every tracker of its rig: the mean over the ten seeds of HOTA (2D; for 3D trackers their tracks
   projected), AMOTA, ID switches and the planner's PKL (3D trackers), or HOTA, IDF1 and ID switches (2D trackers
   on the stereo pair), with the paired difference to the rig's first tracker (``global_hungarian``, ``sort``) and
   its BCa 95% interval (:func:`simrig.report.paired.paired_difference`; ``n.s.``: the interval holds 0).
2. Where each 3D tracker loses most: its mean AMOTA and ID switches per sequence on each road minus its means on
   ``highway_surround6`` (same seeds, unpaired: different scenes), with bootstrap 95% intervals.
   And relative: each tracker's paired difference to ``global_hungarian`` on a road minus the same on the highway.
3. Why, for the worst cell (the largest change in ID switches against the highway): ``simrig run`` of that
   tracker on its seed with the most switches on that road, then ``simrig explain`` of its AMOTA and ID switches:
   each cause's share.

Writes ``reports/roads/index.md``.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from published import command_line, machine, publish
from scipy.stats import bootstrap

from simrig.report.paired import paired_difference

OUT = Path(__file__).resolve().parents[2] / "reports" / "roads" / "index.md"
METRICS_3D = {"2d_HOTA": ("HOTA", 3), "3d_AMOTA": ("AMOTA", 3), "3d_IDS": ("IDS", 1), "3d_PKL": ("PKL", 3)}
METRICS_2D = {"2d_HOTA": ("HOTA", 3), "2d_IDF1": ("IDF1", 3), "2d_IDSW": ("IDSW", 1)}
HIGHWAY = "highway_surround6"


def paired_rows(results: pd.DataFrame, scenario: str, metrics: dict) -> list[str]:
    """Section 1 for one road: means and paired differences to the first tracker run on it."""
    rows = results[results.scenario == scenario]
    trackers = list(dict.fromkeys(rows.tracker))
    table = rows.pivot_table(index="seed", columns="tracker", values=list(metrics))
    lines = [f"| tracker | {' | '.join(name for name, _ in metrics.values())} |", "|---|" + "---|" * len(metrics)]
    for tracker in trackers:
        cells = []
        for column, (_, digits) in metrics.items():
            mean = table[(column, tracker)].mean()
            if tracker == trackers[0]:
                cells.append(f"{mean:.{digits}f}")
            else:
                diff = paired_difference(table[(column, tracker)].to_numpy(), table[(column, trackers[0])].to_numpy())
                cells.append(f"{mean:.{digits}f}<br>{diff.text(digits=digits)}")
        lines.append(f"| {tracker} | {' | '.join(cells)} |")
    return lines


def road_table(results: pd.DataFrame, first: str, samples, digits: int) -> tuple[list[str], pd.DataFrame]:
    """A table of trackers × roads: ``samples(tracker, scenario)`` gives a tracker's values per seed on a scenario;
    each cell is the mean on the road minus the mean on the highway with a bootstrap 95% interval (percentile,
    unpaired: different scenes; ``n.s.``: it holds 0), under the heading ``first`` for the highway's own mean."""
    roads = [s for s in dict.fromkeys(results.scenario) if not s.endswith("stereo")]
    trackers = [tracker for tracker in dict.fromkeys(results[results.scenario.isin(roads)].tracker)
                if samples(tracker, HIGHWAY) is not None]
    lines = [f"| tracker | {first} | " + " | ".join(roads) + " |", "|---|---|" + "---|" * len(roads)]
    cells = []
    for tracker in trackers:
        ref = samples(tracker, HIGHWAY)
        row = [f"| {tracker} | {ref.mean():{'+' if first.startswith('on ') else ''}.{digits}f} |"]
        for road in roads:
            values = samples(tracker, road)
            interval = bootstrap((values, ref), lambda a, b, axis=-1: a.mean(axis=axis) - b.mean(axis=axis),
                                 n_resamples=4000, random_state=np.random.default_rng(0), method="percentile")
            change, (low, high) = values.mean() - ref.mean(), interval.confidence_interval
            held = " n.s." if low <= 0.0 <= high else ""
            row.append(f" {change:+.{digits}f} [{low:+.{digits}f}, {high:+.{digits}f}]{held} |")
            cells.append({"tracker": tracker, "road": road, "change": change, "low": low, "high": high})
        lines.append("".join(row))
    return lines, pd.DataFrame(cells)


def own_values(results: pd.DataFrame, highway: pd.DataFrame, column: str):
    """Section 2: a tracker's values of ``column`` per seed (the highway's from the ``planner`` bench)."""
    def samples(tracker: str, scenario: str) -> np.ndarray:
        frame = highway if scenario == HIGHWAY else results
        return frame[(frame.scenario == scenario) & (frame.tracker == tracker)][column].to_numpy(dtype=float)
    return samples


def against_baseline(results: pd.DataFrame, highway: pd.DataFrame, column: str, base: str):
    """Section 2, relative: a tracker's paired difference to ``base`` per seed (None for ``base`` itself)."""
    def samples(tracker: str, scenario: str) -> np.ndarray | None:
        if tracker == base:
            return None
        frame = highway if scenario == HIGHWAY else results
        table = frame[frame.scenario == scenario].pivot_table(index="seed", columns="tracker", values=column)
        return (table[tracker] - table[base]).to_numpy(dtype=float)
    return samples


def explain_worst(results: pd.DataFrame, worst: pd.Series, scratch: Path) -> list[str]:
    """Section 3: run and explain the worst cell's worst seed."""
    rows = results[(results.scenario == worst.road) & (results.tracker == worst.tracker)]
    seed = int(rows.loc[rows["3d_IDS"].idxmax(), "seed"])
    amota = float(rows.loc[rows["3d_IDS"].idxmax(), "3d_AMOTA"])
    folder = scratch / f"{worst.road}-{worst.tracker}-seed{seed}"
    run = ["simrig", "run", worst.road, "--seed", str(seed), "--tracker", worst.tracker, "--out", str(folder),
           "--overwrite", "--quiet"]
    explain = ["simrig", "explain", str(folder), "--metric", "AMOTA,IDS", "--quiet"]
    subprocess.run(run, check=True, capture_output=True)
    text = subprocess.run(explain, check=True, capture_output=True, text=True).stdout
    return [f"The cell that fares worst against its own highway: `{worst.tracker}` on `{worst.road}`, "
            f"{worst.change:+.1f} ID switches per sequence against the highway [{worst.low:+.1f}, {worst.high:+.1f}]. "
            "Its seed with the most switches there is "
            f"{seed} ({int(rows['3d_IDS'].max())} switches, AMOTA {amota:.3f}). "
            "Reproduce:", "",
            "```bash", " ".join(run), " ".join(explain), "```", "", "```text", text.rstrip(), "```"]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("bench", type=Path, help="the roads bench folder (results.parquet)")
    parser.add_argument("--highway", type=Path, required=True, help="a bench folder with highway_surround6 at the "
                        "same seeds and 3D trackers (the planner suite)")
    parser.add_argument("--scratch", type=Path, default=Path("runs/roads-report"))
    args = parser.parse_args()
    results = pd.read_parquet(args.bench / "results.parquet")
    highway = pd.read_parquet(args.highway / "results.parquet")
    seeds = sorted(results.seed.unique().tolist())
    lines = ["# Every reference tracker on the road layouts", "",
             f"Produced by `{command_line()}` on the results of `simrig bench roads` ({machine()}): seeds "
             f"{seeds[0]}–{seeds[-1]}, which no tracker was tuned on; 200 frames each. Scenario descriptions: "
             "docs/scenarios.md, road layouts.", ""]
    for scenario in dict.fromkeys(results.scenario):
        stereo = scenario.endswith("stereo")
        lines += [f"## {scenario}", "",
                  f"Mean over the seeds; under it the paired difference to `{'sort' if stereo else 'global_hungarian'}`"
                  " per seed with its BCa 95% interval (`n.s.`: it holds 0). Higher is better except IDS, IDSW "
                  "and PKL.", "", *paired_rows(results, scenario, METRICS_2D if stereo else METRICS_3D), ""]
    amota, _ = road_table(results, HIGHWAY, own_values(results, highway, "3d_AMOTA"), 3)
    switches, cells = road_table(results, HIGHWAY, own_values(results, highway, "3d_IDS"), 1)
    relative_amota, _ = road_table(results, f"on {HIGHWAY}",
                                   against_baseline(results, highway, "3d_AMOTA", "global_hungarian"), 3)
    relative_switches, _ = road_table(results, f"on {HIGHWAY}",
                                      against_baseline(results, highway, "3d_IDS", "global_hungarian"), 1)
    worst = cells.loc[cells.change.idxmax()]
    lines += ["## Where each 3D tracker loses most", "",
              f"Each road minus `{HIGHWAY}` (the `planner` bench, the same seeds: its column is the highway's own "
              "mean), with a bootstrap 95% interval (percentile, unpaired: different scenes; `n.s.`: it holds 0). "
              "The roads carry 16–30 vehicles against the highway's 40.", "", "AMOTA:", "", *amota, "",
              "ID switches per sequence:", "", *switches, "",
              "Against `global_hungarian`: a tracker's paired difference to it per seed on each road, minus the "
              "same on the highway (its first column). Positive: on that road the tracker's AMOTA lead grows, or its "
              "extra switches grow.", "", "AMOTA:", "", *relative_amota, "", "ID switches per sequence:", "",
              *relative_switches, "",
              "## Why: the worst cell explained", "", *explain_worst(results, worst, args.scratch), ""]
    publish(lines, OUT)
    return 0


if __name__ == "__main__":
    sys.exit(main())
