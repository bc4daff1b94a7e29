"""``simrig explain``: what each cause of error cost a run's tracker."""

from __future__ import annotations

import argparse
from functools import partial
from pathlib import Path

from .arguments import EXPLAIN_MAX_SAMPLES, int_at_least, name_list, non_negative_float, trust_argument


def register_explain(commands) -> None:
    """``simrig explain``'s options."""
    explainer = commands.add_parser(
        "explain", help="what each cause of detector error cost a run's tracker (counterfactual reruns, Shapley)")
    explainer.add_argument("run_dir", type=Path, help="a 'simrig run' folder (dataset/, tracks/, scores/)")
    explainer.add_argument("--tracker", "--label", dest="label", default=None, metavar="LABEL",
                           help="which tracker run of RUN_DIR/tracks/ (when it holds several), as view --tracker")
    explainer.add_argument("--metric", type=name_list, default=None, metavar="A,B,...",
                           help="overall metrics to explain (default AMOTA,HOTA,IDS,FN,FRAG for a 3D tracker; "
                                "2d:NAME or 3d:NAME picks a dimension)")
    explainer.add_argument("--causes", type=name_list, default=None, metavar="A,B,...",
                           help="cause groups to share among (default: every group present in the scenario)")
    explainer.add_argument("--samples", type=int_at_least(2, EXPLAIN_MAX_SAMPLES), default=None, metavar="N",
                           help="sample N permutations, rounded up to an even number (each order is paired with its "
                                "reverse; default: exact when there are at most 7 groups, else 6); with --tolerance, "
                                "the most to sample (default 24)")
    explainer.add_argument("--tolerance", type=partial(non_negative_float, maximum=1.0), default=None, metavar="F",
                           help="sample 6 permutations, then 4 more at a time, until every share's 95%% half-width is "
                                "within F (in (0, 1], e.g. 0.1) of its metric's scale, the largest change any removal "
                                "made to it; or until --samples are drawn")
    explainer.add_argument("--exact", action="store_true",
                           help="every coalition of the groups (2^k counterfactual runs; at most 12 groups)")
    explainer.add_argument("--engine", choices=("local", "ray"), default="local", help="where the runs go")
    explainer.add_argument("--workers", type=int_at_least(1), default=None,
                           help="processes (local; 1 runs in this process) or CPUs of a local Ray instance")
    explainer.add_argument("--address", default=None, help="Ray cluster to join (default: start a local instance)")
    explainer.add_argument("--quiet", action="store_true", help="no progress bar")
    trust_argument(explainer, "the run folder's tracker.json")
    explainer.set_defaults(run=_cmd_explain)


def _cmd_explain(args: argparse.Namespace) -> int:
    from ..explain import explain

    result = explain(args.run_dir, label=args.label, metrics=args.metric, causes=args.causes, samples=args.samples,
                     tolerance=args.tolerance, exact=args.exact, engine=args.engine, workers=args.workers,
                     address=args.address, progress=not args.quiet, trust_file=args.trust_file)
    print(result.table)
    plots = f"{len(result.plots)} waterfall plot{'s' if len(result.plots) != 1 else ''}"
    print(f"\nwrote     {result.out}: explain.json, explain.md, verdicts.parquet, {plots} "
          f"({result.coalitions} counterfactual runs, {result.seconds:.0f} s)")
    return 0
