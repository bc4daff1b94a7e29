"""simrig inside other people's test suites.

* :func:`run_tracker` — generate a scenario (cached per process), run a tracker on it, score it;
* :mod:`simrig.testing.strategies` — hypothesis strategies that draw small valid scenarios and perturbations
  (``scenarios()``, ``perturbations()``; needs ``hypothesis``);
* :mod:`simrig.testing.replay` — replay files: a failing run written as TOML, ``simrig replay FILE`` reruns it;
* :mod:`simrig.testing.sequential` — :func:`assert_rate_below`: a failure rate asserted at a confidence level by
  Wald's sequential test, running only as many seeds as the decision needs;
* the pytest plugin (:mod:`simrig.testing.plugin`, registered through ``pytest11``): fixtures
  ``simrig_dataset`` and ``simrig_scenario``, and a replay file for every failing test that ran a scenario.
"""

from .replay import load_replay, write_replay
from .runs import Scores, recorded_runs, run_tracker
from .sequential import Verdict, assert_rate_below, sequential_test

__all__ = ["Scores", "Verdict", "assert_rate_below", "load_replay", "recorded_runs", "run_tracker",
           "sequential_test", "write_replay"]
