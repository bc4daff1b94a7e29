"""Long runs of the road layouts: is the traffic alive for 1,000 frames?

    python tests/perf/road_liveness.py [--frames 1000] [--seeds 100 101 102] [--scenarios ...]

For each scenario and seed, :func:`simrig.world.liveness.traffic_liveness` runs the traffic (no rendering) and
gives per 100-frame window the fewest vehicles in view of the rig in a frame, births and deaths, and the mean
speeds; then the crash events. Checks: a vehicle in view in every frame, births and deaths in every window, the
last window's mean speed (other vehicles and ego) at least 50% of the first's, no ego crash. Writes
``reports/roads/liveness.md``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from published import command_line, machine, publish
from simrig.scenarios import load_scenario

from simrig.world.liveness import FLOW_KEPT, WINDOW_FRAMES, traffic_liveness

OUT = Path(__file__).resolve().parents[2] / "reports" / "roads" / "liveness.md"
SCENARIOS = ("merge_surround6", "intersection_surround6", "two_way_surround6", "exit_surround6")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=1000)
    parser.add_argument("--seeds", type=int, nargs="+", default=[100, 101, 102])
    parser.add_argument("--scenarios", nargs="+", default=list(SCENARIOS))
    args = parser.parse_args()
    lines = ["# Road layouts: is the traffic alive over long runs?", "",
             f"Produced by `{command_line()}` ({machine()}). Traffic only (no rendering, no detector), "
             f"{args.frames} frames per run, windows of {WINDOW_FRAMES} frames. In view: boxes projected into some "
             "camera's image (occlusion not counted). Checks: a vehicle in view in every frame; births and "
             f"deaths in every window; the last window's mean speed ≥ {FLOW_KEPT:.0%} of the first's, for the other "
             "vehicles and for the ego; no ego crash.", "",
             "| scenario | seed | fewest in view (per window) | births per window | deaths per window | speed first → "
             "last [m/s] | ego speed first → last [m/s] | ego drove [m] | crash events | wall [s] | verdict |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    crash_lines, failed = [], 0
    for name in args.scenarios:
        scenario = load_scenario(name)
        for seed in args.seeds:
            started = time.perf_counter()
            live = traffic_liveness(scenario, seed, args.frames)
            wall = time.perf_counter() - started
            problems = live.problems()
            failed += bool(problems)
            lines.append(
                f"| {name} | {seed} | {' '.join(map(str, live.in_view_min))} | {' '.join(map(str, live.births))} | "
                f"{' '.join(map(str, live.deaths))} | {live.speed[0]:.1f} → {live.speed[-1]:.1f} | "
                f"{live.ego_speed[0]:.1f} → {live.ego_speed[-1]:.1f} | {live.progress_m:.0f} | {len(live.crashes)} | "
                f"{wall:.0f} | {'alive' if not problems else '; '.join(problems)} |")
            print(lines[-1], flush=True)
            crash_lines += [f"- {name}, seed {seed}, frame {frame}: `{event}`" for frame, event in live.crashes]
    lines += ["", "## Crash events", "", *(crash_lines or ["None."]), "",
              f"{failed} of {len(args.scenarios) * len(args.seeds)} runs not alive.", ""]
    publish(lines, OUT)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
