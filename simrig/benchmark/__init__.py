"""``simrig bench``: scenario × tracker × seed sweeps, resumable, on a local process pool or Ray.

:func:`run_bench` runs a suite (:mod:`simrig.benchmark.suite`) into a folder of results tables
(:mod:`simrig.benchmark.results`); :mod:`simrig.report` turns that folder into a Markdown report with plots.
Names load on first use, so that ``simrig --help`` does not import the scorer and the trackers.
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "BENCH_FILE": ".api", "BenchRun": ".api", "run_bench": ".api",
    "METRIC_COLUMNS": ".evaluate", "BenchError": ".evaluate",
    "Suite": ".suite", "SuiteError": ".suite", "load_suite": ".suite", "suite_catalog": ".suite",
}

__all__ = [*_EXPORTS, "ENGINES"]

from ..engine_names import ENGINES  # noqa: E402  (light: no scorer, no trackers)


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value
    return value
