"""Report: re-ID distances across cameras and viewing angles, next to one camera's distances by frame gap.

    python tests/perf/cross_view.py [--work runs/cross-view] [--seeds 100-103] [--frames 200]

Generates ``stereo_occluder`` (a KITTI-like stereo pair, 0.54 m) and ``highway_surround6`` (a nuScenes-like ring of
six cameras) with their catalog detector, seeds 100–103, and measures the re-ID table of each rig pooled over its
seeds (``simrig detector measure``'s table: one camera by frame gap beside FastReID SBS50 on MOT17 val, then the
same actor seen by two cameras at one frame, by the angle between their rays and by the distance between the
cameras). Writes ``reports/fidelity/cross_view.md``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from published import command_line, machine, publish, seed_range

OUT = Path(__file__).resolve().parents[2] / "reports" / "fidelity" / "cross_view.md"
SCENARIOS = ("stereo_occluder", "highway_surround6")


def main() -> int:
    from simrig.scenarios import load_scenario

    from simrig.detector.measure import pooled_reid
    from simrig.detector.reid import CROSS_CAMERA, format_table
    from simrig.pipeline.generate import generate

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--work", type=Path, default=Path("runs/cross-view"))
    parser.add_argument("--seeds", default="100-103")
    parser.add_argument("--frames", type=int, default=200)
    args = parser.parse_args()
    seeds = seed_range(args.seeds)
    lines = ["# Re-ID across cameras and viewing angles", "",
             f"Produced by `{command_line()}` ({machine()}): each scenario with its catalog detector "
             f"(`bevformer_small`'s re-ID, calibrated by frame gap to FastReID SBS50 on MOT17 val), seeds "
             f"{seeds[0]}–{seeds[-1]}, {args.frames} frames, pooled. d = 0.5·(1 − cos).", ""]
    for name in SCENARIOS:
        paths = []
        for seed in seeds:
            path = args.work / f"{name}-seed{seed}"
            generate(load_scenario(name), seed=seed, frames=args.frames, out=path, overwrite=True)
            paths.append(path)
        rows = pooled_reid(paths)
        by_gap = {row.gaps: row for row in rows}
        cross, gap1 = by_gap[CROSS_CAMERA], by_gap["1"]
        lines += [f"## {name}", "", "```text", format_table(rows), "```", "",
                  f"Same actor, same instant, two cameras: median d {cross.same_median:.3f} against "
                  f"{gap1.same_median:.3f} for one camera one frame later (ratio "
                  f"{cross.same_median / gap1.same_median:.2f}; the check asks ≤ 1.5), AUC {cross.auc:.3f} "
                  f"over {cross.same_pairs} pairs.", ""]
    lines += ["## What the rows can be compared with", "",
              "- By frame gap: FastReID SBS50 on MOT17 val (pedestrians), the source column; no published vehicle "
              "re-ID distances by frame gap were found.",
              "- Across cameras at one instant: the two images of a synchronised stereo pair are nearly the same "
              "picture, so their features can be no further apart than one camera's a frame later — the check "
              "above. The cameras of a surround ring are mounted together: their rays to one car are as close as "
              "a stereo pair's, and what differs is where the car falls in each image (cut by the image edge in "
              "the overlap, so truncated: `truncation_sigma`).",
              "- Across viewing angles: the view part of the model turns with the bearing the car is seen along "
              "(`viewpoint_scale_deg`, 30°). Published vehicle re-ID work (VeRi-776; VANet, Chu et al., ICCV "
              "2019) shows that the same vehicle seen from a different side is often further from itself than "
              "another vehicle seen from the same side; no figure of distance by viewing angle was available to "
              "fit here, so the kernel width is an assumption, not a calibration. In these rigs the angle between "
              "two cameras' rays stays under 5°; large angles occur over time, as a car is overtaken."]
    publish(lines, OUT)
    return 0


if __name__ == "__main__":
    sys.exit(main())
