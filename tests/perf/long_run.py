"""Long-run check: traffic keeps flowing for 5,000 frames and every crash is an event.

Run explicitly (not part of the test suite)::

    python tests/perf/long_run.py [--frames 5000] [--window 500] [--seeds 0 1] [--dense 100] [--before 3704a39]

``highway_surround6`` with rendering off is traffic only, so this runs :class:`simrig.world.TrafficWorld`
(what ``generate`` steps) for each seed, plus one run with ``vehicles`` raised to ``--dense``. Per run:

* the mean speed of the other vehicles over the first and the last ``--window`` frames; the check is that
  the last is within 20% of the first. Also the slowest 100-frame stretch (0 m/s is a freeze);
* crashes as highway-env reports them, observed independently of simrig's events (the crashed flags of
  the non-ego vehicles right after each ``env.step``), against the ``vehicle_crashed`` events of the
  frames; the check is that every observed crash has its event at its frame;
* the vehicles delivered (mean over frames) and the ego's crashes.

With ``--before COMMIT`` the same runs are made with ``simrig/world/traffic.py`` as it was at that commit
(loaded from git, as in ``tests/perf/traffic.py``), for comparison. The table is printed and written to
``reports/perf/long_run.md``.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from simrig.scenarios import load_scenario
from traffic import traffic_world_at

from simrig.seeding import RandomStreams
from simrig.world import TrafficWorld

REPORT = Path(__file__).resolve().parents[2] / "reports" / "perf" / "long_run.md"
SCENARIO = "highway_surround6"
TOLERANCE = 0.20
"""[-] the last window's mean speed may differ from the first's by this fraction at most."""


def long_run(world_type: type, traffic, frame_rate_hz: float, frames: int, seed: int) -> dict:
    """Per-frame mean speed of the other vehicles, their count, and crashes observed vs recorded."""
    streams = RandomStreams(seed)
    world = world_type(traffic, frame_rate_hz, env_seed=streams.integer_seed("traffic"),
                       rng=streams.generator("population"))
    observed: set[tuple[int, int]] = set()  # (frame, actor id) at which highway-env first flags a crash
    flagged: set[int] = set()
    env_step = world.env.step

    def observing_step(*args, **kwargs):
        result = env_step(*args, **kwargs)
        for vehicle in world.env.unwrapped.road.vehicles:
            if vehicle.crashed and vehicle is not world.ego and vehicle.simrig_id not in flagged:
                flagged.add(vehicle.simrig_id)
                observed.add((world._frame + 1, vehicle.simrig_id))  # step() counts the frame after env.step
        return result

    world.env.step = observing_step
    speeds, counts, recorded, ego_crashes = [], [], set(), []
    started = time.perf_counter()
    for frame in range(frames):
        state = world.reset() if frame == 0 else world.step()
        speeds.append(float(np.hypot(state.boxes[:, 7], state.boxes[:, 8]).mean()) if len(state.boxes) else 0.0)
        counts.append(len(state.actor_ids))
        recorded.update((state.frame, int(e.split("id=")[1])) for e in state.events if e.startswith("vehicle_crashed"))
        ego_crashes.extend(state.frame for e in state.events if e == "ego_crashed")
    world.close()
    return {"speeds": np.array(speeds), "counts": counts, "observed": observed, "recorded": recorded,
            "ego_crashes": ego_crashes, "seconds": time.perf_counter() - started}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=5000)
    parser.add_argument("--window", type=int, default=500)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--dense", type=int, default=100, help="vehicles of the extra dense run (0: none)")
    parser.add_argument("--before", default="", help="also run traffic.py as it was at this commit")
    parser.add_argument("--only-before", action="store_true", help="run only the --before version")
    parser.add_argument("--report", type=Path, default=REPORT)
    args = parser.parse_args()
    scenario = load_scenario(SCENARIO)
    cases = [(seed, scenario.traffic) for seed in args.seeds]
    if args.dense:
        cases.append((args.seeds[0], scenario.traffic.model_copy(update={"vehicles": args.dense})))
    versions = {} if args.only_before else {"now": TrafficWorld}
    if args.before:
        versions[f"at {args.before}"] = traffic_world_at(args.before)

    rows, all_ok = [], True
    for label, world_type in versions.items():
        for seed, traffic in cases:
            r = long_run(world_type, traffic, scenario.frame_rate_hz, args.frames, seed)
            speeds, w = r["speeds"], args.window
            first, last = float(speeds[1:w + 1].mean()), float(speeds[-w:].mean())
            blocks = speeds[1:len(speeds) - (len(speeds) - 1) % 100].reshape(-1, 100).mean(axis=1)
            flowing = abs(last - first) <= TOLERANCE * first
            missing = len(r["observed"] - r["recorded"]) if label == "now" else None
            events_ok = missing == 0 if label == "now" else None
            if label == "now":
                all_ok &= flowing and bool(events_ok)
            rows.append(
                f"| {label} | {seed} | {traffic.vehicles} | {statistics.fmean(r['counts']):.1f} | {first:.1f} | "
                f"{last:.1f} | {last / first:.2f} ({'ok' if flowing else 'FAILS'}) | {blocks.min():.1f} | "
                f"{len(r['observed'])} | "
                + (f"{len(r['recorded'])}, {missing} missing ({'ok' if events_ok else 'FAILS'})" if missing is not None
                   else "not recorded")
                + f" | {len(r['ego_crashes'])} | {r['seconds']:.0f} |"
            )
            print(rows[-1], flush=True)

    command = "python tests/perf/long_run.py " + " ".join(sys.argv[1:])
    lines = [
        f"# Long runs: does traffic keep flowing, is every crash recorded? — {SCENARIO}, rendering off",
        "",
        f"Command: `{command.strip()}`  ",
        f"Machine: {platform.machine()}, Python {platform.python_version()}; {args.frames} frames per run. "
        f"Speeds: mean over frames of the other vehicles' mean speed [m/s]; first = frames 1–{args.window}, "
        f"last = the last {args.window}; check: |last − first| ≤ {TOLERANCE:.0%} of first. Crashes observed: "
        "highway-env's crashed flags right after each `env.step`; recorded: `vehicle_crashed` events.",
        "",
        "| traffic.py | seed | vehicles requested | delivered (mean) | speed first | speed last | last/first | "
        "slowest 100 frames | crashes observed | crash events | ego crashes | wall s |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|",
        *rows,
        "",
        f"The long-run check for simrig now: {'PASSES' if all_ok else 'FAILS'}." if "now" in versions else "",
        "",
    ]
    text = "\n".join(lines)
    print(text)
    args.report.parent.mkdir(parents=True, exist_ok=True)
    args.report.write_text(text, encoding="utf-8")
    print(f"written to {args.report}")
    return 0 if all_ok else 1


if __name__ == "__main__":
    sys.exit(main())
