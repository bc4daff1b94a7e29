"""``simrig search``: a tracker's worst case, found, shrunk and written as a regression test."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .arguments import int_at_least, tracker_param, tracker_params


def register_search(commands) -> None:
    """``simrig search``'s options."""
    from simrig.engine_names import ENGINES

    search = commands.add_parser("search", help="look for a tracker's worst case, shrink it, write a regression test")
    search.add_argument("space", help="catalog search space (e.g. occlusion_gaps) or a search space .toml file")
    search.add_argument("--tracker", default=None, help="registered name or module:attribute (default: the file's)")
    search.add_argument("--param", type=tracker_param, action="append", metavar="KEY=VALUE",
                        help="a tracker parameter, repeatable (default: the file's)")
    search.add_argument("--budget", type=int_at_least(1), default=None, help="evaluations per sampler")
    search.add_argument("--sampler", choices=("tpe", "cmaes", "random"), default="tpe",
                        help="the optimiser (default tpe); random sampling also runs as the baseline")
    search.add_argument("--seed", type=int_at_least(0), default=0, help="search seed (default 0)")
    search.add_argument("--engine", choices=ENGINES, default="local",
                        help="where an evaluation's seeds run: local processes (default) or Ray tasks")
    search.add_argument("--workers", type=int_at_least(1), default=1,
                        help="processes (local) or CPUs of the local Ray instance for an evaluation's seeds")
    search.add_argument("--address", default=None, help="Ray cluster to join (default: start a local instance)")
    search.add_argument("--out", type=Path, default=None, help="search folder (default: runs/search/SPACE)")
    search.add_argument("--cache", type=Path, default=None, help="datasets by content key (default: OUT/datasets)")
    search.add_argument("--trust-file", action="store_true",
                        help="let the space file import its module:attribute tracker (data files may otherwise only "
                        "name registered trackers)")
    search.add_argument("--stop-at-failure", action="store_true", help="end each sampler at its first failing case")
    search.add_argument("--quiet", action="store_true", help="no progress bar")
    search.set_defaults(run=_cmd_search)


def _cmd_search(args: argparse.Namespace) -> int:
    import shlex

    from ..search import load_space, run_search

    tracker = args.tracker  # a tracker the user types may be module:attribute; one in the file may not
    space = load_space(args.space, tracker=tracker, params=tracker_params(args.param) if args.param else None,
                       budget=args.budget, trust_file=args.trust_file)
    words = ["simrig", "search", args.space, "--tracker", space.tracker]
    words += [f"--param={key}={value}" for key, value in space.params.items()]
    words += ["--budget", str(space.config.budget), "--sampler", args.sampler, "--seed", str(args.seed)]
    words += ["--stop-at-failure"] if args.stop_at_failure else []
    command = shlex.join(words + (["--out", str(args.out)] if args.out else []))
    try:
        result = run_search(space, sampler=args.sampler, seed=args.seed, workers=args.workers, out=args.out,
                            cache=args.cache, stop_at_failure=args.stop_at_failure, progress=not args.quiet,
                            command=command, engine=args.engine, address=args.address)
    except KeyboardInterrupt:
        print("simrig: interrupted; every finished evaluation is kept: run the same command again to resume",
              file=sys.stderr)
        return 130
    firsts = ", ".join(f"{name} {n or 'none'}" for name, n in result.first_failure.items())
    print(f"search    {result.out}: {result.evaluated_now} evaluations run now; first failing evaluation: {firsts}")
    print(f"results   {result.results}")
    print(f"report    {result.report}")
    if result.worst is not None:
        print(f"worst     {result.worst} (replay file and pytest file of the shrunk case)")
    return 0
