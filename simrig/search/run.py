"""``run_search``: an optimiser looks for a tracker's worst case in a search space; random sampling at the same
budget is the baseline; the best candidates are run again on fresh seeds; the worst failing case is shrunk and
left as a replay file and a pytest file.

The optimiser is Optuna's ("Optuna: A Next-generation Hyperparameter Optimization Framework", Takuya Akiba et
al., 2019): TPE ("Algorithms for Hyper-Parameter Optimization", James Bergstra et al., 2011), CMA-ES, or random
sampling. Proposals are a function of the finished evaluations only (the sampler is seeded anew for each index
from the search seed), so a search resumed from its fragments proposes what the uninterrupted one would have.
"""

from __future__ import annotations

import json
import math
import shlex
import time
import warnings
from concurrent.futures import Executor, ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from simrig.benchmark.evaluate import METRIC_COLUMNS
from simrig.engine_names import ENGINES
from simrig.names import path_part
from simrig.pools import RayExecutor, process_pool, stop_workers
from simrig.reading import read_capped
from simrig.seeding import stream_sequence

from ..dataset.manifest import write_json_atomic
from ..dataset.outputs import check_output_path, check_own_folder, folder_lock
from .evaluate import run_seed
from .fragments import Evaluation, read_evaluations, write_evaluation
from .ranking import CONFIRM, best_candidates, fails, first_failure, objective_of
from .space import Candidate, SearchError, SearchSpace, load_space

SAMPLERS = ("tpe", "cmaes", "random")
SEARCH_FILE = "search.json"
RESULTS = "results.parquet"
REPORT = "report.md"
WORST = "worst"


@dataclass(frozen=True)
class SearchRun:
    """What a search left: its folder, every evaluation by stream, the first failing evaluation (1-based) of
    each search stream (None: none failed), and the worst case's files (None when nothing failed)."""

    out: Path
    evaluations: dict[str, list[Evaluation]]
    first_failure: dict[str, int | None]
    evaluated_now: int
    worst: Path | None

    @property
    def results(self) -> Path:
        return self.out / RESULTS

    @property
    def report(self) -> Path:
        return self.out / REPORT


def run_search(space: SearchSpace | str | Path, *, sampler: str = "tpe", seed: int = 0, workers: int = 1,
               out: Path | str | None = None, cache: Path | str | None = None, baseline: bool = True,
               shrink_budget: int = 60, stop_at_failure: bool = False, progress: bool = False,
               command: str | None = None, engine: str = "local", address: str | None = None) -> SearchRun:
    """Search ``space`` (a :class:`SearchSpace`, catalog name or file) with ``sampler`` seeded by ``seed``, and
    random sampling at the same budget when ``baseline``; an evaluation's seeds run on ``engine``: ``local``
    (``workers`` processes; in this process with 1) or ``ray`` (Ray tasks: the cluster at ``address`` or
    ``RAY_ADDRESS``, else a local instance of ``workers`` CPUs) — the same evaluations either way;
    ``stop_at_failure`` ends each sampler at its first failing evaluation (how soon a sampler finds one).
    Everything goes to ``out`` (default ``runs/search/NAME``); datasets to ``cache`` (default ``OUT/datasets``).
    A rerun with the same settings resumes; with other settings it is an error naming the folder."""
    if sampler not in SAMPLERS:
        raise SearchError(f"--sampler {sampler!r}: choose one of {', '.join(SAMPLERS)}")
    if engine not in ENGINES:
        raise SearchError(f"--engine {engine!r}: choose one of {', '.join(ENGINES)}")
    if workers < 1:
        raise SearchError(f"--workers {workers}: must be at least 1")
    require_optuna()
    if not isinstance(space, SearchSpace):
        space = load_space(space)
    out = Path(out) if out is not None else Path("runs") / "search" / path_part(space.config.name, "search space name")
    cache = Path(cache) if cache is not None else out / "datasets"
    check_output_path(out, what="--out")
    check_own_folder(out, what="search folder", marker=SEARCH_FILE, marker_keys=("space", "sampler", "seed"))
    out.mkdir(parents=True, exist_ok=True)
    with folder_lock(out, "simrig search"):
        return _run(space, sampler, seed, (engine, workers, address), out, cache, baseline, shrink_budget,
                    stop_at_failure, progress, command)


def require_optuna() -> None:
    """A :class:`SearchError` saying how to install the search's samplers when optuna (the ``search`` extra) is
    missing: only ``simrig search`` needs it."""
    try:
        import optuna  # noqa: F401
    except ImportError:
        raise SearchError("simrig search needs optuna, which is not installed: pip install 'simrig-mot[search]' "
                          "(from a checkout: pip install -e '.[search]')") from None


def _settings(space: SearchSpace, sampler: str, seed: int, baseline: bool, stop_at_failure: bool) -> dict:
    return {"space": space.config.model_dump(mode="json"), "sampler": sampler, "seed": seed, "baseline": baseline,
            "stop_at_failure": stop_at_failure}


def _run(space: SearchSpace, sampler: str, seed: int, engine: tuple[str, int, str | None], out: Path, cache: Path,
         baseline: bool, shrink_budget: int, stop_at_failure: bool, progress: bool, command: str | None) -> SearchRun:
    from tqdm import tqdm

    from .report import write_report, write_results
    from .worst import write_worst

    settings = _settings(space, sampler, seed, baseline, stop_at_failure)
    previous = out / SEARCH_FILE
    if previous.exists():
        recorded = json.loads(read_capped(previous, SEARCH_FILE, SearchError))
        if {k: recorded.get(k) for k in settings} != settings:
            raise SearchError(f"search folder {str(out)!r} holds a search with other settings (space, tracker, "
                              "budget, sampler or seed); choose another --out")
    for name in (RESULTS, REPORT):  # until the end the folder must not look finished
        (out / name).unlink(missing_ok=True)
    command = command or shlex.join(["simrig", "search", str(space.path), "--tracker", space.tracker,
                                     "--sampler", sampler, "--seed", str(seed), "--out", str(out)])
    write_json_atomic(previous, settings | {"command": command, "complete": False})
    streams = [sampler] + (["random"] if baseline and sampler != "random" else [])
    config = space.config
    total = config.budget * len(streams) + config.confirm_top
    done_before = sum(len(read_evaluations(out, s)) for s in (*streams, CONFIRM))
    pool = _pool(*engine)
    evaluated_now = 0
    try:
        with tqdm(total=total, initial=done_before, unit="eval", disable=not progress,
                  desc=f"search {config.name}") as bar:
            evaluations = {}
            for stream in streams:
                evaluations[stream], count = _search_stream(space, stream, seed, out, cache, pool, bar,
                                                            stop_at_failure)
                evaluated_now += count
            evaluations[CONFIRM], count = _confirm(space, evaluations[sampler], out, cache, pool, bar)
            evaluated_now += count
    except KeyboardInterrupt:
        if isinstance(pool, ProcessPoolExecutor):
            stop_workers(pool)  # at once: the running evaluations' work is lost, the finished ones are kept
        raise
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
    first = {stream: first_failure(space, evaluations[stream]) for stream in streams}
    worst = write_worst(space, evaluations, out / WORST, cache, shrink_budget, progress) \
        if config.objective.failure is not None else None
    write_results(space, evaluations, out / RESULTS)
    write_report(space, evaluations, first, out / REPORT, command, sampler, worst)
    write_json_atomic(previous, settings | {"command": command, "complete": True,
                                            "first_failure": first})
    return SearchRun(out, evaluations, first, evaluated_now, worst)


def _pool(engine: str, workers: int, address: str | None) -> Executor | None:
    """Where an evaluation's seeds run: None (this process), a pool of spawned processes, or Ray tasks."""
    if engine == "ray":
        return RayExecutor(workers, address)
    if workers == 1:
        return None
    return process_pool(workers)


def evaluate(space: SearchSpace, stream: str, index: int, candidate: Candidate, seeds: list[int], cache: Path,
             pool: Executor | None) -> Evaluation:
    """Run ``candidate`` on every seed (in ``pool`` when given) and collect every metric per seed."""
    scenario = space.scenario_for(candidate)
    started = time.perf_counter()
    arguments = [(scenario, s, space.tracker, space.params, str(cache.absolute())) for s in seeds]  # any node
    if pool is None:
        per_seed = [run_seed(*a) for a in arguments]
    else:
        per_seed = list(pool.map(run_seed, *zip(*arguments, strict=True)))
    metrics = {name: tuple(values[name] for values in per_seed) for name in METRIC_COLUMNS}
    _check_reported(space, metrics)
    return Evaluation(stream, index, _plain(candidate), tuple(seeds), metrics, time.perf_counter() - started)


def _check_reported(space: SearchSpace, metrics: dict[str, tuple[float, ...]]) -> None:
    """Refuse, in one line naming the key and the space file, an objective or failure metric of 3D tracking
    for a tracker that reports no 3D tracks (every 3D metric undefined on every seed): it would be NaN in every
    evaluation and no case could ever fail."""
    if not all(math.isnan(v) for name, values in metrics.items() if name.startswith("3d_") for v in values):
        return
    objective = space.config.objective
    keys = [("objective.metric", objective.metric)]
    keys += [("objective.failure.metric", objective.failure_metric)] if objective.failure is not None else []
    for key, metric in keys:
        if metric.startswith("3d_"):
            raise SearchError(f"{space.path}: {key} {metric!r} is a 3D metric, and tracker {space.tracker!r} reports "
                              "no 3D tracks; a 2D tracker is scored with 2d_* metrics (e.g. 2d_IDSW, 2d_HOTA): "
                              "copy the space file and change the key")


def _plain(candidate: Candidate) -> dict:
    return {k: v.item() if isinstance(v, np.generic) else v for k, v in candidate.items()}


def _distributions(space: SearchSpace) -> dict:
    from optuna.distributions import CategoricalDistribution, FloatDistribution, IntDistribution

    out = {}
    for dimension in space.config.dimensions:
        if dimension.kind == "choice":
            out[dimension.path] = CategoricalDistribution(list(dimension.choices))
        elif dimension.kind == "window":
            start, length = dimension.names
            out[start] = IntDistribution(*dimension.start)
            out[length] = IntDistribution(*dimension.length)
        elif dimension.integer:
            out[dimension.path] = IntDistribution(dimension.low, dimension.high, log=dimension.log)
        else:
            out[dimension.path] = FloatDistribution(float(dimension.low), float(dimension.high), log=dimension.log)
    return out


def startup_trials(budget: int) -> int:
    """Random proposals before a model-based sampler takes over: a twentieth of the budget, 3 … 5. Optuna's
    default is 10 whatever the budget; every start-up proposal is one the optimiser does not steer, and
    multivariate TPE works from a handful of points, so a search for a rare failure gains from starting to
    model early (tests/perf/search_planted.py).

    >>> [startup_trials(b) for b in (8, 40, 80, 100, 1000)]
    [3, 3, 4, 5, 5]
    """
    return min(5, max(3, budget // 20))


def _sampler(stream: str, seed: int, index: int, budget: int):
    import optuna

    state = int(stream_sequence(f"search_{stream}", seed, index).generate_state(1)[0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        if stream == "tpe":
            return optuna.samplers.TPESampler(seed=state, n_startup_trials=startup_trials(budget), multivariate=True)
        if stream == "cmaes":
            return optuna.samplers.CmaEsSampler(seed=state, n_startup_trials=startup_trials(budget),
                                                warn_independent_sampling=False)
        return optuna.samplers.RandomSampler(seed=state)


def _study(space: SearchSpace):
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    return optuna.create_study(direction=space.config.objective.direction)


def _tell_value(space: SearchSpace, evaluation: Evaluation) -> float | None:
    mean = objective_of(space, evaluation).mean
    return None if math.isnan(mean) else mean


def _search_stream(space: SearchSpace, stream: str, seed: int, out: Path, cache: Path, pool, bar,
                   stop_at_failure: bool = False) -> tuple[list[Evaluation], int]:
    """Every evaluation of one sampler, the finished ones read back into the study, the rest run now."""
    import optuna
    from optuna.trial import TrialState, create_trial

    distributions = _distributions(space)
    done = read_evaluations(out, stream)
    study = _study(space)
    seeds = list(range(space.config.seeds))
    evaluations, count = [], 0
    for index in range(space.config.budget):
        if index in done:
            evaluation = done[index]
            value = _tell_value(space, evaluation)
            study.add_trial(create_trial(params=evaluation.candidate, distributions=distributions, value=value,
                                         state=TrialState.COMPLETE if value is not None else TrialState.FAIL))
        else:
            study.sampler = _sampler(stream, seed, index, space.config.budget)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
                trial = study.ask(distributions)
            evaluation = evaluate(space, stream, index, trial.params, seeds, cache, pool)
            write_evaluation(out, evaluation)
            value = _tell_value(space, evaluation)
            study.tell(trial, value, state=TrialState.COMPLETE if value is not None else TrialState.FAIL)
            count += 1
            bar.update(1)
        evaluations.append(evaluation)
        if stop_at_failure and fails(space, evaluation):
            bar.update(space.config.budget - index - 1)
            break
    return evaluations, count


def _confirm(space: SearchSpace, searched: list[Evaluation], out: Path, cache: Path, pool, bar
             ) -> tuple[list[Evaluation], int]:
    """The optimiser's best candidates run again on ``confirm_seeds`` seeds it never saw."""
    config = space.config
    done = read_evaluations(out, CONFIRM)
    seeds = list(range(config.seeds, config.seeds + config.confirm_seeds))
    evaluations, count = [], 0
    for index, best in enumerate(best_candidates(space, searched, config.confirm_top)):
        if index in done and done[index].candidate == best.candidate:
            evaluations.append(done[index])
            continue
        evaluation = evaluate(space, CONFIRM, index, best.candidate, seeds, cache, pool)
        write_evaluation(out, evaluation)
        evaluations.append(evaluation)
        count += 1
        bar.update(1)
    return evaluations, count
