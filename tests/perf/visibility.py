"""Benchmark: the cost of visibility (segmentation render + analytic silhouettes), one draw call per camera
against the node-per-actor pyrender renderer it replaced, side by side in one run.

Run explicitly (not part of the test suite)::

    python tests/perf/visibility.py [--frames 100] [--repeats 2]

Part 1, per camera at the default visibility resolution (``highway_surround6``: 6 cameras, 40 vehicles,
render scale 0.5 → 800×450): milliseconds for the segmentation render with counting — simrig's
one-draw-call pass (:mod:`simrig.render.segmentation`) and, on the same frame and camera, the previous
renderer (pyrender ``RenderFlags.SEG`` with one node per actor, colour-coded ids decoded; kept here as the
peer) in alternating order — and for the analytic silhouettes. Every frame's counts of the two renderers
are compared; any difference is reported.

Part 2, frames per second of the whole ``simrig generate`` with visibility off, on, and on with the previous
renderer patched in, runs alternating so that machine noise hits all; medians. Target: with
visibility on at the default resolution, at least 4 frames per second. The table is printed and written
to ``reports/perf/visibility.md``.
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
import pyrender
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


def node_per_actor_counts(scene: RigScene, camera, rig, ego) -> np.ndarray:
    """The renderer simrig used up to commit 3704a39, as the peer: pyrender ``SEG`` with one node (one draw
    call) per actor, ids as 24-bit colours decoded from the image."""
    nodes = scene._place_nodes()
    scene._use_camera(camera, rig, ego)
    values = np.arange(1, len(nodes) + 1)
    colours = np.stack([(values >> 16) & 255, (values >> 8) & 255, values & 255], axis=1).astype(np.uint8)
    image, _ = scene.renderer.render(
        scene.scene, flags=pyrender.RenderFlags.SEG, seg_node_map=dict(zip(nodes, colours, strict=True))
    )
    image = image.astype(np.int32)
    ids = (image[..., 0] << 16) | (image[..., 1] << 8) | image[..., 2]
    return np.bincount(ids.ravel(), minlength=len(nodes) + 1)[1:].astype(np.int64)


def per_camera_costs(scenario, frames: int, seed: int) -> dict[str, list[float]]:
    """Milliseconds per camera and frame of each visibility stage on ``frames`` frames of the scenario, and
    the number of (camera, actor) counts on which the two renderers differ."""
    rig = build_rig(scenario.rig)
    streams = RandomStreams(seed)
    world = TrafficWorld(scenario.traffic, scenario.frame_rate_hz, env_seed=streams.integer_seed("traffic"),
                         rng=streams.generator("population"))
    state = world.reset()
    meter = VisibilityMeter(rig, scenario.render.visibility_scale, RigScene(world.road_markings()))
    costs = {"one draw call": [], "node per actor": [], "silhouettes": [], "pairs": [], "differences": 0}
    for frame in range(frames):
        if frame:
            state = world.step()
        projection = project_boxes(state.boxes, rig, state.ego)
        cameras, actors = np.nonzero(projection.in_view)
        tick = time.perf_counter()
        silhouette_pixel_counts(part_boxes(state.boxes, state.classes), meter.rig, state.ego, cameras, actors)
        costs["silhouettes"].append((time.perf_counter() - tick) * 1e3 / len(rig.cameras))
        meter.scene.set_frame(state.ego, state.classes, state.boxes)
        for index, camera in enumerate(meter.rig.cameras):
            runs = (("one draw call", meter.scene.visible_pixel_counts), ("node per actor", node_per_actor_counts))
            counts = {}
            for label, render in runs if (frame + index) % 2 else runs[::-1]:
                tick = time.perf_counter()
                counts[label] = render(meter.scene, camera, meter.rig, state.ego) if label == "node per actor" \
                    else render(camera, meter.rig, state.ego)
                if frame:  # the first render of a run pays for shader compilation
                    costs[label].append((time.perf_counter() - tick) * 1e3)
            costs["differences"] += int((counts["one draw call"] != counts["node per actor"]).sum())
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
    labels = ("off", "on", "on, node per actor")
    runs = {label: [] for label in labels}
    stages = {label: [] for label in labels[1:]}
    one_draw_call = RigScene.visible_pixel_counts
    with tempfile.TemporaryDirectory() as tmp:
        for repeat in range(args.repeats):
            for label in labels if repeat % 2 == 0 else labels[::-1]:
                if label == "on, node per actor":
                    RigScene.visible_pixel_counts = node_per_actor_counts
                try:
                    variant = without if label == "off" else scenario
                    out = Path(tmp) / f"{len(runs[label])}{label[:3]}{repeat}"
                    result = generate(variant, seed=args.seed, out=out, frames=args.frames)
                finally:
                    RigScene.visible_pixel_counts = one_draw_call
                runs[label].append(result.times.total)
                if label != "off":
                    stages[label].append(result.times)
    fps = {label: args.frames / statistics.median(times) for label, times in runs.items()}
    median_stage = {
        label: {name: 1e3 * statistics.median(getattr(t, name) for t in times) / args.frames
                for name in ("traffic", "projection", "visibility", "sensor", "writing")}
        for label, times in stages.items()
    }
    new, old = statistics.median(costs["one draw call"]), statistics.median(costs["node per actor"])

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
        f"| segmentation render + counting, one draw call (simrig now) | {new:.1f} | "
        f"{np.percentile(costs['one draw call'], 90):.1f} |",
        f"| segmentation render + id decoding + counting, node per actor (before) | {old:.1f} | "
        f"{np.percentile(costs['node per actor'], 90):.1f} |",
        f"| analytic silhouettes | {statistics.median(costs['silhouettes']):.2f} | "
        f"{np.percentile(costs['silhouettes'], 90):.2f} |",
        "",
        f"Render speed-up (before / now, medians): **{old / new:.2f}×**. Counts compared on every frame and "
        f"camera: {costs['differences']} (camera, actor) counts differ between the two renderers.",
        "",
        f"Whole `generate`, {args.frames} frames, medians of {args.repeats} alternating runs:",
        "",
        "| visibility | frames/s | ms/frame: traffic | projection | visibility | sensor | writing | target |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |",
        f"| off | {fps['off']:.1f} | | | | | | |",
        *(
            f"| {label} ({resolution}) | {fps[label]:.1f} | "
            + " | ".join(f"{value:.1f}" for value in median_stage[label].values())
            + f" | ≥ 4 frames/s: {'met' if fps[label] >= 4 else 'MISSED'} |"
            for label in labels[1:]
        ),
        "",
        f"Ratios: on/off {fps['on'] / fps['off']:.2f}; whole `generate` with visibility on, now / before: "
        f"{fps['on'] / fps['on, node per actor']:.2f}× the frames per second.",
        "",
    ]
    text = "\n".join(lines)
    print(text)
    REPORT.parent.mkdir(parents=True, exist_ok=True)
    REPORT.write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
