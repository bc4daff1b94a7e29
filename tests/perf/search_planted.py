"""Benchmark: how soon the optimiser finds a planted weakness, against random sampling over the same space.

Run explicitly (not part of the test suite)::

    python tests/perf/search_planted.py [--runs 5] [--budget 40] [--sampler tpe] [--out reports/search/planted.md]

The weakness: saga with ``max_age_s = 0.8`` (saga's default is 1.0 s) drops a track after 8 frames without an
update, so an actor hidden for longer comes back under a new identity. The space
(tests/perf/spaces/planted_occlusions.toml) searches the lengths (1 … 14 frames) of three occlusions of the
actor nearest to the ego; a failing case has three ID switches (3d_IDS ≥ 3, or ``--at-least``); the optimiser
maximises 3d_IDS.
Each of ``--runs`` searches (search seeds 0 … runs − 1) runs the optimiser and random sampling until the first
failing evaluation or the budget (then counted as budget + 1, a lower bound). Datasets are shared between runs
through one cache (same candidate, same bytes), so repeated candidates cost only tracking and scoring.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

from published import command_line, machine, publish  # tests/perf helpers

from simrig.search import load_space, run_search

SPACE = Path(__file__).with_name("spaces") / "planted_occlusions.toml"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--budget", type=int, default=40)
    parser.add_argument("--sampler", default="tpe", choices=("tpe", "cmaes"))
    parser.add_argument("--out", type=Path, default=Path("reports/search/planted.md"))
    parser.add_argument("--scratch", type=Path, default=None, help="search folders and the dataset cache")
    parser.add_argument("--at-least", type=int, default=3, help="ID switches that make a failing case (default 3)")
    args = parser.parse_args()
    scratch = args.scratch or Path(tempfile.mkdtemp(prefix="simrig-planted-"))
    scratch.mkdir(parents=True, exist_ok=True)
    text = SPACE.read_text(encoding="utf-8")
    variant = scratch / SPACE.name  # the same space with the failure threshold of --at-least
    variant.write_text(text.replace("at_least = 3 }", f"at_least = {args.at_least} }}"), encoding="utf-8")
    space = load_space(variant, budget=args.budget)
    rows, firsts = [], {args.sampler: [], "random": []}
    for seed in range(args.runs):
        started = time.perf_counter()
        result = run_search(space, sampler=args.sampler, seed=seed, out=scratch / f"seed{seed}",
                            cache=scratch / "datasets", stop_at_failure=True, shrink_budget=0)
        values = {stream: n if n is not None else args.budget + 1 for stream, n in result.first_failure.items()}
        for stream, value in values.items():
            firsts[stream].append(value)
        rows.append(f"| {seed} | {_shown(result.first_failure[args.sampler], args.budget)} | "
                    f"{_shown(result.first_failure['random'], args.budget)} | {time.perf_counter() - started:.0f} |")
        print(rows[-1], flush=True)
    medians = {stream: statistics.median(values) for stream, values in firsts.items()}
    ratio = medians["random"] / medians[args.sampler]
    lines = ["# The planted weakness: evaluations to the first failing case, optimiser against random sampling", "",
             f"Produced by `{command_line()}` on {machine()}.", "",
             f"Space `{SPACE.relative_to(Path(__file__).parents[2]) if SPACE.is_absolute() else SPACE}`: saga with "
             "max_age_s = 0.8 (a track dies after 8 frames without an update); three occlusions of the nearest "
             f"actor, lengths 1 … 14 frames each; failing: 3d_IDS ≥ {args.at_least} on seed 0; the optimiser "
             "maximises 3d_IDS. "
             f"Budget {args.budget} evaluations per sampler; '>{args.budget}' means none failed (counted as "
             f"{args.budget + 1} in the median, so that median is a lower bound).", "",
             f"| search seed | {args.sampler} | random | seconds |", "|---:|---:|---:|---:|", *rows, "",
             f"Median evaluations to the first failing case: {args.sampler} {medians[args.sampler]:g}, random "
             f"{medians['random']:g}: random needs {ratio:.2f}x as many (target: at least 3x).", ""]
    publish(lines, args.out)


def _shown(value: int | None, budget: int) -> str:
    return str(value) if value is not None else f">{budget}"


if __name__ == "__main__":
    main()
