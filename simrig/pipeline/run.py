"""``run``: the whole bench on one scenario — generate, track, score, report — into one folder, resumable.

Layout of ``out``: :mod:`simrig.dataset.run_folder`.

Resumable and reproducible: a complete dataset already in ``out/dataset`` that matches the resolved scenario,
seed and frame count is reused (and said so), so a second tracker, or a rerun after a kill, does not generate
again; one that does not match is refused unless ``overwrite``. Tracking and scoring always run (they are
deterministic and cheap next to generation) and every file is written atomically, so a rerun after a kill at any
moment writes the same bytes as an uninterrupted run.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import re
import shlex
import time
from dataclasses import dataclass
from pathlib import Path

from simrig.dataset import Dataset
from simrig.dataset.manifest import read_manifest, write_json_atomic
from simrig.dataset.outputs import atomic_file, check_output_path, check_own_folder, write_text_atomic
from simrig.dataset.run_folder import DATASET_DIR, REPORT, SCORES_DIR, TRACKER_RECORD, TRACKS_DIR, what_folder_holds
from simrig.errors import DatasetError, DatasetExistsError
from simrig.names import path_part
from simrig.pipeline.generate import generate
from simrig.pipeline.guard import FRAME_TIME_LIMIT_S
from simrig.pipeline.track import (
    TrackingError,
    TrackingRun,
    build_tracker,
    run_tracker,
    tracker_display,
    tracker_reference,
)
from simrig.rig import build_rig
from simrig.scenarios import Scenario, load_scenario
from simrig.scoring import ScoreReport, score


@dataclass(frozen=True)
class PipelineResult:
    """What ``run_pipeline`` produced: the score report, the tracking run, every file it wrote, the scenario,
    the dataset folder, whether that dataset was reused from an earlier run, and the run's label."""

    report: ScoreReport
    tracking: TrackingRun
    written: tuple[Path, ...]
    scenario: Scenario
    dataset: Path
    reused: bool
    label: str


LABEL_LIMIT = 80
"""[characters] a run label longer than this keeps the tracker's name and the key alone."""


def run_label(tracker: str, params: dict | None, camera: str | None) -> str:
    """The folder name of a tracker run: the tracker's name, then each parameter as ``KEY=VALUE`` and the
    camera (characters other than letters, digits, ``_.=-`` replaced), then an 8-digit key of the parameters and
    camera, which keeps two runs apart whose readable parts look alike; past :data:`LABEL_LIMIT` characters,
    the name and the key alone.

    >>> run_label("saga", None, None), run_label("saga", {"gate": 4}, None)
    ('saga', 'saga-gate=4-fb0d72d1')
    """
    name = re.sub(r"[^\w.-]", "_", tracker)
    if not params and camera is None:
        return name
    identity = json.dumps({"params": params or {}, "camera": camera}, sort_keys=True, default=str)
    key = hashlib.sha256(identity.encode()).hexdigest()[:8]
    readable = [f"{k}={v}" for k, v in sorted((params or {}).items())] + ([f"camera={camera}"] if camera else [])
    label = re.sub(r"[^\w.=-]", "_", "-".join([name, *readable, key]))
    return label if len(label) <= LABEL_LIMIT else f"{name}-{key}"


def _matching_dataset(folder: Path, scenario: Scenario, seed: int, frames: int) -> bool | None:
    """Whether ``folder`` holds a complete dataset of exactly (``scenario``, ``seed``, ``frames``); None when it
    holds no complete dataset."""
    if not folder.is_dir():
        return None
    try:
        manifest = read_manifest(folder)
    except DatasetError:  # a damaged dataset, or one from an older simrig: never reused
        return False
    if manifest is None:
        return None
    return (manifest["scenario"] == scenario.model_dump(mode="json") and manifest["seed"] == seed
            and manifest["frames"] == frames)


def run_pipeline(
    scenario: str | Path | Scenario,
    *,
    seed: int = 0,
    tracker="saga",
    params: dict | None = None,
    out: Path | str | None = None,
    frames: int | None = None,
    overwrite: bool = False,
    progress: bool = False,
    camera: str | None = None,
    frame_time_limit_s: float | None = FRAME_TIME_LIMIT_S,
    images: bool = False,
) -> PipelineResult:
    """Generate ``scenario`` with ``seed`` (or reuse the matching complete dataset in ``out/dataset``), run
    ``tracker`` with ``params`` on it, score (only ``camera``, in 2D, when given) and report. ``images``: the
    dataset has a PNG per camera and frame, handed to the tracker in each
    :class:`~simrig.types.SensorFrame`'s ``images`` (a reused dataset without images is generated again).

    The tracker is built before generating, so a bad tracker name or parameter fails at once. ``overwrite``
    regenerates the dataset even when it matches (and replaces one that does not)."""
    loaded = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    out = Path(out) if out is not None else Path("runs") / f"{path_part(loaded.name, 'scenario name')}-seed{seed}"
    check_output_path(out, what="--out")
    check_own_folder(out, what="run folder", marker=DATASET_DIR,  # a run writes its dataset first
                     hint=what_folder_holds(out) if out.is_dir() else "")
    build_tracker(tracker, params)  # checked early: a typo should not cost a generation
    if camera is not None:  # and the camera too: the rig is known before anything is generated
        cameras = build_rig(loaded.rig).camera_names
        if camera not in cameras:
            raise TrackingError(f"--camera {camera!r}: scenario {loaded.name!r}'s rig has cameras "
                                f"{', '.join(cameras)}")
    folder = out / DATASET_DIR
    reused, generation_s = _dataset_for(loaded, seed, out, frames, overwrite, progress, images)
    dataset = Dataset.open(folder)
    reference = tracker if isinstance(tracker, str) else tracker_reference(tracker)
    label = run_label(reference or tracker_display(tracker), params, camera)
    tracking = run_tracker(dataset, tracker, out / TRACKS_DIR / label, params, frame_time_limit_s=frame_time_limit_s)
    _record_tracker(tracking.out, tracker, params, camera)
    report = score(dataset, tracking.tracks, camera=camera)  # scored in memory; the folder is for the user
    report = dataclasses.replace(report, dataset=DATASET_DIR, tracks=f"{TRACKS_DIR}/{label}")  # relative to out
    command = command_line(scenario, seed, reference or tracker_display(tracker), params, frames, camera, images)
    scores = out / SCORES_DIR / label
    written = _write_scores(report, scores, f"## {loaded.name}, seed {seed}, tracker {tracker}", command)
    write_json_atomic(scores / "timings.json", {
        "generation_s": generation_s, "dataset_reused": reused, "frames": tracking.frames,
        "step_s": tracking.step_seconds, "step_frames_per_second": tracking.frames_per_second})
    index = write_index(out)
    return PipelineResult(report, tracking, (folder, tracking.out, *written, index), loaded, folder, reused, label)


def _dataset_for(loaded: Scenario, seed: int, out: Path, frames: int | None, overwrite: bool, progress: bool,
                 images: bool) -> tuple[bool, float | None]:
    """Make ``out/dataset`` hold ``loaded`` at ``seed``: (whether a matching complete dataset was reused, the
    generation's seconds or ``None``). One of another scenario, seed or frame count, or without the ``images``
    asked for, is replaced only with ``overwrite``; a run folder this call made is removed again if generation
    fails before writing into it."""
    folder = out / DATASET_DIR
    matches = _matching_dataset(folder, loaded, seed, loaded.frames if frames is None else frames)
    if matches and images and Dataset.open(folder).image_folder is None:
        matches = False  # the same world, but without the images this run asks for
    if matches and not overwrite:
        return True, None
    if matches is False and not overwrite:
        manifest = read_manifest(folder)  # a damaged one raises its own one-line error here
        raise DatasetExistsError(
            f"{str(folder)!r} holds a dataset of another scenario, seed or frame count, or without images "
            f"({manifest['scenario']['name']}, seed {manifest['seed']}, {manifest['frames']} frames"
            f"{', no images' if images else ''}); "
            "pass --overwrite to replace it or choose another --out")
    started = time.perf_counter()
    existed = out.exists()
    try:
        generate(loaded, seed=seed, out=folder, frames=frames, overwrite=overwrite, progress=progress, images=images)
    except BaseException:
        if not existed and out.is_dir() and not any(out.iterdir()):  # a run folder this call made, still empty
            out.rmdir()
        raise
    return False, time.perf_counter() - started


def _write_scores(report, scores: Path, heading: str, command: str) -> tuple[Path, ...]:
    """``score.json``, ``errors.parquet``, ``plan.parquet`` (when the report has a plan; an earlier run's is
    removed otherwise) and ``report.md`` in ``scores``, each atomically; the paths written, in that order."""
    scores.mkdir(parents=True, exist_ok=True)
    json_path, errors_path, markdown = scores / "score.json", scores / "errors.parquet", scores / REPORT
    write_text_atomic(json_path, json.dumps(report.to_dict(), indent=2) + "\n")
    with atomic_file(errors_path) as partial:
        report.write_errors(partial)
    plan_path = scores / "plan.parquet"
    if report.plan is not None:
        report.write_plan(plan_path)
    elif plan_path.is_file():  # an earlier run's plan, of a tracker run that now has none
        plan_path.unlink()
    write_text_atomic(markdown, f"{heading}\n\nProduced by `{command}`.\n\n```\n{report.table()}\n```\n")
    planned = (plan_path,) if report.plan is not None else ()
    return (json_path, errors_path, *planned, markdown)


def _record_tracker(folder: Path, tracker, params: dict | None, camera: str | None) -> None:
    """``folder/tracker.json``: what rebuilds the tracker (``simrig explain`` reruns it). A tracker object or
    factory passed in Python, or parameters JSON cannot hold, cannot be named in a file: no record then (and
    any older one is removed)."""
    record = folder / TRACKER_RECORD
    try:
        text = json.dumps({"tracker": tracker, "params": params or {}, "camera": camera}, allow_nan=False)
    except (TypeError, ValueError):
        text = None
    if not isinstance(tracker, str) or text is None:
        record.unlink(missing_ok=True)
        return
    write_json_atomic(record, json.loads(text))


def write_index(out: Path) -> Path:
    """Rewrite ``out/report.md`` from the run sections in ``out/scores/*/report.md``."""
    index = out / REPORT
    write_text_atomic(index, _index(out))
    return index


def _index(out: Path) -> str:
    """``out/report.md``: every tracker run in ``out``, one section each, sorted by label."""
    sections = [path.read_text(encoding="utf-8") for path in sorted((out / SCORES_DIR).glob(f"*/{REPORT}"))]
    return (f"# Tracker runs in this folder ({len(sections)})\n\nThe dataset in `{DATASET_DIR}/` is shared; each "
            f"run's tracks are in `{TRACKS_DIR}/LABEL/`, its scores in `{SCORES_DIR}/LABEL/`.\n\n"
            + "\n".join(sections))


def command_line(scenario, seed, tracker, params, frames, camera=None, images=False, verb: str = "run") -> str:
    """The command that reproduces a run (or a ``drive``: ``verb``), with ``--out`` left for the reader (no path in
    a results file)."""
    words = ["simrig", verb, str(scenario.name if isinstance(scenario, Scenario) else scenario),
             "--seed", str(seed), "--tracker", tracker]
    for key, value in (params or {}).items():
        words += ["--param", f"{key}={value}"]
    if frames is not None:
        words += ["--frames", str(frames)]
    if camera is not None:
        words += ["--camera", camera]
    if images:
        words += ["--images"]
    return shlex.join(words) + " --out THIS_FOLDER"
