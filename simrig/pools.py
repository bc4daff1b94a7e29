"""Where work runs when simrig fans out: a local pool of spawned processes (the default) or Ray tasks, one home for
both (:func:`map_on`), used by the bench, a collection, an explanation and a search.

No scheduler of our own: :class:`concurrent.futures.ProcessPoolExecutor` (``spawn`` processes: pyrender's
EGL contexts are not safe to fork) or Ray's.

Pool workers die with their driver: each asks the kernel for ``SIGKILL`` when its parent dies
(``PR_SET_PDEATHSIG``, Linux) and also watches its parent id from a thread (any POSIX system), so a driver
killed with ``kill -9`` leaves no worker running on. Workers ignore ``SIGINT``: Ctrl-C reaches the driver,
which stops the running workers at once (their work is lost, and the driver says how much) instead of
waiting for them.
"""

from __future__ import annotations

import multiprocessing
import os
import socket
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager
from types import ModuleType

from .engine_names import ENGINES
from .errors import SimrigError
from .lifeline import die_with


def map_on(engine: str, function: Callable, items: list, workers: int | None, address: str | None = None, *,
           inline_one: bool = False) -> Iterator[tuple]:
    """``(item, function(item))`` for every item, as they finish, on ``engine``: Ray tasks (:func:`ray_map`) or a
    local pool of ``workers`` processes (default: every processor this process may use, at most one per item;
    :func:`local_map`). ``inline_one``: one local worker runs the items in this process, in order, with no pool."""
    if engine not in ENGINES:
        raise SimrigError(f"--engine {engine!r}: choose one of {', '.join(ENGINES)}")
    if engine == "ray":
        return ray_map(function, items, workers, address)
    workers = max(1, min(workers or machine_workers(), len(items)))
    if inline_one and workers == 1:
        return ((item, function(item)) for item in items)
    return local_map(function, items, workers)


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during a bench: ``running`` cells were stopped (their work is lost; ``None`` when the engine
    cannot tell running from queued), ``pending`` never started."""

    def __init__(self, running: int | None, pending: int):
        super().__init__(running, pending)
        self.running = running
        self.pending = pending


def machine_workers() -> int:
    """The processors this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def local_map(function: Callable, items: list, workers: int) -> Iterator[tuple]:
    """``(item, function(item))`` for every item, as they finish, from a pool of ``workers`` spawned
    processes (``function`` must be importable by name). An error cancels what has not started and waits for
    the running items; Ctrl-C stops the running workers at once and raises :class:`Interrupted`."""
    pool = process_pool(workers)
    pending = {}
    try:
        pending = {pool.submit(function, item): item for item in items}
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in done:
                item = pending.pop(future)
                yield item, future.result()
    except KeyboardInterrupt:
        # a future counts as running once queued to the pool (up to one extra per worker): at most one per worker
        running = min(sum(future.running() for future in pending), workers)
        stop_workers(pool)
        raise Interrupted(running, len(pending) - running) from None
    except GeneratorExit:  # the caller stopped early (Ctrl-C while it recorded a cell): do not wait either
        stop_workers(pool)
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


QUIET_RESOURCE_TRACKER = "ignore::UserWarning:multiprocessing.resource_tracker"
"""A ``PYTHONWARNINGS`` entry for multiprocessing's resource tracker: workers stopped at Ctrl-C leave their
pool's semaphores to it, which it removes at shutdown with a "leaked semaphore" warning printed after simrig's
own last line (nothing is left behind; the warning only buries the message that says what was kept)."""


def process_pool(workers: int) -> ProcessPoolExecutor:
    """A pool of ``workers`` spawned processes that die with this one (see the module docstring): the one
    pool every simrig command that fans out locally uses. The resource tracker multiprocessing starts with the
    first pool inherits :data:`QUIET_RESOURCE_TRACKER`."""
    warnings = os.environ.get("PYTHONWARNINGS", "")
    if QUIET_RESOURCE_TRACKER not in warnings.split(","):
        os.environ["PYTHONWARNINGS"] = ",".join(filter(None, [warnings, QUIET_RESOURCE_TRACKER]))
    return ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                               initializer=die_with, initargs=(os.getpid(),))


def stop_workers(pool: ProcessPoolExecutor) -> None:
    """Terminate every worker of ``pool`` now (their cells are abandoned; a partial dataset folder they were
    writing is hidden and removed by the next run)."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    for process in processes:
        if process.is_alive():
            process.terminate()
    for process in processes:
        process.join(timeout=5)
        if process.is_alive():
            process.kill()


RAY_MISSING = "--engine ray needs Ray: pip install 'simrig-mot[ray]'"


def require_ray() -> None:
    """Refuse ``--engine ray`` before any work when Ray is not installed (found without importing it)."""
    import importlib.util

    if importlib.util.find_spec("ray") is None:
        raise SimrigError(RAY_MISSING)


@contextmanager
def ray_session(workers: int | None, address: str | None) -> Iterator[ModuleType]:
    """The ``ray`` module, connected: to the cluster at ``address`` (or ``RAY_ADDRESS``) when one is given,
    else to a local Ray instance of ``workers`` CPUs started here; what was started or joined here is left again
    on exit (a Ray the caller had already initialised is used as it is and left running)."""
    try:
        import ray
    except ImportError:
        raise SimrigError(RAY_MISSING) from None
    started_here = not ray.is_initialized()
    if started_here:
        if address or os.environ.get("RAY_ADDRESS"):
            _check_reachable(address or os.environ["RAY_ADDRESS"])
            try:
                ray.init(address=address, log_to_driver=False)
            except ConnectionError as error:
                raise SimrigError(f"--address {address or os.environ['RAY_ADDRESS']!r}: cannot join the Ray "
                                  f"cluster there: {error}") from None
        else:
            ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
    try:
        yield ray
    finally:
        if started_here:
            ray.shutdown()


def _check_reachable(address: str, timeout_s: float = 10.0) -> None:
    """Refuse a ``HOST:PORT`` Ray address nothing answers on within ``timeout_s`` (Ray itself waits minutes);
    ``auto`` and ``ray://`` addresses are left to Ray."""
    host, _, port = address.rpartition(":")
    if address == "auto" or "://" in address or not host or not port.isdigit():
        return
    try:
        socket.create_connection((host, int(port)), timeout=timeout_s).close()
    except OSError as error:
        raise SimrigError(f"--address {address!r}: no Ray cluster answers there ({error.strerror or error})") from None


def ray_map(function: Callable, items: list, workers: int | None, address: str | None) -> Iterator[tuple]:
    """``(item, function(item))`` for every item, as they finish, as Ray tasks of one CPU each, on the Ray of
    :func:`ray_session` (the cluster at ``address`` or ``RAY_ADDRESS``, else a local instance of ``workers``
    CPUs started and stopped here)."""
    with ray_session(workers, address) as ray:
        pending = {}
        try:
            task = ray.remote(num_cpus=1, max_retries=0)(function)
            pending = {task.remote(item): item for item in items}
            while pending:
                done, _ = ray.wait(list(pending), num_returns=1)
                item = pending.pop(done[0])
                try:
                    result = ray.get(done[0])
                except ray.exceptions.RayTaskError as error:
                    raise error.as_instanceof_cause() from None
                yield item, result
        except KeyboardInterrupt:
            raise Interrupted(None, len(pending)) from None
        finally:
            for reference in pending:
                ray.cancel(reference, force=True)


class RayExecutor(Executor):
    """A :class:`concurrent.futures.Executor` whose calls run as Ray tasks of one CPU each (the search's seeds of
    an evaluation), on the Ray of :func:`ray_session`; :meth:`shutdown` leaves it again. A task's error is
    raised as the task's own exception type."""

    def __init__(self, workers: int | None, address: str | None):
        self._session = ray_session(workers, address)
        self._ray = self._session.__enter__()
        self._tasks: dict = {}

    def submit(self, fn, /, *args, **kwargs) -> Future:
        task = self._tasks.get(fn)
        if task is None:
            task = self._tasks[fn] = self._ray.remote(num_cpus=1, max_retries=0)(fn)
        return task.remote(*args, **kwargs).future()

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        if self._session is not None:
            session, self._session = self._session, None
            session.__exit__(None, None, None)
