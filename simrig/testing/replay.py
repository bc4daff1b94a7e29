"""Replay files: a run written as TOML so that ``simrig replay FILE`` reproduces it anywhere.

Layout: ``seed``, ``tracker`` (a registered name or ``module:attribute``; absent when unknown), ``camera``
(when one camera was scored), ``failure`` (the failing test's message), ``[params]`` (the tracker's),
``[scores]`` (the failing run's overall 2D and 3D metrics, to compare a replay against) and ``[scenario]``
(the complete scenario, loadable on its own).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import tomli_w
from pydantic import ValidationError

from simrig.scenarios import describe_errors
from simrig.scenarios.files import read_toml, validate_strict
from simrig.scenarios.schema import Scenario

from ..dataset.outputs import check_output_path, check_own_folder, write_text_atomic
from ..errors import SimrigError
from ..pipeline.trust import TrackerReferenceError, check_file_reference
from ..scoring import ScoreReport


class ReplayError(SimrigError):
    """A replay file is missing or malformed; the message names the file and the key."""


@dataclass(frozen=True)
class Replay:
    scenario: Scenario
    seed: int
    tracker: str | None
    params: dict
    camera: str | None
    failure: str | None
    scores: dict


def _headline(report: ScoreReport) -> dict:
    """The overall metrics a replay is compared on: ``{"2d": {...}, "3d": {...}}`` without NaN."""
    out = {}
    for key, metrics in (("2d", report.metrics2d), ("3d", report.metrics3d)):
        if metrics is not None:
            out[key] = {name: float(value) for name, value in metrics["overall"].items()
                        if isinstance(value, (int, float)) and not math.isnan(value)}
    return out


def write_replay(path: Path | str, scenario: Scenario, seed: int, *, tracker: str | None = None,
                 params: dict | None = None, camera: str | None = None, failure: str | None = None,
                 scores: ScoreReport | None = None) -> Path:
    """Write a replay file (folders created); returns its path."""
    document = {"seed": int(seed)}
    if tracker:
        document["tracker"] = tracker
    if camera:
        document["camera"] = camera
    if failure:
        document["failure"] = failure[:4000]
    document["params"] = {k: v for k, v in (params or {}).items() if v is not None}
    document["scores"] = _headline(scores) if scores is not None else {}
    document["scenario"] = scenario.model_dump(mode="json", exclude_none=True, exclude_unset=True)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    header = "# simrig replay file: `simrig replay THIS_FILE` reruns the scenario below with the tracker.\n"
    write_text_atomic(path, header + tomli_w.dumps(document))
    return path


def load_replay(path: Path | str) -> Replay:
    """Read a replay file; a :class:`ReplayError` naming the file and key otherwise (strict types: ``seed``
    an integer, ``tracker`` and ``camera`` text, ``params`` a table, ``scores`` tables of numbers)."""
    path = Path(path)
    where = f"replay file {str(path)!r}"
    document = read_toml(path, "replay file", ReplayError)
    if "scenario" not in document or type(document.get("seed")) is not int or document["seed"] < 0:
        raise ReplayError(f"{where}: needs an integer 'seed' ≥ 0 and a [scenario] table")
    unknown = sorted(set(document) - {"seed", "tracker", "camera", "failure", "params", "scores", "scenario"})
    if unknown:
        raise ReplayError(f"{where}: {unknown[0]}: unknown key")
    for key in ("tracker", "camera", "failure"):
        if key in document and (not isinstance(document[key], str) or not document[key]):
            raise ReplayError(f"{where}: {key}: must be non-empty text, got {document[key]!r}")
    for key in ("params", "scores", "scenario"):
        if not isinstance(document.get(key, {}), dict):
            raise ReplayError(f"{where}: {key}: must be a table, got {document[key]!r}")
    for dimension, metrics in document.get("scores", {}).items():
        if dimension not in ("2d", "3d") or not isinstance(metrics, dict):
            raise ReplayError(f"{where}: scores.{dimension}: expected tables [scores.2d] / [scores.3d] of metrics")
        for metric, value in metrics.items():
            if type(value) not in (int, float) or not math.isfinite(value):
                raise ReplayError(f"{where}: scores.{dimension}.{metric}: must be a finite number, got {value!r}")
    try:
        scenario = validate_strict(Scenario, document["scenario"])
    except ValidationError as error:
        raise ReplayError(f"{where}: scenario: {describe_errors(error)}") from None
    except ValueError as error:
        raise ReplayError(f"{where}: scenario: {error}") from None
    return Replay(scenario, document["seed"], document.get("tracker"), dict(document.get("params", {})),
                  document.get("camera"), document.get("failure"), dict(document.get("scores", {})))


@dataclass(frozen=True)
class ReplayResult:
    """A rerun: its report, the recorded headline metrics and the differences (metric → (recorded, now))."""

    report: ScoreReport
    recorded: dict
    differences: dict

    @property
    def reproduced(self) -> bool:
        """Every recorded metric came out the same (:func:`replay` refuses a file that recorded none)."""
        return bool(self.recorded) and not self.differences

    def summary(self) -> str:
        if self.reproduced:
            count = sum(len(v) for v in self.recorded.values())
            return f"reproduced: all {count} recorded metrics are the same as in the failing run"
        lines = [f"  {key}: recorded {old}, now {new}" for key, (old, new) in sorted(self.differences.items())]
        return "NOT reproduced: metrics differ from the failing run\n" + "\n".join(lines)


def replay(path: Path | str, *, tracker: str | None = None, params: dict | None = None,
           out: Path | str | None = None, trust_file: bool = False) -> ReplayResult:
    """Rerun a replay file: generate its scenario with its seed (into ``out`` or a temporary folder), run its
    tracker (or ``tracker``) with its parameters (or ``params``) and compare the headline metrics.

    The file's own tracker may be a ``module:attribute`` only with ``trust_file`` (``--trust-file``): replay
    files travel with bug reports and are data. ``tracker`` given here is the caller's choice."""
    import tempfile

    from simrig.dataset import Dataset
    from simrig.pipeline.generate import generate
    from simrig.pipeline.track import run_tracker

    from ..scoring import score

    loaded = load_replay(path)
    if not any(loaded.scores.values()):
        raise ReplayError(f"replay file {str(path)!r} records no scores ([scores] is empty), so a rerun cannot be "
                          "checked against anything")
    name = tracker or loaded.tracker
    if not name:
        raise ReplayError(f"replay file {str(path)!r} names no tracker (it was an object without an importable "
                          "name); pass --tracker NAME or module:attribute")
    if tracker is None:
        try:
            check_file_reference(name, trusted=trust_file, where=f"replay file {str(path)!r}")
        except TrackerReferenceError as error:
            raise ReplayError(str(error)) from None
    if out is not None:  # it writes out/dataset and out/tracks: never into a dataset or a user's folder
        check_output_path(out, what="--out")
        check_own_folder(Path(out), what="replay folder", marker="dataset", made=("tracks",))
    with tempfile.TemporaryDirectory(prefix="simrig-replay-") as scratch:
        root = Path(out) if out is not None else Path(scratch)
        dataset = Dataset.open(generate(loaded.scenario, seed=loaded.seed, out=root / "dataset", overwrite=True).path)
        run = run_tracker(dataset, name, root / "tracks", loaded.params if params is None else params)
        report = score(dataset, run.tracks, camera=loaded.camera)
    now = _headline(report)
    differences = {}
    for dimension, metrics in loaded.scores.items():
        for metric, value in metrics.items():
            current = now.get(dimension, {}).get(metric)
            if current is None or not math.isclose(current, value, rel_tol=1e-9, abs_tol=1e-12):
                differences[f"{dimension}.{metric}"] = (value, current)
    return ReplayResult(report, loaded.scores, differences)
