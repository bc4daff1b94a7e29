"""The ``simrig detector`` subcommands: ``measure`` a dataset's detector, ``fit`` a detector model."""

from __future__ import annotations

import argparse
from pathlib import Path


def _file_output(path: Path, what: str, inputs) -> None:
    """``path`` checked as a file output before any work; a symbolic link is refused (no write follows one)."""
    from ..dataset.outputs import check_output_path
    from ..errors import SimrigError

    if path.is_symlink():
        raise SimrigError(f"{what} {str(path)!r} is a symbolic link; simrig does not write through links")
    check_output_path(path, what=what, inputs=inputs, folder=False)


def _cmd_measure(args: argparse.Namespace) -> int:
    import json
    from dataclasses import asdict

    from ..dataset.outputs import write_text_atomic
    from ..detector.measure import measure, pooled_reid
    from ..detector.reid import format_table

    if args.json is not None:  # checked before any work, as every command's outputs are
        _file_output(args.json, "--json", args.dataset)
    results = [measure(path) for path in args.dataset]
    print("\n\n".join(result.table() for result in results))
    pooled = pooled_reid(args.dataset) if len(results) > 1 else None
    if pooled is not None:
        print(f"\nre-ID pooled over the {len(results)} datasets (the same number of pairs from each)")
        print(format_table(pooled))
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        document = asdict(results[0]) if pooled is None else {
            "datasets": [asdict(result) for result in results], "reid_pooled": [asdict(row) for row in pooled]}
        text = json.dumps(_json_safe(document), indent=2, allow_nan=False)  # an empty band is null, not NaN
        write_text_atomic(args.json, text + "\n")
        print(f"written to {args.json}")
    return 0


def _json_safe(value):
    """``value`` with every NaN or infinite float as None (JSON has no NaN: strict readers refuse the file)."""
    import math

    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {key: _json_safe(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(item) for item in value]
    return value


def _cmd_fit(args: argparse.Namespace) -> int:
    from ..errors import SimrigError

    # the input files must not be overwritten (a folder input may hold the output: a data root, say)
    files = [path for path in (args.embeddings, args.detections, args.truth) if path is not None and path.is_file()]
    _file_output(args.out, "--out", files)
    if args.embeddings is not None:
        from ..detector.fit_appearance import fit_embeddings_to_toml

        for name in ("detections", "truth", "cameras"):
            if getattr(args, name) is not None:
                raise SimrigError(f"--{name}: not with --embeddings (a re-ID log is fitted on its own)")
        print(fit_embeddings_to_toml(args.embeddings, args.out, args.frame_rate_hz,
                                     lookalike_weight=args.lookalike_weight, colours=args.colours))
        return 0
    if args.detections is None:
        raise SimrigError("detector fit: give --detections (a detector's output) or --embeddings (a re-ID log)")
    for name, default in (("frame_rate_hz", 10.0), ("lookalike_weight", 0.3), ("colours", 8)):
        if getattr(args, name) != default:
            raise SimrigError(f"--{name.replace('_', '-')}: only with --embeddings")
    from ..detector.fit import fit_to_toml

    print(fit_to_toml(args.detections, args.truth, args.out, args.cameras))
    return 0


def register_detector(commands) -> None:
    """Add ``detector measure`` and ``detector fit`` to the CLI's subcommands."""
    detector = commands.add_parser("detector", help="measure a dataset's detector errors or fit a detector model")
    actions = detector.add_subparsers(dest="detector_command", required=True, metavar="ACTION")
    measure = actions.add_parser("measure", help="nuScenes TP errors, recall/precision by band, autocorrelation, "
                                                 "re-ID distances by frame gap")
    measure.add_argument("dataset", type=Path, nargs="+",
                         help="dataset folder(s); with several, the re-ID table is also pooled over them")
    measure.add_argument("--json", type=Path, default=None, metavar="OUT", help="also write the numbers as JSON")
    measure.set_defaults(run=_cmd_measure)
    fit = actions.add_parser("fit", help="fit the detector model's parameters and write a [sensor] table")
    fit.add_argument("--detections", type=Path, default=None,
                     help="a simrig dataset folder, or a nuScenes detection-results JSON")
    fit.add_argument("--embeddings", type=Path, default=None, metavar="FILE",
                     help="instead: a re-ID model's log (Parquet: frame, camera, identity, embedding[, sequence]); "
                          "writes a [sensor.embedding] table")
    fit.add_argument("--frame-rate-hz", type=float, default=10.0, metavar="HZ",
                     help="with --embeddings: the log's frame rate (default 10)")
    fit.add_argument("--lookalike-weight", type=float, default=0.3, metavar="W",
                     help="with --embeddings: kept, not fitted (default 0.3, the realistic presets')")
    fit.add_argument("--colours", type=int, default=8, metavar="N",
                     help="with --embeddings: kept, not fitted (default 8)")
    fit.add_argument("--truth", type=Path, default=None,
                     help="ground truth of a detection-results JSON: the nuScenes tables folder (or the data "
                          "root above it) or a simrig dataset (leave out for a simrig dataset's own detections)")
    fit.add_argument("--cameras", type=int, default=None, metavar="N",
                     help="cameras of the rig the fitted model runs on: a JSON's clutter per sample is divided "
                          "by N (default 6, nuScenes)")
    fit.add_argument("--out", type=Path, required=True, help="the TOML file to write")
    fit.set_defaults(run=_cmd_fit)
