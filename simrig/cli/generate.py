"""``simrig generate``: a dataset from a scenario, or a collection from a space."""

from __future__ import annotations

import argparse
import contextlib
import sys
import time
from pathlib import Path

from simrig.scenarios import DEFAULT_SCENARIO, ScenarioError, load_scenario

from ..errors import SimrigError
from .arguments import int_at_least, scenario_arguments


def register_generate(commands) -> None:
    """``simrig generate``'s options."""
    from simrig.engine_names import ENGINES
    from simrig.scenarios import MAX_SEQUENCES, space_catalog

    gen = commands.add_parser("generate", help="generate a dataset from a scenario, or a collection from a space")
    scenario_arguments(gen, default=None)
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
    collection.add_argument("--count", type=int_at_least(1, MAX_SEQUENCES), default=None, metavar="N",
                            help="sequences to sample")
    collection.add_argument("--shard-size", type=int_at_least(1, MAX_SEQUENCES), default=100, metavar="K",
                            help="sequences per shard folder (default 100)")
    collection.add_argument("--engine", choices=ENGINES, default="local",
                            help="local: a process pool (default); ray: Ray tasks (the 'ray' extra)")
    collection.add_argument("--workers", type=int_at_least(1), default=None,
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
    from ..collection import generate_collection, load_generation_space
    from ..collection.run import CollectionInterrupted

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

    from ..dataset import Dataset

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
    from . import STARTED

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

    from ..dataset import Dataset

    for message in ineffective_settings(scenario, Dataset.open(dataset_path)):
        print(f"warning: {message}", file=sys.stderr)
