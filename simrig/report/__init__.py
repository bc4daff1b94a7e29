"""``simrig report``: a bench folder as ``reports/<suite>/index.md`` — results per tracker, robustness curves
with seed bands, errors by cause, and the worst cell seen from above and through the cameras."""

from .api import write_report
from .load import BenchResults, ReportError, load_bench

__all__ = ["BenchResults", "ReportError", "load_bench", "write_report"]
