"""Robustness curves: each metric against each swept parameter, one line per tracker, the seeds as a band.

For a parameter p, the points used are its sweep's and the base points of the scenarios it applies to (at
their own value of p). At each value: per seed, the mean over those scenarios; the line is the mean over
seeds and the band spans the lowest to the highest seed.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

from ..benchmark.results import PARAMETER_PREFIX  # noqa: E402
from ..dataset.outputs import save_figure  # noqa: E402
from ..markdown import table  # noqa: E402
from .groups import Group  # noqa: E402
from .load import BenchResults  # noqa: E402


def _sweep_points(bench: BenchResults, parameter: str) -> pd.DataFrame:
    """The points on ``parameter``'s curves, one per (cell, tracker), with ``x`` = the cell's value of it."""
    column = PARAMETER_PREFIX + parameter
    frame = bench.results
    frame = frame[frame["sweep"].isin([parameter, ""]) & frame[column].notna()]
    return bench.unique_cells(frame).assign(x=lambda f: f[column])


def curve(points: pd.DataFrame, metric: str) -> pd.DataFrame:
    """Per (tracker, x): ``mean``, ``low`` and ``high`` over seeds of the per-seed mean over scenarios, and
    ``scenarios``: how many scenarios are behind each seed's mean."""
    per_seed = points.groupby(["tracker", "x", "seed"], sort=False).agg(
        value=(metric, "mean"), scenarios=("scenario", "nunique"))
    lines = per_seed.groupby(["tracker", "x"], sort=False).agg(
        mean=("value", "mean"), low=("value", "min"), high=("value", "max"),
        scenarios=("scenarios", "min")).reset_index()
    order = {tracker: index for index, tracker in enumerate(dict.fromkeys(points["tracker"]))}
    return lines.sort_values(["tracker", "x"], key=lambda c: c.map(order) if c.name == "tracker" else c,
                             kind="stable")


def colours(trackers: list[str]) -> dict[str, tuple]:
    """A fixed colour per tracker, in suite order."""
    palette = plt.cm.tab10.colors
    return {tracker: palette[index % len(palette)] for index, tracker in enumerate(trackers)}


def plot_sweep(bench: BenchResults, parameter: str, groups: list[Group], out: Path) -> Path | None:
    """One figure for ``parameter``: a row per group, a column per curve metric. None if it has no points."""
    points = _sweep_points(bench, parameter)
    groups = [group for group in groups if (points["scored"] == group.key).any()]
    if not groups:
        return None
    palette = colours(list(dict.fromkeys(bench.results["tracker"])))
    columns = max(len(group.curve_metrics) for group in groups)
    figure, axes = plt.subplots(len(groups), columns, figsize=(4.2 * columns, 3.4 * len(groups)), squeeze=False,
                                dpi=100)
    for row, group in enumerate(groups):
        mine = points[points["scored"] == group.key]
        for col, (metric, name) in enumerate(group.curve_metrics):
            axis = axes[row][col]
            for tracker, line in curve(mine, metric).groupby("tracker", sort=False):
                axis.plot(line["x"], line["mean"], marker="o", markersize=3, color=palette[tracker], label=tracker)
                axis.fill_between(line["x"], line["low"], line["high"], color=palette[tracker], alpha=0.18,
                                  linewidth=0)
            where = {"3d": "", "2d": " (2D trackers)"}.get(group.key, f" (camera {group.key})")
            axis.set_title(f"{name}{where}", fontsize=10)
            axis.set_xlabel(parameter)
            axis.grid(alpha=0.3)
        axes[row][0].legend(fontsize=7, loc="best")
        for col in range(len(group.curve_metrics), columns):
            axes[row][col].set_visible(False)
    figure.suptitle(f"{bench.suite}: metrics against {parameter} (line: mean over seeds of the mean over "
                    "scenarios; band: lowest to highest seed)", fontsize=10)
    figure.tight_layout()
    save_figure(figure, out)
    plt.close(figure)
    return out


def plot_sweep_by_scenario(bench: BenchResults, parameter: str, out: Path) -> Path | None:
    """HOTA against ``parameter``, a panel per scenario: where the mean curve comes from. Camera-scored
    trackers are dashed."""
    points = _sweep_points(bench, parameter)
    scenarios = list(dict.fromkeys(points["scenario"]))
    if not scenarios:
        return None
    palette = colours(list(dict.fromkeys(bench.results["tracker"])))
    columns = min(4, len(scenarios))
    rows = -(-len(scenarios) // columns)
    figure, axes = plt.subplots(rows, columns, figsize=(3.6 * columns, 2.9 * rows), squeeze=False, dpi=100)
    for index, scenario in enumerate(scenarios):
        axis = axes[index // columns][index % columns]
        mine = points[points["scenario"] == scenario]
        for tracker, line in curve(mine, "2d_HOTA").groupby("tracker", sort=False):
            dashed = (~mine.loc[mine["tracker"] == tracker, "scored"].isin(("3d", "2d"))).any()
            axis.plot(line["x"], line["mean"], marker="o", markersize=2.5, color=palette[tracker],
                      linestyle="--" if dashed else "-", label=tracker)
            axis.fill_between(line["x"], line["low"], line["high"], color=palette[tracker], alpha=0.15, linewidth=0)
        axis.set_title(scenario, fontsize=9)
        axis.grid(alpha=0.3)
        axis.tick_params(labelsize=7)
    for index in range(len(scenarios), rows * columns):
        axes[index // columns][index % columns].set_visible(False)
    handles, labels = axes[0][0].get_legend_handles_labels()
    figure.legend(handles, labels, loc="lower right", fontsize=7)
    figure.suptitle(f"{bench.suite}: HOTA against {parameter} per scenario (dashed: scored on one camera)",
                    fontsize=10)
    figure.tight_layout()
    save_figure(figure, out)
    plt.close(figure)
    return out


def curve_table(bench: BenchResults, parameter: str, group: Group, metric: str, name: str) -> list[str]:
    """The numbers behind one curve: rows trackers, columns values of ``parameter`` (mean over seeds)."""
    points = _sweep_points(bench, parameter)
    lines = curve(points[points["scored"] == group.key], metric)
    if lines.empty:
        return []
    values = sorted(set(lines["x"]))
    rows = []
    for tracker, line in lines.groupby("tracker", sort=False):
        by_x = dict(zip(line["x"], line["mean"], strict=True))
        rows.append([f"`{tracker}`"] + [by_x.get(x, float("nan")) for x in values])
    return table([f"{name} \\ {parameter}"] + [f"{x:g}" for x in values], rows)
