"""The ``simrig`` command line.

Every user error (a bad scenario, a bad argument, an output folder that holds a dataset) is printed as one
line ``simrig: error: ...`` with exit status 2; no traceback.
"""

from __future__ import annotations

import time

STARTED = time.perf_counter()
"""When this module began loading: the start of the simrig command's own work (the interpreter's start-up
before it, tens of milliseconds, is the only part of the process a printed time leaves out)."""

import argparse  # noqa: E402
import contextlib  # noqa: E402
import math  # noqa: E402
import os  # noqa: E402
import sys  # noqa: E402
from pathlib import Path  # noqa: E402

from simrig.scenarios import DEFAULT_SCENARIO, MAX_FRAMES, ScenarioError, catalog, load_scenario  # noqa: E402

from .errors import SimrigError  # noqa: E402
from .interrupts import interrupted, noting_interrupts  # noqa: E402

"""The most frames a scenario may ask for (``scenarios.schema.Scenario.frames``)."""
EXPLAIN_MAX_SAMPLES = 10_000
"""The most permutations ``--samples`` / ``--explain-samples`` may ask for (``simrig.explain.api.MAX_SAMPLES``,
repeated here so that parsing the options imports nothing heavy)."""


def _int_at_least(minimum: int, maximum: int = 2**63 - 1):
    """An argparse type: an integer in ``minimum … maximum``, with a one-line message otherwise."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be at least {minimum}, got {value}")
        if value > maximum:
            raise argparse.ArgumentTypeError(f"must be at most {maximum}, got {text}")
        return value

    return parse


class _OneLineParser(argparse.ArgumentParser):
    """argparse, but a usage error is one line naming the argument (``--help`` still shows the usage)."""

    def error(self, message: str):
        self.exit(2, f"simrig: error: {message} (see '{self.prog} --help')\n")


def _output(path: Path | None, what: str, *, inputs=(), folder: bool = True) -> Path | None:
    """``path`` checked as an output before any work (:func:`simrig.dataset.outputs.check_output_path`)."""
    if path is None:
        return None
    from .dataset.outputs import check_output_path

    return check_output_path(path, what=what, inputs=inputs, folder=folder)


def _register_generate(commands) -> None:
    """``simrig generate``'s options."""
    from simrig.benchmark.engine_names import ENGINES
    from simrig.scenarios import MAX_SEQUENCES, space_catalog

    gen = commands.add_parser("generate", help="generate a dataset from a scenario, or a collection from a space")
    _scenario_arguments(gen, default=None)
    gen.add_argument("--out", type=Path, required=True, help="output dataset folder (a collection's folder with "
                     "--space)")
    gen.add_argument("--overwrite", action="store_true", help="replace a complete dataset already in --out")
    gen.add_argument("--images", action="store_true", help="also write a PNG per camera and frame (slow)")
    gen.add_argument("--quiet", action="store_true", help="no progress bar")
    collection = gen.add_argument_group(
        "collection", "with --space: COUNT sequences sampled from a space into one folder with an index table; "
        "--seed is the collection's seed; a rerun resumes")
    collection.add_argument("--space", default=None, help=f"named space ({', '.join(space_catalog())}) or a space "
                            ".toml file (the format simrig search reads)")
    collection.add_argument("--count", type=_int_at_least(1, MAX_SEQUENCES), default=None, metavar="N",
                            help="sequences to sample")
    collection.add_argument("--shard-size", type=_int_at_least(1, MAX_SEQUENCES), default=100, metavar="K",
                            help="sequences per shard folder (default 100)")
    collection.add_argument("--engine", choices=ENGINES, default="local",
                            help="local: a process pool (default); ray: Ray tasks (the 'ray' extra)")
    collection.add_argument("--workers", type=_int_at_least(1), default=None,
                            help="processes (local) or CPUs of the local Ray instance (default: this machine's)")
    collection.add_argument("--address", default=None, help="Ray cluster to join (default: start a local instance)")
    gen.set_defaults(run=_cmd_generate)


COLLECTION_ONLY = ("count", "engine", "workers", "address")
SCENARIO_ONLY = ("scenario", "frames", "overwrite", "images")


def _check_generate_options(args: argparse.Namespace) -> None:
    """Options of one dataset and of a collection are not mixed: each mistake is one line."""
    defaults = {"engine": "local", "overwrite": False, "images": False}
    if args.space is None:
        given = [name for name in COLLECTION_ONLY if getattr(args, name) != defaults.get(name)]
        if args.shard_size != 100:
            given.append("shard_size")
        if given:
            raise SimrigError(f"--{given[0].replace('_', '-')}: only with --space SPACE (a collection)")
        return
    if args.count is None:
        raise SimrigError("--space: give --count N, the number of sequences to sample")
    for name in SCENARIO_ONLY:
        if getattr(args, name) != defaults.get(name):
            option = {"scenario": "a scenario", "frames": "--frames (set frames in the space file)",
                      "overwrite": "--overwrite (a collection resumes; remove its folder to start again)",
                      "images": "--images"}[name]
            raise SimrigError(f"--space: not with {option}")


def _cmd_generate_collection(args: argparse.Namespace) -> int:
    from .collection import generate_collection, load_generation_space
    from .collection.run import CollectionInterrupted

    space = load_generation_space(args.space)
    if space.ignored:
        print(f"note      the space's {', '.join(space.ignored)} are a search's; generate ignores them",
              file=sys.stderr)
    started = time.perf_counter()
    try:
        result = generate_collection(space, count=args.count, out=args.out, seed=args.seed,
                                     shard_size=args.shard_size, engine=args.engine, workers=args.workers,
                                     address=args.address, progress=not args.quiet)
    except CollectionInterrupted as stop:
        print(f"simrig: {stop.message()}", file=sys.stderr)
        return 130
    seconds = time.perf_counter() - started
    rate = f" ({60 * result.made / max(seconds, 1e-9):.1f} sequences/min made)" if result.made else ""
    print(f"collection {result.out}: {result.sequences} sequences ({result.kept} finished earlier, {result.made} "
          f"made now) in {seconds:.1f} s{rate}")
    print(f"index      {result.index}")
    return 0


def _cmd_generate(args: argparse.Namespace) -> int:
    _check_generate_options(args)
    if args.space is not None:
        return _cmd_generate_collection(args)
    from simrig.pipeline.generate import generate

    from .dataset import Dataset

    args.scenario = DEFAULT_SCENARIO if args.scenario is None else args.scenario
    with _naming_scenario_file(args.scenario):
        scenario = load_scenario(args.scenario)
        result = generate(
            scenario,
            seed=args.seed,
            out=args.out,
            frames=args.frames,
            overwrite=args.overwrite,
            images=args.images,
            progress=not args.quiet,
        )
    print(Dataset.open(result.path).summary())
    times = result.times
    process = time.perf_counter() - STARTED
    print(
        f"time      {process:.1f} s in all: start-up (imports, scenario) {process - times.total:.1f} s, "
        f"generation {times.total:.1f} s — traffic {times.traffic:.1f} s, projection {times.projection:.1f} s, "
        f"visibility {times.visibility:.1f} s, sensor {times.sensor:.1f} s, plans {times.planning:.1f} s, "
        f"images {times.images:.1f} s, "
        f"writing {times.writing:.1f} s ({result.manifest['frames'] / times.total:.1f} frames/s)"
    )
    for event in result.manifest["events"]:
        if event["event"] in ("ego_crashed", "env_terminated"):
            print(
                f"warning: {event['event']} at frame {event['frame']}; the scenario ran on to its last frame",
                file=sys.stderr,
            )
    _warn_ineffective(scenario, result.path)
    return 0


@contextlib.contextmanager
def _naming_scenario_file(name_or_path: str):
    """A :class:`ScenarioError` raised while a scenario file is used — not only while it is read, e.g. a
    perturbation naming a camera its rig lacks, found when the rig is built — names the file."""
    try:
        yield
    except ScenarioError as error:
        text = str(error)
        if Path(str(name_or_path)).suffix == ".toml" and not text.startswith("scenario file "):
            raise ScenarioError(f"scenario file {str(name_or_path)!r}: {text}") from None
        raise


def _warn_ineffective(scenario, dataset_path: Path) -> None:
    """``warning: ...`` on stderr for every setting that could not take effect in the generated dataset."""
    from simrig.pipeline.checks import ineffective_settings

    from .dataset import Dataset

    for message in ineffective_settings(scenario, Dataset.open(dataset_path)):
        print(f"warning: {message}", file=sys.stderr)


def _register_scenarios(commands) -> None:
    """``simrig scenarios``'s options."""
    scen = commands.add_parser("scenarios", help="list the scenario catalog")
    scen.set_defaults(run=_cmd_scenarios)


def _cmd_scenarios(args: argparse.Namespace) -> int:
    entries = catalog()
    width = max(len(name) for name in entries)
    for name in entries:
        scenario = load_scenario(name)
        marker = "*" if name == DEFAULT_SCENARIO else " "
        print(f"{marker} {name:<{width}}  {scenario.description}")
    print(f"(* default; {len(entries)} scenarios in {Path(next(iter(entries.values()))).parent})")
    return 0


def _register_info(commands) -> None:
    """``simrig info``'s options."""
    info = commands.add_parser("info", help="summarise a dataset folder")
    info.add_argument("dataset", type=Path)
    info.add_argument("--verify", action="store_true", help="also check every file's SHA-256")
    info.set_defaults(run=_cmd_info)


def _cmd_info(args: argparse.Namespace) -> int:
    from .dataset import Dataset

    dataset = Dataset.open(args.dataset)
    extra = dataset.verify() if args.verify else []
    print(dataset.summary())
    if args.verify:
        print("verified  the manifest and every file it lists match their SHA-256")
        if extra:
            shown = ", ".join(extra[:10]) + (f" and {len(extra) - 10} more" if len(extra) > 10 else "")
            print(f"extra     {len(extra)} file(s) not in the manifest (not part of the dataset): {shown}")
    return 0


def _register_render(commands) -> None:
    """``simrig render``'s options."""
    render = commands.add_parser("render", help="a mosaic PNG of every camera and a bird's-eye view of one frame")
    render.add_argument("dataset", type=Path)
    render.add_argument("--frame", type=_int_at_least(0), required=True, help="frame index")
    render.add_argument("--out", type=Path, default=None, help="PNG path (default: DIR/mosaic_FRAME.png)")
    render.add_argument("--tracks", type=Path, default=None,
                        help="also draw a tracker's boxes (a tracks folder or file, any format 'score' reads)")
    render.set_defaults(run=_cmd_render)


def _cmd_render(args: argparse.Namespace) -> int:
    from simrig.figures.mosaic import render_mosaic

    from .dataset import Dataset
    from .dataset.manifest import MANIFEST_NAME

    dataset = Dataset.open(args.dataset)
    if args.out is not None and args.out.suffix.lower() != ".png":
        raise SimrigError(f"--out {str(args.out)!r}: the mosaic is a PNG; name a .png file")
    out = _output(args.out, "--out", folder=False) or Path(args.dataset) / f"mosaic_{args.frame:06d}.png"
    if out.resolve().parent == dataset.path.resolve() and (
            out.name == MANIFEST_NAME or out.name in {entry["file"] for entry in dataset.manifest["files"].values()}):
        raise SimrigError(f"--out {str(out)!r} is one of the dataset's own files; write elsewhere")
    print(render_mosaic(dataset.path, args.frame, out, tracks=args.tracks))
    return 0


def _register_view(commands) -> None:
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


def _register_replay(commands) -> None:
    """``simrig replay``'s options."""
    replay = commands.add_parser("replay", help="rerun a replay file (a failing test's scenario) and compare")
    replay.add_argument("file", type=Path)
    replay.add_argument("--tracker", default=None, help="registered name or module:attribute (default: the file's)")
    replay.add_argument("--param", type=_tracker_param, action="append", metavar="KEY=VALUE",
                        help="a tracker parameter, repeatable (default: the file's)")
    replay.add_argument("--out", type=Path, default=None, help="keep the dataset and tracks here (default: temporary)")
    _trust_argument(replay, "the replay file")
    replay.set_defaults(run=_cmd_replay)


def _cmd_replay(args: argparse.Namespace) -> int:
    from .testing.replay import replay

    result = replay(args.file, tracker=args.tracker, params=_params(args.param) if args.param else None, out=args.out,
                    trust_file=args.trust_file)
    print(result.report.table())
    print()
    print(result.summary())
    return 0 if result.reproduced else 1


def _register_export(commands) -> None:
    """``simrig export``'s options."""
    exporter = commands.add_parser("export", help="write a dataset (and a tracker's output) for other tools")
    exporter.add_argument("dataset", type=Path)
    exporter.add_argument("--format", required=True, choices=("motchallenge", "kitti", "nuscenes"))
    exporter.add_argument("--tracks", type=Path, default=None, help="a tracks folder or file to export too")
    exporter.add_argument("--out", type=Path, required=True, help="folder to write (must not exist)")
    exporter.add_argument("--overwrite", action="store_true", help="replace OUT if it exists")
    exporter.add_argument("--evaluation", type=_tracker_param, action="append", metavar="KEY=VALUE",
                          help="an [evaluation] key, as for score: the ignored ground truth is written as distractors")
    exporter.set_defaults(run=_cmd_export)


def _cmd_export(args: argparse.Namespace) -> int:
    from simrig.formats.evaluation import evaluation_overrides
    from simrig.formats.export import export

    out = export(args.dataset, args.format, args.out, tracks=args.tracks, overwrite=args.overwrite,
                 evaluation=evaluation_overrides(args.evaluation))
    print(f"wrote {out} ({args.format})")
    return 0


def _register_import(commands) -> None:
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

    from .dataset import Dataset

    import_dataset(args.format, args.src, args.out, overwrite=args.overwrite)
    print(Dataset.open(args.out).summary())
    return 0


def _register_score(commands) -> None:
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
    scorer.add_argument("--lookback", type=_non_negative_float, default=1.0,
                        help="[s] an ID switch is also tagged with the causes this long before it (default 1)")
    scorer.add_argument("--camera", default=None, metavar="NAME",
                        help="score only this camera, in 2D (e.g. a stereo pair's ego camera 'left')")
    scorer.add_argument("--evaluation", type=_tracker_param, action="append", metavar="KEY=VALUE",
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

    from .scoring import score

    for option in ("json", "errors"):
        _output(getattr(args, option), f"--{option}", inputs=(args.dataset, args.tracks), folder=False)
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


def _tracker_param(text: str) -> tuple[str, object]:
    """An argparse type for ``--param key=value``: the value becomes an int, a float, a bool
    (``true``/``false``) or stays a string."""
    key, sep, raw = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"expected key=value, got {text!r}")
    for convert in (int, float):
        try:
            value = convert(raw)
        except ValueError:
            continue
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"{key}={raw}: a parameter must be a finite number")
        return key, value
    lowered = raw.lower()
    if lowered in ("true", "false"):
        return key, lowered == "true"
    return key, raw


def _params(pairs: list[tuple[str, object]] | None) -> dict[str, object]:
    params: dict[str, object] = {}
    for key, value in pairs or []:
        if key in params:
            raise SimrigError(f"--param {key} given twice")
        params[key] = value
    return params


def _register_track(commands) -> None:
    """``simrig track``'s options."""
    track = commands.add_parser("track", help="run a registered tracker over a dataset and write its tracks")
    track.add_argument("dataset", type=Path)
    _tracker_arguments(track)
    track.add_argument("--out", type=Path, required=True, help="tracks folder to write")
    track.add_argument("--overwrite", action="store_true", help="replace the tracks already in --out")
    track.add_argument("--images", action="store_true",
                       help="the tracker needs images: fail unless the dataset has them (SensorFrame.images)")
    track.set_defaults(run=_cmd_track)


def _cmd_track(args: argparse.Namespace) -> int:
    from simrig.pipeline.track import run_tracker

    from .dataset import Dataset

    _output(args.out, "--out", inputs=(args.dataset,))
    from .dataset.tracks_file import TRACKS2D_FILE, TRACKS3D_FILE

    held = [name for name in (TRACKS3D_FILE, TRACKS2D_FILE) if (args.out / name).exists()]
    if held and not args.overwrite:
        raise SimrigError(f"--out {str(args.out)!r} already holds tracks ({', '.join(held)}); pass --overwrite to "
                          "replace them or choose another folder")
    dataset = Dataset.open(args.dataset)
    if args.images and dataset.image_folder is None:
        raise SimrigError(f"--images: {args.dataset} has no images (generate it with --images)")
    result = run_tracker(dataset, args.tracker, args.out, _params(args.param),
                         frame_time_limit_s=args.frame_time_limit)
    print(
        f"tracked   {result.frames} frames with {args.tracker}: {result.track_rows} track rows, "
        f"{result.frames_per_second:.0f} frames/s in step()"
    )
    print(f"wrote     {result.out}")
    return 0


def _register_trackers(commands) -> None:
    """``simrig trackers``'s options."""
    trackers = commands.add_parser("trackers", help="list the registered trackers and their parameters")
    trackers.set_defaults(run=_cmd_trackers)


def _cmd_trackers(args: argparse.Namespace) -> int:
    import inspect

    from simrig import trackers as tracker

    from .installation import ownership_warning

    warning = ownership_warning()
    if warning:
        print(warning, file=sys.stderr)
    for name in tracker.available():
        settings = ", ".join(
            f"{key}={value!r}" if value is not inspect.Parameter.empty else key
            for key, value in tracker.parameters(name).items()
        )
        print(f"{name}: {settings}")
    return 0


def _register_run(commands) -> None:
    """``simrig run``'s options."""
    run = commands.add_parser("run", help="generate a scenario, track it, score it and write a report")
    _scenario_arguments(run)
    _tracker_arguments(run)
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
    run.add_argument("--workers", type=_int_at_least(1), default=None,
                     help="processes for --explain's counterfactual runs (default: this machine's)")
    run.set_defaults(run=_cmd_run)


def _register_drive(commands) -> None:
    drive = commands.add_parser(
        "drive", help="closed loop: drive the ego on a tracker's output and on the ground truth; compare outcomes")
    _scenario_arguments(drive)
    _tracker_arguments(drive)
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
    result = drive_folder(scenario, seed=args.seed, tracker=args.tracker, params=_params(args.param), out=out,
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

    from .dataset import Dataset

    with _naming_scenario_file(args.scenario):
        result = run_pipeline(
            args.scenario, seed=args.seed, tracker=args.tracker, params=_params(args.param), out=args.out,
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
    if args.explain:
        from .explain import add_to_run_report, explain

        explained = explain(result.dataset.parent, label=result.label, workers=args.workers,
                            trust_file=True)  # the tracker was named on this command line
        print(f"\n{explained.table}\n")
        print(f"wrote     {explained.out} ({explained.coalitions} counterfactual runs, {explained.seconds:.0f} s)")
        print(f"wrote     {add_to_run_report(result.dataset.parent, result.label, explained.document)}")
    return 0


def _seed_list(text: str) -> list[int]:
    try:
        seeds = [int(part) for part in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seeds separated by commas (0,1), got {text!r}") from None
    if any(seed < 0 for seed in seeds):
        raise argparse.ArgumentTypeError(f"seeds are ≥ 0, got {text!r}")
    if len(set(seeds)) != len(seeds):
        raise argparse.ArgumentTypeError(f"a seed is listed twice in {text!r}")
    return seeds


def _names(text: str) -> list[str]:
    """An argparse type for a comma-separated list of names."""
    names = [name.strip() for name in text.split(",") if name.strip()]
    if not names:
        raise argparse.ArgumentTypeError(f"expected comma-separated names, got {text!r}")
    return names


def _register_explain(commands) -> None:
    """``simrig explain``'s options."""
    explainer = commands.add_parser(
        "explain", help="what each cause of detector error cost a run's tracker (counterfactual reruns, Shapley)")
    explainer.add_argument("run_dir", type=Path, help="a 'simrig run' folder (dataset/, tracks/, scores/)")
    explainer.add_argument("--tracker", "--label", dest="label", default=None, metavar="LABEL",
                           help="which tracker run of RUN_DIR/tracks/ (when it holds several), as view --tracker")
    explainer.add_argument("--metric", type=_names, default=None, metavar="A,B,...",
                           help="overall metrics to explain (default AMOTA,HOTA,IDS,FN,FRAG for a 3D tracker; "
                                "2d:NAME or 3d:NAME picks a dimension)")
    explainer.add_argument("--causes", type=_names, default=None, metavar="A,B,...",
                           help="cause groups to share among (default: every group present in the scenario)")
    explainer.add_argument("--samples", type=_int_at_least(2, EXPLAIN_MAX_SAMPLES), default=None, metavar="N",
                           help="sample N permutations (default: exact when there are at most 7 groups, else 12)")
    explainer.add_argument("--engine", choices=("local", "ray"), default="local", help="where the runs go")
    explainer.add_argument("--workers", type=_int_at_least(1), default=None,
                           help="processes (local; 1 runs in this process) or CPUs of a local Ray instance")
    explainer.add_argument("--address", default=None, help="Ray cluster to join (default: start a local instance)")
    explainer.add_argument("--quiet", action="store_true", help="no progress bar")
    _trust_argument(explainer, "the run folder's tracker.json")
    explainer.set_defaults(run=_cmd_explain)


def _cmd_explain(args: argparse.Namespace) -> int:
    from .explain import explain

    result = explain(args.run_dir, label=args.label, metrics=args.metric, causes=args.causes, samples=args.samples,
                     engine=args.engine, workers=args.workers, address=args.address, progress=not args.quiet,
                     trust_file=args.trust_file)
    print(result.table)
    plots = f"{len(result.plots)} waterfall plot{'s' if len(result.plots) != 1 else ''}"
    print(f"\nwrote     {result.out}: explain.json, explain.md, verdicts.parquet, {plots} "
          f"({result.coalitions} counterfactual runs, {result.seconds:.0f} s)")
    return 0


def _non_negative_float(text: str, maximum: float = 86_400.0) -> float:
    """A number of seconds in 0 … ``maximum`` (a day by default: a longer limit or look-back means none)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not 0.0 <= value <= maximum:
        raise argparse.ArgumentTypeError(f"must be a finite number in 0 … {maximum:g}, got {text}")
    return value


def _check_explain_options(args: argparse.Namespace) -> None:
    """``--explain-*`` options make sense only with ``--explain``, and ``--explain-seeds`` must be seeds of the
    suite: both checked before the bench runs (not after it, minutes later)."""
    given = [name for name, value in (("--explain-samples", args.explain_samples),
                                      ("--explain-seeds", args.explain_seeds)) if value is not None]
    if given and not args.explain:
        raise SimrigError(f"{' and '.join(given)} {'needs' if len(given) == 1 else 'need'} --explain")
    if args.explain_seeds is not None:
        from .benchmark.suite import load_suite
        from .explain.bench import check_explain_seeds

        suite, _ = load_suite(args.suite, trust_file=args.trust_file)
        check_explain_seeds(args.explain_seeds, suite.seeds, f"suite {suite.name!r}")


def _register_bench(commands) -> None:
    """``simrig bench``'s options."""
    from simrig.benchmark.engine_names import ENGINES
    from simrig.scenarios import suite_catalog

    bench = commands.add_parser("bench", help="run a suite: scenarios x trackers x seeds x sweeps, resumable")
    bench.add_argument("suite", help=f"named suite ({', '.join(suite_catalog())}) or a suite .toml file")
    bench.add_argument("--engine", choices=ENGINES, default="local",
                       help="local: a process pool (default); ray: Ray tasks (the 'ray' extra)")
    bench.add_argument("--workers", type=_int_at_least(1), default=None,
                       help="processes (local) or CPUs of the local Ray instance (default: this machine's)")
    bench.add_argument("--out", type=Path, default=None, help="bench folder (default: runs/bench/SUITE)")
    bench.add_argument("--cache", type=Path, default=None,
                       help="datasets by content key, shareable between suites (default: OUT/datasets)")
    bench.add_argument("--address", default=None, help="Ray cluster to join (default: start a local instance)")
    bench.add_argument("--quiet", action="store_true", help="no progress bar")
    bench.add_argument("--explain", action="store_true",
                       help="then explain every tracker on every base cell (simrig explain; the report's 'What each "
                            "cause costs' section)")
    bench.add_argument("--explain-samples", type=_int_at_least(2, EXPLAIN_MAX_SAMPLES), default=None, metavar="N",
                       help="permutations --explain samples (default: exact up to 7 cause groups, else 12)")
    bench.add_argument("--explain-seeds", type=_seed_list, default=None, metavar="A,B,...",
                       help="explain only the base cells of these seeds (default: every seed of the suite)")
    _trust_argument(bench, "the suite file")
    bench.set_defaults(run=_cmd_bench)


CLOSED_LOOP_EXPLAIN = ("--explain: the suite drives closed loop (closed_loop = true), and explain reruns the sensor "
                       "on a fixed world; a drive's world changes with every cause removed")


def _cmd_bench(args: argparse.Namespace) -> int:
    from .benchmark import run_bench
    from .benchmark.api import BenchInterrupted

    _check_explain_options(args)
    if args.explain:
        from .benchmark.suite import load_suite

        if load_suite(args.suite, trust_file=args.trust_file)[0].closed_loop:
            raise SimrigError(CLOSED_LOOP_EXPLAIN)
    try:
        result = run_bench(args.suite, engine=args.engine, workers=args.workers, out=args.out, cache=args.cache,
                           address=args.address, progress=not args.quiet, trust_file=args.trust_file)
    except BenchInterrupted as stop:
        print(f"simrig: {stop.message()}", file=sys.stderr)
        return 130
    except KeyboardInterrupt:  # before any cell ran (loading the suite, making the plan)
        print("simrig: interrupted before any cell ran; nothing was lost", file=sys.stderr)
        return 130
    print(f"bench     {result.out}: {result.points} points, {result.cells} cells ({result.cells_skipped} finished "
          f"earlier, {result.cells_run} run now), {result.rows} result rows")
    print(f"results   {result.results}")
    if args.explain:
        import pyarrow.parquet as pq

        from .explain.bench import explain_bench, not_explained

        path = explain_bench(result.out, samples=args.explain_samples, seeds=args.explain_seeds, engine=args.engine,
                             workers=args.workers, address=args.address, progress=not args.quiet)
        print(f"explain   {path}: what each cause costs every tracker on the base cells")
        for entry in not_explained(pq.read_schema(path)):
            print(f"explain   not explained: {entry['tracker']} on cell {entry['cell']}: {entry['reason']}")
    print(f"report    simrig report {result.out}")
    return 0


def _register_report(commands) -> None:
    """``simrig report``'s options."""
    report = commands.add_parser("report", help="write a bench's report (index.md with plots) from its folder")
    report.add_argument("results", type=Path, help="a bench folder (or its results.parquet)")
    report.add_argument("--out", type=Path, default=None, help="report folder (default: BENCH/report)")
    report.set_defaults(run=_cmd_report)


def _cmd_report(args: argparse.Namespace) -> int:
    from .report import write_report

    print(write_report(args.results, out=args.out))
    return 0


def _register_search(commands) -> None:
    """``simrig search``'s options."""
    from simrig.benchmark.engine_names import ENGINES

    search = commands.add_parser("search", help="look for a tracker's worst case, shrink it, write a regression test")
    search.add_argument("space", help="catalog search space (e.g. occlusion_gaps) or a search space .toml file")
    search.add_argument("--tracker", default=None, help="registered name or module:attribute (default: the file's)")
    search.add_argument("--param", type=_tracker_param, action="append", metavar="KEY=VALUE",
                        help="a tracker parameter, repeatable (default: the file's)")
    search.add_argument("--budget", type=_int_at_least(1), default=None, help="evaluations per sampler")
    search.add_argument("--sampler", choices=("tpe", "cmaes", "random"), default="tpe",
                        help="the optimiser (default tpe); random sampling also runs as the baseline")
    search.add_argument("--seed", type=_int_at_least(0), default=0, help="search seed (default 0)")
    search.add_argument("--engine", choices=ENGINES, default="local",
                        help="where an evaluation's seeds run: local processes (default) or Ray tasks")
    search.add_argument("--workers", type=_int_at_least(1), default=1,
                        help="processes (local) or CPUs of the local Ray instance for an evaluation's seeds")
    search.add_argument("--address", default=None, help="Ray cluster to join (default: start a local instance)")
    search.add_argument("--out", type=Path, default=None, help="search folder (default: runs/search/SPACE)")
    search.add_argument("--cache", type=Path, default=None, help="datasets by content key (default: OUT/datasets)")
    search.add_argument("--trust-file", action="store_true",
                        help="let the space file import its module:attribute tracker (data files may otherwise only "
                        "name registered trackers)")
    search.add_argument("--stop-at-failure", action="store_true", help="end each sampler at its first failing case")
    search.add_argument("--quiet", action="store_true", help="no progress bar")
    search.set_defaults(run=_cmd_search)


def _cmd_search(args: argparse.Namespace) -> int:
    import shlex

    from .search import load_space, run_search

    tracker = args.tracker  # a tracker the user types may be module:attribute; one in the file may not
    space = load_space(args.space, tracker=tracker, params=_params(args.param) if args.param else None,
                       budget=args.budget, trust_file=args.trust_file)
    words = ["simrig", "search", args.space, "--tracker", space.tracker]
    words += [f"--param={key}={value}" for key, value in space.params.items()]
    words += ["--budget", str(space.config.budget), "--sampler", args.sampler, "--seed", str(args.seed)]
    words += ["--stop-at-failure"] if args.stop_at_failure else []
    command = shlex.join(words + (["--out", str(args.out)] if args.out else []))
    try:
        result = run_search(space, sampler=args.sampler, seed=args.seed, workers=args.workers, out=args.out,
                            cache=args.cache, stop_at_failure=args.stop_at_failure, progress=not args.quiet,
                            command=command, engine=args.engine, address=args.address)
    except KeyboardInterrupt:
        print("simrig: interrupted; every finished evaluation is kept: run the same command again to resume",
              file=sys.stderr)
        return 130
    firsts = ", ".join(f"{name} {n or 'none'}" for name, n in result.first_failure.items())
    print(f"search    {result.out}: {result.evaluated_now} evaluations run now; first failing evaluation: {firsts}")
    print(f"results   {result.results}")
    print(f"report    {result.report}")
    if result.worst is not None:
        print(f"worst     {result.worst} (replay file and pytest file of the shrunk case)")
    return 0


class _VersionAction(argparse.Action):
    """``--version``: the version, the distribution to pip install, and a warning line when another installed
    distribution owns files of the simrig package (:mod:`simrig.installation`)."""

    def __call__(self, parser, namespace, values, option_string=None):
        from .installation import ownership_warning
        from .version import DISTRIBUTION, __version__

        print(f"simrig {__version__} (pip: {DISTRIBUTION})")
        warning = ownership_warning()
        if warning:
            print(warning, file=sys.stderr)
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    parser = _OneLineParser(
        prog="simrig", description="A test bench for multi-camera multi-object trackers on moving vehicles."
    )
    parser.add_argument("--version", action=_VersionAction, nargs=0, help="show the version and exit")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    from .detector.cli import add_detector_command

    for register in COMMANDS + (add_detector_command,):  # each command's options sit next to its handler
        register(commands)
    return parser


COMMANDS = (_register_generate, _register_scenarios, _register_info, _register_render, _register_view,
            _register_score, _register_replay, _register_export, _register_import, _register_track,
            _register_trackers, _register_bench, _register_search, _register_report, _register_run,
            _register_drive, _register_explain)
"""The commands in the order ``simrig --help`` lists them (``detector`` last, from :mod:`simrig.detector.cli`)."""


def _trust_argument(parser: argparse.ArgumentParser, what: str) -> None:
    parser.add_argument("--trust-file", action="store_true",
                        help=f"let {what} import its module:attribute trackers (a data file may otherwise only "
                        "name registered trackers)")


def _scenario_name(text: str) -> str:
    """A scenario argument: an empty one is a mistake, not a request for the default."""
    if not text.strip():
        raise argparse.ArgumentTypeError("an empty scenario name; give a catalog name (simrig scenarios) or a .toml "
                                         f"file, or leave it out for {DEFAULT_SCENARIO}")
    return text


def _scenario_arguments(parser: argparse.ArgumentParser, default: str | None = DEFAULT_SCENARIO) -> None:
    """The scenario (``default`` when omitted; ``None``: the command decides), ``--seed`` and ``--frames``."""
    parser.add_argument("scenario", nargs="?", default=default, type=_scenario_name,
                        help=f"catalog name or .toml file (default: {DEFAULT_SCENARIO})")
    parser.add_argument("--seed", type=_int_at_least(0), default=0, help="scenario seed (default 0)")
    parser.add_argument("--frames", type=_int_at_least(1, MAX_FRAMES), default=None,
                        help="frames to generate (default: the scenario's)")


def _tracker_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--tracker", default="saga", help="registered tracker name (default: saga; see "
                        "'simrig trackers'), or module:attribute — a tracker factory or class to import")
    parser.add_argument("--param", type=_tracker_param, action="append", metavar="KEY=VALUE",
                        help="a tracker parameter, repeatable (e.g. --param gate=4 --param life=mutr3d)")
    parser.add_argument("--frame-time-limit", type=_non_negative_float, default=60.0, metavar="SECONDS",
                        help="stop the tracker when one step() runs longer than this (default 60; 0: no limit)")


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    with noting_interrupts():  # a KeyboardInterrupt can surface as another error (inside a lazy import, say)
        try:
            return args.run(args)
        except (KeyboardInterrupt, Exception) as error:
            if isinstance(error, KeyboardInterrupt) or interrupted():
                print("simrig: interrupted (a generation in progress leaves no dataset behind)", file=sys.stderr)
                return 130
            if isinstance(error, (SimrigError, ScenarioError)):
                if os.environ.get("SIMRIG_TRACEBACK") == "1" and error.__cause__ is not None:
                    import traceback

                    traceback.print_exception(error.__cause__, file=sys.stderr)
                print(f"simrig: error: {_one_line(str(error))}", file=sys.stderr)
                return 2
            if isinstance(error, BrokenPipeError):  # the reader left early: console() leaves quietly
                raise
            if isinstance(error, OSError):  # the file system said no: a read-only folder, a name too long, ...
                where = f": {_shortened(error.filename)}" if error.filename else ""
                print(f"simrig: error: {error.strerror or error}{where}", file=sys.stderr)
                return 2
            if isinstance(error, RecursionError):
                print("simrig: error: an input file is nested too deeply to be read", file=sys.stderr)
                return 2
            raise


def _one_line(message: str) -> str:
    """A message folded onto one line (a library's error text embedded in ours may hold line breaks)."""
    return " ".join(part.strip() for part in message.splitlines() if part.strip())


def _shortened(name: object, limit: int = 120) -> str:
    """A path for a message: repr, cut to ``limit`` characters."""
    text = repr(str(name))
    return text if len(text) <= limit else text[: limit - 1] + "…"


def console() -> None:
    """The ``simrig`` command: :func:`main`, then the process's exit.

    A process that rendered (visibility or images) keeps its one OpenGL context to the end (see
    :mod:`simrig.render.scene`); tearing it down with the interpreter has been seen to abort a finished run at
    exit under load ("terminate called without an active exception", exit status -6, after every file was
    written). Such a process leaves with ``os._exit`` once its output is flushed: everything simrig writes is
    committed (atomically) before :func:`main` returns, so nothing is lost by skipping the interpreter's
    teardown."""
    try:
        code = main()
        if sys.stdout is not None:  # None when the command was started with its output closed (simrig info >&-)
            sys.stdout.flush()
    except BrokenPipeError:  # the reader left early (`simrig scenarios | head`): not an error of simrig's
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error at exit's flush
        code = 1
    scene = sys.modules.get("simrig.render.scene")
    if scene is not None and scene.offscreen_renderer.cache_info().currsize:
        for stream in (sys.stdout, sys.stderr):
            if stream is not None:
                stream.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":
    console()
