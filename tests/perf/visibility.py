"""Benchmark: the cost of visibility (pyrender segmentation + analytic silhouettes) and of the sensor model.

Run explicitly (not part of the test suite)::

    python tests/perf/visibility.py [--frames 100] [--repeats 2]

Part 1, per camera at the default visibility resolution (``highway_surround6``: 6 cameras, 40 vehicles,
render scale 0.5 → 800×450): milliseconds for the segmentation render with id decoding and counting, and
for the analytic silhouettes, measured on the frames of a real run.

Part 2, frames per second of the whole ``simrig generate`` with visibility on and off, runs alternating
(off, on, off, on, ...) so that machine noise hits both; medians. Target (issue 3): with visibility on at
the default resolution, at least 4 frames per second. The table is printed and written to
``reports/perf/visibility.md``.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from simrig.scenarios import load_scenario
from simrig.scenarios.sensor_schema import RenderConfig

from simrig.geometry import project_boxes
from simrig.pipeline.generate import generate
from simrig.render.meter import VisibilityMeter
from simrig.render.scene import RigScene
from simrig.render.shapes import part_boxes
from simrig.render.silhouette import silhouette_pixel_counts
from simrig.rig import build_rig
from simrig.seeding import RandomStreams
from simrig.world import TrafficWorld

REPORT = Path(__file__).resolve().parents[2] / "reports" / "perf" / "visibility.md"
SCENARIO = "highway_surround6"


def per_camera_costs(scenario, frames: int, seed: int) -> dict[str, list[float]]:
    """Milliseconds per camera and frame of each visibility stage on ``frames`` frames of the scenario."""
    rig = build_rig(scenario.rig)
    streams = RandomStreams(seed)
    world = TrafficWorld(scenario.traffic, scenario.frame_rate_hz, env_seed=streams.integer_seed("traffic"),
                         rng=streams.generator("population"))
    state = world.reset()
    meter = VisibilityMeter(rig, scenario.render.visibility_scale, RigScene(world.road_markings()))
    costs = {"segmentation": [], "silhouettes": [], "pairs": []}
    for frame in range(frames):
        if frame:
            state = world.step()
        projection = project_boxes(state.boxes, rig, state.ego)
        cameras, actors = np.nonzero(projection.in_view)
        tick = time.perf_counter()
        silhouette_pixel_counts(part_boxes(state.boxes, state.classes), meter.rig, state.ego, cameras, actors)
        costs["silhouettes"].append((time.perf_counter() - tick) * 1e3 / len(rig.cameras))
        meter.scene.set_frame(state.ego, state.classes, state.boxes)
        for camera in meter.rig.cameras:
            tick = time.perf_counter()
            meter.scene.visible_pixel_counts(camera, meter.rig, state.ego)
            if frame:  # the first render of a run pays for shader compilation
                costs["segmentation"].append((time.perf_counter() - tick) * 1e3)
        costs["pairs"].append(len(cameras))
    world.close()
    return costs


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    scenario = load_scenario(SCENARIO)
    without = scenario.model_copy(update={"render": RenderConfig(visibility=False)})
    rig = build_rig(scenario.rig)
    resolution = f"{round(rig.cameras[0].width * scenario.render.visibility_scale)}×" \
                 f"{round(rig.cameras[0].height * scenario.render.visibility_scale)}"

    costs = per_camera_costs(scenario, args.frames, args.seed)
    runs = {"off": [], "on": []}
    stages = []
    with tempfile.TemporaryDirectory() as tmp:
        for repeat in range(args.repeats):
            for label, variant in (("off", without), ("on", scenario)):
                result = generate(variant, seed=args.seed, out=Path(tmp) / f"{label}{repeat}", frames=args.frames)
                runs[label].append(result.times.total)
                if label == "on":
                    stages.append(result.times)
    fps = {label: args.frames / statistics.median(times) for label, times in runs.items()}
    median_stage = {name: 1e3 * statistics.median(getattr(t, name) for t in stages) / args.frames
                    for name in ("traffic", "projection", "visibility", "sensor", "writing")}

    lines = [
        "# Visibility and generation speed",
        "",
        f"Command: `python tests/perf/visibility.py --frames {args.frames} --repeats {args.repeats}` "
        f"({SCENARIO}, seed {args.seed}; {platform.processor() or platform.machine()}, "
        f"Python {platform.python_version()}, {sys.platform}).",
        "",
        f"Per camera at the default visibility resolution ({resolution}), medians over {args.frames} frames "
        f"× {len(rig.cameras)} cameras (mean {statistics.fmean(costs['pairs']):.0f} actor-camera pairs in view "
        "per frame):",
        "",
        "| stage | ms per camera (median) | p90 |",
        "| --- | ---: | ---: |",
        f"| segmentation render + id decoding + counting | {statistics.median(costs['segmentation']):.1f} | "
        f"{np.percentile(costs['segmentation'], 90):.1f} |",
        f"| analytic silhouettes | {statistics.median(costs['silhouettes']):.2f} | "
        f"{np.percentile(costs['silhouettes'], 90):.2f} |",
        "",
        f"Whole `generate`, {args.frames} frames, medians of {args.repeats} alternating runs:",
        "",
        "| visibility | frames/s | target |",
        "| --- | ---: | --- |",
        f"| off | {fps['off']:.1f} | |",
        f"| on ({resolution}) | {fps['on']:.1f} | ≥ 4 frames/s: {'met' if fps['on'] >= 4 else 'MISSED'} |",
        "",
        f"Ratio on/off: {fps['on'] / fps['off']:.2f}. Where a frame goes with visibility on (ms per frame): "
        + ", ".join(f"{name} {value:.1f}" for name, value in median_stage.items()) + ".",
        "",
    ]
    text = "\n".join(lines)
    print(text)
    REPORT.parent.mkdir(parents=True, exist_ok=True)
    REPORT.write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
