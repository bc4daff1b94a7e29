"""Lane coordinates computed once per position: highway-env asks a lane for the local coordinates of the same
vehicle position over and over within one simulation step (every vehicle's neighbour search walks every other
vehicle on up to three lanes, MOBIL asks again for each lane it weighs), and the answer depends on nothing but the
lane and the position.

:func:`memoise_lanes` gives each lane of a road network a memo of its own ``local_coordinates`` keyed by the exact
position (its two floats), returning the very values highway-env's own method returned, so datasets keep their
bytes. :func:`forget` empties the memos; simrig calls it after every simulation step, when vehicles have moved
(a memo never answers for a position it did not see, so a stale entry is only memory, never a wrong answer).
"""

from __future__ import annotations

MAX_ENTRIES = 200_000
"""Entries a lane's memo may hold before it is emptied (a step of a dense road holds a few hundred)."""


class _Memo:
    """``lane.local_coordinates`` with a memo of its answers by position."""

    __slots__ = ("compute", "answers")

    def __init__(self, compute):
        self.compute = compute
        self.answers: dict[tuple[float, float], tuple[float, float]] = {}

    def __call__(self, position):
        key = (float(position[0]), float(position[1]))
        found = self.answers.get(key)
        if found is None:
            if len(self.answers) >= MAX_ENTRIES:
                self.answers.clear()
            found = self.answers[key] = self.compute(position)
        return found


def memoise_lanes(network) -> list:
    """Give every lane of ``network`` (a highway-env ``RoadNetwork``) a memoised ``local_coordinates``; returns
    the memos (for :func:`forget`). A lane memoised before keeps its memo."""
    memos = []
    for lane in network.lanes_list():
        memo = lane.__dict__.get("local_coordinates")
        if not isinstance(memo, _Memo):
            memo = _Memo(lane.local_coordinates)
            lane.local_coordinates = memo  # an instance attribute: the class's method stays as it is
        memos.append(memo)
    return memos


def forget(memos: list) -> None:
    """Empty the memos (after a simulation step: every vehicle has moved)."""
    for memo in memos:
        memo.answers.clear()
