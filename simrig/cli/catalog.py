"""``simrig scenarios`` and ``simrig trackers``: what is there to choose from."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from simrig.scenarios import DEFAULT_SCENARIO, catalog, load_scenario


def register_scenarios(commands) -> None:
    """``simrig scenarios``'s options."""
    scen = commands.add_parser("scenarios", help="list the scenario catalog")
    scen.set_defaults(run=_cmd_scenarios)


def _cmd_scenarios(args: argparse.Namespace) -> int:
    entries = catalog()
    width = max(len(name) for name in entries)
    for name in entries:
        scenario = load_scenario(name)
        marker = "*" if name == DEFAULT_SCENARIO else " "
        print(f"{marker} {name:<{width}}  {scenario.description}")
    print(f"(* default; {len(entries)} scenarios in {Path(next(iter(entries.values()))).parent})")
    return 0


def register_trackers(commands) -> None:
    """``simrig trackers``'s options."""
    trackers = commands.add_parser("trackers", help="list the registered trackers and their parameters")
    trackers.set_defaults(run=_cmd_trackers)


def _cmd_trackers(args: argparse.Namespace) -> int:
    import inspect

    from simrig import trackers as tracker

    from ..installation import ownership_warning

    warning = ownership_warning()
    if warning:
        print(warning, file=sys.stderr)
    for name in tracker.available():
        settings = ", ".join(
            f"{key}={value!r}" if value is not inspect.Parameter.empty else key
            for key, value in tracker.parameters(name).items()
        )
        print(f"{name}: {settings}")
    return 0
