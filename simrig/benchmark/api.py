"""``run_bench``: every point of a suite, on a local pool or Ray, resumable, into one folder."""

from __future__ import annotations

import shlex
import sys
from dataclasses import dataclass
from pathlib import Path

from tqdm import tqdm

from ..dataset.manifest import write_json_atomic
from ..dataset.outputs import check_output_path, check_own_folder, folder_lock, write_table_atomic
from ..engine_names import ENGINES
from ..pipeline.cache import check_cache_folder
from ..pools import Interrupted, machine_workers
from .engines import run_cells
from .plan import FRAME_SECONDS, Plan, make_plan
from .results import TABLES, assemble, finished, write_fragment
from .suite import SuiteError, load_suite

BENCH_FILE = "bench.json"


@dataclass(frozen=True)
class BenchRun:
    """What a bench run did: its folder, how many points and cells the suite has, how many cells (with every
    tracker) were already finished and how many ran now."""

    out: Path
    points: int
    rows: int
    cells: int
    cells_skipped: int
    cells_run: int

    @property
    def results(self) -> Path:
        return self.out / TABLES[0]


def run_bench(
    suite: str | Path,
    *,
    engine: str = "local",
    workers: int | None = None,
    out: Path | str | None = None,
    cache: Path | str | None = None,
    address: str | None = None,
    progress: bool = False,
    trust_file: bool = False,
) -> BenchRun:
    """Run every point of ``suite`` (a named suite or a suite file) that has not finished in ``out``
    (default ``runs/bench/SUITE``), then write the tables. ``cache`` holds the datasets by content key
    (default ``OUT/datasets``); ``workers`` defaults to the processors of this machine. ``trust_file`` allows the
    suite's ``module:attribute`` trackers to be imported (``--trust-file``)."""
    if engine not in ENGINES:
        raise SuiteError(f"--engine {engine!r}: choose one of {', '.join(ENGINES)}")
    if workers is not None and workers < 1:
        raise SuiteError(f"--workers {workers}: must be at least 1")
    loaded, scenarios = load_suite(suite, trust_file=trust_file)
    if loaded.closed_loop:
        from ..pipeline.drive import DriveError, check_drivable

        for scenario in scenarios.values():
            try:
                check_drivable(scenario)
            except DriveError as error:
                raise SuiteError(f"{suite}: closed_loop = true: {error}") from None
    plan = make_plan(loaded, scenarios)
    out = Path(out) if out is not None else Path("runs") / "bench" / loaded.name
    cache = Path(cache) if cache is not None else out / "datasets"
    check_output_path(out, what="--out")
    check_own_folder(out, what="bench folder", marker=BENCH_FILE, marker_keys=("suite", "command", "cells"))
    check_cache_folder(cache)
    out.mkdir(parents=True, exist_ok=True)
    with folder_lock(out, "simrig bench"):
        return _run(plan, suite, out, cache, engine, workers, address, progress)


def _run(plan: Plan, suite: str | Path, out: Path, cache: Path, engine: str, workers: int | None,
         address: str | None, progress: bool) -> BenchRun:
    loaded = plan.suite
    for name in TABLES:  # from here until the end, the folder must not look finished
        (out / name).unlink(missing_ok=True)
    write_json_atomic(out / BENCH_FILE, _description(plan, suite, out, engine, cache, complete=False))
    jobs = plan.jobs(finished(out), cache.absolute())  # a task may run on another node, in another folder
    workers = min(workers or machine_workers(), max(len(jobs), 1))
    _warn_if_long(jobs, workers, engine)
    results = run_cells(jobs, engine, workers, address)
    bar = tqdm(total=len(plan.cells), initial=len(plan.cells) - len(jobs), unit="cell", disable=not progress,
               desc=f"bench {loaded.name}")
    done_now = 0
    with bar:
        try:
            for _, outcomes, dataset_s in results:
                for outcome in outcomes:
                    write_fragment(out, outcome, dataset_s)
                done_now += 1
                bar.update(1)
        except Interrupted as stop:
            raise BenchInterrupted(out, len(plan.cells) - len(jobs), done_now, stop.running,
                                   stop.pending) from None
        except KeyboardInterrupt:  # arrived while a finished cell was being recorded
            results.close()
            raise BenchInterrupted(out, len(plan.cells) - len(jobs), done_now, None,
                                   len(jobs) - done_now) from None
    tables = assemble(plan, out)
    for name, table in tables.items():
        write_table_atomic(table, out / name)
    write_json_atomic(out / BENCH_FILE, _description(plan, suite, out, engine, cache, complete=True))
    return BenchRun(out, len(plan.points), tables[TABLES[0]].num_rows, len(plan.cells),
                    len(plan.cells) - len(jobs), len(jobs))


def _warn_if_long(jobs: list, workers: int, engine: str) -> None:
    """Say before it starts when a bench will take more than an hour by a rough estimate
    (:data:`~simrig.benchmark.plan.FRAME_SECONDS` per frame and worker)."""
    frames = sum(job.frames for job in jobs)
    seconds = frames * FRAME_SECONDS / max(workers, 1)
    if seconds > 3600 and engine == "local":
        print(f"simrig: {len(jobs):,} cells to run ({frames:,} frames): roughly {seconds / 3600:.1f} h on {workers} "
              f"workers at ~{FRAME_SECONDS:g} s per frame and worker; Ctrl-C keeps every finished cell and a rerun "
              "resumes",
              file=sys.stderr)


class BenchInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped a bench; :meth:`message` says what was kept and what was lost."""

    def __init__(self, out: Path, earlier: int, now: int, running: int | None, pending: int):
        super().__init__(out, earlier, now, running, pending)
        self.out, self.earlier, self.now, self.running, self.pending = out, earlier, now, running, pending

    def message(self) -> str:
        kept = f"{self.earlier + self.now} finished cells are kept in {str(self.out)!r} ({self.now} of them this run)"
        if self.running is None:
            lost = f"{self.pending} unfinished cells (running or queued) were stopped; the running ones' work is lost"
        else:
            lost = (f"{self.running} running cells were stopped and their work is lost, {self.pending} had not "
                    "started")
        return f"interrupted: {kept}; {lost}; run the same command again to finish"


def _description(plan: Plan, suite: str | Path, out: Path, engine: str, cache: Path, *, complete: bool) -> dict:
    """bench.json: enough to rerun the suite and to regenerate any cell (the report needs one)."""
    return {
        "suite": plan.suite.name,
        "command": shlex.join(["simrig", "bench", str(suite), "--out", str(out)]),
        "out": str(out),
        "suite_settings": plan.suite.model_dump(mode="json"),
        "engine": engine,
        "cache": str(cache.absolute()),  # the report finds the datasets from any folder
        "parameters": list(plan.parameters),
        "cells": {key: {"scenario": scenario.model_dump(mode="json"), "seed": seed, "frames": frames}
                  for key, (scenario, seed, frames) in plan.cells.items()},
        "complete": complete,
    }
