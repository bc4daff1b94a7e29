"""``simrig scenarios`` and ``simrig trackers``: what is there to choose from."""

from __future__ import annotations

import argparse
import os
import sys
import traceback
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
    broken = 0
    for name in tracker.available():
        try:
            parameters = tracker.parameters(name)
        except (Exception, SystemExit) as error:  # a plugin's module that fails to import: say so, list the rest
            broken += 1
            if os.environ.get("SIMRIG_TRACEBACK") == "1":
                traceback.print_exc()
            print(f"simrig: tracker {name!r} cannot be imported ({type(error).__name__}: {error}); "
                  "SIMRIG_TRACEBACK=1 shows where", file=sys.stderr)
            continue
        settings = ", ".join(
            f"{key}={value!r}" if value is not inspect.Parameter.empty else key
            for key, value in parameters.items()
        )
        print(f"{name}: {settings}")
    return 1 if broken else 0
