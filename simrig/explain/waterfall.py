"""The waterfall plot of one metric: from the actual score, each cause group's share, to the perfect sensor."""

from __future__ import annotations

import textwrap
from pathlib import Path

from simrig.dataset.outputs import save_figure


def waterfall(document: dict, metric: str, path: Path) -> Path:
    """Draw ``metric`` of an ``explain.json`` document to ``path`` (PNG): a bar per cause group from the running
    total before it to the one after it (green: removing it improves the metric, red: it worsens it; whiskers
    the 95 % interval when sampled), the actual and perfect scores as full bars. Returns ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    entry = document["metrics"][metric]
    causes = document["causes"]
    actual = entry["actual"] if entry["actual"] is not None else float("nan")
    shares = [entry["shares"][c] or 0.0 for c in causes]
    errors = [entry.get("ci95", {}).get(c) or 0.0 for c in causes]
    higher_is_better = (entry["perfect"] or 0.0) >= actual
    figure, axes = plt.subplots(figsize=(1.2 + 0.7 * (len(causes) + 2), 4.0), constrained_layout=True)
    labels = ["actual", *causes, "perfect"]
    axes.bar(0, actual, color="0.55")
    total = actual
    for i, (share, error) in enumerate(zip(shares, errors, strict=True), start=1):
        good = (share >= 0) == higher_is_better
        axes.bar(i, share, bottom=total, color="tab:green" if good else "tab:red",
                 yerr=error if error else None, capsize=3)
        total += share
    axes.bar(len(labels) - 1, entry["perfect"] if entry["perfect"] is not None else float("nan"), color="0.25")
    axes.set_xticks(range(len(labels)), labels, rotation=45, ha="right")
    axes.set_ylabel(metric)
    mode = "exact" if document["mode"] == "exact" else f"sampled, {document['samples']} permutations"
    axes.set_title(f"{metric}: {document['tracker']} on {document['scenario']} seed {document['seed']} ({mode})",
                   fontsize=9)
    # the command that made the plot, wrapped to the figure's width (about 20 characters an inch at 6 pt) and
    # laid out below the tick labels (a plain figure.text was cut at the right edge and overlapped them)
    width = int(figure.get_figwidth() * 20)
    figure.supxlabel(textwrap.fill(document["command"], width, break_on_hyphens=False), fontsize=6, color="0.4",
                     x=0.01, ha="left")
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        save_figure(figure, path, dpi=110)
    finally:
        plt.close(figure)
    return path
