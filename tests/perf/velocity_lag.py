"""Report: how far each 3D reference tracker's velocity lags a braking lead car.

    python tests/perf/velocity_lag.py [--work runs/velocity-lag] [--seeds 100-109] [--workers 1]

``lead_brake`` (the car 40 m ahead in the ego's lane brakes to a stop at 8 m/s²; the car the ego follows — that
one, or traffic spawned between them, which then brakes for it — is the one measured), open loop (the ego
drives on the ground truth, so every tracker sees the same world), seeds 100–109 (fresh: no tracker was tuned on
them), with the scenario's default detector and with the ``perfect`` preset (exact boxes and velocities, no misses).
Per tracker and frame from the braking onwards, the track nearest the braking car (centre within 2 m) is its track;
its speed is its velocity along the car's heading. Reported per tracker and preset, median over seeds:

* lag [s]: time from the start of braking until the track's speed is within 1 m/s of the car's true speed and stays
  there until 4 s after braking started (the car has stopped by then); ``never`` when it is not within 1 m/s at the
  end; a frame where no track is near the car counts as not within;
* peak error [m/s]: the largest |track speed − true speed| in those 4 s (frames with a track);
* lost [frames]: frames in those 4 s with no track within 2 m of the car.

Writes ``reports/velocity_lag/index.md``.
"""

from __future__ import annotations

import argparse
import re
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from published import command_line, machine, publish, seed_range

OUT = Path(__file__).resolve().parents[2] / "reports" / "velocity_lag" / "index.md"
TRACKERS = ("global_hungarian", "saga", "simpletrack", "polymot", "mutr3d", "percam_merge")
PRESETS = ("default", "perfect")
WINDOW_S = 4.0
"""[s] after braking starts: the car (≤ 25 m/s at 8 m/s²) has stopped within ~3 s."""
WITHIN_MPS = 1.0
NEAR_M = 2.0
FRAMES = 100


BRAKING_MPS2 = 2.0
"""[m/s²] the ego's leader has started braking when it first decelerates harder than this."""


def _braking(dataset) -> tuple[int, int]:
    """(frame the ego's leader starts braking, its actor id). The leader is the nearest vehicle ahead of the ego in
    its lane when the scripted car brakes (traffic spawned between them on the one-lane road makes it another car,
    which then brakes for it)."""
    truth = dataset.ground_truth
    rate = dataset.manifest["frame_rate_hz"]
    scripted = next(int(e["frame"]) for e in dataset.manifest["events"]
                    if re.search(r"lead_brake#\d+ brakes at", e["event"]))
    ego = truth.egos[scripted]
    rows = np.flatnonzero(truth.frame == scripted)
    ahead = truth.boxes[rows, 0] - ego.x
    rows, ahead = rows[(ahead > 0) & (np.abs(truth.boxes[rows, 1] - ego.y) < 2.0)], ahead[
        (ahead > 0) & (np.abs(truth.boxes[rows, 1] - ego.y) < 2.0)]
    leader = int(truth.actor_id[rows[np.argmin(ahead)]])
    mine = np.flatnonzero(truth.actor_id == leader)
    frames, speed = truth.frame[mine], truth.boxes[mine, 7]
    slowing = np.flatnonzero((frames[1:] >= scripted) & (np.diff(speed) * rate < -BRAKING_MPS2))
    return int(frames[slowing[0]]), leader


def _one(job: tuple[int, str, Path]) -> list[dict]:
    from simrig.scenarios import load_scenario
    from simrig.scenarios.overrides import with_setting

    import simrig
    from simrig.dataset.tracks_file import read_tracks

    seed, preset, work = job
    scenario = load_scenario("lead_brake")
    if preset != "default":
        scenario = with_setting(scenario, "sensor.preset", preset)
    dataset = simrig.generate(scenario, seed=seed, frames=FRAMES, out=work / f"{preset}-seed{seed}", overwrite=True)
    start, car = _braking(dataset)
    truth = dataset.ground_truth
    rate = dataset.manifest["frame_rate_hz"]
    window = np.arange(start, min(start + int(WINDOW_S * rate) + 1, FRAMES))
    rows = []
    for tracker in TRACKERS:
        folder = work / f"{preset}-seed{seed}-tracks" / tracker
        simrig.track(dataset, tracker, out=folder)
        tracks = read_tracks(folder, frame_count=FRAMES, cameras=dataset.rig.camera_names).tracks3d
        errors = np.full(len(window), np.nan)
        for k, frame in enumerate(window):
            row = np.flatnonzero((truth.frame == frame) & (truth.actor_id == car))
            if not len(row):
                continue
            box = truth.boxes[row[0]]
            heading = np.array([np.cos(box[6]), np.sin(box[6])])
            mine = np.flatnonzero(tracks.frame == frame)
            if not len(mine):
                continue
            distance = np.hypot(*(tracks.boxes[mine, :2] - box[:2]).T)
            nearest = mine[int(np.argmin(distance))]
            if distance.min() <= NEAR_M:
                errors[k] = tracks.boxes[nearest, 7:9] @ heading - box[7:9] @ heading
        within = np.abs(np.nan_to_num(errors, nan=np.inf)) <= WITHIN_MPS
        settled = np.flatnonzero(~within)
        lag = None if not within[-1] else (0.0 if not len(settled) else (settled[-1] + 1) / rate)
        rows.append({"seed": seed, "preset": preset, "tracker": tracker, "lag_s": lag,
                     "peak_mps": float(np.nanmax(np.abs(errors))) if np.isfinite(errors).any() else None,
                     "lost": int(np.isnan(errors).sum()), "errors": errors})
    return rows


EXPLANATION = [
    "- `global_hungarian`, `saga`, `simpletrack`, `percam_merge`: AB3DMOT's constant-velocity Kalman filter "
    "(Weng et al., IROS 2020) with AB3DMOT's noise — per 0.1 s step, 1 m² on the position and 1 (m/s)² on the "
    "velocity, R 1 m² — which measures positions only: the detector's velocity is used once, at birth. A "
    "constant-velocity filter follows a constant deceleration a with a steady-state speed error of a·T·(α/β − ½), α "
    "and β its steady-state gains: 8.5 m/s at 8 m/s² with these noises (`tests/test_trackers.py` checks the filter "
    "against that formula). The car has stopped about 2.5 s after it starts braking, before the error gets there: it "
    "peaks at about 4.4 m/s with exact positions, and the filter then takes seconds more to believe the stop, hence "
    "lags of 3–4 s with either preset. With exact positions the track is never lost (its position follows with "
    "α ≈ 0.65); with the default detector the lost frames are missed and occluded detections. Corrected while "
    "measuring this: these trackers took AB3DMOT's per-frame noise as per-second values, 10× less on the position "
    "and 1000× less on the velocity (AB3DMOT's velocity is in metres per frame), and then lagged by up to 8.9 m/s "
    "and lost the car for 19 of 41 frames even with exact detections; they now step with AB3DMOT's noise at 10 Hz "
    "(`simrig.trackers.motion.KalmanConfig`).",
    "- `polymot`: Poly-MOT's category-specific motion (Li et al., IROS 2023): a constant-turn-rate-and-acceleration "
    "filter for cars, with acceleration in its state, so it follows the braking within about 2 m/s and keeps the "
    "track; what remains is the time the acceleration estimate takes to build up.",
    "- `mutr3d`: MUTR3D moves a query with the velocity its network predicts from the images (Zhang et al., CVPR "
    "Workshops 2022, Eq. 7), not a filter's estimate from positions; simrig's `mutr3d` takes that velocity from its "
    "best matched detection. With exact velocities its speed is exact; with the default detector it is as good as "
    "the detector's velocity (peak error under 1 m/s), and its lag is the frames where no track is near the car "
    "(missed or occluded detections) rather than a speed error.",
]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--work", type=Path, default=Path("runs/velocity-lag"))
    parser.add_argument("--seeds", default="100-109")
    parser.add_argument("--workers", type=int, default=1)
    args = parser.parse_args()
    seeds = seed_range(args.seeds)
    jobs = [(seed, preset, args.work) for preset in PRESETS for seed in seeds]
    with ProcessPoolExecutor(args.workers) as pool:
        rows = [row for rows in pool.map(_one, jobs) for row in rows]
    lines = ["# Velocity lag on a braking lead car", "",
             f"Produced by `{command_line()}` ({machine()}): `lead_brake` open loop (the ego drives on the ground "
             f"truth), {FRAMES} frames, seeds {seeds[0]}–{seeds[-1]}; the car ahead brakes to a stop at 8 m/s² from "
             "frame 50; measured on the car the ego follows, from the frame it starts braking (> 2 m/s²). "
             "Lag: time from the start of braking until the tracker's speed of the car is within "
             f"{WITHIN_MPS:g} m/s of the truth and stays there until {WINDOW_S:g} s after; `never`: not within at "
             f"the end; a frame with no track within {NEAR_M:g} m of the car counts as not within. Peak error: the "
             f"largest |track − true| speed in those {WINDOW_S:g} s. Medians over seeds (lag: median of the seeds "
             "that settle, with how many did).", "",
             "| tracker | preset | lag [s] (seeds settled) | peak speed error [m/s] | frames lost (of "
             f"{int(WINDOW_S * 10) + 1}) |", "|---|---|---|---|---|"]
    for tracker in TRACKERS:
        for preset in PRESETS:
            mine = [r for r in rows if r["tracker"] == tracker and r["preset"] == preset]
            lags = [r["lag_s"] for r in mine if r["lag_s"] is not None]
            peaks = [r["peak_mps"] for r in mine if r["peak_mps"] is not None]
            lag = f"{np.median(lags):.1f} ({len(lags)} of {len(mine)})" if lags else f"never (0 of {len(mine)})"
            peak = f"{np.median(peaks):.1f}" if peaks else "–"
            lines.append(f"| `{tracker}` | {preset} | {lag} | {peak} | {np.median([r['lost'] for r in mine]):.0f} |")
    lines += ["", "Speed error [m/s] of the first seed, frames 50–90 every 5 (track − truth; blank: no track):", "",
              "| tracker | preset | " + " | ".join(str(50 + k) for k in range(0, 41, 5)) + " |",
              "|---|---|" + "---|" * 9]
    for r in rows:
        if r["seed"] == seeds[0]:
            cells = ["" if np.isnan(e) else f"{e:+.1f}" for e in r["errors"][::5]]
            lines.append(f"| `{r['tracker']}` | {r['preset']} | " + " | ".join(cells) + " |")
    lines += ["", "## Why, tracker by tracker", "", *EXPLANATION]
    publish(lines, OUT)
    return 0


if __name__ == "__main__":
    sys.exit(main())
