"""``simrig run`` and ``simrig drive``: the whole job on one scenario, open loop and closed loop."""

from __future__ import annotations

import argparse
from pathlib import Path

from simrig.scenarios import load_scenario

from .arguments import int_at_least, scenario_arguments, tracker_arguments, tracker_params, warn_if_no_tracks
from .generate import _naming_scenario_file, _warn_ineffective


def register_run(commands) -> None:
    """``simrig run``'s options."""
    run = commands.add_parser("run", help="generate a scenario, track it, score it and write a report")
    scenario_arguments(run)
    tracker_arguments(run)
    run.add_argument("--out", type=Path, default=None,
                     help="output folder (default: runs/SCENARIO-seedSEED); holds dataset/, tracks/, report.md")
    run.add_argument("--overwrite", action="store_true", help="replace a complete dataset already in OUT/dataset")
    run.add_argument("--camera", default=None, metavar="NAME", help="score only this camera, in 2D")
    run.add_argument("--images", action="store_true",
                     help="also render a PNG per camera and frame (slow); the tracker gets their paths in "
                          "SensorFrame.images")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.add_argument("--explain", action="store_true",
                     help="also split the gap to a perfect sensor among the causes (simrig explain) and add it "
                          "to report.md")
    run.add_argument("--workers", type=int_at_least(1), default=None,
                     help="processes for --explain's counterfactual runs (default: this machine's)")
    run.set_defaults(run=_cmd_run)


def register_drive(commands) -> None:
    drive = commands.add_parser(
        "drive", help="closed loop: drive the ego on a tracker's output and on the ground truth; compare outcomes")
    scenario_arguments(drive)
    tracker_arguments(drive)
    drive.add_argument("--out", type=Path, default=None,
                       help="drive folder (default: runs/drive/SCENARIO-seedSEED); holds reference/, drives/LABEL/, "
                            "report.md")
    drive.add_argument("--quiet", action="store_true", help="no progress bar")
    drive.set_defaults(run=_cmd_drive)


def _cmd_drive(args: argparse.Namespace) -> int:
    from simrig.names import path_part
    from simrig.pipeline.drive import drive_folder

    with _naming_scenario_file(args.scenario):
        scenario = load_scenario(args.scenario)
    out = args.out or Path("runs") / "drive" / f"{path_part(scenario.name, 'scenario name')}-seed{args.seed}"
    result = drive_folder(scenario, seed=args.seed, tracker=args.tracker, params=tracker_params(args.param), out=out,
                          frames=args.frames, progress=not args.quiet,
                          frame_time_limit_s=args.frame_time_limit)
    if result.reused:
        print(f"reference reusing the ground-truth drive in {result.reference.dataset}\n")
    print(result.report.read_text(encoding="utf-8"))
    print(f"wrote     {result.tracked.dataset.parent}")
    if not result.reused:
        print(f"wrote     {result.reference.dataset.parent}")
    print(f"wrote     {result.report}")
    return 0


def _cmd_run(args: argparse.Namespace) -> int:
    from simrig.pipeline.run import run_pipeline

    from ..dataset import Dataset

    with _naming_scenario_file(args.scenario):
        result = run_pipeline(
            args.scenario, seed=args.seed, tracker=args.tracker, params=tracker_params(args.param), out=args.out,
            frames=args.frames, overwrite=args.overwrite, progress=not args.quiet, camera=args.camera,
            frame_time_limit_s=args.frame_time_limit,
            images=args.images,
        )
    manifest = Dataset.open(result.dataset).manifest
    if result.reused:
        print(f"dataset   reusing the complete dataset in {result.dataset} ({manifest['scenario']['name']}, "
              f"seed {manifest['seed']}, {manifest['frames']} frames: the same resolved scenario and seed)\n")
    print(result.report.table())
    print(f"\ntracked   {result.tracking.frames} frames with {args.tracker} "
          f"({result.tracking.frames_per_second:.0f} frames/s in step())")
    for path in result.written:
        if not (result.reused and Path(path) == Path(result.dataset)):  # said above: reused, not written
            print(f"wrote     {path}")
    if not result.reused:
        _warn_ineffective(result.scenario, result.dataset)
    warn_if_no_tracks(args.tracker, result.tracking.frames, result.tracking.track_rows)
    if args.explain:
        from ..explain import add_to_run_report, explain

        explained = explain(result.dataset.parent, label=result.label, workers=args.workers,
                            trust_file=True)  # the tracker was named on this command line
        print(f"\n{explained.table}\n")
        print(f"wrote     {explained.out} ({explained.coalitions} counterfactual runs, {explained.seconds:.0f} s)")
        print(f"wrote     {add_to_run_report(result.dataset.parent, result.label, explained.document)}")
    return 0
