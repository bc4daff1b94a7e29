"""The report section of a closed-loop bench that says which open-loop metric predicts driving
(:mod:`simrig.report.metric_validity`), with its figure: every metric against every outcome."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..dataset.outputs import save_figure
from ..markdown import table
from .load import BenchResults
from .metric_validity import (
    METRICS,
    OUTCOMES,
    REPLICATES,
    TTC_CAP_S,
    Correlations,
    TooFewCells,
    correlate,
)

FIGURE = "metric-validity.png"
"""The figure's file name in the report folder."""


def metric_validity_section(bench: BenchResults, out: Path) -> list[str]:
    """The section's markdown lines (and ``out/FIGURE``); a line saying why when the bench cannot tell."""
    lines = ["## Which metric predicts driving", ""]
    try:
        found = correlate(bench.results)
    except TooFewCells as error:
        return lines + [f"Not computed: {error}.", ""]
    world = ("the world of the cell's ground-truth drive, the log, where the tracker ran open loop"
             if bench.description["suite_settings"].get("scores_on") == "reference" else
             "the world each tracker drove itself (so a drive that went wrong is also scored on what followed)")
    lines += [
        f"A configuration is a tracker at one detector setting on one scenario ({_counts(found)}). Its open-loop "
        f"metric (scored on {world}) and its closed-loop outcome are means over the {len(found.seeds)} seeds; the "
        f"least time to collision is capped at {TTC_CAP_S:g} s. Spearman's ρ and Kendall's τ-b over the "
        "configurations of each scenario, then the mean over scenarios; every metric and outcome is oriented so "
        "that higher is better (a positive correlation is agreement: e.g. PKL and collisions enter negated). "
        f"Brackets: 95 % BCa bootstrap intervals over seeds ({REPLICATES} replicates, the configurations paired); "
        "`†`: 90 % or more of the bootstrap replicates lay on one side of the estimate (a resample repeats seeds, so "
        "its means average fewer of them), and the interval is the jackknife's (each seed left out once); `n.s.`: "
        "the interval contains 0. Method: `simrig.report.metric_validity`.", "",
        "`–`: the metric or the outcome is the same in every configuration (e.g. no drive collided), so it orders "
        "nothing.", "",
        "Spearman's ρ, mean over scenarios:", "", *_matrix(found, "spearman", "all"), "",
        "Kendall's τ-b, mean over scenarios:", "", *_matrix(found, "kendall", "all"), "",
        *_verdicts(found), "",
        "Spearman's ρ per scenario (point estimates; `*`: interval excludes 0; `–`: the same value in every "
        "configuration, e.g. no drive collided):", "",
        *_per_scenario(found), "",
    ]
    figure = _plot(found, out / FIGURE)
    lines += [f"![every metric against every outcome]({figure.name})", "",
              "*Each point a configuration (mean over seeds), one colour per scenario, as stored (not oriented): "
              "open-loop metric across, closed-loop outcome up.*", ""]
    return lines


def _counts(found: Correlations) -> str:
    return ", ".join(f"{count} on {scenario}" for scenario, count in found.configurations.items())


def _cell(found: Correlations, kind: str, scenario: str, metric: str, outcome: str) -> str:
    point = getattr(found, kind)[(scenario, metric, outcome)]
    if not np.isfinite(point):  # the metric or the outcome the same in every configuration (no drive collided)
        return "–"
    low, high = found.interval(kind, scenario, metric, outcome)
    flag = " n.s." if not low > 0 and not high < 0 else ""
    mark = "†" if found.uses_jackknife(kind, scenario, metric, outcome) else ""
    return f"{point:+.2f} [{low:+.2f}, {high:+.2f}]{mark}{flag}"


def _matrix(found: Correlations, kind: str, scenario: str) -> list[str]:
    rows = [[metric, *(_cell(found, kind, scenario, metric, outcome) for outcome, _, _ in OUTCOMES)]
            for metric, _, _ in METRICS]
    return table(["metric", *(outcome for outcome, _, _ in OUTCOMES)], rows)


def _verdicts(found: Correlations) -> list[str]:
    """Per outcome: the metric with the highest mean ρ, its lead over the runner-up and over AMOTA (paired)."""
    lines = ["Best predictor of each outcome (highest mean ρ), and its lead, paired on the same replicates:", ""]
    for outcome, _, _ in OUTCOMES:
        ranked = sorted((metric for metric, _, _ in METRICS if np.isfinite(found.spearman[("all", metric, outcome)])),
                        key=lambda m: -found.spearman[("all", m, outcome)])
        if not ranked:
            lines.append(f"- **{outcome}**: the same in every configuration (e.g. no drive collided): nothing to "
                         "predict")
            continue
        best = ranked[0]
        text = f"- **{outcome}**: {best}, ρ {_cell(found, 'spearman', 'all', best, outcome)}"
        for other in dict.fromkeys((*ranked[1:2], "AMOTA")):
            if other != best and other in ranked:
                point, low, high = found.difference("all", best, other, outcome)  # jackknife's where lopsided
                flag = " n.s." if low <= 0 <= high else ""
                text += f"; ahead of {other} by {point:+.2f} [{low:+.2f}, {high:+.2f}]{flag}"
        lines.append(text)
    return lines


def _per_scenario(found: Correlations) -> list[str]:
    header = ["metric"] + [f"{scenario}: {outcome}" for scenario in found.scenarios for outcome, _, _ in OUTCOMES]
    rows = []
    for metric, _, _ in METRICS:
        row = [metric]
        for scenario in found.scenarios:
            for outcome, _, _ in OUTCOMES:
                point = found.spearman[(scenario, metric, outcome)]
                if not np.isfinite(point):  # an outcome (or metric) the same in every configuration
                    row.append("–")
                    continue
                low, high = found.interval("spearman", scenario, metric, outcome)
                star = "*" if low > 0 or high < 0 else ""
                row.append(f"{point:+.2f}{star}")
        rows.append(row)
    return table(header, rows)


def _plot(found: Correlations, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(len(METRICS), len(OUTCOMES), figsize=(3.0 * len(OUTCOMES), 2.2 * len(METRICS)),
                                squeeze=False)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for row, (metric, metric_column, metric_sign) in enumerate(METRICS):
        for col, (outcome, outcome_column, outcome_sign) in enumerate(OUTCOMES):
            axis = axes[row][col]
            for index, scenario in enumerate(found.scenarios):
                means = found.means[scenario]
                axis.scatter(metric_sign * means[metric_column], outcome_sign * means[outcome_column], s=12,
                             color=colours[index % len(colours)], label=scenario)
            axis.set_title(f"{outcome} vs {metric}: ρ {found.spearman[('all', metric, outcome)]:+.2f}", fontsize=8)
            axis.tick_params(labelsize=7)
            axis.set_xlabel(metric, fontsize=8)
            axis.set_ylabel(outcome, fontsize=8)
    axes[0][0].legend(fontsize=7, loc="best")
    figure.tight_layout()
    save_figure(figure, path, dpi=80)
    plt.close(figure)
    return path
