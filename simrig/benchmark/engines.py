"""Where bench cells run: :func:`simrig.pools.map_on` over the cells, yielding (job, outcomes, dataset seconds) as
cells finish; the caller records them, so the order of completion never reaches the results."""

from __future__ import annotations

from collections.abc import Iterator

from ..pools import map_on
from .evaluate import Outcome, evaluate
from .plan import Job

Finished = tuple[Job, list[Outcome], float]


def run_cells(jobs: list[Job], engine: str, workers: int | None, address: str | None) -> Iterator[Finished]:
    """Run ``jobs`` on ``engine`` (a local pool of ``workers`` spawned processes, or Ray tasks of one CPU each; with
    no ``address`` and none in ``RAY_ADDRESS`` a local Ray instance of ``workers`` CPUs is started and stopped
    again). An error cancels what has not started; Ctrl-C stops the running cells at once and raises
    :class:`simrig.pools.Interrupted`."""
    results = map_on(engine, evaluate, jobs, workers, address)
    try:
        for job, (outcomes, dataset_s) in results:
            yield job, outcomes, dataset_s
    finally:
        results.close()
