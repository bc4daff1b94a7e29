"""A tracker for the interrupt tests of ``simrig search``: ``saga``, except that each tracking run first takes a
ticket from the folder named by ``SIMRIG_TEST_GATE`` (when set), so that a test decides how many evaluations a
search process finishes and knows, from evidence on disk, where it stands when it signals it
(``--tracker gated_trackers:GatedSaga``, with this folder on ``PYTHONPATH``).

A ticket is a file ``ticket-*`` in the gate folder; taking it renames it (atomic). With no ticket left the
tracker writes ``waiting`` into the gate folder and polls until the test adds one: a process in that state has
finished and recorded every evaluation before the current one, and cannot finish another.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

from simrig.pipeline.track import build_tracker

GATE = "SIMRIG_TEST_GATE"
WAITING = "waiting"


def add_tickets(gate: Path, count: int) -> None:
    """Let ``count`` more tracking runs start."""
    gate.mkdir(parents=True, exist_ok=True)
    first = len(list(gate.glob("ticket-*")))
    for number in range(first, first + count):
        (gate / f"ticket-{number:04d}").touch()


def _take_ticket(gate: Path) -> None:
    announced = False
    while True:
        for ticket in sorted(gate.glob("ticket-*[0-9]")):
            try:
                ticket.rename(ticket.with_name(ticket.name + ".taken"))
            except FileNotFoundError:  # another process took it first
                continue
            return
        if not announced:
            (gate / WAITING).write_text(f"{os.getpid()}\n", encoding="utf-8")
            announced = True
        time.sleep(0.01)


class GatedSaga:
    """``saga`` with ``params``; ``reset`` waits for a ticket when ``SIMRIG_TEST_GATE`` names a folder."""

    def __init__(self, **params):
        self._inner = build_tracker("saga", params)

    def reset(self, *, rig, seed=None):
        gate = os.environ.get(GATE)
        if gate:
            _take_ticket(Path(gate))
        self._inner.reset(rig=rig, seed=seed)

    def step(self, frame):
        return self._inner.step(frame)
