"""Benchmark: the cost of simrig's traffic upkeep against the vehicle count, now and at an older commit.

Run explicitly (not part of the test suite)::

    python tests/perf/traffic.py [--frames 300] [--vehicles 10 25 50 100] [--before 3704a39]

For each requested vehicle count, ``highway_surround6``'s traffic (seed 0) runs ``--frames`` frames with
:class:`simrig.world.TrafficWorld` as it is now and as it was at ``--before`` (its ``traffic.py`` loaded from
git, the rest of simrig as it is now), alternating, so that machine noise hits both. Timed per frame:
highway-env's own ``env.step`` (IDM, MOBIL, collisions: not simrig's), the window upkeep (removing crashed
and far vehicles, spawning: ``_remove_crashed``, ``_remove_far``, ``_fill``) and the ground-truth conversion
(``_state``). Also: the vehicles delivered (mean over frames) and how many crashed. The table is printed and
written to ``reports/perf/traffic.md``.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import subprocess
import sys
import time
import types
from pathlib import Path

from simrig.scenarios import load_scenario

from simrig.seeding import RandomStreams
from simrig.world import TrafficWorld

ROOT = Path(__file__).resolve().parents[2]
REPORT = ROOT / "reports" / "perf" / "traffic.md"
SCENARIO = "highway_surround6"
UPKEEP = ("_remove_crashed", "_remove_far", "_fill")


def traffic_world_at(commit: str) -> type:
    """``TrafficWorld`` as ``simrig/world/traffic.py`` was at ``commit`` (the rest of simrig as it is now)."""
    source = subprocess.run(
        ["git", "-C", str(ROOT), "show", f"{commit}:simrig/world/traffic.py"], capture_output=True, text=True,
        check=True,
    ).stdout
    name = f"simrig.world._traffic_{commit}"
    module = types.ModuleType(name)
    module.__package__ = "simrig.world"
    sys.modules[name] = module
    exec(compile(source, f"<simrig/world/traffic.py at {commit}>", "exec"), module.__dict__)  # noqa: S102
    return module.TrafficWorld


def _timed(clock: dict, key: str, function):
    def wrapper(*args, **kwargs):
        tick = time.perf_counter()
        try:
            return function(*args, **kwargs)
        finally:
            clock[key] += time.perf_counter() - tick
    return wrapper


def run(world_type: type, scenario, vehicles: int, frames: int, seed: int) -> dict[str, float]:
    """Milliseconds per frame of each part of ``TrafficWorld.step``, vehicles delivered, crashes."""
    config = scenario.traffic.model_copy(update={"vehicles": vehicles})
    streams = RandomStreams(seed)
    world = world_type(config, scenario.frame_rate_hz, env_seed=streams.integer_seed("traffic"),
                       rng=streams.generator("population"))
    world.reset()
    clock = dict.fromkeys(("env.step", "upkeep", "state", "total"), 0.0)
    world.env.step = _timed(clock, "env.step", world.env.step)
    for name in UPKEEP:
        if hasattr(world, name):
            setattr(world, name, _timed(clock, "upkeep", getattr(world, name)))
    world._state = _timed(clock, "state", world._state)
    counts, crashed = [], set()
    for _ in range(frames):
        tick = time.perf_counter()
        state = world.step()
        clock["total"] += time.perf_counter() - tick
        counts.append(len(state.actor_ids))
        crashed.update(v.simrig_id for v in world.env.unwrapped.road.vehicles if v.crashed and v is not world.ego)
        crashed.update(int(e.split("id=")[1]) for e in state.events if e.startswith("vehicle_crashed"))
    world.close()
    result = {key: 1e3 * value / frames for key, value in clock.items()}
    return {**result, "vehicles": statistics.fmean(counts), "crashes": len(crashed)}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--vehicles", type=int, nargs="+", default=[10, 25, 50, 100])
    parser.add_argument("--before", default="3704a39", help="the commit to compare with")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    scenario = load_scenario(SCENARIO)
    versions = {"now": TrafficWorld, f"at {args.before}": traffic_world_at(args.before)}
    results = {}
    for index, vehicles in enumerate(args.vehicles):
        order = list(versions.items()) if index % 2 == 0 else list(versions.items())[::-1]
        for label, world_type in order:
            results[label, vehicles] = run(world_type, scenario, vehicles, args.frames, args.seed)

    command = "python tests/perf/traffic.py " + " ".join(sys.argv[1:])
    lines = [
        f"# Traffic upkeep against the vehicle count — {SCENARIO}, seed {args.seed}",
        "",
        f"Command: `{command.strip()}`  ",
        f"Machine: {platform.machine()}, Python {platform.python_version()}; {args.frames} frames per run, "
        f"simrig now and `simrig/world/traffic.py` at {args.before}, alternating. ms per frame.",
        "",
        "| traffic.py | requested | delivered (mean) | crashes | env.step (highway-env) | upkeep | "
        "upkeep µs per vehicle | ground truth | whole step |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for label in versions:
        for vehicles in args.vehicles:
            r = results[label, vehicles]
            lines.append(
                f"| {label} | {vehicles} | {r['vehicles']:.1f} | {r['crashes']} | {r['env.step']:.2f} | "
                f"{r['upkeep']:.3f} | {1e3 * r['upkeep'] / max(r['vehicles'], 1):.1f} | {r['state']:.3f} | "
                f"{r['total']:.2f} |"
            )
    low, high = min(args.vehicles), max(args.vehicles)
    lines.append("")
    for label in versions:
        a, b = results[label, low], results[label, high]
        lines.append(
            f"- {label}: from {low} to {high} requested ({b['vehicles'] / a['vehicles']:.1f}× the vehicles "
            f"delivered), upkeep ×{b['upkeep'] / a['upkeep']:.1f}, env.step ×{b['env.step'] / a['env.step']:.1f}."
        )
    lines.append("")
    text = "\n".join(lines)
    print(text)
    REPORT.parent.mkdir(parents=True, exist_ok=True)
    REPORT.write_text(text, encoding="utf-8")
    print(f"written to {REPORT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
