"""``simrig replay``: run a replay file (a failing test's scenario) again and compare."""

from __future__ import annotations

import argparse
from pathlib import Path

from .arguments import tracker_param, tracker_params, trust_argument


def register_replay(commands) -> None:
    """``simrig replay``'s options."""
    replay = commands.add_parser("replay", help="rerun a replay file (a failing test's scenario) and compare")
    replay.add_argument("file", type=Path)
    replay.add_argument("--tracker", default=None, help="registered name or module:attribute (default: the file's)")
    replay.add_argument("--param", type=tracker_param, action="append", metavar="KEY=VALUE",
                        help="a tracker parameter, repeatable (default: the file's)")
    replay.add_argument("--out", type=Path, default=None, help="keep the dataset and tracks here (default: temporary)")
    trust_argument(replay, "the replay file")
    replay.set_defaults(run=_cmd_replay)


def _cmd_replay(args: argparse.Namespace) -> int:
    from ..testing.replay import replay

    params = tracker_params(args.param) if args.param else None
    result = replay(args.file, tracker=args.tracker, params=params, out=args.out, trust_file=args.trust_file)
    print(result.report.table())
    if args.out is None:
        print("\n(the dataset and tracks above were in a temporary folder, now removed; --out DIR keeps them)")
    print()
    print(result.summary())
    return 0 if result.reproduced else 1
