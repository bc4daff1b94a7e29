"""Options and argument types shared by the commands, and the parser class that keeps every error on one line."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from simrig.scenarios import DEFAULT_SCENARIO, MAX_FRAMES

from ..errors import SimrigError

EXPLAIN_MAX_SAMPLES = 10_000
"""The most permutations ``--samples`` / ``--explain-samples`` may ask for (``simrig.explain.api.MAX_SAMPLES``,
repeated here so that parsing the options imports nothing heavy)."""


def int_at_least(minimum: int, maximum: int = 2**63 - 1):
    """An argparse type: an integer in ``minimum … maximum``, with a one-line message otherwise."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be at least {minimum}, got {value}")
        if value > maximum:
            raise argparse.ArgumentTypeError(f"must be at most {maximum}, got {text}")
        return value

    return parse


class OneLineParser(argparse.ArgumentParser):
    """argparse, but a usage error is one line naming the argument (``--help`` still shows the usage)."""

    def error(self, message: str):
        if message.startswith("argument "):  # argparse's "argument --frames: ..." in simrig's "--frames: ..." form
            message = message[len("argument "):]
        self.exit(2, f"simrig: error: {message} (see '{self.prog} --help')\n")


def output_path(path: Path | None, what: str, *, inputs=(), folder: bool = True) -> Path | None:
    """``path`` checked as an output before any work (:func:`simrig.dataset.outputs.check_output_path`)."""
    if path is None:
        return None
    from ..dataset.outputs import check_output_path

    return check_output_path(path, what=what, inputs=inputs, folder=folder)


def tracker_param(text: str) -> tuple[str, object]:
    """An argparse type for ``--param key=value``: the value becomes an int, a float, a bool
    (``true``/``false``) or stays a string."""
    key, sep, raw = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"expected key=value, got {text!r}")
    for convert in (int, float):
        try:
            value = convert(raw)
        except ValueError:
            continue
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"{key}={raw}: a parameter must be a finite number")
        return key, value
    lowered = raw.lower()
    if lowered in ("true", "false"):
        return key, lowered == "true"
    return key, raw


def tracker_params(pairs: list[tuple[str, object]] | None) -> dict[str, object]:
    params: dict[str, object] = {}
    for key, value in pairs or []:
        if key in params:
            raise SimrigError(f"--param {key} given twice")
        params[key] = value
    return params


def seed_list(text: str) -> list[int]:
    try:
        seeds = [int(part) for part in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seeds separated by commas (0,1), got {text!r}") from None
    if any(seed < 0 for seed in seeds):
        raise argparse.ArgumentTypeError(f"seeds are ≥ 0, got {text!r}")
    if len(set(seeds)) != len(seeds):
        raise argparse.ArgumentTypeError(f"a seed is listed twice in {text!r}")
    return seeds


def name_list(text: str) -> list[str]:
    """An argparse type for a comma-separated list of names."""
    names = [name.strip() for name in text.split(",") if name.strip()]
    if not names:
        raise argparse.ArgumentTypeError(f"expected comma-separated names, got {text!r}")
    return names


def non_negative_float(text: str, maximum: float = 86_400.0) -> float:
    """A number of seconds in 0 … ``maximum`` (a day by default: a longer limit or look-back means none)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not 0.0 <= value <= maximum:
        raise argparse.ArgumentTypeError(f"must be a finite number in 0 … {maximum:g}, got {text}")
    return value


def check_explain_options(args: argparse.Namespace) -> None:
    """``--explain-*`` options make sense only with ``--explain``, and ``--explain-seeds`` must be seeds of the
    suite: both checked before the bench runs (not after it, minutes later)."""
    given = [name for name, value in (("--explain-samples", args.explain_samples),
                                      ("--explain-seeds", args.explain_seeds)) if value is not None]
    if given and not args.explain:
        raise SimrigError(f"{' and '.join(given)} {'needs' if len(given) == 1 else 'need'} --explain")
    if args.explain_seeds is not None:
        from ..benchmark.suite import load_suite
        from ..explain.bench import check_explain_seeds

        suite, _ = load_suite(args.suite, trust_file=args.trust_file)
        check_explain_seeds(args.explain_seeds, suite.seeds, f"suite {suite.name!r}")


def trust_argument(parser: argparse.ArgumentParser, what: str) -> None:
    parser.add_argument("--trust-file", action="store_true",
                        help=f"let {what} import its module:attribute trackers (a data file may otherwise only "
                        "name registered trackers)")


def scenario_name(text: str) -> str:
    """A scenario argument: an empty one is a mistake, not a request for the default."""
    if not text.strip():
        raise argparse.ArgumentTypeError("an empty scenario name; give a catalog name (simrig scenarios) or a .toml "
                                         f"file, or leave it out for {DEFAULT_SCENARIO}")
    return text


def scenario_arguments(parser: argparse.ArgumentParser, default: str | None = DEFAULT_SCENARIO) -> None:
    """The scenario (``default`` when omitted; ``None``: the command decides), ``--seed`` and ``--frames``."""
    parser.add_argument("scenario", nargs="?", default=default, type=scenario_name,
                        help=f"catalog name or .toml file (default: {DEFAULT_SCENARIO})")
    parser.add_argument("--seed", type=int_at_least(0), default=0, help="scenario seed (default 0)")
    parser.add_argument("--frames", type=int_at_least(1, MAX_FRAMES), default=None,
                        help="frames to generate (default: the scenario's)")


def tracker_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--tracker", default="saga", help="registered tracker name (default: saga; see "
                        "'simrig trackers'), or module:attribute — a tracker factory or class to import")
    parser.add_argument("--param", type=tracker_param, action="append", metavar="KEY=VALUE",
                        help="a tracker parameter, repeatable (e.g. --param gate=4 --param life=mutr3d)")
    parser.add_argument("--frame-time-limit", type=non_negative_float, default=60.0, metavar="SECONDS",
                        help="stop the tracker when one step() runs longer than this (default 60; 0: no limit)")


def warn_if_no_tracks(tracker: str, frames: int, track_rows: int) -> None:
    """``warning: ...`` on stderr when a tracker reported no track in any frame of a run: the scores are then all
    misses, which a tracker whose output latency exceeds the run (``degraded``'s ``latency_s``) or that never
    confirms a track produces without an error."""
    if track_rows == 0 and frames > 0:
        print(f"warning: {tracker} reported no track in any of the {frames} frames (an output latency longer than "
              "the run, or a tracker that never confirms a track, does this); every ground-truth box counts as "
              "missed", file=sys.stderr)
