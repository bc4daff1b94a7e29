"""Where cells run: a local process pool (the default) or Ray tasks. Both yield (job, outcomes, dataset
seconds) as cells finish; the caller records them, so the order of completion never reaches the results.

No scheduler of our own: :class:`concurrent.futures.ProcessPoolExecutor` (``spawn`` processes: pyrender's
EGL contexts are not safe to fork) or Ray's.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

from ..errors import SimrigError
from .evaluate import Outcome, evaluate
from .plan import Job

Finished = tuple[Job, list[Outcome], float]


def machine_workers() -> int:
    """The processors this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def local_engine(jobs: list[Job], workers: int) -> Iterator[Finished]:
    """Run ``jobs`` in a pool of ``workers`` spawned processes. Ctrl-C or an error cancels what has not
    started and stops the pool."""
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"))
    try:
        pending = {pool.submit(evaluate, job): job for job in jobs}
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in done:
                job = pending.pop(future)
                outcomes, dataset_s = future.result()
                yield job, outcomes, dataset_s
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def ray_engine(jobs: list[Job], workers: int | None, address: str | None) -> Iterator[Finished]:
    """Run ``jobs`` as Ray tasks of one CPU each. With no ``address`` (and none in ``RAY_ADDRESS``) a local
    Ray instance of ``workers`` CPUs is started and stopped again; with one, the cluster there is joined."""
    try:
        import ray
    except ImportError:
        raise SimrigError("--engine ray needs Ray: pip install 'simrig[ray]'") from None
    started_here = not ray.is_initialized()
    if started_here:
        if address or os.environ.get("RAY_ADDRESS"):
            ray.init(address=address, log_to_driver=False)
        else:
            ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
    pending = {}
    try:
        task = ray.remote(num_cpus=1, max_retries=0)(evaluate)
        pending = {task.remote(job): job for job in jobs}
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            job = pending.pop(done[0])
            try:
                outcomes, dataset_s = ray.get(done[0])
            except ray.exceptions.RayTaskError as error:
                raise error.as_instanceof_cause() from None
            yield job, outcomes, dataset_s
    finally:
        for reference in pending:
            ray.cancel(reference, force=True)
        if started_here:
            ray.shutdown()
