"""Report: the 3D reference trackers in the loop.

    python tests/perf/closed_loop.py [--work runs/closed-loop] [--workers 2]

Every 3D reference tracker drives ``cut_in``, ``lead_brake``, ``stalled_vehicle`` and ``hidden_cut_in``, seeds
100–104 (fresh: no tracker was tuned on them), closed loop (``simrig.pipeline.drive.drive``), next to the drive on
the ground truth of the same scenario and seed. Per scenario and tracker: drives with a collision and with a near
miss (time to collision < 1.5 s), the median least time to collision, hard brakes and progress per drive, and the
paired difference of progress to the ground-truth drive with its BCa 95% interval. Then every collision or near
miss a tracker caused that the ground-truth drive of that scenario and seed did not have, with its frame, and a
mosaic of the first of them (``simrig render`` of the drive's dataset with the tracker's tracks).

Writes ``reports/closed_loop/index.md``.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from published import command_line, machine, publish

from simrig.report.paired import paired_difference

OUT = Path(__file__).resolve().parents[2] / "reports" / "closed_loop"
SCENARIOS = ("cut_in", "lead_brake", "stalled_vehicle", "hidden_cut_in")
SEEDS = (100, 101, 102, 103, 104)
TRACKERS = ("global_hungarian", "saga", "simpletrack", "polymot", "mutr3d", "percam_merge")
GROUND_TRUTH = "ground truth"


def _drive(job: tuple[str, int, str | None, Path]) -> dict:
    from simrig.scenarios import load_scenario

    from simrig.pipeline.drive import drive

    scenario, seed, tracker, folder = job
    loaded = load_scenario(scenario)
    done = _finished(folder, loaded, seed)
    if done is None:
        done = drive(loaded, seed=seed, out=folder, tracker=tracker, overwrite=True).outcome
    outcome = done
    return {"scenario": scenario, "seed": seed, "tracker": tracker or GROUND_TRUTH, "folder": str(folder),
            "kind": _collision_kind(folder, outcome), **outcome.to_dict()}


def _collision_kind(folder: Path, outcome) -> str | None:
    """How the ego's first collision happened, from where the other road user was in the ego frame at that frame:
    ``rear-end`` (the ego ran into a car ahead of it in its lane: centres within 0.5 m across), ``hit from
    behind``, ``side`` (the other was beside the ego's path: in these scenarios a vehicle changing lanes, yawed
    10–20° to the ego), ``obstacle``."""
    if outcome.collision_frame is None:
        return None
    if outcome.collision_actor is None or outcome.collision_actor < 0:
        return "obstacle" if outcome.collision_actor == -2 else None
    from simrig.dataset import Dataset

    truth = Dataset.open(folder / "dataset").ground_truth
    ego = truth.egos[int(np.searchsorted(truth.frames, outcome.collision_frame))]
    row = np.flatnonzero((truth.frame == outcome.collision_frame) & (truth.actor_id == outcome.collision_actor))[0]
    dx, dy = truth.boxes[row, 0] - ego.x, truth.boxes[row, 1] - ego.y
    along, across = dx * np.cos(ego.yaw) + dy * np.sin(ego.yaw), -dx * np.sin(ego.yaw) + dy * np.cos(ego.yaw)
    if abs(across) >= 0.5:
        return "side"
    return "rear-end" if along > 0 else "hit from behind"


def _finished(folder: Path, scenario, seed: int):
    """The outcome of the drive already in ``folder`` when it is complete and of this scenario and seed (a rerun
    of the report after one scenario changed drives only that one again); None otherwise."""
    from simrig.dataset import Dataset
    from simrig.errors import DatasetError
    from simrig.scoring.drive_outcome import drive_outcome

    try:
        dataset = Dataset.open(folder / "dataset")
    except DatasetError:
        return None
    if dataset.manifest["scenario"] != scenario.model_dump(mode="json") or dataset.seed != seed:
        return None
    return drive_outcome(dataset.ground_truth)


def _table(rows: list[dict]) -> list[str]:
    lines = ["| scenario | perception | collisions | near misses | median min TTC [s] | hard brakes per drive | "
             "progress [m] (paired to ground truth) |", "|---|---|---|---|---|---|---|"]
    for scenario in SCENARIOS:
        truth = {r["seed"]: r for r in rows if r["scenario"] == scenario and r["tracker"] == GROUND_TRUTH}
        for tracker in (GROUND_TRUTH, *TRACKERS):
            mine = sorted((r for r in rows if r["scenario"] == scenario and r["tracker"] == tracker),
                          key=lambda r: r["seed"])
            ttc = np.median([np.inf if r["min_ttc_s"] is None else r["min_ttc_s"] for r in mine])
            progress = np.mean([r["progress_m"] for r in mine])
            paired = "" if tracker == GROUND_TRUTH else "<br>" + paired_difference(
                [r["progress_m"] for r in mine], [truth[r["seed"]]["progress_m"] for r in mine]).text(digits=1)
            kinds = [r["kind"] for r in mine if r["kind"]]
            how = f" ({', '.join(f'{kinds.count(k)} {k}' for k in sorted(set(kinds)))})" if kinds else ""
            lines.append(f"| {scenario} | {tracker} | {sum(r['collisions'] > 0 for r in mine)} of {len(mine)}{how} "
                         f"| {sum(bool(r['near_misses']) for r in mine)} of {len(mine)} | {ttc:.2f} "
                         f"| {np.mean([len(r['hard_brakes']) for r in mine]):.1f} | {progress:.1f}{paired} |")
    return lines


def _caused(rows: list[dict]) -> list[dict]:
    """Drives with a collision or near miss where the ground-truth drive of that scenario and seed had none."""
    truth = {(r["scenario"], r["seed"]): r for r in rows if r["tracker"] == GROUND_TRUTH}
    out = []
    for r in rows:
        if r["tracker"] == GROUND_TRUTH:
            continue
        t = truth[(r["scenario"], r["seed"])]
        if r["collisions"] and not t["collisions"]:
            speed = "" if r["collision_speed_mps"] is None else f", closing at {r['collision_speed_mps']:.1f} m/s"
            out.append({**r, "what": f"collision ({r['kind']}{speed})", "frame": r["collision_frame"]})
        elif r["near_misses"] and not t["near_misses"] and not t["collisions"]:
            out.append({**r, "what": "near miss", "frame": r["near_misses"][0]})
    return sorted(out, key=lambda r: (not r["what"].startswith("collision"), r["scenario"], r["seed"], r["tracker"]))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--work", type=Path, default=Path("runs/closed-loop"), help="where the drives are written")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    jobs = [(scenario, seed, tracker, args.work / scenario / f"seed{seed}" / (tracker or "ground_truth"))
            for scenario in SCENARIOS for seed in SEEDS for tracker in (None, *TRACKERS)]
    with ProcessPoolExecutor(args.workers) as pool:
        rows = list(pool.map(_drive, jobs))
    caused = _caused(rows)
    lines = ["# The reference trackers in the loop", "",
             f"Produced by `{command_line()}` ({machine()}): each 3D reference tracker drives {', '.join(SCENARIOS)} "
             f"closed loop (`simrig drive`), seeds {SEEDS[0]}–{SEEDS[-1]}, next to the drive on the ground truth "
             "(within the class ranges). Near miss: time to collision < 1.5 s; hard brake: deceleration > 4 m/s². "
             "Definitions: docs/planner.md.", "", *_table(rows), "",
             "## Where the ground-truth drive itself collides", ""]
    truth_crashes = [r for r in rows if r["tracker"] == GROUND_TRUTH and r["collisions"]]
    lines += [f"- {r['scenario']}, seed {r['seed']}: {r['kind']} at frame {r['collision_frame']} with actor "
              f"{r['collision_actor']}; `simrig drive {r['scenario']} --seed {r['seed']} --tracker saga` shows it "
              "beside a tracker's drive" for r in truth_crashes] or ["None."]
    lines += ["", "A collision on perfect perception is the scenario's (a scripted or lane-changing vehicle steering "
              "into the ego), not a tracker's; the trackers' drives of that scenario and seed are left out of the "
              "list below.", "", "## Collisions and near misses the ground truth did not have", ""]
    if not caused:
        lines.append("None in these drives.")
    for r in caused:
        ttc = "" if r["min_ttc_s"] is None else f" (least TTC {r['min_ttc_s']:.2f} s at frame {r['min_ttc_frame']})"
        lines.append(f"- `{r['tracker']}` on {r['scenario']}, seed {r['seed']}: {r['what']} at frame {r['frame']}"
                     f"{ttc}; `simrig drive {r['scenario']} --seed {r['seed']} --tracker {r['tracker']}`")
    if caused:
        first = caused[0]
        folder = Path(first["folder"])
        picture = OUT / f"{first['scenario']}-seed{first['seed']}-{first['tracker']}-frame{first['frame']}.png"
        picture.parent.mkdir(parents=True, exist_ok=True)
        subprocess.run(["simrig", "render", str(folder / "dataset"), "--frame", str(first["frame"]), "--tracks",
                        str(folder / "tracks"), "--out", str(picture)], check=True, capture_output=True)
        lines += ["", f"![{first['tracker']} on {first['scenario']} seed {first['seed']}, frame {first['frame']}]"
                      f"({picture.name})", "",
                  f"*The first of them: `{first['tracker']}` drives {first['scenario']}, seed {first['seed']}, "
                  f"frame {first['frame']} (`simrig render DRIVE/dataset --frame {first['frame']} --tracks "
                  "DRIVE/tracks`): ground truth solid, detections dashed, the tracker's tracks dotted.*"]
    publish(lines, OUT / "index.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
