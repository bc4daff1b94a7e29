"""``simrig bench`` and ``simrig report``: suites and their reports."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import SimrigError
from .arguments import EXPLAIN_MAX_SAMPLES, check_explain_options, int_at_least, seed_list, trust_argument


def register_bench(commands) -> None:
    """``simrig bench``'s options."""
    from simrig.engine_names import ENGINES
    from simrig.scenarios import suite_catalog

    bench = commands.add_parser("bench", help="run a suite: scenarios x trackers x seeds x sweeps, resumable")
    bench.add_argument("suite", help=f"named suite ({', '.join(suite_catalog())}) or a suite .toml file")
    bench.add_argument("--engine", choices=ENGINES, default="local",
                       help="local: a process pool (default); ray: Ray tasks (the 'ray' extra)")
    bench.add_argument("--workers", type=int_at_least(1), default=None,
                       help="processes (local) or CPUs of the local Ray instance (default: this machine's)")
    bench.add_argument("--out", type=Path, default=None, help="bench folder (default: runs/bench/SUITE)")
    bench.add_argument("--cache", type=Path, default=None,
                       help="datasets by content key, shareable between suites (default: OUT/datasets)")
    bench.add_argument("--address", default=None, help="Ray cluster to join (default: start a local instance)")
    bench.add_argument("--quiet", action="store_true", help="no progress bar")
    bench.add_argument("--explain", action="store_true",
                       help="then explain every tracker on every base cell (simrig explain; the report's 'What each "
                            "cause costs' section)")
    bench.add_argument("--explain-samples", type=int_at_least(2, EXPLAIN_MAX_SAMPLES), default=None, metavar="N",
                       help="permutations --explain samples (default: exact up to 7 cause groups, else 12)")
    bench.add_argument("--explain-seeds", type=seed_list, default=None, metavar="A,B,...",
                       help="explain only the base cells of these seeds (default: every seed of the suite)")
    trust_argument(bench, "the suite file")
    bench.set_defaults(run=_cmd_bench)


CLOSED_LOOP_EXPLAIN = ("--explain: the suite drives closed loop (closed_loop = true), and explain reruns the sensor "
                       "on a fixed world; a drive's world changes with every cause removed")


def _cmd_bench(args: argparse.Namespace) -> int:
    from ..benchmark import run_bench
    from ..benchmark.api import BenchInterrupted

    check_explain_options(args)
    if args.explain:
        from ..benchmark.suite import load_suite

        if load_suite(args.suite, trust_file=args.trust_file)[0].closed_loop:
            raise SimrigError(CLOSED_LOOP_EXPLAIN)
    try:
        result = run_bench(args.suite, engine=args.engine, workers=args.workers, out=args.out, cache=args.cache,
                           address=args.address, progress=not args.quiet, trust_file=args.trust_file)
    except BenchInterrupted as stop:
        print(f"simrig: {stop.message()}", file=sys.stderr)
        return 130
    except KeyboardInterrupt:  # before any cell ran (loading the suite, making the plan)
        print("simrig: interrupted before any cell ran; nothing was lost", file=sys.stderr)
        return 130
    print(f"bench     {result.out}: {result.points} points, {result.cells} cells ({result.cells_skipped} finished "
          f"earlier, {result.cells_run} run now), {result.rows} result rows")
    print(f"results   {result.results}")
    if args.explain:
        import pyarrow.parquet as pq

        from ..explain.bench import explain_bench, not_explained

        path = explain_bench(result.out, samples=args.explain_samples, seeds=args.explain_seeds, engine=args.engine,
                             workers=args.workers, address=args.address, progress=not args.quiet)
        print(f"explain   {path}: what each cause costs every tracker on the base cells")
        for entry in not_explained(pq.read_schema(path)):
            print(f"explain   not explained: {entry['tracker']} on cell {entry['cell']}: {entry['reason']}")
    print(f"report    simrig report {result.out}")
    return 0


def register_report(commands) -> None:
    """``simrig report``'s options."""
    report = commands.add_parser("report", help="write a bench's report (index.md with plots) from its folder")
    report.add_argument("results", type=Path, help="a bench folder (or its results.parquet)")
    report.add_argument("--out", type=Path, default=None, help="report folder (default: BENCH/report)")
    report.set_defaults(run=_cmd_report)


def _cmd_report(args: argparse.Namespace) -> int:
    from ..report import write_report

    print(write_report(args.results, out=args.out))
    return 0
