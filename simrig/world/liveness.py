"""Is a scenario's traffic alive over a long run? Vehicles in view, births and deaths, flow, crashes.

A scenario is meant to keep stressing a tracker for as many frames as it is run: vehicles around the ego in view of
its cameras, new ones appearing and old ones leaving, traffic flowing rather than jammed, and crashes rare and
recorded. :func:`traffic_liveness` runs the scenario's traffic (:class:`~simrig.world.TrafficWorld`, what
``generate`` steps; no rendering, no detector) and measures this per window of frames: the fewest vehicles in view
of any camera in a frame (a box projected into some camera's image, :func:`~simrig.geometry.project_boxes`;
occlusion not counted), births and deaths, and the mean speeds. Used by ``tests/perf/road_liveness.py`` (1,000-frame
runs) and by the catalog's tests (200 frames).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simrig.geometry import project_boxes
from simrig.rig import build_rig
from simrig.seeding import RandomStreams

from .traffic import TrafficWorld

WINDOW_FRAMES = 100
"""[-] frames per window of :class:`Liveness`."""
FLOW_KEPT = 0.5
"""[-] the last window's mean speed must be at least this fraction of the first's."""


@dataclass(frozen=True)
class Liveness:
    """Per window of :data:`WINDOW_FRAMES` frames (the last may be shorter): ``in_view_min`` (the fewest vehicles
    in view in one frame), ``births``, ``deaths``, ``speed`` (mean speed of the other vehicles [m/s]) and
    ``ego_speed`` [m/s]; over the run: ``crashes`` (frame, event) and the ego's ``progress_m`` (distance driven)."""

    in_view_min: np.ndarray
    births: np.ndarray
    deaths: np.ndarray
    speed: np.ndarray
    ego_speed: np.ndarray
    crashes: tuple[tuple[int, str], ...]
    progress_m: float

    def problems(self) -> list[str]:
        """What keeps the run from counting as alive, one line each (empty: alive): a window without a vehicle
        in view in some frame, a window without births or deaths, the last window's mean speed (the others', or
        the ego's) under :data:`FLOW_KEPT` of the first's, or an ego crash."""
        out = []
        for name, values in (("a frame without a vehicle in view", self.in_view_min == 0),
                             ("no vehicle born", self.births == 0), ("no vehicle left", self.deaths == 0)):
            for window in np.flatnonzero(values):
                out.append(f"frames {window * WINDOW_FRAMES}–{(window + 1) * WINDOW_FRAMES - 1}: {name}")
        for name, speeds in (("other vehicles", self.speed), ("ego", self.ego_speed)):
            if speeds[-1] < FLOW_KEPT * speeds[0]:
                out.append(f"{name}' mean speed fell from {speeds[0]:.1f} m/s (first window) to {speeds[-1]:.1f} "
                           f"m/s (last), under {FLOW_KEPT:.0%}")
        out += [f"frame {frame}: the ego crashed" for frame, event in self.crashes if event == "ego_crashed"]
        return out


def traffic_liveness(scenario, seed: int, frames: int) -> Liveness:
    """Run ``scenario``'s traffic for ``frames`` frames from ``seed`` (the seed's traffic streams, as ``generate``
    draws them) and measure it (module docstring)."""
    streams = RandomStreams(seed)
    world = TrafficWorld(scenario.traffic, scenario.frame_rate_hz, env_seed=streams.integer_seed("traffic"),
                         rng=streams.generator("population"))
    rig = build_rig(scenario.rig)
    in_view, speeds, ego_speeds, ids, crashes = [], [], [], [], []
    start = None
    try:
        for frame in range(frames):
            state = world.reset() if frame == 0 else world.step()
            visible = project_boxes(state.boxes, rig, state.ego).in_view.any(axis=0) if len(state.boxes) else []
            in_view.append(int(np.count_nonzero(visible)))
            speeds.append(float(np.hypot(state.boxes[:, 7], state.boxes[:, 8]).mean()) if len(state.boxes) else 0.0)
            ego_speeds.append(float(np.hypot(state.ego.vx, state.ego.vy)))
            ids.append(set(state.actor_ids.tolist()))
            crashes += [(frame, event) for event in state.events if "crashed" in event]
            position = np.array([state.ego.x, state.ego.y])
            start = position if start is None else start
            progress = float(np.hypot(*(position - start)))
    finally:
        world.close()
    births = [len(now - before) for before, now in zip(ids[:-1], ids[1:], strict=True)]
    deaths = [len(before - now) for before, now in zip(ids[:-1], ids[1:], strict=True)]
    windows = np.arange(0, frames, WINDOW_FRAMES)
    return Liveness(
        in_view_min=np.minimum.reduceat(np.array(in_view), windows),
        births=np.add.reduceat(np.array([0, *births]), windows),
        deaths=np.add.reduceat(np.array([0, *deaths]), windows),
        speed=np.add.reduceat(np.array(speeds), windows) / np.diff([*windows, frames]),
        ego_speed=np.add.reduceat(np.array(ego_speeds), windows) / np.diff([*windows, frames]),
        crashes=tuple(crashes), progress_m=progress,
    )
