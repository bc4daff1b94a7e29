"""Report: the reference trackers side by side on the same detections (issue 5's comparison table).

Run explicitly (not part of the test suite)::

    python tests/perf/compare_trackers.py [--scenarios highway_surround6 handover_surround6] [--seeds 0 1 2]
        [--frames 300] [--data runs/compare] [--out reports/trackers/comparison.md]

Each (scenario, seed) dataset is generated once into ``--data`` (reused when a complete one with the same
frame count is there) and every tracker runs on its detections with its default parameters. Per tracker the
table sums the counts (IDS, FRAG, MT, ML, TP, FP, FN) over the sequences and averages AMOTA, AMOTP and MOTA
over them (3D, every class). The verdict compares ``saga`` with ``global_hungarian`` against the target:
IDS at most one third, AMOTA not lower.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from published import cached_dataset, command_line, machine, publish  # tests/perf helpers
from simrig.scenarios import load_scenario

from simrig.pipeline.track import run_tracker
from simrig.scoring import score

TRACKERS = ("saga", "global_hungarian", "percam_merge", "simpletrack",
            "saga:duplicate_iou=0", "global_hungarian:duplicate_iou=0.3")
"""Trackers by name, a variant as ``name:key=value,key=value`` (ablations of one rule)."""
AVERAGED = ("AMOTA", "AMOTP", "MOTA")
SUMMED = ("IDS", "FRAG", "MT", "ML", "TP", "FP", "FN")


def parse_variant(text: str) -> tuple[str, dict]:
    """``"saga:duplicate_iou=0"`` → ``("saga", {"duplicate_iou": 0.0})``."""
    name, _, rest = text.partition(":")
    params = {}
    for item in filter(None, rest.split(",")):
        key, _, value = item.partition("=")
        params[key] = float(value)
    return name, params


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", nargs="+", default=["highway_surround6", "handover_surround6"])
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--trackers", nargs="+", default=list(TRACKERS))
    parser.add_argument("--data", type=Path, default=Path("runs/compare"))
    parser.add_argument("--out", type=Path, default=Path("reports/trackers/comparison.md"))
    args = parser.parse_args()

    rows: dict[tuple[str, str], list[dict]] = {}
    speed: dict[str, list[float]] = {name: [] for name in args.trackers}
    overlaps = {}
    for scenario in args.scenarios:
        overlaps[scenario] = load_scenario(scenario).rig.overlap_deg
        for seed in args.seeds:
            dataset = cached_dataset(scenario, seed, args.frames, args.data)
            for name in args.trackers:
                base, params = parse_variant(name)
                folder = args.data / "tracks" / f"{scenario}-seed{seed}" / name.replace(":", "-").replace("=", "")
                run = run_tracker(dataset, base, folder, params)
                metrics = score(dataset, run.out).metrics3d["overall"]
                rows.setdefault((scenario, name), []).append(metrics)
                speed[name].append(run.frames_per_second)
                print(f"{scenario} seed {seed} {name:17s} AMOTA {metrics['AMOTA']:.3f} IDS {metrics['IDS']:.0f} "
                      f"({run.frames_per_second:.0f} frames/s)", flush=True)

    def line(label: str, metrics: list[dict]) -> str:
        avg = [f"{np.mean([m[k] for m in metrics]):.3f}" for k in AVERAGED]
        tot = [f"{sum(m[k] for m in metrics):.0f}" for k in SUMMED]
        return f"| `{label}` | " + " | ".join(avg + tot) + " |"

    header = "| tracker | " + " | ".join(AVERAGED + SUMMED) + " |\n|---|" + "---:|" * (len(AVERAGED) + len(SUMMED))
    command = command_line()
    lines = [
        "# Reference trackers on the same detections",
        "",
        f"Produced by `{command}` ({machine()}). Scenarios: "
        + ", ".join(f"`{s}` (surround6, {overlaps[s]:g}° overlap)" for s in args.scenarios)
        + f"; seeds {', '.join(map(str, args.seeds))}; {args.frames} frames each at 10 Hz; every tracker with "
        "its default parameters on the same generated detections. 3D metrics over every class (BEV centre "
        "distance < 2 m; class ranges as in `simrig score`): AMOTA, AMOTP, MOTA averaged over the sequences, "
        "counts summed.",
        "",
    ]
    everything: dict[str, list[dict]] = {name: [] for name in args.trackers}
    for scenario in args.scenarios:
        lines += [f"## {scenario}", "", header]
        for name in args.trackers:
            lines.append(line(name, rows[(scenario, name)]))
            everything[name] += rows[(scenario, name)]
        lines.append("")
    lines += ["## All sequences", "", header]
    lines += [line(name, everything[name]) for name in args.trackers]
    lines += ["", "Tracker speed (`step()` only, mean over sequences): "
              + ", ".join(f"{name} {np.mean(speed[name]):.0f} frames/s" for name in args.trackers) + ".", ""]
    if "saga" in everything and "global_hungarian" in everything:
        ids_saga = sum(m["IDS"] for m in everything["saga"])
        ids_hung = sum(m["IDS"] for m in everything["global_hungarian"])
        amota_saga = np.mean([m["AMOTA"] for m in everything["saga"]])
        amota_hung = np.mean([m["AMOTA"] for m in everything["global_hungarian"]])
        ratio = ids_saga / ids_hung if ids_hung else float("nan")
        met = ratio <= 1 / 3 and amota_saga >= amota_hung
        lines += [
            "## Target",
            "",
            f"`saga` IDS / `global_hungarian` IDS = {ids_saga:.0f} / {ids_hung:.0f} = **{ratio:.2f}** (target ≤ 0.33); "
            f"AMOTA {amota_saga:.3f} vs {amota_hung:.3f} (target: not lower). "
            + ("**Met.**" if met else "**Missed.**"),
            "",
        ]
    pairs = (("saga:duplicate_iou=0", "global_hungarian"), ("saga", "global_hungarian:duplicate_iou=0.3"))
    ablations = [(a, b) for a, b in pairs if a in everything and b in everything]
    for a, b in ablations:
        ids_a, ids_b = (sum(m["IDS"] for m in everything[k]) for k in (a, b))
        amota_a, amota_b = (np.mean([m["AMOTA"] for m in everything[k]]) for k in (a, b))
        lines += [f"Ablation: `{a}` against `{b}`: IDS {ids_a:.0f} / {ids_b:.0f} = {ids_a / max(ids_b, 1):.2f}, "
                  f"AMOTA {amota_a:.3f} vs {amota_b:.3f}.", ""]
    publish(lines, args.out)


if __name__ == "__main__":
    main()
