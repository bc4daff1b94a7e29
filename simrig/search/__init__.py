"""``simrig search``: look for a tracker's worst case on purpose, shrink it, keep it as a regression test.

* :mod:`~simrig.search.space` — a search space (TOML, schema in :mod:`simrig.scenarios.search_schema`) checked
  against its base scenario, tracker and the scorer's metrics;
* :mod:`~simrig.search.run` — :func:`run_search`: Optuna's TPE / CMA-ES against random sampling at the same
  budget, several seeds per candidate, the best re-evaluated, resumable from one fragment per evaluation;
* :mod:`~simrig.search.shrink` — delta debugging over scenario settings while the failure holds;
* :mod:`~simrig.search.worst` — the shrunk case as a replay file and a ready-to-run pytest file.
"""

from .run import SAMPLERS, SearchRun, run_search
from .space import SearchError, SearchSpace, load_space

__all__ = ["SAMPLERS", "SearchError", "SearchRun", "SearchSpace", "load_space", "run_search"]
