"""Which tracker references a data file may hold, and what an imported reference must be.

A scenario, suite or replay file is data: it may name a tracker by registered name (or an installed
``simrig.trackers`` entry point, which is registered too), never make simrig import a module the user did not
name. A ``module:attribute`` reference read from a file is refused unless the user allowed it explicitly
(``--trust-file`` on the command line, ``trust_file=True`` in Python); a reference given on the command line or
in Python is the user's own choice.

Whatever its origin, an imported reference must be a *tracker factory* before it is called with parameters: a
class with ``reset`` and ``step`` methods, or a Python function whose return annotation is such a class (or
:class:`~simrig.trackers.Tracker`). ``os:system`` or ``shutil:rmtree`` are neither and are never called.
"""

from __future__ import annotations

import inspect
import os
import typing
from pathlib import Path

import simrig.trackers as tracker_registry
from simrig.trackers.registry import imported

from ..errors import SimrigError

TRUST_FLAG = "--trust-file"


class TrackerReferenceError(SimrigError):
    """A tracker reference may not be followed (untrusted file) or does not lead to a tracker factory."""


def is_import_reference(spec: object) -> bool:
    """Whether ``spec`` is a ``module:attribute`` string rather than a registered tracker name."""
    return isinstance(spec, str) and ":" in spec and spec not in tracker_registry.available()


def check_file_reference(spec: object, *, trusted: bool, where: str, override: str | None = "--tracker") -> None:
    """Refuse a ``module:attribute`` read from a data file (``where`` names file and key) unless ``trusted``;
    ``override``: the command's option that names a tracker instead of the file (None: the command has none,
    as ``bench``)."""
    if trusted or not is_import_reference(spec):
        return
    instead = f" or name the tracker on the command line with {override}" if override else ""
    raise TrackerReferenceError(
        f"{where}: tracker {spec!r} is a module:attribute reference, and a data file may only name registered "
        f"trackers (see 'simrig trackers'); to import it, pass {TRUST_FLAG} (you trust this file){instead}"
    )


def _has_tracker_methods(target: object) -> bool:
    """A class with ``step`` and a ``reset`` that takes the rig (``reset(*, rig, seed)``, or ``**kwargs``):
    a class that merely has methods of those names (a gymnasium ``Env``: ``reset(*, seed, options)``) is not
    a tracker."""
    if not isinstance(target, type) or not all(callable(getattr(target, name, None)) for name in ("reset", "step")):
        return False
    try:
        parameters = inspect.signature(target.reset).parameters.values()
    except (TypeError, ValueError):  # a builtin without a signature
        return False
    return any(p.name == "rig" or p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters)


def is_tracker_factory(target: object) -> bool:
    """A class with ``reset``/``step`` methods, or a Python function annotated to return one."""
    if _has_tracker_methods(target):
        return True
    if not inspect.isfunction(target):
        return False
    try:
        returned = typing.get_type_hints(target).get("return")
    except Exception:  # an annotation that cannot be resolved says nothing we can trust
        return False
    return _has_tracker_methods(returned)


def _in_working_folder(module_name: str) -> bool:
    """Whether the top-level module of ``module_name`` is a file or package in the current folder."""
    top = Path(module_name.partition(".")[0])
    return Path(f"{top}.py").is_file() or (top / "__init__.py").is_file()


def import_tracker_factory(spec: str):
    """``"package.module:Attribute.path"`` → the tracker factory it names; a :class:`TrackerReferenceError`
    naming the spec when it cannot be imported or is not a tracker factory (nothing of it is called)."""
    module_name, _, attribute = spec.partition(":")
    if not module_name or not attribute:
        raise TrackerReferenceError(f"tracker {spec!r}: expected module:attribute")
    if module_name.startswith("."):
        raise TrackerReferenceError(f"tracker {spec!r}: {module_name!r} is a relative module name; name the module "
                                    "from the top of its package (package.module:attribute)")
    try:
        target = imported(spec)
    except (ImportError, AttributeError, ValueError) as error:
        hint = ""
        if isinstance(error, ModuleNotFoundError) and _in_working_folder(module_name):
            hint = ("; it is in the current folder, which the simrig command does not search: run with "
                    "PYTHONPATH=. or pip install your package")
        raise TrackerReferenceError(f"tracker {spec!r}: cannot import it ({error}){hint}") from None
    except (Exception, SystemExit) as error:  # the module's own code failed on import (exit() included)
        raise TrackerReferenceError(f"tracker {spec!r}: importing {module_name} raised {type(error).__name__}: "
                                    f"{error}{raised_at(error)}") from error
    if not is_tracker_factory(target):
        kind = type(target).__name__
        raise TrackerReferenceError(
            f"tracker {spec!r} is a {kind}, not a tracker factory: it must be a class with reset() and step() "
            "methods, or a function annotated to return one (-> MyTracker); it was not called"
        )
    return target


TRACEBACK_VARIABLE = "SIMRIG_TRACEBACK"
"""Set to 1 to have the command line print the whole traceback of an error raised by a user's code."""


def raised_at(error: BaseException) -> str:
    """`` (at FILE:LINE in FUNCTION; SIMRIG_TRACEBACK=1 shows the whole traceback)``: where in the tracker's code
    ``error`` was raised — the innermost frame outside simrig and the standard library's own machinery (the hint
    left out when the variable is already set)."""
    import traceback

    shown = os.environ.get(TRACEBACK_VARIABLE) == "1"  # then the whole traceback is printed: no hint
    hint = "" if shown else f"; {TRACEBACK_VARIABLE}=1 shows the whole traceback"
    if isinstance(error, SyntaxError) and error.filename:
        return f" (at {error.filename}:{error.lineno}{hint})"
    ours = (str(Path(__file__).parents[1]) + os.sep, str(Path(tracker_registry.__file__).parent) + os.sep)
    mine = [f for f in traceback.extract_tb(error.__traceback__) if not f.filename.startswith(ours)
            and not f.filename.startswith("<frozen importlib")]
    if not mine:
        return ""
    where = mine[-1]
    return f" (at {where.filename}:{where.lineno} in {where.name}{hint})"
