"""Regression test written by simrig search: the worst case found for 'global_hungarian'
in search space 'planner_hazards', shrunk to 1 actor(s) and 22 frames (see shrink.json next to this file).

It fails while the tracker fails the case: 3d_HZ_MISS >= 15.0 on seed 0.
Run it: pytest test_worst_case.py
On another tracker: SIMRIG_TRACKER=saga SIMRIG_TRACKER_PARAMS='{}' pytest test_worst_case.py
"""

import json
import os
from pathlib import Path

from simrig.benchmark.evaluate import metric_values
from simrig.testing import load_replay, run_tracker

REPLAY = Path(__file__).with_name('worst.toml')
METRIC = '3d_HZ_MISS'
AT_LEAST = 15.0


def test_worst_case_of_planner_hazards():
    replay = load_replay(REPLAY)
    tracker = os.environ.get("SIMRIG_TRACKER", replay.tracker)
    if "SIMRIG_TRACKER_PARAMS" in os.environ:
        params = json.loads(os.environ["SIMRIG_TRACKER_PARAMS"])
    else:
        params = replay.params if tracker == replay.tracker else {}
    value = metric_values(run_tracker(tracker, replay.scenario, seed=replay.seed, params=params))[METRIC]
    assert not value >= AT_LEAST, (
        f"{tracker} {params} still fails the shrunk worst case: {METRIC} = {value} "
        f">= {AT_LEAST} (simrig replay {REPLAY})")
