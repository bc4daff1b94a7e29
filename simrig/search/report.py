"""A search's tables and report: ``results.parquet`` (one row per evaluation), ``report.md`` and
``objective.png`` (the best objective so far over evaluations, optimiser against random sampling)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pyarrow as pa

from simrig.benchmark.results import PARAMETER_PREFIX
from simrig.dataset.outputs import save_figure, write_table_atomic, write_text_atomic
from simrig.markdown import table

from . import coverage
from .evaluate import Estimate
from .fragments import Evaluation
from .ranking import CONFIRM, fails
from .space import SearchSpace

PLOT = "objective.png"


def _names(space: SearchSpace) -> list[str]:
    return [name for dimension in space.config.dimensions for name in dimension.names]


def write_results(space: SearchSpace, evaluations: dict[str, list[Evaluation]], path: Path) -> None:
    """``results.parquet``: stream, index, every parameter, seeds, the objective's mean and confidence interval,
    the failure metric's mean, whether it failed, and the wall time."""
    objective = space.config.objective
    rows = []
    for stream, items in evaluations.items():
        for e in items:
            estimate = Estimate.of(e.values(objective.metric))
            failure = Estimate.of(e.values(objective.failure_metric)).mean if objective.failure else math.nan
            rows.append({"stream": stream, "index": e.index, "seeds": json.dumps(list(e.seeds)),
                         **{PARAMETER_PREFIX + n: _cell(e.candidate.get(n)) for n in _names(space)},
                         "objective": estimate.mean, "objective_low": estimate.low, "objective_high": estimate.high,
                         "failure_metric": failure, "failing": fails(space, e), "seconds": e.seconds})
    fields = [("stream", pa.string()), ("index", pa.int64()), ("seeds", pa.string())]
    fields += [(PARAMETER_PREFIX + n, pa.string()) for n in _names(space)]
    fields += [(n, pa.float64()) for n in ("objective", "objective_low", "objective_high", "failure_metric")]
    fields += [("failing", pa.bool_()), ("seconds", pa.float64())]
    write_table_atomic(pa.Table.from_pylist(rows, schema=pa.schema(fields)), path)


def _cell(value) -> str | None:
    """A parameter value as text (ranges, windows and choices of any type share one column type)."""
    return None if value is None else json.dumps(value)


def _best_so_far(space: SearchSpace, evaluations: list[Evaluation]) -> np.ndarray:
    """The best mean objective after each evaluation (NaN until the first finite one)."""
    values = np.array([Estimate.of(e.values(space.config.objective.metric)).mean for e in evaluations])
    better = np.fmax if space.config.objective.direction == "maximize" else np.fmin
    return better.accumulate(values) if len(values) else values


def _plot(space: SearchSpace, streams: dict[str, list[Evaluation]], path: Path, command: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axis = plt.subplots(figsize=(6.4, 3.6), dpi=100)
    for stream, items in streams.items():
        curve = _best_so_far(space, items)
        axis.step(np.arange(1, len(curve) + 1), curve, where="post", label=stream)
    axis.set_xlabel("evaluation")
    axis.set_ylabel(f"best {space.config.objective.metric} so far")
    axis.set_title(f"{space.config.name}, {space.tracker}", fontsize=10)
    axis.legend()
    figure.text(0.01, 0.01, command, fontsize=6, color="gray")
    figure.tight_layout(rect=(0, 0.04, 1, 1))
    save_figure(figure, path)
    plt.close(figure)


def write_report(space: SearchSpace, evaluations: dict[str, list[Evaluation]], first: dict[str, int | None],
                 path: Path, command: str, sampler: str, worst: Path | None) -> None:
    """``report.md`` with the objective over evaluations (a table and ``objective.png``), the first failing
    evaluation of each stream, the re-evaluated best candidates with confidence intervals, and the worst case."""
    config = space.config
    objective = config.objective
    streams = {s: items for s, items in evaluations.items() if s != CONFIRM}
    _plot(space, streams, path.with_name(PLOT), command)
    lines = [f"# Search {config.name}: {space.tracker} {space.params or ''}".rstrip(), "",
             f"Produced by `{command}`.", "",
             f"Objective: {objective.direction} `{objective.metric}` (mean over {config.seeds} seed(s) per "
             f"evaluation); budget {config.budget} evaluations per sampler."]
    if objective.failure is not None:
        failure = objective.failure
        relation = f">= {failure.at_least}" if failure.at_least is not None else f"<= {failure.at_most}"
        lines.append(f"A failing case: mean `{objective.failure_metric}` {relation}.")
    lines += ["", f"## Best objective so far ({sampler} against random sampling at the same budget)", "",
              f"![best objective so far]({PLOT})", ""]
    curves = {s: _best_so_far(space, items) for s, items in streams.items()}
    marks = sorted({n for n in (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, config.budget) if n <= config.budget})
    lines += table(["evaluations", *curves], [[str(n), *(_shown(c[n - 1]) if n <= len(c) else "(stopped)"
                                                         for c in curves.values())] for n in marks], first_left=False)
    if objective.failure is not None:
        lines += ["", *table(["sampler", "first failing evaluation", "failing evaluations"],
                             [[s, str(first.get(s) or "none"), f"{sum(fails(space, e) for e in items)} of {len(items)}"]
                              for s, items in streams.items()])]
    names = _names(space)
    lines += ["", f"## The best candidates of {sampler}, re-evaluated on {config.confirm_seeds} fresh seeds", "",
              f"Ranked by their {objective.metric} during the search (on its seeds); the fresh seeds' values below "
              "may order them differently.", ""]
    rows = []
    for rank, e in enumerate(evaluations.get(CONFIRM, []), start=1):
        estimate = Estimate.of(e.values(objective.metric))
        rows.append([str(rank), *(_cell(e.candidate.get(n)) or "" for n in names),
                     f"{_shown(estimate.mean)} [{_shown(estimate.low)}, {_shown(estimate.high)}]"])
    lines += table(["rank", *(f"`{n}`" for n in names), f"{objective.metric} (95% CI)"], rows,
                   first_left=False, align=["---:", *["---"] * (len(names) + 1)])
    lines += ["", "## Coverage: evaluations per bin of each dimension", "",
              "A 0 is a part of the space this search never tried.", ""]
    for dimension in config.dimensions:
        for name in dimension.names:
            labels = [label for label, _ in coverage.bins(dimension, name)]
            lines += table([f"`{name}`", *labels],
                           [[stream, *(str(n) for n in coverage.counts(dimension, name,
                                                                       [e.candidate.get(name) for e in items]))]
                            for stream, items in streams.items()])
            lines.append("")
    lines += ["## The worst case, shrunk", ""]
    if worst is None:
        lines.append("No evaluation failed: nothing to shrink." if objective.failure is not None
                     else "The space defines no failure (objective.failure): nothing to shrink.")
    else:
        log = json.loads((worst / "shrink.json").read_text(encoding="utf-8"))
        before, after = log["before"], log["after"]
        lines += [f"From evaluation {log['source']['index'] + 1} of {log['source']['stream']}, seed {log['seed']}: "
                  f"{before['actors']} → {after['actors']} actors, {before['frames']} → {after['frames']} frames, "
                  f"{before['perturbations']} → {after['perturbations']} perturbations in "
                  f"{log['evaluations']} shrinking evaluations.", "",
                  f"- replay: `simrig replay {worst / 'worst.toml'}`",
                  f"- regression test: `pytest {worst / 'test_worst_case.py'}`",
                  "- kept reductions: " + ("; ".join(log["kept"]) or "none")]
    write_text_atomic(path, "\n".join(lines) + "\n")


def _shown(value: float) -> str:
    """A metric in a table cell: 4 significant digits, a dash when undefined."""
    return "—" if value is None or math.isnan(value) else f"{value:.4g}"
