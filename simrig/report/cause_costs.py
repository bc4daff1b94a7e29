"""The bench report's "What each cause costs" section: per tracker, the mean Shapley share of each cause
group in the gap between a perfect sensor and the actual one (``simrig bench --explain``'s ``explain.parquet``)."""

from __future__ import annotations

from pathlib import Path

import pyarrow.parquet as pq

from ..explain.bench import EXPLAIN_TABLE
from .markdown import table

HEADLINE_METRIC = "HOTA"
"""The metric each tracker's one-line summary names (2D HOTA: every tracker has it)."""


def cause_costs_section(folder: Path, suite: str) -> list[str]:
    """The section's Markdown lines; a pointer to ``--explain`` when the bench folder has no explanation."""
    lines = ["## What each cause costs", ""]
    path = folder / EXPLAIN_TABLE
    if not path.is_file():
        return lines + [f"Not computed for this bench: `simrig bench {suite} --explain` re-simulates each base cell's "
                        "sensor without each cause group and splits every tracker's gap to a perfect sensor among "
                        "them (`simrig explain`).", ""]
    frame = pq.read_table(path).to_pandas()
    cells = frame.drop_duplicates(["cell"])
    modes = sorted(set(frame["mode"]))
    lines += [f"Each tracker on each scenario at its own settings ({len(cells)} cells: scenarios × seeds), its sensor "
              "re-simulated without cause groups (traffic and every other random draw kept) and the gap between the "
              "perfect sensor's score and the actual one split among the groups by Shapley value "
              f"({' and '.join(modes)}; `simrig explain`). A share is how much removing the group moves the metric "
              "toward the perfect sensor (negative for counts: removing it lowers them); shares add up to perfect − "
              "actual. Means over cells.", ""]
    summaries = []
    for tracker in dict.fromkeys(frame["tracker"]):
        mine = frame[frame["tracker"] == tracker]
        metrics = list(dict.fromkeys(mine["metric"]))
        causes = list(dict.fromkeys(mine["cause"]))
        means = mine.groupby(["metric", "cause"])["share"].mean()
        ends = mine.drop_duplicates(["cell", "metric"]).groupby("metric")[["actual", "perfect"]].mean()
        rows = [["actual", *(ends.loc[m, "actual"] for m in metrics)],
                ["perfect sensor", *(ends.loc[m, "perfect"] for m in metrics)]]
        rows += [[cause, *(_signed(means.get((m, cause))) for m in metrics)] for cause in causes]
        lines += [f"### {tracker}", ""] + table(["", *metrics], rows) + [""]
        if HEADLINE_METRIC in metrics:
            shares = {cause: means.get((HEADLINE_METRIC, cause)) for cause in causes}
            worst = max(shares, key=lambda cause: shares[cause])
            gap = ends.loc[HEADLINE_METRIC, "perfect"] - ends.loc[HEADLINE_METRIC, "actual"]
            summaries.append(f"`{tracker}` loses most of its {HEADLINE_METRIC} to {worst.replace('_', ' ')} "
                             f"({shares[worst]:+.3f} of a {gap:.3f} gap)")
    if summaries:
        lines[2:2] = ["In one line each: " + "; ".join(summaries) + ".", ""]
    return lines


def _signed(value) -> str:
    return "-" if value is None else f"{value:+.3f}"
