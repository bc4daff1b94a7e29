"""Report: the reference trackers side by side on the same detections.

Run explicitly (not part of the test suite)::

    python tests/perf/compare_trackers.py [--scenarios highway_surround6 handover_surround6
        roundabout_surround6] [--seeds 0 1 2 10 11 12] [--held-out 10 11 12] [--frames 200]
        [--data runs/compare] [--out reports/trackers/comparison.md]

Each (scenario, seed) dataset is generated once into ``--data`` (reused when a complete one with the same
frame count is there) and every tracker runs on its detections (the detector is the catalog scenario's own:
``bevformer_small``). Every tracker is online; a variant is ``name:key=value,…``. Per tracker the tables sum the counts
(IDS, FRAG, MT, ML, TP, FP, FN) over the sequences and average AMOTA, AMOTP and MOTA (3D, every class). The IDS
ratio against ``global_hungarian`` is given per sequence and pooled, separately for the seeds used while the
trackers were built and for the ``--held-out`` seeds no one tuned on. A finished (sequence, tracker) keeps
its metrics in ``--data``/tracks/…/metrics.json, so a rerun only scores what is new.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from published import cached_dataset, command_line, machine, publish  # tests/perf helpers
from simrig.scenarios import load_scenario

from simrig.pipeline.track import run_tracker
from simrig.report.paired import paired_difference
from simrig.scoring import score

PURE_FOTA = "saga:birth_merge_m=0,duplicate_iou=0"
TRACKERS = ("saga", PURE_FOTA, "saga:one_per_camera=false", PURE_FOTA + ",one_per_camera=false",
            "global_hungarian", "global_hungarian:duplicate_iou=0.3", "percam_merge", "simpletrack", "mutr3d",
            "polymot", "polymot:coast_s=0")
"""Trackers by name, a variant as ``name:key=value,key=value`` (ablations of one rule)."""
SCORING = {"interpolation": "devkit", "2d_range": "dropped"}
"""The scoring rules a cached ``metrics.json`` was made under: one made under others is scored again."""
LABELS = {
    "saga": "saga (as shipped: FOTA, one detection per camera, birth merge, duplicate rule)",
    PURE_FOTA: "pure FOTA (one detection per camera; no birth merge, no duplicate rule)",
    "saga:one_per_camera=false": "saga without the per-camera constraint",
    PURE_FOTA + ",one_per_camera=false": "pure FOTA without the per-camera constraint",
    "global_hungarian:duplicate_iou=0.3": "global_hungarian + duplicate rule",
    "polymot:coast_s=0": "polymot without reporting coasting tracks",
}
AVERAGED = ("AMOTA", "AMOTP", "MOTA")
SUMMED = ("IDS", "FRAG", "MT", "ML", "TP", "FP", "FN")
REFERENCE = "global_hungarian"
PAIRED_REFERENCE = "saga"


def parse_variant(text: str) -> tuple[str, dict]:
    """``"saga:duplicate_iou=0,life=mutr3d"`` → ``("saga", {"duplicate_iou": 0, "life": "mutr3d"})``, each value
    read as ``simrig track --param`` reads it."""
    from simrig.cli.arguments import tracker_param

    name, _, rest = text.partition(":")
    return name, dict(tracker_param(item) for item in filter(None, rest.split(",")))


def label(name: str) -> str:
    return f"`{name}`" + (f" — {LABELS[name]}" if name in LABELS else "")


def run_one(dataset, scenario: str, seed: int, name: str, data: Path) -> tuple[dict, float]:
    """(3D overall metrics, frames per second) of tracker ``name`` on one sequence, cached in ``data``."""
    base, params = parse_variant(name)
    folder = data / "tracks" / f"{scenario}-seed{seed}-{dataset.frame_count}f" / (
        name.replace(":", "-").replace("=", "").replace(",", "-"))
    cached = folder / "metrics.json"
    detections = dataset.manifest["manifest_sha256"]  # a dataset made since (another detector) invalidates it
    saved = json.loads(cached.read_text()) if cached.exists() else {}
    if saved.get("dataset") == detections and saved.get("scoring") == SCORING:
        return saved["metrics"], saved["frames_per_second"]
    if saved.get("dataset") == detections and (folder / "tracks3d.parquet").exists():
        out, frames_per_second = folder, saved["frames_per_second"]  # the same tracks, scored by newer rules
    else:
        run = run_tracker(dataset, base, folder, params)
        out, frames_per_second = run.out, run.frames_per_second
    metrics = {k: float(v) for k, v in score(dataset, out).metrics3d["overall"].items()
               if isinstance(v, int | float)}
    cached.write_text(json.dumps({"dataset": detections, "scoring": SCORING, "metrics": metrics,
                                  "frames_per_second": frames_per_second}))
    return metrics, frames_per_second


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", nargs="+",
                        default=["highway_surround6", "handover_surround6", "roundabout_surround6"])
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2, 10, 11, 12])
    parser.add_argument("--held-out", nargs="*", type=int, default=[10, 11, 12])
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--trackers", nargs="+", default=list(TRACKERS))
    parser.add_argument("--data", type=Path, default=Path("runs/compare"))
    parser.add_argument("--out", type=Path, default=Path("reports/trackers/comparison.md"))
    args = parser.parse_args()

    rows: dict[tuple[str, int, str], dict] = {}
    speed: dict[str, list[float]] = {name: [] for name in args.trackers}
    overlaps = {}
    for scenario in args.scenarios:
        overlaps[scenario] = load_scenario(scenario).rig.overlap_deg
        for seed in args.seeds:
            dataset = cached_dataset(scenario, seed, args.frames, args.data)
            for name in args.trackers:
                metrics, fps = run_one(dataset, scenario, seed, name, args.data)
                rows[(scenario, seed, name)] = metrics
                speed[name].append(fps)
                print(f"{scenario} seed {seed} {name:40s} AMOTA {metrics['AMOTA']:.3f} IDS {metrics['IDS']:.0f} "
                      f"({fps:.0f} frames/s)", flush=True)

    held_out = [s for s in args.seeds if s in set(args.held_out)]
    tuning = [s for s in args.seeds if s not in set(args.held_out)]
    groups = [(f"seeds {', '.join(map(str, g))}" + (" (held out: never used while tuning)" if g is held_out
                                                   else ""), g) for g in (tuning, held_out) if g]

    def pick(name: str, scenarios, seeds) -> list[dict]:
        return [rows[(sc, se, name)] for sc in scenarios for se in seeds]

    def line(name: str, metrics: list[dict]) -> str:
        avg = [f"{np.mean([m[k] for m in metrics]):.3f}" for k in AVERAGED]
        tot = [f"{sum(m[k] for m in metrics):.0f}" for k in SUMMED]
        return f"| {label(name)} | " + " | ".join(avg + tot) + " |"

    header = "| tracker | " + " | ".join(AVERAGED + SUMMED) + " |\n|---|" + "---:|" * (len(AVERAGED) + len(SUMMED))
    lines = [
        "# Reference trackers on the same detections",
        "",
        f"Produced by `{command_line()}` ({machine()}). Scenarios: "
        + ", ".join(f"`{s}` (surround6, {overlaps[s]:g}° overlap)" for s in args.scenarios)
        + f"; seeds {', '.join(map(str, args.seeds))} (held out, never used while building or tuning any tracker: "
        f"{', '.join(map(str, held_out)) or 'none'}); {args.frames} frames each at 10 Hz. Detector: each scenario's "
        "own, the catalog's `bevformer_small` with FastReID-like re-ID features. Every tracker is online, with its "
        "default parameters unless the variant says otherwise, on the same generated detections. 3D metrics over "
        "every class (BEV centre distance < 2 m; class ranges as in `simrig score`): AMOTA, AMOTP, MOTA averaged "
        "over the sequences, counts summed.",
        "",
    ]
    for title, seeds in groups:
        for scenario in args.scenarios:
            lines += [f"## {scenario}, {title}", "", header]
            lines += [line(name, pick(name, [scenario], seeds)) for name in args.trackers]
            lines.append("")
        lines += [f"## All scenarios, {title}", "", header]
        lines += [line(name, pick(name, args.scenarios, seeds)) for name in args.trackers]
        lines.append("")

    if REFERENCE in args.trackers:
        others = [name for name in args.trackers if name != REFERENCE]
        lines += [f"## IDS against `{REFERENCE}`, per sequence and pooled", "",
                  f"IDS of each tracker / IDS of `{REFERENCE}` on the same sequence (target for FOTA after the "
                  "SAGA-Track paper's 1,998 → 522: at most 1/3). Pooled: the sums' ratio.", "",
                  "| sequence | " + " | ".join(f"`{n}`" for n in others) + f" | `{REFERENCE}` IDS |",
                  "|---|" + "---:|" * (len(others) + 1)]

        def ratio(a: float, b: float) -> str:
            return f"{a / b:.2f}" if b else ("0/0" if a == 0 else "∞")

        for scenario in args.scenarios:
            for seed in args.seeds:
                ref = rows[(scenario, seed, REFERENCE)]["IDS"]
                cells = [f"{ratio(rows[(scenario, seed, n)]['IDS'], ref)} ({rows[(scenario, seed, n)]['IDS']:.0f})"
                         for n in others]
                lines.append(f"| {scenario} seed {seed} | " + " | ".join(cells) + f" | {ref:.0f} |")
        for title, seeds in groups:
            ref = sum(m["IDS"] for m in pick(REFERENCE, args.scenarios, seeds))
            cells = [f"**{ratio(sum(m['IDS'] for m in pick(n, args.scenarios, seeds)), ref)}**" for n in others]
            lines.append(f"| pooled, {title} | " + " | ".join(cells) + f" | {ref:.0f} |")
        lines.append("")
        lines += ["Sequences meeting the 1/3 target (IDS ≤ ⅓ of the reference's; a sequence where the reference has "
                  "no IDS meets it only with none):", ""]
        for name in others:
            met = [rows[(sc, se, name)]["IDS"] * 3 <= rows[(sc, se, REFERENCE)]["IDS"]
                   for sc in args.scenarios for se in args.seeds]
            lines.append(f"- {label(name)}: {sum(met)} of {len(met)}")
        lines.append("")

    if PAIRED_REFERENCE in args.trackers:
        lines += [f"## Paired against `{PAIRED_REFERENCE}`", "",
                  f"Per sequence (scenario × seed), tracker − `{PAIRED_REFERENCE}`: the mean difference with its 95 % "
                  "BCa bootstrap interval over sequences (`simrig.report.paired`); `n.s.`: the interval contains 0.",
                  ""]
        for title, seeds in groups:
            lines += [f"### {title}", "", "| tracker | sequences | Δ AMOTA | Δ MOTA | Δ IDS per sequence |",
                      "|---|---:|---:|---:|---:|"]
            reference = pick(PAIRED_REFERENCE, args.scenarios, seeds)
            for name in args.trackers:
                if name == PAIRED_REFERENCE:
                    continue
                mine = pick(name, args.scenarios, seeds)
                cells = [paired_difference([m[k] for m in mine], [r[k] for r in reference])
                         .text(digits=1 if k == "IDS" else 3) for k in ("AMOTA", "MOTA", "IDS")]
                lines.append(f"| {label(name)} | {len(mine)} | " + " | ".join(cells) + " |")
            lines.append("")

    lines += ["## AMOTA order", "", "Mean AMOTA over the sequences, highest first (the nuScenes leaderboard orders the "
              "modern filter baselines above SimpleTrack-style and AB3DMOT-style trackers):", ""]
    for title, seeds in groups:
        order = sorted(args.trackers, key=lambda n: -np.mean([m["AMOTA"] for m in pick(n, args.scenarios, seeds)]))
        lines.append(f"- {title}: " + " > ".join(
            f"`{n}` {np.mean([m['AMOTA'] for m in pick(n, args.scenarios, seeds)]):.3f}" for n in order))
    lines += ["", "Tracker speed (`step()` only, mean over sequences): "
              + ", ".join(f"`{name}` {np.mean(speed[name]):.0f} frames/s" for name in args.trackers) + ".", ""]
    publish(lines, args.out)


if __name__ == "__main__":
    main()
