"""The ``simrig detector`` subcommands: ``measure`` a dataset's detector, ``fit`` a detector model."""

from __future__ import annotations

import argparse
from pathlib import Path


def _cmd_measure(args: argparse.Namespace) -> int:
    from .measure import measure

    result = measure(args.dataset)
    print(result.table())
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(result.to_json() + "\n", encoding="utf-8")
        print(f"written to {args.json}")
    return 0


def _cmd_fit(args: argparse.Namespace) -> int:
    from .fit import fit_to_toml

    print(fit_to_toml(args.detections, args.truth, args.out, args.cameras))
    return 0


def add_detector_command(commands) -> None:
    """Add ``detector measure`` and ``detector fit`` to the CLI's subcommands."""
    detector = commands.add_parser("detector", help="measure a dataset's detector errors or fit a detector model")
    actions = detector.add_subparsers(dest="detector_command", required=True, metavar="ACTION")
    measure = actions.add_parser("measure", help="nuScenes TP errors, recall/precision by band, autocorrelation")
    measure.add_argument("dataset", type=Path)
    measure.add_argument("--json", type=Path, default=None, metavar="OUT", help="also write the numbers as JSON")
    measure.set_defaults(run=_cmd_measure)
    fit = actions.add_parser("fit", help="fit the detector model's parameters and write a [sensor] table")
    fit.add_argument("--detections", type=Path, required=True,
                     help="a simrig dataset folder, or a nuScenes detection-results JSON")
    fit.add_argument("--truth", type=Path, default=None,
                     help="ground truth of a detection-results JSON: the nuScenes tables folder (or the data "
                          "root above it) or a simrig dataset (leave out for a simrig dataset's own detections)")
    fit.add_argument("--cameras", type=int, default=None, metavar="N",
                     help="cameras of the rig the fitted model runs on: a JSON's clutter per sample is divided "
                          "by N (default 6, nuScenes)")
    fit.add_argument("--out", type=Path, required=True, help="the TOML file to write")
    fit.set_defaults(run=_cmd_fit)
