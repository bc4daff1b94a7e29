"""What each cause costs every tracker of a bench: the Shapley shares (:mod:`.api`) on each base cell (every
scenario at its own settings, every seed) of a finished bench folder, one row per (cell, tracker, metric,
cause) in ``OUT/explain.parquet`` — what ``simrig report`` turns into its "What each cause costs" section."""

from __future__ import annotations

import json
import shlex
from itertools import groupby
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from simrig.dataset import Dataset
from simrig.dataset.outputs import atomic_file
from simrig.pipeline.guard import FRAME_TIME_LIMIT_S
from simrig.reading import read_json
from simrig.scenarios.schema import scenario_from_record
from simrig.sensor.groups import present_groups

from ..benchmark.api import BENCH_FILE
from ..benchmark.results import RESULTS
from ..benchmark.suite import TrackerEntry
from .api import ExplainError, choose_metrics, failed_coalition, plan_game, run_tasks, settle, tracker_run
from .coalition import CoalitionTask, TrackerRun
from .shapley import coalition_order

EXPLAIN_TABLE = "explain.parquet"
EXPLAIN_CACHE = "explain-cache"
SCHEMA = pa.schema([
    pa.field("scenario", pa.string()), pa.field("seed", pa.int64()), pa.field("cell", pa.string()),
    pa.field("tracker", pa.string()), pa.field("metric", pa.string()), pa.field("cause", pa.string()),
    pa.field("share", pa.float64()), pa.field("ci95", pa.float64()), pa.field("actual", pa.float64()),
    pa.field("perfect", pa.float64()), pa.field("mode", pa.string()),
])
"""One row per (base cell, tracker, metric, cause): the cause's share of (perfect − actual); ``ci95`` the
half-width of its 95 % interval (null when exact)."""
NOT_EXPLAINED = "not_explained"
"""The table's metadata key listing (JSON) the (tracker, cell, reason) left out: a tracker that failed on the
cell in the bench, or on one of its counterfactuals (a timeout, an exception, a malformed return)."""


def not_explained(schema: pa.Schema) -> list[dict]:
    """The ``{tracker, cell, reason}`` entries the schema of an explanation table lists as left out (none for an
    older one)."""
    return json.loads((schema.metadata or {}).get(NOT_EXPLAINED.encode(), b"[]"))


def check_explain_seeds(seeds, known, of: str) -> None:
    """An :class:`ExplainError` naming every one of ``seeds`` that is not in ``known`` (the seeds of ``of``: a
    suite, checked before a bench runs, or a finished bench)."""
    unknown = sorted(set(seeds) - set(known))
    if unknown:
        raise ExplainError(f"--explain-seeds: {', '.join(map(str, unknown))} not a seed of {of} (its seeds: "
                           f"{', '.join(map(str, sorted(known)))})")


def _finished_bench(out: Path) -> dict:
    """``bench.json`` of the finished open-loop bench in ``out``; an :class:`ExplainError` saying why not
    otherwise."""
    try:
        description = read_json(out / BENCH_FILE, BENCH_FILE, ValueError)
    except (OSError, ValueError) as error:
        raise ExplainError(f"{out}: not a finished bench folder ({error})") from None
    if not description.get("complete") or not (out / RESULTS).is_file():
        raise ExplainError(f"{out}: the bench did not finish; run '{description.get('command')}' again first")
    if description["suite_settings"].get("closed_loop"):
        raise ExplainError(f"{out}: the bench drove closed loop (closed_loop = true); explain reruns the sensor on a "
                           "fixed world, and a drive's world changes with every cause removed")
    return description


def _share_rows(games: list[tuple], outcomes: list[dict], skipped: list[tuple]) -> list[dict]:
    """The ``explain.parquet`` rows of every settled game (one per metric and cause); a game whose tracker failed
    on one of its counterfactuals is added to ``skipped`` instead (the others stay explained)."""
    rows = []
    for (scenario_name, seed, cell, tracker, chosen, plan), outcome in zip(games, outcomes, strict=True):
        failed = failed_coalition(outcome)
        if failed is not None:
            skipped.append((tracker, cell, failed))
            continue
        game = settle(plan, outcome)
        mode = "exact" if game.exact else "sampled"
        for metric, values in game.metrics(chosen).items():
            for cause, share in values["shares"].items():
                rows.append({"scenario": scenario_name, "seed": seed, "cell": cell, "tracker": tracker,
                             "metric": metric, "cause": cause, "share": share,
                             "ci95": values.get("ci95", {}).get(cause), "actual": values["actual"],
                             "perfect": values["perfect"], "mode": mode})
    return rows


def explain_bench(out: Path | str, *, samples: int | None = None, metrics: list[str] | None = None,
                  seeds: list[int] | None = None, engine: str = "local", workers: int | None = None,
                  address: str | None = None, progress: bool = False) -> Path:
    """Explain every tracker on every base cell of the finished bench folder ``out`` (only those of ``seeds``
    when given: each cell costs about 2k+2 counterfactual sensor runs and as many runs of every tracker);
    writes and returns ``out/explain.parquet``. Counterfactual datasets are cached in
    ``out/explain-cache/CELL``."""
    out = Path(out)
    description = _finished_bench(out)
    entries = {TrackerEntry.model_validate(entry).name: entry for entry in description["suite_settings"]["trackers"]}
    limit = description["suite_settings"].get("frame_time_limit_s", FRAME_TIME_LIMIT_S)
    results = pq.read_table(out / RESULTS)
    wanted = ("scenario", "seed", "sweep", "cell", "tracker", "scored", "failure")
    columns = [name for name in wanted if name in results.schema.names]
    base = [r for r in results.select(columns).to_pylist() if r["sweep"] == ""]
    if seeds is not None:
        check_explain_seeds(seeds, {r["seed"] for r in base}, "this bench")
        base = [r for r in base if r["seed"] in seeds]
    pairs = sorted({(r["scenario"], r["seed"], r["cell"], r["tracker"], r["scored"]) for r in base
                    if not r.get("failure")})
    # a tracker that failed on a cell in the bench (a timeout) has no actual score to explain there
    skipped = sorted({(r["tracker"], r["cell"], f"it failed in the bench: {r['failure']}") for r in base
                      if r.get("failure")})
    games = []  # (scenario, seed, cell, tracker, chosen metrics, plan) of every explained pair
    members: dict[tuple[str, frozenset], list[int]] = {}  # (dataset, coalition) → the games that need it
    tasks: list[CoalitionTask] = []
    for (scenario_name, seed, cell), cell_pairs in groupby(pairs, key=lambda pair: pair[:3]):
        dataset = Dataset.open(Path(description["cache"]) / cell)
        scenario = scenario_from_record(dataset.scenario, f"dataset {dataset.path}")
        runs: dict[frozenset, list[TrackerRun]] = {}
        for *_, tracker, scored in cell_pairs:
            entry = entries[tracker]
            record = {"tracker": entry["tracker"], "params": entry.get("params") or {}, "camera": entry.get("camera")}
            players = present_groups(scenario, len(dataset.rig.cameras), scored_in_3d=scored == "3d")
            chosen = choose_metrics(metrics, scored == "3d")
            plan = plan_game(dataset, players, samples)
            for coalition in plan.needed:
                runs.setdefault(coalition, []).append(tracker_run(record, chosen, errors=False,
                                                                  frame_time_limit_s=limit))
                members.setdefault((str(dataset.path), coalition), []).append(len(games))
            games.append((scenario_name, seed, cell, tracker, chosen, plan))
        # one task per (cell, coalition): the sensor reruns once for every tracker that needs it
        tasks += [CoalitionTask(str(dataset.path), tuple(sorted(c)), str(out / EXPLAIN_CACHE / cell), tuple(r))
                  for c, r in sorted(runs.items(), key=lambda item: coalition_order(item[0]))]
    outcomes: list[dict] = [{} for _ in games]
    for task, results in run_tasks(tasks, engine, workers, address, progress):
        coalition = frozenset(task.removed)
        for index, result in zip(members[(task.dataset, coalition)], results, strict=True):
            outcomes[index][coalition] = result
    rows = _share_rows(games, outcomes, skipped)
    command = ["simrig", "bench", str(description["suite"]), "--out", str(out), "--explain"]
    command += ["--explain-samples", str(samples)] if samples is not None else []
    command += ["--explain-seeds", ",".join(map(str, seeds))] if seeds is not None else []
    not_explained = [{"tracker": tracker, "cell": cell, "reason": reason} for tracker, cell, reason in sorted(skipped)]
    table = pa.Table.from_pylist(rows, schema=SCHEMA.with_metadata({"command": shlex.join(command),
                                                                    NOT_EXPLAINED: json.dumps(not_explained)}))
    path = out / EXPLAIN_TABLE
    with atomic_file(path) as partial:
        pq.write_table(table, partial)
    return path
