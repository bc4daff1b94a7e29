"""Report: how the simulated vehicles move — yaw rate, lateral and longitudinal acceleration, lane-change duration —
for the ego and the other vehicles, on every catalog scenario, against naturalistic driving figures.

    python tests/perf/motion.py --label after [--seeds 100-109] [--frames 200] [--workers 2]

Runs the traffic of each catalog scenario (``TrafficWorld``, as ``simrig generate`` does; nothing rendered, no
detector) for ``--frames`` frames per seed and measures, per vehicle and frame step: yaw rate |Δyaw|/Δt [deg/s],
lateral acceleration (the component of the velocity's change normal to the velocity) and longitudinal acceleration
[m/s²], and on the straight roads (highway-v0 and the long layouts) the duration of each lane change (a stretch
where a vehicle moves sideways faster than 0.1 m/s and covers at least 3 m). The statistics of one run are saved
under ``--label`` in ``reports/motion/runs.json``; ``reports/motion/index.md`` shows every label saved, so a run
before a change and one after stand side by side (rerun the "before" label from the earlier commit).
"""

from __future__ import annotations

import argparse
import json
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from published import command_line, machine, publish, seed_range

OUT = Path(__file__).resolve().parents[2] / "reports" / "motion"
LATERAL_SPEED_MPS = 0.1
"""[m/s] a vehicle moving sideways faster than this is changing lanes (or merging)."""
LANE_CHANGE_M = 3.0
"""[m] the least sideways distance a lane change covers (lanes are 4 m wide)."""
STRAIGHT = ("highway-v0",)
PUBLISHED = [
    "- Lane-change duration: mean 4.6 s (s.d. 2.3 s, range about 1–13 s) on US-101 and I-80 (NGSIM), Toledo and "
    "Zohar, \"Modeling duration of lane changes\", Transportation Research Record 1999, 2007.",
    "- Lateral acceleration in lane changes: mostly below 1 m/s², rarely above 2 m/s² on highways (naturalistic "
    "highway data such as the highD dataset, Krajewski et al., ITSC 2018; the bound simrig's steering keeps is "
    "2 m/s² for the lane change itself).",
    "- Yaw rate: at highway speed a lane change at 1–2 m/s² lateral acceleration is a yaw rate of a few degrees "
    "per second (a_lat / v: 2 m/s² at 25 m/s is 4.6°/s).",
]


def _track(world, frames: int) -> dict[int, np.ndarray]:
    """Per actor (−1: the ego) an array of rows (frame, x, y, yaw, vx, vy), world frame."""
    rows: dict[int, list] = {}
    state = world.reset()
    for frame in range(frames):
        if frame:
            state = world.step()
        e = state.ego
        rows.setdefault(-1, []).append((state.frame, e.x, e.y, e.yaw, e.vx, e.vy))
        for actor, box in zip(state.actor_ids.tolist(), state.boxes, strict=True):
            rows.setdefault(actor, []).append((state.frame, box[0], box[1], box[6], box[7], box[8]))
    return {actor: np.array(values) for actor, values in rows.items()}


def _statistics(tracks: dict[int, np.ndarray], rate: float, straight: bool) -> dict[str, dict[str, list]]:
    """Per group (ego, others): every yaw rate, lateral and longitudinal acceleration, lane-change duration."""
    out = {group: {"yaw_rate": [], "lateral": [], "longitudinal": [], "lane_change_s": []}
           for group in ("ego", "others")}
    for actor, rows in tracks.items():
        group = out["ego" if actor == -1 else "others"]
        steps = np.diff(rows[:, 0]) == 1
        if not steps.any():
            continue
        dt = 1.0 / rate
        yaw = np.abs((np.diff(rows[:, 3]) + np.pi) % (2 * np.pi) - np.pi)[steps] / dt
        velocity = rows[:, 4:6]
        change = np.diff(velocity, axis=0)[steps] / dt
        speed = np.hypot(*velocity[:-1][steps].T)
        moving = speed > 1.0
        unit = velocity[:-1][steps][moving] / speed[moving, None]
        group["yaw_rate"] += np.rad2deg(yaw[speed > 1.0]).tolist()
        group["lateral"] += np.abs(change[moving, 0] * unit[:, 1] - change[moving, 1] * unit[:, 0]).tolist()
        group["longitudinal"] += (change[moving] * unit).sum(axis=1).tolist()
        if straight:
            group["lane_change_s"] += _lane_changes(rows, rate)
    return out


def _lane_changes(rows: np.ndarray, rate: float) -> list[float]:
    """Durations [s] of the stretches of consecutive frames moving sideways (|vy| > LATERAL_SPEED_MPS, one
    direction) that cover at least LANE_CHANGE_M, and that start and end inside the record."""
    vy = rows[:, 5]
    sign = np.where(vy > LATERAL_SPEED_MPS, 1, np.where(vy < -LATERAL_SPEED_MPS, -1, 0))
    durations, start = [], None
    for index in range(len(sign) + 1):
        current = sign[index] if index < len(sign) else 0
        if start is not None and current != sign[start]:
            if start > 0 and index < len(sign) and abs(rows[index - 1, 2] - rows[start, 2]) >= LANE_CHANGE_M:
                durations.append((index - start) / rate)
            start = None
        if start is None and current != 0:
            start = index
    return durations


def _one(job: tuple[str, int, int]) -> dict:
    from simrig.scenarios import load_scenario
    from simrig.scenarios.overrides import with_setting

    from simrig.pipeline.generate import _SimulatedWorld
    from simrig.seeding import RandomStreams

    name, seed, frames = job
    scenario = with_setting(load_scenario(name), "render.visibility", False)
    world = _SimulatedWorld(scenario, None, RandomStreams(seed), False).traffic
    try:
        tracks = _track(world, min(frames, scenario.frames))
    finally:
        world.close()
    straight = scenario.traffic.env in STRAIGHT
    return {"scenario": name, "seed": seed, **_statistics(tracks, scenario.frame_rate_hz, straight)}


def _summary(results: list[dict]) -> dict:
    """Per scenario and group: the largest and 99th-percentile yaw rate and lateral acceleration, the 1st and 99th
    percentile of the longitudinal acceleration, lane changes (count, median and 10th percentile duration)."""
    summary: dict = {}
    for name in sorted({r["scenario"] for r in results}):
        mine = [r for r in results if r["scenario"] == name]
        summary[name] = {}
        for group in ("ego", "others"):
            values = {key: np.array([v for r in mine for v in r[group][key]]) for key in mine[0][group]}

            def pct(key: str, q: float, values: dict = values) -> float | None:
                return float(np.percentile(values[key], q)) if len(values[key]) else None

            summary[name][group] = {
                "yaw_max": pct("yaw_rate", 100), "yaw_p99": pct("yaw_rate", 99),
                "lat_max": pct("lateral", 100), "lat_p99": pct("lateral", 99),
                "long_p1": pct("longitudinal", 1), "long_p99": pct("longitudinal", 99),
                "lane_changes": int(len(values["lane_change_s"])), "lc_median": pct("lane_change_s", 50),
                "lc_p10": pct("lane_change_s", 10),
            }
    return summary


def _cell(value: float | None, digits: int = 1) -> str:
    return "–" if value is None else f"{value:.{digits}f}"


def main() -> int:
    from simrig.scenarios import catalog

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--label", required=True, help="the name this run is saved under (e.g. before, after)")
    parser.add_argument("--seeds", default="100-109")
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    jobs = [(name, seed, args.frames) for name in sorted(catalog()) for seed in seed_range(args.seeds)]
    with ProcessPoolExecutor(args.workers) as pool:
        results = list(pool.map(_one, jobs))
    store = OUT / "runs.json"
    saved = json.loads(store.read_text()) if store.is_file() else {}
    saved[args.label] = {"command": command_line(), "machine": machine(), "seeds": args.seeds,
                         "frames": args.frames, "summary": _summary(results)}
    store.parent.mkdir(parents=True, exist_ok=True)
    store.write_text(json.dumps(saved, indent=1, sort_keys=True))
    lines = ["# How the simulated vehicles move", "",
             "Per catalog scenario, its traffic alone (no rendering, no detector), seeds and frames as each run "
             "says. Yaw rate [°/s] and lateral acceleration [m/s²]: largest and 99th percentile over every vehicle "
             "and frame step at more than 1 m/s; longitudinal acceleration [m/s²]: 1st and 99th percentile; lane "
             "changes on the straight roads (highway-v0 scenarios): how many, and the median and 10th-percentile "
             "duration [s].", "", "Published figures to compare with:", "", *PUBLISHED, ""]
    for label, run in saved.items():
        lines += [f"## {label}", "", f"Produced by `{run['command']}` ({run['machine']}): seeds {run['seeds']}, "
                  f"{run['frames']} frames.", "",
                  "| scenario | who | yaw rate max / p99 | lateral acc. max / p99 | longitudinal p1 / p99 "
                  "| lane changes (median, p10 duration) |", "|---|---|---|---|---|---|"]
        for name, groups in run["summary"].items():
            for group, s in groups.items():
                changes = (f"{s['lane_changes']} ({_cell(s['lc_median'])} s, {_cell(s['lc_p10'])} s)"
                           if s["lane_changes"] else "–")
                lines.append(f"| {name} | {group} | {_cell(s['yaw_max'])} / {_cell(s['yaw_p99'])} | "
                             f"{_cell(s['lat_max'])} / {_cell(s['lat_p99'])} | {_cell(s['long_p1'])} / "
                             f"{_cell(s['long_p99'])} | {changes} |")
        lines.append("")
    publish(lines, OUT / "index.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
