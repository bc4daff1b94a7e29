"""The ``simrig`` command line.

Every user error (a bad scenario, a bad argument, an output folder that holds a dataset) is printed as one
line ``simrig: error: ...`` with exit status 2; no traceback.
"""

from __future__ import annotations

import time

STARTED = time.perf_counter()
"""When this module began loading: the start of the simrig command's own work (the interpreter's start-up
before it, tens of milliseconds, is the only part of the process a printed time leaves out)."""

import argparse  # noqa: E402
import os  # noqa: E402
import sys  # noqa: E402

from simrig.scenarios import ScenarioError  # noqa: E402

from ..errors import OptionError, SimrigError  # noqa: E402
from ..interrupts import interrupted, noting_interrupts  # noqa: E402
from .arguments import OneLineParser  # noqa: E402
from .bench import register_bench, register_report  # noqa: E402
from .catalog import register_scenarios, register_trackers  # noqa: E402
from .detector import register_detector  # noqa: E402
from .explain import register_explain  # noqa: E402
from .formats import register_export, register_import  # noqa: E402
from .generate import register_generate  # noqa: E402
from .inspect import register_info, register_render, register_view  # noqa: E402
from .replay import register_replay  # noqa: E402
from .run import register_drive, register_run  # noqa: E402
from .score import register_score, register_track  # noqa: E402
from .search import register_search  # noqa: E402


class _VersionAction(argparse.Action):
    """``--version``: the version, the distribution to pip install, and a warning line when another installed
    distribution owns files of the simrig package (:mod:`simrig.installation`)."""

    def __call__(self, parser, namespace, values, option_string=None):
        from ..installation import ownership_warning
        from ..version import DISTRIBUTION, __version__

        print(f"simrig {__version__} (pip: {DISTRIBUTION})")
        warning = ownership_warning()
        if warning:
            print(warning, file=sys.stderr)
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog="simrig", description="A test bench for multi-camera multi-object trackers on moving vehicles."
    )
    parser.add_argument("--version", action=_VersionAction, nargs=0, help="show the version and exit")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for register in COMMANDS:  # each command's options sit next to its handler, one module per command
        register(commands)
    return parser


COMMANDS = (register_generate, register_scenarios, register_info, register_render, register_view,
            register_score, register_replay, register_export, register_import, register_track,
            register_trackers, register_bench, register_search, register_report, register_run,
            register_drive, register_explain, register_detector)
"""The commands in the order ``simrig --help`` lists them, each registered by its module of :mod:`simrig.cli`."""


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    with noting_interrupts():  # a KeyboardInterrupt can surface as another error (inside a lazy import, say)
        try:
            return args.run(args)
        except (KeyboardInterrupt, Exception) as error:
            if isinstance(error, KeyboardInterrupt) or interrupted():
                print("simrig: interrupted (a generation in progress leaves no dataset behind)", file=sys.stderr)
                return 130
            if isinstance(error, (SimrigError, ScenarioError)):
                if os.environ.get("SIMRIG_TRACEBACK") == "1" and error.__cause__ is not None:
                    import traceback

                    traceback.print_exception(error.__cause__, file=sys.stderr)
                hint = f" (see 'simrig {args.command} --help')" if isinstance(error, OptionError) else ""
                print(f"simrig: error: {_one_line(str(error))}{hint}", file=sys.stderr)
                return 2
            if isinstance(error, BrokenPipeError):  # the reader left early: console() leaves quietly
                raise
            if isinstance(error, OSError):  # the file system said no: a read-only folder, a name too long, ...
                where = f": {_shortened(error.filename)}" if error.filename else ""
                print(f"simrig: error: {error.strerror or error}{where}", file=sys.stderr)
                return 2
            if isinstance(error, RecursionError):
                print("simrig: error: an input file is nested too deeply to be read", file=sys.stderr)
                return 2
            raise


def _one_line(message: str) -> str:
    """A message folded onto one line (a library's error text embedded in ours may hold line breaks)."""
    return " ".join(part.strip() for part in message.splitlines() if part.strip())


def _shortened(name: object, limit: int = 120) -> str:
    """A path for a message: repr, cut to ``limit`` characters."""
    text = repr(str(name))
    return text if len(text) <= limit else text[: limit - 1] + "…"


def console() -> None:
    """The ``simrig`` command: :func:`main`, then the process's exit.

    A process that rendered (visibility or images) keeps its one OpenGL context to the end (see
    :mod:`simrig.render.scene`); tearing it down with the interpreter has been seen to abort a finished run at
    exit under load ("terminate called without an active exception", exit status -6, after every file was
    written). Such a process leaves with ``os._exit`` once its output is flushed: everything simrig writes is
    committed (atomically) before :func:`main` returns, so nothing is lost by skipping the interpreter's
    teardown."""
    try:
        code = main()
        if sys.stdout is not None:  # None when the command was started with its output closed (simrig info >&-)
            sys.stdout.flush()
    except BrokenPipeError:  # the reader left early (`simrig scenarios | head`): not an error of simrig's
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error at exit's flush
        code = 1
    scene = sys.modules.get("simrig.render.scene")
    if scene is not None and scene.offscreen_renderer.cache_info().currsize:
        for stream in (sys.stdout, sys.stderr):
            if stream is not None:
                stream.flush()
        os._exit(code)
    sys.exit(code)

