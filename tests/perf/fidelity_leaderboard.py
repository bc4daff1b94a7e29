"""Report: the leaderboard in a box — reference trackers under a realistic detector preset, beside the paper.

Run explicitly (not part of the test suite)::

    python tests/perf/fidelity_leaderboard.py [--seeds 0] [--frames 200] [--data runs/fidelity]

For each surround catalog scene and each detector (``monodis``, the catalog's ``bevformer_small`` and the old
model ``ideal_noise``) it
generates the dataset once (reused from ``--data`` when complete), runs the 3D reference trackers with
their default parameters and scores them (3D, every class). Beside them: the SAGA-Track paper's Table 3
(nuScenes val, MonoDIS-class detections, Mahalanobis cost: KM AMOTA 0.143, IDS 1,998 → FOTA 0.242, 522).
Then the re-ID question: the HOTA and IDF1 advantage of ``deepsort`` (appearance) over ``sort`` on
``highway_surround6``'s front camera, and of ``collabmot`` over ``sort`` on ``highway_stereo``'s left
camera, under both detectors. Written to ``reports/fidelity/leaderboard.md``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from published import cached_dataset, command_line, machine, publish  # tests/perf helpers

from simrig.pipeline.track import run_tracker
from simrig.scoring import score

SCENES = ("highway_surround6", "handover_surround6", "roundabout_surround6")
TRACKERS = ("global_hungarian", "saga", "percam_merge", "simpletrack")
DETECTORS = ("monodis", "bevformer_small", "ideal_noise")  # SAGA-Track's detector class, the catalog's, the old model
PAPER = {"global_hungarian": (0.143, 1998), "saga": (0.242, 522)}  # SAGA-Track paper, Table 3 (KM, FOTA)
REID = (("highway_surround6", "CAM_FRONT", "deepsort"), ("highway_stereo", "left", "collabmot"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", nargs="+", type=int, default=[0])
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--data", type=Path, default=Path("runs/fidelity"))
    parser.add_argument("--out", type=Path, default=Path("reports/fidelity/leaderboard.md"))
    args = parser.parse_args()
    lines = [
        "# The leaderboard in a box: reference trackers under a realistic camera detector",
        "",
        f"Produced by `{command_line()}` ({machine()}); seeds {args.seeds}, {args.frames} frames at 10 Hz, "
        "visibility rendered, every tracker with its default parameters, 3D metrics over every class (BEV centre "
        "distance < 2 m, class ranges as in `simrig score`). Paper: SAGA-Track, Table 3 (nuScenes val, "
        "Mahalanobis cost; KM = Kuhn–Munkres, simrig's `global_hungarian`; FOTA = simrig's `saga`).",
        "",
        "| scene | detector | tracker | AMOTA | recall | IDS | paper AMOTA | paper IDS |",
        "|---|---|---|---:|---:|---:|---:|---:|",
    ]
    ids: dict[tuple[str, str], float] = {}
    for scene in SCENES:
        for detector in DETECTORS:
            for seed in args.seeds:
                dataset = cached_dataset(scene, seed, args.frames, args.data, preset=detector)
                for name in TRACKERS:
                    folder = args.data / "tracks" / f"{scene}-{detector}-seed{seed}" / name
                    metrics = score(dataset, run_tracker(dataset, name, folder).out).metrics3d["overall"]
                    paper = PAPER.get(name) if detector == "monodis" else None
                    recall = metrics["TP"] / max(metrics["TP"] + metrics["FN"], 1)
                    ids[(detector, name)] = ids.get((detector, name), 0.0) + metrics["IDS"]
                    lines.append(f"| {scene} (seed {seed}) | {detector} | `{name}` | {metrics['AMOTA']:.3f} | "
                                 f"{recall:.3f} | {metrics['IDS']:.0f} | "
                                 f"{paper[0] if paper else ''} | {paper[1] if paper else ''} |")
                    print(lines[-1], flush=True)
    lines += ["", "IDS ratio `global_hungarian` / `saga` summed over scenes (paper: 1998 / 522 = 3.83): " + ", ".join(
        f"{detector} {ids[(detector, 'global_hungarian')] / max(ids[(detector, 'saga')], 1):.2f}"
        for detector in DETECTORS) + ".", "",
        "## Re-ID: what appearance buys over SORT", "",
        "| scene / camera | detector | tracker | HOTA | IDF1 | IDSW | advantage over `sort` (HOTA, IDF1) |",
        "|---|---|---|---:|---:|---:|---|"]
    for scene, camera, tracker in REID:
        for detector in DETECTORS:
            for seed in args.seeds:
                dataset = cached_dataset(scene, seed, args.frames, args.data, preset=detector)
                results = {}
                for name in ("sort", tracker):
                    folder = args.data / "tracks" / f"{scene}-{detector}-seed{seed}" / name
                    report = score(dataset, run_tracker(dataset, name, folder).out, camera=camera)
                    results[name] = report.metrics2d["overall"]
                for name, metrics in results.items():
                    gain = "" if name == "sort" else (f"{metrics['HOTA'] - results['sort']['HOTA']:+.3f}, "
                                                      f"{metrics['IDF1'] - results['sort']['IDF1']:+.3f}")
                    lines.append(f"| {scene} / {camera} (seed {seed}) | {detector} | `{name}` | {metrics['HOTA']:.3f} "
                                 f"| {metrics['IDF1']:.3f} | {metrics['IDSW']:.0f} | {gain} |")
                    print(lines[-1], flush=True)
    publish(lines, args.out)


if __name__ == "__main__":
    main()
