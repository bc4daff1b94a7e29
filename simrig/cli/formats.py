"""``simrig export`` and ``simrig import``: datasets and tracks in other tools' formats."""

from __future__ import annotations

import argparse
from pathlib import Path

from .arguments import tracker_param


def register_export(commands) -> None:
    """``simrig export``'s options."""
    exporter = commands.add_parser("export", help="write a dataset (and a tracker's output) for other tools")
    exporter.add_argument("dataset", type=Path)
    exporter.add_argument("--format", required=True, choices=("motchallenge", "kitti", "nuscenes"))
    exporter.add_argument("--tracks", type=Path, default=None, help="a tracks folder or file to export too")
    exporter.add_argument("--out", type=Path, required=True, help="folder to write (must not exist)")
    exporter.add_argument("--overwrite", action="store_true", help="replace OUT if it exists")
    exporter.add_argument("--evaluation", type=tracker_param, action="append", metavar="KEY=VALUE",
                          help="an [evaluation] key, as for score: the ignored ground truth is written as distractors")
    exporter.set_defaults(run=_cmd_export)


def _cmd_export(args: argparse.Namespace) -> int:
    from simrig.formats.evaluation import evaluation_overrides
    from simrig.formats.export import export

    out = export(args.dataset, args.format, args.out, tracks=args.tracks, overwrite=args.overwrite,
                 evaluation=evaluation_overrides(args.evaluation))
    print(f"wrote {out} ({args.format})")
    return 0


def register_import(commands) -> None:
    """``simrig import``'s options."""
    importer = commands.add_parser("import", help="make a dataset of ground truth from MOTChallenge, KITTI or nuScenes")
    importer.add_argument("src", type=Path, help="MOTChallenge: a sequence, benchmark or TrackEval folder; KITTI: a "
                          "label_02 folder (or an export's); nuScenes: the folder of the version's tables")
    importer.add_argument("--format", required=True, choices=("motchallenge", "kitti", "nuscenes"))
    importer.add_argument("--out", type=Path, required=True, help="dataset folder to write")
    importer.add_argument("--overwrite", action="store_true", help="replace a dataset already in --out")
    importer.set_defaults(run=_cmd_import)


def _cmd_import(args: argparse.Namespace) -> int:
    from simrig.formats.importing import import_dataset

    from ..dataset import Dataset

    import_dataset(args.format, args.src, args.out, overwrite=args.overwrite)
    print(Dataset.open(args.out).summary())
    return 0
