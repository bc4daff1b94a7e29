"""Benchmark: wall time of ``simrig explain`` on the run ``simrig run highway_surround6 --seed 0 --tracker saga``
(200 frames, every cause group present in the scenario), cold: the counterfactual cache is emptied first; and,
with ``--exact``, how far each sampled share lands from the exact Shapley value (every coalition run), against
the 95 % half-width it states.

Run explicitly (not part of the test suite)::

    python tests/perf/explain.py [--run-dir runs/highway_surround6-seed0] [--mode samples=12]
                                 [--mode tolerance=0.1] [--exact] [--workers 2] [--out reports/perf/explain.md]

The run folder is made with ``simrig run`` (in Python) when it holds no saga run. Each configuration is timed
once (a cold explain is minutes long); the table gives wall time, counterfactual runs, seconds per run and the
machine's load average before and after, since the machine may be shared.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import time
from pathlib import Path

from published import command_line, machine, publish  # tests/perf helpers

from simrig.explain import explain
from simrig.explain.api import CACHE_DIR, EXPLAIN_DIR, explain_table
from simrig.pipeline.run import run_pipeline

TARGET_S = 60.0


def ensure_run(run_dir: Path) -> None:
    if not (run_dir / "tracks" / "saga" / "tracker.json").exists():
        run_pipeline("highway_surround6", seed=0, tracker="saga", out=run_dir)


def mode(text: str) -> dict:
    """``samples=N``, ``tolerance=F`` or ``tolerance=F,samples=N``: the explain keywords of one row."""
    words = dict(part.split("=") for part in text.split(","))
    return {"samples": int(words["samples"]) if "samples" in words else None,
            "tolerance": float(words["tolerance"]) if "tolerance" in words else None}


def timed(run_dir: Path, workers: int, **keywords) -> tuple[dict, int, float, float, float]:
    """One cold explain: (document, counterfactual runs, wall [s], load before, load after)."""
    shutil.rmtree(run_dir / EXPLAIN_DIR / CACHE_DIR, ignore_errors=True)
    load_before = os.getloadavg()[0]
    started = time.perf_counter()
    result = explain(run_dir, workers=workers, **keywords)
    wall = time.perf_counter() - started
    print(result.table, flush=True)
    return result.document, result.coalitions, wall, load_before, os.getloadavg()[0]


def accuracy_rows(sampled: dict, exact: dict) -> tuple[list[str], int, int]:
    """Per metric: the largest |sampled − exact| share, the largest stated half-width, and how many of the
    groups' exact values lie inside the sampled interval; with the totals (inside, groups × metrics)."""
    rows, inside, total = [], 0, 0
    for name, entry in sampled["metrics"].items():
        truth = exact["metrics"][name]["shares"]
        errors = {g: abs(entry["shares"][g] - truth[g]) for g in entry["shares"]}
        halves = entry.get("ci95") or {}
        held = [g for g in errors if halves.get(g) is not None and errors[g] <= halves[g] + 1e-12]
        inside, total = inside + len(held), total + len(errors)
        worst = max(errors, key=errors.get)
        rows.append(f"| {name} | {worst} | {errors[worst]:.4g} | {halves.get(worst) or float('nan'):.4g} | "
                    f"{max((h for h in halves.values() if h is not None), default=float('nan')):.4g} | "
                    f"{len(held)} of {len(errors)} |")
    return rows, inside, total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--run-dir", type=Path, default=Path("runs/highway_surround6-seed0"))
    parser.add_argument("--mode", type=mode, action="append", default=None,
                        help="samples=N, tolerance=F or both, comma-separated (repeatable; default: the "
                             "explainer's default mode)")
    parser.add_argument("--exact", action="store_true", help="also every coalition, and each row's error against it")
    parser.add_argument("--exact-from", type=Path, default=None,
                        help="the explain.json of an exact explanation of the same run (from an earlier --exact), "
                             "instead of computing it again")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=Path("reports/perf/explain.md"))
    args = parser.parse_args()
    ensure_run(args.run_dir)
    rows = [(keywords, *timed(args.run_dir, args.workers, **keywords)) for keywords in args.mode or [{}]]
    exact = timed(args.run_dir, args.workers, exact=True) if args.exact else None
    if args.exact_from:
        exact = (json.loads(args.exact_from.read_text()), None, None, None, None)
    lines = [
        "# `simrig explain` wall time and accuracy", "",
        f"Produced by `{command_line()}` on {machine()}, {os.cpu_count()} cores (load average given: the machine "
        "may be shared, so times are upper bounds of what an idle machine does).", "",
        f"Run: `simrig run highway_surround6 --seed 0 --tracker saga` (200 frames); target ≤ {TARGET_S:.0f} s, "
        "counterfactual cache emptied before each row (cold).", "",
        "| groups | mode | tolerance | permutations | counterfactual runs | workers | wall [s] | s per run "
        "| load before / after | target |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for _, document, coalitions, wall, before, after in rows + ([(None, *exact)] if exact and exact[2] else []):
        tolerance = document.get("tolerance")
        lines.append(f"| {len(document['causes'])} | {document['mode']} | "
                     f"{'-' if tolerance is None else format(tolerance, 'g')} | {document['samples'] or '-'} | "
                     f"{coalitions} | {args.workers} | {wall:.0f} | {wall / coalitions:.2f} | {before:.1f} / "
                     f"{after:.1f} | {'met' if wall <= TARGET_S else 'missed'} |")
    last = rows[-1][1]
    lines += ["", f"Groups: {', '.join(last['causes'])}.", ""]
    if exact:
        source = (f"from `{args.exact_from}`, an earlier `--exact` explanation of the same run" if args.exact_from
                  else "computed in this run")
        lines += ["## Sampled shares against the exact values", "", f"Exact values {source}.", "",
                  "Per row and metric: the group whose sampled share is furthest from its exact Shapley value, that "
                  "distance, the half-width the sampled table states for it, the widest half-width stated, and how "
                  "many groups' exact values lie inside their sampled 95 % intervals.", ""]
        for keywords, document, *_ in rows:
            table, inside, total = accuracy_rows(document, exact[0])
            lines += [f"### {document['samples']} permutations"
                      + (f" (tolerance {keywords['tolerance']:g})" if keywords.get("tolerance") is not None else ""),
                      "",
                      "| metric | furthest group | abs. error | its half-width | widest half-width | exact inside |",
                      "| --- | --- | --- | --- | --- | --- |", *table, "",
                      f"{inside} of {total} exact values inside their intervals ({inside / total:.0%}).", ""]
        lines += ["Exact shares (every coalition):", "", "```", explain_table(exact[0]), "```", ""]
    lines += ["Shares of the last sampled row (the explainer's table):", "", "```", explain_table(last), "```", ""]
    publish(lines, args.out)


if __name__ == "__main__":
    main()
