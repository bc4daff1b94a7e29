"""Report: `mutr3d`'s 3D association gate against its former image gate, scored with and without gap filling.

Run explicitly (not part of the test suite)::

    python tests/perf/mutr3d_gate.py [--scenarios highway_surround6 handover_surround6 roundabout_surround6]
        [--seeds 100-109] [--frames 200] [--data runs/mutr3d] [--out reports/trackers/mutr3d_gate.md]

On each (scenario, seed) dataset (the catalog scenario's own detector, generated once into ``--data``) it runs
`global_hungarian`, `mutr3d` (3D Mahalanobis gate, as shipped) and `mutr3d` with ``cost2d=iou`` (the image IoU
gate it had before) and scores each twice: as the nuScenes devkit ships (gaps inside a track filled, ``simrig
score``'s default) and with ``interpolation="none"``. Per tracker and scoring: the 3D identity switches summed, the
paired per-sequence difference to `global_hungarian` (IDS and AMOTA, 95 % BCa intervals) and the pooled IDS ratio
with its BCa interval (:mod:`simrig.report.paired`).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from published import cached_dataset, command_line, machine, publish, seed_range  # tests/perf helpers

from simrig.pipeline.track import run_tracker
from simrig.report.paired import paired_difference, paired_ratio
from simrig.scoring import score

REFERENCE = "global_hungarian"
TRACKERS = {REFERENCE: {}, "mutr3d": {}, "mutr3d (image IoU gate)": {"cost2d": "iou"}}
"""Label → (tracker, parameters): every label but the reference runs `mutr3d`."""
SCORINGS = ("devkit", "none")
"""Interpolation rules compared: the devkit's gap filling, and the tracks as given."""


def _sequence(dataset, label: str, params: dict, folder: Path) -> dict[str, dict[str, float]]:
    """3D IDS and AMOTA of one tracker on one dataset under each scoring rule, cached in ``folder``."""
    cached = folder / "metrics.json"
    key = dataset.manifest["manifest_sha256"]
    saved = json.loads(cached.read_text()) if cached.exists() else {}
    if saved.get("dataset") == key:
        return saved["metrics"]
    tracker = "mutr3d" if label != REFERENCE else REFERENCE
    out = run_tracker(dataset, tracker, folder, params).out
    metrics = {}
    for rule in SCORINGS:
        overall = score(dataset, out, interpolation=rule, planner=False).metrics3d["overall"]
        metrics[rule] = {"IDS": float(overall["IDS"]), "AMOTA": float(overall["AMOTA"])}
    cached.write_text(json.dumps({"dataset": key, "metrics": metrics}))
    return metrics


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", nargs="+",
                        default=["highway_surround6", "handover_surround6", "roundabout_surround6"])
    parser.add_argument("--seeds", type=seed_range, default=seed_range("100-109"))
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--data", type=Path, default=Path("runs/mutr3d"))
    parser.add_argument("--out", type=Path, default=Path("reports/trackers/mutr3d_gate.md"))
    args = parser.parse_args()

    rows: dict[str, list[dict]] = {label: [] for label in TRACKERS}
    for scenario in args.scenarios:
        for seed in args.seeds:
            dataset = cached_dataset(scenario, seed, args.frames, args.data)
            for label, params in TRACKERS.items():
                folder = args.data / "tracks" / f"{scenario}-seed{seed}-{args.frames}f" / label.split()[0] / (
                    "-".join(f"{k}{v}" for k, v in params.items()) or "default")
                folder.mkdir(parents=True, exist_ok=True)
                rows[label].append(_sequence(dataset, label, params, folder))
                print(f"{scenario} seed {seed} {label:28s} IDS " + " / ".join(
                    f"{rows[label][-1][rule]['IDS']:.0f}" for rule in SCORINGS), flush=True)

    sequences = len(rows[REFERENCE])
    lines = ["# `mutr3d`: 3D gate against the image IoU gate, with and without gap filling", "",
             f"Produced by `{command_line()}` ({machine()}). Scenarios {', '.join(f'`{s}`' for s in args.scenarios)}"
             f" × seeds {args.seeds[0]}–{args.seeds[-1]} ({sequences} sequences, {args.frames} frames at 10 Hz), each "
             "with its catalog detector (`bevformer_small`). 3D identity switches (nuScenes IDS) and AMOTA over every "
             f"class; Δ: paired per-sequence difference to `{REFERENCE}` with its 95 % BCa bootstrap interval over "
             "sequences (`n.s.`: the interval holds 0); pooled ratio: the sums' ratio with its BCa interval over "
             "sequences resampled in pairs.", ""]
    for rule in SCORINGS:
        title = ("scored as the devkit ships (gaps inside a track filled)" if rule == "devkit"
                 else "scored without gap filling (`--interpolation none`)")
        lines += [f"## {title}", "",
                  "| tracker | IDS (sum) | Δ IDS per sequence | pooled IDS ratio | Δ AMOTA |",
                  "|---|---:|---:|---:|---:|"]
        reference_ids = [row[rule]["IDS"] for row in rows[REFERENCE]]
        reference_amota = [row[rule]["AMOTA"] for row in rows[REFERENCE]]
        lines.append(f"| `{REFERENCE}` | {sum(reference_ids):.0f} | | | |")
        for label in TRACKERS:
            if label == REFERENCE:
                continue
            ids = [row[rule]["IDS"] for row in rows[label]]
            amota = [row[rule]["AMOTA"] for row in rows[label]]
            ratio, low, high = paired_ratio(ids, reference_ids)
            lines.append(f"| `{label}` | {sum(ids):.0f} | {paired_difference(ids, reference_ids).text(digits=1)} | "
                         f"{ratio:.2f} [{low:.2f}, {high:.2f}] | "
                         f"{paired_difference(amota, reference_amota).text()} |")
        lines.append("")
    publish(lines, args.out)


if __name__ == "__main__":
    main()
