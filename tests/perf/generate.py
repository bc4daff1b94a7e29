"""Benchmark: frames per second of ``simrig generate`` against bare highway-env stepping of the same traffic.

Run explicitly (not part of the test suite)::

    python tests/perf/generate.py [--frames 300] [--repeats 3] [--preset monodis]

Both sides start from the same populated highway (``highway_surround6``: 40 vehicles, seed 0):

* bare — ``env.step(None)`` on that traffic, nothing else (no window upkeep, projection or writing), with
  highway-env's own road stepping, neighbour search and lane coordinates (the peer), and again with the faster
  versions of those that simrig's world installs (same answers);
* generate — the whole of :func:`simrig.pipeline.generate.generate` with visibility rendering off (traffic with window
  upkeep, projection into six cameras, the sensor model, Parquet writing, hashing, manifest). The cost of
  rendering is measured by ``tests/perf/visibility.py``.

Runs alternate (bare, generate, bare, generate, ...) so that machine noise hits both; the table reports
medians and the overhead ratio. Target: generate adds at most 30% over bare stepping; the sensor
model's ms per frame at 40 vehicles × 6 cameras: at most 4 ms. ``--preset`` runs the detector
preset of that name instead of the scenario's. The table is printed and written to
``reports/perf/generate.md`` (``generate-PRESET.md`` with ``--preset``).
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

from simrig.scenarios import load_scenario
from simrig.scenarios.sensor_schema import RenderConfig, SensorConfig

from simrig.pipeline.generate import generate
from simrig.seeding import RandomStreams
from simrig.world import TrafficWorld

REPORT = Path(__file__).resolve().parents[2] / "reports" / "perf" / "generate.md"
SCENARIO = "highway_surround6"


def bare_stepping_seconds(scenario, frames: int, seed: int, highway_envs_own: bool) -> tuple[float, float]:
    """Seconds for ``frames − 1`` bare ``env.step(None)`` calls after the same reset as ``generate``,
    plus the mean vehicle count during them. ``highway_envs_own``: the road steps and searches with highway-env's
    own methods (``Road.step``, ``Road.neighbour_vehicles``, ``lane.local_coordinates``), as highway-env alone
    would; otherwise with the faster ones simrig's world installs (same answers, same bytes)."""
    streams = RandomStreams(seed)
    world = TrafficWorld(
        scenario.traffic, scenario.frame_rate_hz,
        env_seed=streams.integer_seed("traffic"), rng=streams.generator("population"),
    )
    world.reset()
    env = world.env
    road = env.unwrapped.road
    if highway_envs_own:  # simrig installs its versions as instance attributes: removed, the classes' own answer
        for name in ("step", "neighbour_vehicles"):
            road.__dict__.pop(name, None)
        for lane in road.network.lanes_list():
            lane.__dict__.pop("local_coordinates", None)
    counts = []
    started = time.perf_counter()
    for _ in range(frames - 1):
        env.step(None)
        counts.append(len(road.vehicles) - 1)
    elapsed = time.perf_counter() - started
    world.close()
    return elapsed, statistics.fmean(counts)


PLANS = "planner on the ground truth"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--preset", default=None, help="detector preset (default: the scenario's detector)")
    args = parser.parse_args()
    scenario = load_scenario(SCENARIO)
    update = {"render": RenderConfig(visibility=False)}
    if args.preset:
        update["sensor"] = SensorConfig.model_validate({"preset": args.preset})
    scenario = scenario.model_copy(update=update)
    report = REPORT.with_name(f"generate-{args.preset}.md") if args.preset else REPORT

    bare, fast, full, traffic, projection, sensor, plans, writing, vehicles = [], [], [], [], [], [], [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for repeat in range(args.repeats):
            seconds, mean_vehicles = bare_stepping_seconds(scenario, args.frames, args.seed, highway_envs_own=True)
            bare.append(seconds)
            vehicles.append(mean_vehicles)
            fast.append(bare_stepping_seconds(scenario, args.frames, args.seed, highway_envs_own=False)[0])
            result = generate(scenario, seed=args.seed, out=Path(tmp) / f"run{repeat}", frames=args.frames)
            full.append(result.times.total)
            traffic.append(result.times.traffic)
            projection.append(result.times.projection)
            sensor.append(result.times.sensor + result.times.visibility)
            plans.append(result.times.planning)
            writing.append(result.times.writing)

    steps = args.frames - 1
    bare_fps = steps / statistics.median(bare)
    fast_fps = steps / statistics.median(fast)
    full_fps = args.frames / statistics.median(full)
    overhead = bare_fps / full_fps - 1.0
    per_frame_ms = {name: 1000 * statistics.median(values) / args.frames for name, values in (
        ("traffic (highway-env + window upkeep)", traffic), ("projection (6 cameras)", projection),
        (f"sensor model ({args.preset or 'scenario detector'}; no rendering; target ≤ 4 ms)", sensor),
        (f"{PLANS} (the ground truth's plans)", plans),
        ("writing (Parquet, hashes, manifest)", writing),
    )}
    foundation_ms = sum(ms for name, ms in per_frame_ms.items() if not name.startswith(("sensor", PLANS)))
    foundation_overhead = foundation_ms / (1000 / bare_fps) - 1.0
    command = "python tests/perf/generate.py " + " ".join(sys.argv[1:])
    lines = [
        f"# `simrig generate` vs bare highway-env stepping — {SCENARIO}",
        "",
        f"Command: `{command.strip()}`  ",
        f"Machine: {platform.machine()}, Python {platform.python_version()}, "
        f"{args.frames} frames × {args.repeats} alternating repeats, medians; "
        f"{statistics.fmean(vehicles):.1f} other vehicles on average.",
        "",
        "| what | frames/s | ms/frame |",
        "|---|---:|---:|",
        f"| bare highway-env `env.step(None)`, with highway-env's own stepping and searches | {bare_fps:.1f} | "
        f"{1000 / bare_fps:.2f} |",
        f"| the same, with the stepping and searches simrig's world installs (same answers) | {fast_fps:.1f} | "
        f"{1000 / fast_fps:.2f} |",
        f"| `simrig generate` (everything) | {full_fps:.1f} | {1000 / full_fps:.2f} |",
        *(f"| &nbsp;&nbsp;of which {name} | | {ms:.2f} |" for name, ms in per_frame_ms.items()),
        "",
        f"Overhead of generate over bare highway-env stepping: **{overhead * 100:+.1f}%** (target: at most +30%; "
        f"{'met' if overhead <= 0.30 else 'MISSED'}); over the same stepping with simrig's faster methods "
        f"{(fast_fps / full_fps - 1.0) * 100:+.1f}%. The target was set for the foundation alone (traffic, "
        f"projection, writing: {foundation_overhead * 100:+.1f}%); the sensor model and the plans added since then are "
        "listed separately.",
        "",
    ]
    text = "\n".join(lines)
    print(text)
    report.parent.mkdir(parents=True, exist_ok=True)
    report.write_text(text)
    print(f"written to {report}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
