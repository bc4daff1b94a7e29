"""``simrig score`` and ``simrig track``: a tracker's output scored, a tracker run over a dataset."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import SimrigError
from .arguments import (
    non_negative_float,
    output_path,
    tracker_arguments,
    tracker_param,
    tracker_params,
    warn_if_no_tracks,
)


def register_score(commands) -> None:
    """``simrig score``'s options."""
    scorer = commands.add_parser("score", help="score a tracker's output (tracks folder or file) on a dataset")
    scorer.add_argument("dataset", type=Path)
    scorer.add_argument("tracks", type=Path, help="folder with tracks3d.parquet / tracks2d.parquet, or one file; "
                        "or MOTChallenge, KITTI or nuScenes files (see --format)")
    scorer.add_argument("--format", default=None, choices=("simrig", "motchallenge", "kitti", "nuscenes"),
                        help="the tracks' format (default: detected; MOTChallenge/KITTI: CAMERA.txt files or an "
                             "export folder; nuScenes: a results .json)")
    scorer.add_argument("--json", type=Path, default=None, help="also write every metric as JSON here")
    scorer.add_argument("--errors", type=Path, default=None,
                        help="also write every FN / IDS / FRAG with its causes as Parquet here")
    scorer.add_argument("--lookback", type=non_negative_float, default=1.0,
                        help="[s] an ID switch is also tagged with the causes this long before it (default 1)")
    scorer.add_argument("--camera", default=None, metavar="NAME",
                        help="score only this camera, in 2D (e.g. a stereo pair's ego camera 'left')")
    scorer.add_argument("--evaluation", type=tracker_param, action="append", metavar="KEY=VALUE",
                        help="an [evaluation] key on top of the dataset's (e.g. min_height_px=40, range_m.car=60, "
                             "ignore=false, classes=any); repeatable")
    scorer.add_argument("--interpolation", choices=("devkit", "corrected", "none"), default="devkit",
                        help="fill the gaps inside 3D tracks before the AMOTA family: devkit (default: the nuScenes "
                             "devkit 1.2.0 as shipped, its inverted weights included), corrected (linear) or none")
    scorer.add_argument("--no-planner", dest="planner", action="store_false",
                        help="do not ask the ego's planner: the planner-aware scores and each miss's consequence are "
                             "left out (reported as not asked)")
    scorer.set_defaults(run=_cmd_score)


def _cmd_score(args: argparse.Namespace) -> int:
    from simrig.formats.evaluation import evaluation_overrides

    from ..scoring import score

    for option in ("json", "errors"):
        output_path(getattr(args, option), f"--{option}", inputs=(args.dataset, args.tracks), folder=False)
    report = score(args.dataset, args.tracks, lookback_s=args.lookback, camera=args.camera,
                   evaluation=evaluation_overrides(args.evaluation), fmt=args.format, interpolation=args.interpolation,
                   planner=args.planner)
    print(report.table())
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        report.write_json(args.json)
        print(f"wrote {args.json}")
    if args.errors is not None:
        args.errors.parent.mkdir(parents=True, exist_ok=True)
        report.write_errors(args.errors)
        print(f"wrote {args.errors} ({report.errors.num_rows} errors with their causes)")
    return 0


def register_track(commands) -> None:
    """``simrig track``'s options."""
    track = commands.add_parser("track", help="run a registered tracker over a dataset and write its tracks")
    track.add_argument("dataset", type=Path)
    tracker_arguments(track)
    track.add_argument("--out", type=Path, required=True, help="tracks folder to write")
    track.add_argument("--overwrite", action="store_true", help="replace the tracks already in --out")
    track.add_argument("--images", action="store_true",
                       help="the tracker needs images: fail unless the dataset has them (SensorFrame.images)")
    track.set_defaults(run=_cmd_track)


def _cmd_track(args: argparse.Namespace) -> int:
    from simrig.pipeline.track import run_tracker

    from ..dataset import Dataset

    output_path(args.out, "--out", inputs=(args.dataset,))
    from ..dataset.tracks_file import TRACKS2D_FILE, TRACKS3D_FILE

    held = [name for name in (TRACKS3D_FILE, TRACKS2D_FILE) if (args.out / name).exists()]
    if held and not args.overwrite:
        raise SimrigError(f"--out {str(args.out)!r} already holds tracks ({', '.join(held)}); pass --overwrite to "
                          "replace them or choose another folder")
    dataset = Dataset.open(args.dataset)
    if args.images and dataset.image_folder is None:
        raise SimrigError(f"--images: {args.dataset} has no images (generate it with --images)")
    result = run_tracker(dataset, args.tracker, args.out, tracker_params(args.param),
                         frame_time_limit_s=args.frame_time_limit)
    print(
        f"tracked   {result.frames} frames with {args.tracker}: {result.track_rows} track rows, "
        f"{result.frames_per_second:.0f} frames/s in step()"
    )
    print(f"wrote     {result.out}")
    warn_if_no_tracks(args.tracker, result.frames, result.track_rows)
    return 0
