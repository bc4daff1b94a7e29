"""``run``: the whole bench on one scenario — generate, track, score, report — into one folder.

Layout of ``out``: ``dataset/`` (the generated dataset), ``tracks/TRACKER/`` (the tracker's output),
``score.json`` (every metric), ``errors.parquet`` (every FN/IDS/FRAG with its causes) and ``report.md``
(the score table and the command that reproduces it).
"""

from __future__ import annotations

import shlex
from dataclasses import dataclass
from pathlib import Path

from simrig.dataset import Dataset
from simrig.pipeline.generate import generate
from simrig.pipeline.track import TrackingRun, build_tracker, run_tracker
from simrig.scenarios import Scenario, load_scenario
from simrig.scoring import ScoreReport, score


@dataclass(frozen=True)
class PipelineResult:
    """What ``run_pipeline`` produced: the score report, the tracking run and every file it wrote."""

    report: ScoreReport
    tracking: TrackingRun
    written: tuple[Path, ...]


def run_pipeline(
    scenario: str | Path | Scenario,
    *,
    seed: int = 0,
    tracker: str = "saga",
    params: dict | None = None,
    out: Path | str | None = None,
    frames: int | None = None,
    overwrite: bool = False,
    progress: bool = False,
    camera: str | None = None,
    images: bool = False,
) -> PipelineResult:
    """Generate ``scenario`` with ``seed``, run ``tracker`` with ``params`` on it, score (only ``camera``, in
    2D, when given) and report. ``images``: generate a PNG per camera and frame, handed to the tracker in
    each :class:`~simrig.types.SensorFrame`'s ``images``.

    The tracker is built before generating, so a bad tracker name or parameter fails at once."""
    loaded = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    out = Path(out) if out is not None else Path("runs") / f"{loaded.name}-seed{seed}"
    build_tracker(tracker, params)  # checked early: a typo should not cost a generation
    generated = generate(loaded, seed=seed, out=out / "dataset", frames=frames, overwrite=overwrite, progress=progress,
                         images=images)
    dataset = Dataset.open(generated.path)
    tracking = run_tracker(dataset, tracker, out / "tracks" / tracker, params)
    report = score(dataset, tracking.tracks, camera=camera)  # scored in memory; the folder is for the user
    json_path, errors_path, markdown = out / "score.json", out / "errors.parquet", out / "report.md"
    report.write_json(json_path)
    report.write_errors(errors_path)
    command = _command(scenario, seed, tracker, params, out, frames, overwrite, camera, images)
    markdown.write_text(
        f"# {loaded.name}, seed {seed}, tracker {tracker}\n\n"
        f"Produced by `{command}`.\n\n"
        f"The tracker's `step()` ran at {tracking.frames_per_second:.0f} frames/s over {tracking.frames} frames.\n\n"
        f"```\n{report.table()}\n```\n"
    )
    return PipelineResult(report, tracking, (dataset.path, tracking.out, json_path, errors_path, markdown))


def _command(scenario, seed, tracker, params, out, frames, overwrite, camera=None, images=False) -> str:
    words = ["simrig", "run", str(scenario.name if isinstance(scenario, Scenario) else scenario),
             "--seed", str(seed), "--tracker", tracker]
    for key, value in (params or {}).items():
        words += ["--param", f"{key}={value}"]
    if frames is not None:
        words += ["--frames", str(frames)]
    if camera is not None:
        words += ["--camera", camera]
    words += ["--out", str(out)] + (["--overwrite"] if overwrite else []) + (["--images"] if images else [])
    return shlex.join(words)
