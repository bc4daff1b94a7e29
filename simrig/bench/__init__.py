"""``simrig bench``: scenario × tracker × seed sweeps, resumable, on a local process pool or Ray.

:func:`run_bench` runs a suite (:mod:`simrig.bench.suite`) into a folder of results tables
(:mod:`simrig.bench.results`); :mod:`simrig.report` turns that folder into a Markdown report with plots.
"""

from .api import BENCH_FILE, BenchRun, run_bench
from .evaluate import METRIC_COLUMNS, BenchError
from .suite import Suite, SuiteError, load_suite, suite_catalog

__all__ = ["BENCH_FILE", "METRIC_COLUMNS", "BenchError", "BenchRun", "Suite", "SuiteError", "load_suite",
           "run_bench", "suite_catalog"]
