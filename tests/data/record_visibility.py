"""Records the visibility answer of the renderer as it is, for tests/test_render_counts.py to compare against.

Run explicitly, and only with a renderer whose answer is trusted::

    python tests/data/record_visibility.py

Writes ``tests/data/visibility_counts.npz``: for a few frames of several scenarios, the frame's inputs (ego
pose, actor classes and boxes: stored, so the check does not depend on today's traffic) and the renderer's
``visible_px`` and ``silhouette_px`` per camera and actor. It was first run on the node-per-actor renderer
(commit 3704a39) before the one-mesh renderer replaced it.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from simrig.scenarios import load_scenario
from simrig.scenarios.perturbation_schema import WORLD_KINDS

from simrig.geometry import project_boxes
from simrig.render.meter import VisibilityMeter
from simrig.render.scene import RigScene
from simrig.rig import build_rig
from simrig.seeding import RandomStreams
from simrig.world import TrafficWorld

OUT = Path(__file__).with_name("visibility_counts.npz")
CASES = (  # scenario, seed, frames recorded (indices of a run from reset)
    ("highway_surround6", 0, tuple(range(0, 60, 5))),
    ("truck_occlusion", 1, tuple(range(0, 120, 15))),
    ("roundabout_surround6", 0, tuple(range(0, 80, 10))),
    ("highway_stereo", 0, tuple(range(0, 80, 10))),
)


def record(name: str, seed: int, frames: tuple[int, ...]) -> dict[str, np.ndarray]:
    scenario = load_scenario(name)
    rig = build_rig(scenario.rig)
    streams = RandomStreams(seed)
    world = TrafficWorld(
        scenario.traffic, scenario.frame_rate_hz, env_seed=streams.integer_seed("traffic"),
        rng=streams.generator("population"),
        scripted=tuple((i, p) for i, p in enumerate(scenario.perturbations) if p.kind in WORLD_KINDS),
    )
    meter = None
    egos, boxes, classes, counts, visible, silhouette = [], [], [], [0], [], []
    for frame in range(max(frames) + 1):
        state = world.reset() if frame == 0 else world.step()
        if meter is None:
            meter = VisibilityMeter(rig, scenario.render.visibility_scale, RigScene(world.road_markings()))
        if frame not in frames:
            continue
        result = meter.measure(state, project_boxes(state.boxes, rig, state.ego))
        e = state.ego
        egos.append([e.x, e.y, e.z, e.yaw, e.vx, e.vy])
        boxes.append(state.boxes)
        classes.extend(state.classes.tolist())
        counts.append(counts[-1] + len(state.boxes))
        visible.append(result.visible_px.T.ravel())  # actor-major: (N, C) flattened
        silhouette.append(result.silhouette_px.T.ravel())
    world.close()
    return {
        f"{name}/seed": np.array(seed), f"{name}/ego": np.array(egos), f"{name}/boxes": np.concatenate(boxes),
        f"{name}/classes": np.array(classes, dtype=str), f"{name}/offsets": np.array(counts),
        f"{name}/visible_px": np.concatenate(visible), f"{name}/silhouette_px": np.concatenate(silhouette),
    }


def main() -> int:
    arrays = {}
    for case in CASES:
        arrays.update(record(*case))
        print(case[0], "recorded", int(arrays[f"{case[0]}/visible_px"].sum()), "visible pixels")
    np.savez_compressed(OUT, **arrays)
    print("written to", OUT)
    return 0


if __name__ == "__main__":
    sys.exit(main())
