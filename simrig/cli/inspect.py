"""``simrig info``, ``simrig render`` and ``simrig view``: looking at a dataset or a run."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import SimrigError
from .arguments import int_at_least, output_path


def register_info(commands) -> None:
    """``simrig info``'s options."""
    info = commands.add_parser("info", help="summarise a dataset folder")
    info.add_argument("dataset", type=Path)
    info.add_argument("--verify", action="store_true",
                      help="also check every file's SHA-256, and that the recorded scenario and seed regenerate the "
                           "opening frames")
    info.set_defaults(run=_cmd_info)


def _cmd_info(args: argparse.Namespace) -> int:
    from ..dataset import Dataset

    dataset = Dataset.open(args.dataset)
    extra = dataset.verify() if args.verify else []
    print(dataset.summary())
    if args.verify:
        from ..pipeline.reproduce import check_reproduces

        print("verified  the manifest and every file it lists match their SHA-256")
        note = check_reproduces(dataset)
        print(f"note      {note}" if note else "reproduced its scenario and seed regenerate its opening frames "
                                                "(ego poses and ground truth) byte for byte")
        if extra:
            shown = ", ".join(extra[:10]) + (f" and {len(extra) - 10} more" if len(extra) > 10 else "")
            print(f"extra     {len(extra)} file(s) not in the manifest (not part of the dataset): {shown}")
    return 0


def register_render(commands) -> None:
    """``simrig render``'s options."""
    render = commands.add_parser("render", help="a mosaic PNG of every camera and a bird's-eye view of one frame")
    render.add_argument("dataset", type=Path)
    render.add_argument("--frame", type=int_at_least(0), required=True, help="frame index")
    render.add_argument("--out", type=Path, default=None, help="PNG path (default: DIR/mosaic_FRAME.png)")
    render.add_argument("--tracks", type=Path, default=None,
                        help="also draw a tracker's boxes (a tracks folder or file, any format 'score' reads)")
    render.set_defaults(run=_cmd_render)


def _cmd_render(args: argparse.Namespace) -> int:
    from simrig.figures.mosaic import render_mosaic

    from ..dataset import Dataset
    from ..dataset.manifest import MANIFEST_NAME

    dataset = Dataset.open(args.dataset)
    if args.out is not None and args.out.suffix.lower() != ".png":
        raise SimrigError(f"--out {str(args.out)!r}: the mosaic is a PNG; name a .png file")
    out = output_path(args.out, "--out", folder=False) or Path(args.dataset) / f"mosaic_{args.frame:06d}.png"
    if out.resolve().parent == dataset.path.resolve() and (
            out.name == MANIFEST_NAME or out.name in {entry["file"] for entry in dataset.manifest["files"].values()}):
        raise SimrigError(f"--out {str(out)!r} is one of the dataset's own files; write elsewhere")
    print(render_mosaic(dataset.path, args.frame, out, tracks=args.tracks))
    return 0


def register_view(commands) -> None:
    """``simrig view``'s options."""
    view = commands.add_parser("view", help="look at a run frame by frame in rerun (the 'view' extra)")
    view.add_argument("run_dir", type=Path, help="a folder 'simrig run' wrote (or a dataset folder)")
    view.add_argument("--save", type=Path, default=None, metavar="FILE.rrd",
                      help="write a rerun recording here instead of opening the viewer")
    view.add_argument("--tracker", default=None, metavar="LABEL",
                      help="which run of RUN_DIR/tracks/ to show when it holds several")
    view.set_defaults(run=_cmd_view)


def _cmd_view(args: argparse.Namespace) -> int:
    from simrig.figures.viewer import log_run

    if args.save is not None and args.save.suffix.lower() != ".rrd":
        raise SimrigError(f"--save {str(args.save)!r}: a rerun recording is an .rrd file; name one")
    saved = log_run(args.run_dir, tracker=args.tracker, save=args.save, save_option="--save")
    print(f"wrote     {saved}" if saved is not None else "logged to a rerun viewer")
    return 0
