"""``simrig explain``: what each cause of detector error cost a tracker, by re-simulating without it.

For a ``simrig run`` folder, the run's sensor is rerun with sets of cause groups removed
(:mod:`simrig.sensor.groups`; traffic and visibility reused, every other random draw identical), the run's
tracker is rebuilt from its record (``tracks/LABEL/tracker.json``) and rerun on each counterfactual, and the gap
between the perfect sensor's score and the actual score is split among the groups by Shapley value
(:mod:`.shapley`) — exactly over all 2^k coalitions when k is small, by permutation sampling with a 95 %
confidence interval otherwise. Each FN / IDS / FRAG of the actual run also gets a verdict: the groups whose
removal alone makes it disappear (matched by dimension, kind, actor, frame and camera).

Writes ``RUN_DIR/explain/LABEL/``: ``explain.json`` (last), ``explain.md`` (the table and its command),
``verdicts.parquet`` and a waterfall plot per metric; counterfactual datasets are cached in
``RUN_DIR/explain/cache/``.
"""

from __future__ import annotations

import shlex
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from simrig.dataset import Dataset
from simrig.dataset.manifest import write_json_atomic
from simrig.dataset.outputs import atomic_file, write_text_atomic
from simrig.dataset.run_folder import DATASET_DIR, EXPLAIN_DIR, REPORT, SCORES_DIR, TRACKER_RECORD, TRACKS_DIR
from simrig.errors import OptionError, SimrigError
from simrig.pipeline.guard import FRAME_TIME_LIMIT_S
from simrig.pipeline.track import TrackingError, build_tracker
from simrig.pipeline.trust import TrackerReferenceError, check_file_reference
from simrig.reading import read_json
from simrig.scenarios.schema import scenario_from_record
from simrig.scoring.attribution import KINDS
from simrig.scoring.drive_outcome import traffic_crashes
from simrig.scoring.planner import PLANNER_METRICS
from simrig.scoring.results import METRICS_2D, METRICS_3D
from simrig.sensor.groups import all_groups, present_groups

from ..engine_names import ENGINES
from ..pools import map_on
from .coalition import CoalitionResult, CoalitionTask, TrackerRun, evaluate_coalition
from .shapley import Coalition, all_coalitions, coalition_order, exact_shares, prefixes, sample_orders, sampled_shares
from .waterfall import waterfall

EXPLAINABLE_3D = (*METRICS_3D, *PLANNER_METRICS)
"""The 3D metrics a run can be explained on: the nuScenes family and the planner-aware scores."""

CACHE_DIR = "cache"
THRESHOLDED_COUNTS = ("TP", "FP", "FN")
"""3D counts taken at the run's best-MOTA score threshold (:mod:`simrig.scoring.amota`): said beside the table."""
EXPLAIN_FILE = "explain.json"
"""The explain folder's document, written last: a folder without it did not finish."""
EXACT_LIMIT = 7
"""Up to this many groups the Shapley values are exact (2^7 = 128 coalitions); above, sampled."""
DEFAULT_SAMPLES = 6
"""Permutations sampled when the groups are too many for the exact values and ``samples`` is not given: three
antithetic pairs (with two, the 95 % Student's t quantile is 12.7 and the intervals dwarf the shares; with three,
4.3); on the default run's ten groups, 57 counterfactual runs, under a minute on two cores, 49 of 50 shares within
their interval of the exact values (``reports/perf/explain.md``)."""
TOLERANCE_SAMPLES = 24
"""The most permutations a game sampled to a tolerance draws when ``samples`` is not given."""
EXACT_MAX = 12
"""Most groups ``exact=True`` (``--exact``) computes every coalition for (2^12 = 4,096 counterfactual runs)."""
FIRST_ROUND = 6
"""Permutations of the first round of a game sampled to a tolerance (three antithetic pairs: with two, a count
metric's pair means are often equal, and a zero-width interval would stop the game at once)."""
ROUND = 4
"""Permutations each further round of a game sampled to a tolerance adds."""
MAX_SAMPLES = 10_000
"""Most permutations one game may sample: the orders are held in memory, and far fewer already give a
half-width below the run-to-run noise."""
DEFAULT_METRICS_3D = ("AMOTA", "HOTA", "IDS", "FN", "FRAG")
DEFAULT_METRICS_2D = ("HOTA", "IDSW", "CLR_FN", "Frag")


class ExplainError(SimrigError):
    """``simrig explain`` cannot run: the message names the folder, record, cause or metric."""


class ExplainOptionError(ExplainError, OptionError):
    """An option of ``simrig explain`` (or a combination of them) is not valid: the message starts with it."""


@dataclass(frozen=True)
class ExplainResult:
    """What :func:`explain` wrote (``out``), its JSON document, the readable table, the plots, how many
    coalitions were evaluated and the wall time [s]."""

    out: Path
    document: dict
    table: str
    plots: tuple[Path, ...]
    coalitions: int
    seconds: float


def explain(run_dir: Path | str, *, label: str | None = None, metrics: list[str] | None = None,
            causes: list[str] | None = None, samples: int | None = None, tolerance: float | None = None,
            exact: bool = False, engine: str = "local", workers: int | None = None, address: str | None = None,
            progress: bool = False, trust_file: bool = False) -> ExplainResult:
    """Explain the tracker run ``label`` of the ``simrig run`` folder ``run_dir`` (see the module docstring).

    ``metrics``: overall metric names (3D first when the tracker has 3D tracks; ``2d:NAME``/``3d:NAME`` to
    choose); ``causes``: the groups to share among (default: every group present in the scenario — an absent
    one is a null cause, share exactly 0); ``samples``: permutations to sample (default: exact when there are
    at most :data:`EXACT_LIMIT` groups, else :data:`DEFAULT_SAMPLES`); ``tolerance``: sample in rounds until
    every share's 95 % half-width is within ``tolerance`` × its metric's scale (:meth:`Game.within`), or
    ``samples`` (default :data:`TOLERANCE_SAMPLES`) are drawn; ``exact``: every coalition whatever the number of
    groups (up to :data:`EXACT_MAX`); ``engine`` ``local`` (a process pool of ``workers``; 1 runs in this process)
    or ``ray``. A run folder is data: its ``tracker.json`` may name a registered tracker; a ``module:attribute``
    there is imported only with ``trust_file`` (``--trust-file``, :mod:`simrig.pipeline.trust`)."""
    started = time.perf_counter()
    run_dir = Path(run_dir)
    dataset = _dataset(run_dir, label)
    label = _label(run_dir, label)
    record = _tracker_record(run_dir, label, trust_file)
    if not (run_dir / SCORES_DIR / label / "errors.parquet").is_file():
        raise ExplainError(f"{run_dir / SCORES_DIR / label}: no errors.parquet (the run was not scored; run "
                           "'simrig run' again into this folder)")
    scenario = scenario_from_record(dataset.scenario, f"dataset {dataset.path}")
    known = all_groups(scenario)
    has_3d = (run_dir / TRACKS_DIR / label / "tracks3d.parquet").exists() and record["camera"] is None
    present = present_groups(scenario, len(dataset.rig.cameras), scored_in_3d=has_3d)
    players = _players(causes, known, present, scenario.name)
    chosen = choose_metrics(metrics, has_3d)
    game = play(dataset, record, players, chosen, samples, run_dir / EXPLAIN_DIR / CACHE_DIR, engine=engine,
                workers=workers, address=address, verdicts=True, progress=progress, tolerance=tolerance,
                exact=exact)
    verdicts = _verdicts(run_dir, label, players, game.results)
    document = _document(scenario.name, dataset, label, record, chosen, known, present, game, verdicts, run_dir)
    out = run_dir / EXPLAIN_DIR / label
    out.mkdir(parents=True, exist_ok=True)
    (out / EXPLAIN_FILE).unlink(missing_ok=True)  # written last: until then the folder must not look finished
    with atomic_file(out / "verdicts.parquet") as partial:
        pq.write_table(verdicts["table"], partial)
    plots = tuple(waterfall(document, name, out / f"waterfall-{_file_name(name)}.png") for name in chosen)
    for stale in set(out.glob("waterfall-*.png")) - set(plots):  # an earlier explain's other metrics
        stale.unlink()
    table = explain_table(document)
    write_text_atomic(out / "explain.md", _explain_markdown(document, table))
    write_json_atomic(out / EXPLAIN_FILE, document)
    return ExplainResult(out, document, table, plots, len(game.results), time.perf_counter() - started)


@dataclass(frozen=True)
class Game:
    """The coalitions run (``results`` by removed groups) and the groups' shares ``{group: (M,)}`` of the
    chosen metrics, with the 95 % half-widths when sampled (``half`` None when exact)."""

    players: tuple[str, ...]
    exact: bool
    orders: list[tuple[str, ...]] | None
    results: dict[Coalition, CoalitionResult]
    shares: dict[str, np.ndarray]
    half: dict[str, np.ndarray] | None
    tolerance: float | None = None
    """The stopping rule's tolerance (sampled to a tolerance), else None."""

    def scale(self) -> np.ndarray:
        """``(M,)`` each metric's scale: the largest change any coalition run made to it (at least |perfect −
        actual|; 0 for a metric no removal changed, NaN where it is undefined in every run)."""
        values = np.array([result.values for result in self.results.values()], dtype=float)
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # a metric undefined in every run: NaN, not held
            return np.nanmax(np.abs(values - self.actual), axis=0)

    def beyond(self, tolerance: float) -> list[int]:
        """The metrics (indices) with a share whose 95 % half-width is beyond ``tolerance`` × :meth:`scale`
        (none when exact; a metric undefined in every run is not held to it)."""
        if self.half is None:
            return []
        scale = self.scale()
        return [m for m in range(len(scale)) if np.isfinite(scale[m]) and any(
            not self.half[p][m] <= tolerance * scale[m] for p in self.players)]

    def within(self, tolerance: float) -> bool:
        """Whether every share's 95 % half-width is within ``tolerance`` × its metric's :meth:`scale`."""
        return not self.beyond(tolerance)

    @property
    def actual(self) -> np.ndarray:
        return self.results[frozenset()].values

    @property
    def perfect(self) -> np.ndarray:
        return self.results[frozenset(self.players)].values

    def metrics(self, chosen: dict[str, tuple[str, str]]) -> dict[str, dict]:
        """``{metric: {dimension, actual, perfect, shares, residual[, ci95]}}`` (JSON-ready, NaN as None)."""
        out = {}
        for i, name in enumerate(chosen):
            share = {p: float(self.shares[p][i]) for p in self.players}
            gap = float(self.perfect[i] - self.actual[i])
            entry = {"dimension": chosen[name][0], "actual": _json_number(self.actual[i]),
                     "perfect": _json_number(self.perfect[i]), "shares": {p: _json_number(v) for p, v in share.items()},
                     "residual": _json_number(gap - sum(share.values()))}
            if self.half is not None:
                entry["ci95"] = {p: _json_number(self.half[p][i]) for p in self.players}
            out[name] = entry
        return out


@dataclass(frozen=True)
class GamePlan:
    """The coalitions a game needs (``needed``, smallest first) and those whose error keys are kept for the
    verdicts; ``orders`` the sampled permutations (None when exact)."""

    players: tuple[str, ...]
    exact: bool
    orders: list[tuple[str, ...]] | None
    needed: tuple[Coalition, ...]
    keep_errors: frozenset[Coalition]


def plan_game(dataset: Dataset, players: tuple[str, ...], samples: int | None, verdicts: bool = False,
              exact: bool = False) -> GamePlan:
    """The coalitions the Shapley values of ``players`` need: all 2^k when ``samples`` is None and there are at
    most :data:`EXACT_LIMIT` players, else the prefixes of ``samples`` (default :data:`DEFAULT_SAMPLES`)
    permutations drawn from the dataset's seed (the same for every tracker of one dataset); ``exact``: all 2^k
    whatever k. ``verdicts``: also each single removal, and the error keys of those and of the actual run."""
    if samples is not None and samples < 2:
        raise ExplainOptionError(f"--samples: at least 2 permutations (an order and its reverse) are needed, "
                                 f"got {samples}")
    if samples is not None and samples > MAX_SAMPLES:
        raise ExplainOptionError(f"--samples: at most {MAX_SAMPLES:,} permutations, got {samples:,}")
    exact = samples is None and (exact or len(players) <= EXACT_LIMIT)
    orders = None if exact else sample_orders(players, samples or DEFAULT_SAMPLES, dataset.seed)
    singles = {frozenset({p}) for p in players} if verdicts else set()
    needed = set(all_coalitions(players)) if exact else prefixes(orders) | singles
    needed |= {frozenset(), frozenset(players)}
    keep_errors = frozenset(singles | {frozenset()}) if verdicts else frozenset()
    return GamePlan(players, exact, orders, tuple(sorted(needed, key=coalition_order)), keep_errors)


def settle(plan: GamePlan, results: dict[Coalition, CoalitionResult], tolerance: float | None = None) -> Game:
    """The game's shares from the results of every coalition of ``plan`` (``tolerance``: the stopping rule's,
    when it was sampled to one)."""
    values = {c: r.values for c, r in results.items()}
    if plan.exact:
        shares, half = exact_shares(plan.players, values) if plan.players else {}, None
    else:
        sampled = sampled_shares(plan.players, plan.orders, values)
        shares, half = sampled.shares, sampled.half_width
    return Game(plan.players, plan.exact, plan.orders, results, shares, half, None if plan.exact else tolerance)


def tracker_run(record: dict, chosen: dict[str, tuple[str, str]], errors: bool,
                frame_time_limit_s: float | None = FRAME_TIME_LIMIT_S) -> TrackerRun:
    """What a coalition task needs to rebuild, run and score the tracker of ``record`` (a run's
    ``tracker.json``: tracker, params, camera), each of its calls limited to ``frame_time_limit_s`` [s]."""
    return TrackerRun(record["tracker"], tuple(sorted(record["params"].items())), record["camera"],
                      tuple(chosen.values()), errors, frame_time_limit_s)


def play(dataset: Dataset, record: dict, players: tuple[str, ...], chosen: dict[str, tuple[str, str]],
         samples: int | None, scratch: Path, *, engine: str = "local", workers: int | None = None,
         address: str | None = None, verdicts: bool = False, progress: bool = False,
         tolerance: float | None = None, exact: bool = False) -> Game:
    """Run the coalitions of :func:`plan_game` on ``dataset`` with the tracker of ``record`` (counterfactual
    datasets cached in ``scratch``) and compute the Shapley values (:func:`settle`). With a ``tolerance`` (and
    more groups than exact values are computed for), in rounds: :data:`FIRST_ROUND` permutations, then as many
    more until :meth:`Game.within` the tolerance or ``samples`` (default :data:`DEFAULT_SAMPLES`) are drawn; the
    orders of a round start with those of the round before, so ``--samples N`` reproduces a game that stopped
    at N. ``exact``: every coalition, whatever the number of groups."""
    if tolerance is not None and not 0 < tolerance <= 1:
        raise ExplainOptionError(f"--tolerance: a fraction in (0, 1] of each metric's scale, got {tolerance:g}; "
                                 "to sample a fixed number of permutations, give --samples alone")
    if tolerance is not None and samples is not None and samples < FIRST_ROUND:
        raise ExplainOptionError(f"--tolerance needs --samples {FIRST_ROUND} or more (three antithetic pairs), "
                                 f"got {samples}")
    if exact and (samples is not None or tolerance is not None):
        raise ExplainOptionError("--exact computes every coalition: it takes no --samples or --tolerance")
    if exact and len(players) > EXACT_MAX:
        raise ExplainOptionError(f"--exact: {len(players)} groups would be {2 ** len(players):,} counterfactual "
                                 f"runs; at most {EXACT_MAX} groups (choose them with --causes), or sample")
    exact = exact or samples is None and len(players) <= EXACT_LIMIT
    if tolerance is None or exact:
        plan = plan_game(dataset, players, samples, verdicts, exact)
        return settle(plan, _run_coalitions(plan, {}, dataset, record, chosen, scratch, engine, workers, address,
                                            progress))
    cap, results = samples or TOLERANCE_SAMPLES, {}
    count = min(cap, FIRST_ROUND)
    while True:
        plan = plan_game(dataset, players, count, verdicts)
        results = _run_coalitions(plan, results, dataset, record, chosen, scratch, engine, workers, address,
                                  progress)
        game = settle(plan, results, tolerance)
        if count >= cap or game.within(tolerance):
            return game
        count = min(cap, count + ROUND)


def _run_coalitions(plan: GamePlan, done: dict[Coalition, CoalitionResult], dataset: Dataset, record: dict,
                    chosen: dict[str, tuple[str, str]], scratch: Path, engine: str, workers: int | None,
                    address: str | None, progress: bool) -> dict[Coalition, CoalitionResult]:
    """``done`` with every coalition of ``plan`` it lacks run; an :class:`ExplainError` naming the first one the
    tracker failed on."""
    tasks = [CoalitionTask(str(dataset.path), tuple(sorted(c)), str(scratch),
                           (tracker_run(record, chosen, c in plan.keep_errors),)) for c in plan.needed if c not in done]
    results = dict(done)
    results |= {frozenset(task.removed): result for task, (result,) in run_tasks(tasks, engine, workers, address,
                                                                                  progress)}
    failed = failed_coalition(results)
    if failed is not None:
        raise ExplainError(failed)
    return results


def failed_coalition(results: dict[Coalition, CoalitionResult]) -> str | None:
    """Why a game cannot be settled — the first (smallest) coalition its tracker failed on, named by the
    groups removed, with the failure — or None when every coalition ran."""
    failed = sorted((c for c, r in results.items() if r.failure), key=coalition_order)
    if not failed:
        return None
    removed = ", ".join(sorted(failed[0])) or "nothing (the actual sensor)"
    return f"on the counterfactual without {removed}: {results[failed[0]].failure}"


def _players(causes: list[str] | None, known: tuple[str, ...], present: tuple[str, ...],
             scenario: str) -> tuple[str, ...]:
    if not causes:
        return present
    unknown = [name for name in causes if name not in known]
    if unknown:
        raise ExplainOptionError(f"--causes: unknown cause group {unknown[0]!r}; {scenario!r} has: {', '.join(known)}")
    return tuple(dict.fromkeys(causes))


def _dataset(run_dir: Path, label: str | None = None) -> Dataset:
    if run_dir.is_file():
        raise ExplainError(f"{str(run_dir)!r} is a file; give the folder of a 'simrig run'")
    if not run_dir.is_dir():
        raise ExplainError(f"run folder {str(run_dir)!r} does not exist")
    if run_dir.name in (DATASET_DIR, TRACKS_DIR) and (run_dir.parent / DATASET_DIR).is_dir():
        raise ExplainError(f"{run_dir} is the {run_dir.name} folder of a run; give the run folder itself: "
                           f"simrig explain {run_dir.parent}" + (f" --tracker {label}" if label else ""))
    try:
        return Dataset.open(run_dir / DATASET_DIR)
    except SimrigError as error:
        raise ExplainError(f"{run_dir}: not a 'simrig run' folder with a complete dataset ({error})") from None


def _label(run_dir: Path, label: str | None) -> str:
    tracks = run_dir / TRACKS_DIR
    labels = sorted(p.name for p in tracks.iterdir() if p.is_dir()) if tracks.is_dir() else []
    if not labels:
        raise ExplainError(f"{tracks}: no tracker run in this folder (run 'simrig run ... --out {run_dir}' first)")
    if label is None:
        if len(labels) > 1:
            raise ExplainError(f"{tracks}: holds {len(labels)} tracker runs ({', '.join(labels)}); choose one "
                               "with --tracker")
        return labels[0]
    if label not in labels:
        raise ExplainError(f"--tracker {label!r}: {tracks} holds {', '.join(labels)}")
    return label


def _tracker_record(run_dir: Path, label: str, trust_file: bool = False) -> dict:
    """The tracker's record, checked by building the tracker once; a one-line error when it cannot be, or when
    it names a ``module:attribute`` and the folder is not trusted (nothing is imported then)."""
    path = run_dir / TRACKS_DIR / label / TRACKER_RECORD
    try:
        record = read_json(path, TRACKER_RECORD, ExplainError)
        tracker, params, camera = record["tracker"], record["params"], record["camera"]
        if not isinstance(tracker, str) or not isinstance(params, dict):
            raise TypeError("tracker must be a name, params a table")
    except FileNotFoundError:
        raise ExplainError(f"{path}: missing, so the tracker of this run cannot be recreated (tracks written by "
                           "'simrig track' or by a tracker passed as an object in Python, or a run made before "
                           "simrig recorded its tracker); make the run with 'simrig run' and a registered tracker "
                           "or module:attribute") from None
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise ExplainError(f"{path}: not a tracker record ({error})") from None
    try:
        check_file_reference(tracker, trusted=trust_file, where=str(path), override=None)
        build_tracker(tracker, params)
    except TrackerReferenceError as error:
        raise ExplainError(str(error)) from None
    except TrackingError as error:
        raise ExplainError(f"{path}: the tracker cannot be recreated: {error}") from None
    return {"tracker": tracker, "params": params, "camera": camera}


def choose_metrics(names: list[str] | None, has_3d: bool) -> dict[str, tuple[str, str]]:
    """Display name → (dimension, metric name)."""
    names = list(names or (DEFAULT_METRICS_3D if has_3d else DEFAULT_METRICS_2D))
    chosen = {}
    for name in names:
        dimension, _, bare = name.rpartition(":")
        if dimension == "3d" and has_3d and bare in EXPLAINABLE_3D or dimension == "2d" and bare in METRICS_2D:
            chosen[name] = (dimension, bare)
        elif not dimension and has_3d and bare in EXPLAINABLE_3D:
            chosen[name] = ("3d", bare)
        elif not dimension and bare in METRICS_2D:
            chosen[name] = ("2d", bare)
        else:
            raise ExplainOptionError(f"--metric: {name!r} is not a metric of this run; {_metric_choices(has_3d)}")
    return chosen


def _metric_choices(has_3d: bool) -> str:
    """The metrics a run can be explained on, per dimension, for an error message."""
    two_d = ", ".join(METRICS_2D)
    if not has_3d:
        return f"its tracker has no 3D tracks, so choose a 2D metric: {two_d}"
    return (f"3D: {', '.join(EXPLAINABLE_3D)}; 2D: {two_d}; a bare name is the 3D metric where both have it, 2d:NAME "
            "or 3d:NAME picks the dimension")


def run_tasks(tasks: list[CoalitionTask], engine: str, workers: int | None, address: str | None,
              progress: bool = False) -> list[tuple[CoalitionTask, tuple[CoalitionResult, ...]]]:
    """Every coalition task with its runs' results, on the chosen engine, in the order they finish;
    ``progress``: a bar on stderr."""
    from tqdm import tqdm

    if engine not in ENGINES:
        raise ExplainOptionError(f"--engine {engine!r}: choose local or ray")
    finished = map_on(engine, evaluate_coalition, tasks, workers, address, inline_one=True)
    return list(tqdm(finished, total=len(tasks), desc="explain", unit="run", disable=not progress))


def _verdicts(run_dir: Path, label: str, players: tuple[str, ...],
              results: dict[Coalition, CoalitionResult]) -> dict:
    """The run's FN/IDS/FRAG rows (with their context causes) and, per row, the groups whose removal alone
    makes it disappear; counts per kind and group."""
    actual = pq.read_table(run_dir / SCORES_DIR / label / "errors.parquet")
    actual = actual.filter(pc.is_in(actual.column("kind"), value_set=pa.array(KINDS)))
    rows = actual.select(["dimension", "kind", "actor_id", "frame", "camera"]).to_pydict()
    keys = list(zip(rows["dimension"], rows["kind"], rows["actor_id"], rows["frame"], rows["camera"], strict=True))
    fixed = [[p for p in players if key not in results[frozenset({p})].errors] for key in keys]
    table = actual.append_column("fixed_by", pa.array(fixed, type=pa.list_(pa.string())))
    counts: dict[str, dict[str, dict[str, int]]] = {}
    for (dimension, kind, *_), groups in zip(keys, fixed, strict=True):
        entry = counts.setdefault(dimension, {}).setdefault(kind, {"total": 0, "no single cause": 0,
                                                                   **{p: 0 for p in players}})
        entry["total"] += 1
        for group in groups:
            entry[group] += 1
        if not groups:
            entry["no single cause"] += 1
    counts = {dimension: {kind: kinds[kind] for kind in KINDS if kind in kinds}  # FN, IDS, FRAG in order
              for dimension, kinds in counts.items()}
    return {"table": table, "counts": counts}


def _document(scenario: str, dataset: Dataset, label: str, record: dict, chosen: dict, known: tuple[str, ...],
              present: tuple[str, ...], game: Game, verdicts: dict, run_dir: Path) -> dict:
    players, exact, orders = game.players, game.exact, game.orders
    words = ["simrig", "explain", "RUN_DIR", "--label", label, "--metric", ",".join(chosen)]
    words += ["--causes", ",".join(players)] if players else []
    words += [] if exact else ["--samples", str(len(orders))]
    return {
        "scenario": scenario, "seed": dataset.seed, "frames": dataset.frame_count, "label": label,
        "tracker": record["tracker"], "params": record["params"], "camera": record["camera"],
        "mode": "exact" if exact else "sampled", "samples": None if exact else len(orders),
        "tolerance": game.tolerance,
        "within_tolerance": None if game.tolerance is None else game.within(game.tolerance),
        "beyond_tolerance": [] if game.tolerance is None else [list(chosen)[m] for m in game.beyond(game.tolerance)],
        "coalitions": len(game.results), "causes": list(players),
        "null_causes": [name for name in known if name not in present and name not in players],
        "kept_on": [name for name in present if name not in players],
        "metrics": game.metrics(chosen), "verdicts": verdicts["counts"],
        "traffic_crashes": traffic_crashes(dataset.ground_truth),
        "command": shlex.join(words).replace("RUN_DIR", shlex.quote(str(run_dir))),
    }


def _json_number(value) -> float | None:
    """A float for the JSON document, None (null) for NaN."""
    value = float(value)
    return None if np.isnan(value) else value


def _file_name(metric: str) -> str:
    return metric.replace(":", "-")


def _format(value: float | None, count: bool, signed: bool = False) -> str:
    if value is None:
        return "-"
    text = f"{value:+.1f}" if count and signed else f"{value:.1f}" if count else (
        f"{value:+.3f}" if signed else f"{value:.3f}")
    return text


def explain_table(document: dict) -> str:
    """The readable table: actual, perfect and each group's share per metric (± the 95 % half-width when
    sampled), the residual, and the per-error verdict counts."""
    from simrig.scoring.results import COUNT_METRICS

    metrics = document["metrics"]
    names = list(metrics)
    counts = {name: name.rpartition(":")[2] in COUNT_METRICS for name in names}
    sampled = document["mode"] == "sampled"
    interval = sampled and any(value is not None for entry in metrics.values() for value in entry["ci95"].values())
    head = (f"exact Shapley values over {document['coalitions']} coalitions" if not sampled else
            f"Shapley values sampled from {document['samples']} permutations{_stopping(document)} "
            f"({document['coalitions']} coalitions; "
            + ("± half-width of the 95% confidence interval)" if interval else
               "one order and its reverse: no confidence interval, --samples 3 or more gives one)"))
    who = document["tracker"] + (f" ({document['label']})" if document["label"] != document["tracker"] else "")
    lines = [f"explain   {who} on {document['scenario']}, seed "
             f"{document['seed']}, {document['frames']} frames: {head}",
             "share    how much removing the cause group moves the metric toward the perfect sensor "
             "(shares add up to perfect − actual)", ""]
    width = max([len(p) for p in document["causes"]] + [16]) + 2
    cell = 18 if interval else 10
    lines.append(" " * width + "".join(name.rjust(cell) for name in names))
    for row in ("actual", "perfect"):
        lines.append(row.ljust(width) + "".join(_format(metrics[n][row], counts[n]).rjust(cell) for n in names))
    for cause in document["causes"]:
        cells = []
        for n in names:
            text = _format(metrics[n]["shares"][cause], counts[n], signed=True)
            if interval:
                text += " ±" + _format(metrics[n]["ci95"][cause], counts[n])
            cells.append(text.rjust(cell))
        lines.append(cause.ljust(width) + "".join(cells))
    lines.append("residual".ljust(width) + "".join(
        (f"{metrics[n]['residual']:.1e}" if metrics[n]["residual"] is not None else "-").rjust(cell) for n in names))
    thresholded = [n for n in names if n.removeprefix("3d:") in THRESHOLDED_COUNTS]
    if thresholded:
        lines.append(f"{', '.join(thresholded)}: counted at each run's own score threshold (the one that maximises "
                     "its MOTA, as nuScenes does), so a share also holds that operating point moving, not only "
                     "errors added or removed")
    if document["null_causes"]:
        lines.append("not an imperfection here (share 0 exactly): " + ", ".join(document["null_causes"]))
    if document["kept_on"]:
        lines.append("not in --causes (on in every run): " + ", ".join(document["kept_on"]))
    for dimension, kinds in document["verdicts"].items():
        lines += ["", f"{dimension.upper()} errors of the actual run that removing one cause group alone fixes"]
        lines.append(f"{'':<{width}}" + "".join(kind.rjust(8) for kind in kinds))
        for row in ("total", *document["causes"], "no single cause"):
            lines.append(row.ljust(width) + "".join(str(kinds[k][row]).rjust(8) for k in kinds))
    return "\n".join(lines)


def _stopping(document: dict) -> str:
    """How a game sampled to a tolerance stopped, for the table's head ('' for a fixed number of samples)."""
    tolerance = document.get("tolerance")
    if tolerance is None:
        return ""
    percent = f"{100 * tolerance:.3g} %"
    if document["within_tolerance"]:
        return f", stopped with every half-width within {percent} of its metric's scale"
    return (f", the most allowed, before every half-width was within {percent} of its metric's scale (still wider: "
            f"{', '.join(document['beyond_tolerance'])})")


def _explain_markdown(document: dict, table: str | None = None) -> str:
    """``explain.md``: the table in a code block under the command that produced it."""
    table = explain_table(document) if table is None else table
    crashes = document.get("traffic_crashes") or 0
    crashed = (f"The traffic itself crashed {crashes} time{'s' * (crashes != 1)} in this world (collisions between "
               "road users other than the ego: `simrig info` on the dataset lists them); no sensor cause removes "
               "those, so errors around them stay in every coalition.\n\n") if crashes else ""
    return (f"### What each cause cost {document['label']}\n\nProduced by `{document['command']}`.\n\n"
            f"{crashed}```\n{table}\n```\n")


def add_to_run_report(run_dir: Path | str, label: str, document: dict) -> Path:
    """Append the explanation to ``scores/LABEL/report.md`` (replacing an earlier one) and rewrite the run
    folder's ``report.md``."""
    from simrig.pipeline.run import write_index

    run_dir = Path(run_dir)
    path = run_dir / SCORES_DIR / label / REPORT
    text = path.read_text(encoding="utf-8")
    marker = "### What each cause cost"
    text = text.split(f"\n{marker}")[0].rstrip("\n") + "\n\n" + _explain_markdown(document)
    write_text_atomic(path, text)
    return write_index(run_dir)
