"""A search's evaluations on disk: one JSON fragment per finished evaluation, written atomically.

Layout: ``DIR/evaluations/STREAM/INDEX.json``, where STREAM is the sampler that proposed the candidate
(``tpe``, ``cmaes``, ``random``) or ``confirm`` (the optimiser's best candidates run again on fresh seeds).
Fragments are the unit of resumption: a rerun reads them back and runs only what has none, so an interrupt
(SIGINT or SIGKILL) loses at most the evaluations in progress and never repeats a finished one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from simrig.reading import read_json

from ..dataset.manifest import write_json_atomic

FOLDER = "evaluations"


@dataclass(frozen=True)
class Evaluation:
    """A finished evaluation: the candidate's values by parameter name, the seeds it ran, every metric per
    seed (NaN where a metric does not apply) and its wall time [s]."""

    stream: str
    index: int
    candidate: dict
    seeds: tuple[int, ...]
    metrics: dict[str, tuple[float, ...]]
    seconds: float

    def values(self, metric: str) -> tuple[float, ...]:
        return self.metrics[metric]


def fragment_path(out: Path, stream: str, index: int) -> Path:
    return out / FOLDER / stream / f"{index:05d}.json"


def write_evaluation(out: Path, evaluation: Evaluation) -> None:
    """Record one finished evaluation atomically (NaN written as null)."""
    path = fragment_path(out, evaluation.stream, evaluation.index)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_json_atomic(path, {
        "stream": evaluation.stream, "index": evaluation.index, "candidate": evaluation.candidate,
        "seeds": list(evaluation.seeds), "seconds": evaluation.seconds,
        "metrics": {name: [None if math.isnan(v) else v for v in values]
                    for name, values in evaluation.metrics.items()},
    })


def read_evaluations(out: Path, stream: str) -> dict[int, Evaluation]:
    """Every finished evaluation of ``stream`` in ``out`` by index (an unreadable fragment is an error that
    names it: delete it to run that evaluation again)."""
    found = {}
    for path in sorted((out / FOLDER / stream).glob("*.json")):
        try:
            raw = read_json(path, "search fragment", ValueError)
        except (OSError, ValueError) as error:
            raise FileNotFoundError(f"search fragment {str(path)!r} is unreadable ({error}); delete it to run "
                                    "that evaluation again") from None
        found[raw["index"]] = Evaluation(
            raw["stream"], raw["index"], raw["candidate"], tuple(raw["seeds"]),
            {name: tuple(math.nan if v is None else float(v) for v in values)
             for name, values in raw["metrics"].items()},
            raw["seconds"])
    return found
