"""The bench report's "What each cause costs" section: per tracker, the mean Shapley share of each cause
group in the gap between a perfect sensor and the actual one (``simrig bench --explain``'s ``explain.parquet``)."""

from __future__ import annotations

from pathlib import Path

import pyarrow.parquet as pq

from ..explain.bench import EXPLAIN_TABLE, not_explained
from ..markdown import table

HEADLINE_METRIC = "HOTA"
"""The metric each tracker's one-line summary names (2D HOTA: every tracker has it)."""


def cause_costs_section(folder: Path, suite: str, order: list[str] | None = None) -> list[str]:
    """The section's Markdown lines, trackers in ``order`` (the suite's; others after them, as found); a
    pointer to ``--explain`` when the bench folder has no explanation."""
    lines = ["## What each cause costs", ""]
    path = folder / EXPLAIN_TABLE
    if not path.is_file():
        return lines + [f"Not computed for this bench: `simrig bench {suite} --explain` re-simulates each base cell's "
                        "sensor without each cause group and splits every tracker's gap to a perfect sensor among "
                        "them (`simrig explain`).", ""]
    explained = pq.read_table(path)
    command = (explained.schema.metadata or {}).get(b"command", b"").decode()
    left_out = [f"- `{entry['tracker']}` on cell `{entry['cell']}`: {entry['reason']}"
                for entry in not_explained(explained.schema)]
    if left_out:
        left_out = ["Not explained (left out of the means below):", "", *left_out, ""]
    if explained.num_rows == 0:
        return lines + (left_out or ["The explanation holds no cell.", ""]) + ([f"Produced by `{command}`.", ""]
                                                                              if command else [])
    frame = explained.to_pandas()
    # a scheduled perturbation's group is one window of one scenario (occlude#1): the bench sums each cell's
    # windows of a kind (Shapley values add up) and shows the kind
    frame["cause"] = frame["cause"].str.replace(r"#\d+$", " (scheduled)", regex=True)
    frame = frame.groupby(["tracker", "cell", "metric", "cause"], sort=False, as_index=False).agg(
        scenario=("scenario", "first"), seed=("seed", "first"), share=("share", "sum"),
        actual=("actual", "first"), perfect=("perfect", "first"), mode=("mode", "first"))
    cells = frame.drop_duplicates(["cell"])
    modes = sorted(set(frame["mode"]))
    seeds = ", ".join(str(seed) for seed in sorted(set(frame["seed"])))
    scenarios = frame["scenario"].nunique()
    lines += [f"Each tracker on each scenario at its own settings ({_count(len(cells), 'cell')}: "
              f"{_count(scenarios, 'scenario')} × seed{'s' if ',' in seeds else ''} {seeds}), its sensor "
              "re-simulated without cause groups (traffic and every other random draw kept) and the gap between the "
              "perfect sensor's score and the actual one split among the groups by Shapley value "
              f"({' and '.join(modes)}; `simrig explain`). A share is how much removing the group moves the metric "
              "toward the perfect sensor (negative for counts: removing it lowers them); shares add up to perfect − "
              "actual. Means over the cells each tracker ran on; a group absent from a cell (no clutter configured, "
              "no scheduled window of that kind) counts 0 there, so the mean shares add up to the mean gap. "
              "Scheduled perturbations are summed per kind.", ""]
    if command:
        lines += [f"Produced by `{command}`.", ""]
    lines += left_out
    summaries = []
    found = list(dict.fromkeys(frame["tracker"]))
    rank = {name: i for i, name in enumerate(order or [])}
    for tracker in sorted(found, key=lambda name: (rank.get(name, len(rank)), found.index(name))):
        mine = frame[frame["tracker"] == tracker]
        metrics = list(dict.fromkeys(mine["metric"]))
        causes = list(dict.fromkeys(mine["cause"]))
        ran = mine["cell"].nunique()
        means = mine.groupby(["metric", "cause"])["share"].sum() / ran
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


def _count(number: int, noun: str) -> str:
    return f"{number} {noun}{'' if number == 1 else 's'}"


def _signed(value) -> str:
    return "-" if value is None else f"{value:+.3f}"
