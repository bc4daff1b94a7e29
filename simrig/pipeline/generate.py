"""``simrig generate``: run a scenario's traffic, see it through the rig, detect it, write the dataset.

Per frame: traffic (highway-env) → analytic projection → visibility (pyrender segmentation + analytic
silhouettes) → the sensor model → optional colour images → the tables.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import numpy as np
from tqdm import tqdm

from simrig.dataset import Dataset, DatasetWriter, check_output_folder
from simrig.dataset.manifest import IMAGES_FOLDER, package_versions
from simrig.errors import DatasetError, TrafficCrashError
from simrig.geometry import Projection, project_boxes
from simrig.interrupts import stop_if_interrupted
from simrig.pipeline.content_keys import drive_key, world_key
from simrig.pipeline.frame_columns import frame_columns
from simrig.pipeline.recorded_world import RecordedWorld
from simrig.render.visibility import Visibility
from simrig.rig import build_rig, rig_to_dict
from simrig.scenarios import Scenario, ScenarioError
from simrig.scenarios.perturbation_schema import WORLD_KINDS
from simrig.scenarios.timing_schema import latency_beyond
from simrig.scoring.planner import PlanningRoad
from simrig.scoring.truth_plans import TruthPlanner
from simrig.seeding import RandomStreams
from simrig.sensor.model import SensorModel
from simrig.types import EGO_ID, OBSTACLE_ID, GroundTruthFrame
from simrig.world import TrafficWorld


class Driver(Protocol):
    """What decides the ego's perception in a closed-loop generation (:mod:`simrig.pipeline.drive`)."""

    record: dict

    def decide(self, state: GroundTruthFrame, columns: dict[str, dict]) -> tuple[np.ndarray, np.ndarray]:
        """World boxes ``(N, 9)`` and idents ``(N,)`` the ego's planner perceives for the next step."""


@dataclass
class StageTimes:
    """Wall-clock seconds spent per stage of a generation run."""

    traffic: float = 0.0
    projection: float = 0.0
    visibility: float = 0.0
    sensor: float = 0.0
    driving: float = 0.0
    planning: float = 0.0
    images: float = 0.0
    writing: float = 0.0
    total: float = 0.0

    @contextmanager
    def stage(self, name: str) -> Iterator[None]:
        """Add the seconds the block takes to stage ``name``."""
        tick = time.perf_counter()
        try:
            yield
        finally:
            setattr(self, name, getattr(self, name) + time.perf_counter() - tick)


@dataclass
class GenerateResult:
    """What a generation produced: the dataset folder, its manifest, and where the time went."""

    path: Path
    manifest: dict
    times: StageTimes = field(default_factory=StageTimes)


def check_generable(scenario: Scenario, frames: int | None = None) -> None:
    """Raise the :class:`~simrig.scenarios.ScenarioError` :func:`generate` raises before any simulation work —
    detection latency beyond the last frame, a perturbation or timing table naming a camera the rig lacks —
    without generating (a few milliseconds: the rig and the sensor model are built and dropped)."""
    too_late = latency_beyond(scenario, scenario.frames if frames is None else frames)
    if too_late:
        raise ScenarioError(too_late)
    SensorModel(scenario, build_rig(scenario.rig), RandomStreams(0))


def generate(
    scenario: Scenario,
    *,
    seed: int,
    out: Path | str,
    frames: int | None = None,
    overwrite: bool = False,
    images: bool = False,
    progress: bool = False,
    world_from: Dataset | None = None,
    removed: frozenset[str] = frozenset(),
    driver: Driver | None = None,
) -> GenerateResult:
    """Generate the dataset of ``scenario`` with ``seed`` into ``out``; ``frames`` defaults to the scenario's.

    ``images`` also writes a PNG per camera and frame at the image resolution. Same scenario, seed and
    frame count give byte-identical files. Raises :class:`~simrig.errors.DatasetExistsError` if ``out``
    holds a complete dataset and ``overwrite`` is false, and :class:`~simrig.scenarios.ScenarioError` for a
    perturbation naming a camera the rig lacks (both checked before any simulation work).

    ``world_from``: a dataset of the same world (same :func:`~simrig.pipeline.content_keys.world_key`: traffic, rig,
    rendering, world perturbations, seed and frames; only the detector's settings and sensor perturbations may
    differ). Its traffic and measured visibility are reused and only the sensor model runs — the files are
    byte-identical to a full generation, in a fraction of the time (no simulation, no rendering).

    ``removed``: cause groups of the detector switched off (:mod:`simrig.sensor.groups`) — a counterfactual
    dataset whose every other random draw is the one of the dataset with all causes on; its manifest records
    them under ``removed_causes`` (absent when none are removed).

    ``driver`` (closed loop, :mod:`simrig.pipeline.drive`): after each frame is written, it is given the frame and
    its columns and answers what the ego's planner perceives for the next step (world boxes and idents); the
    ego then drives on that instead of the real vehicles. Its ``record`` goes into the manifest under ``drive``,
    and the world key covers everything (the world then depends on the detector and the tracker too).
    """
    frames = scenario.frames if frames is None else frames
    out = Path(out)
    _check_request(scenario, seed, frames, images, world_from, driver)
    check_output_folder(out, overwrite=overwrite)
    streams = RandomStreams(seed)
    rig = build_rig(scenario.rig)
    sensor = SensorModel(scenario, rig, streams, removed=removed)
    times = StageTimes()
    started = time.perf_counter()
    world = (_SimulatedWorld(scenario, rig, streams, images, ego_on_perception=driver is not None)
             if world_from is None else RecordedWorld(world_from, rig))
    with times.stage("planning"):
        plans = _TruthPlans(scenario, seed, world_from)
    events: list[dict] = []
    try:
        with DatasetWriter(out, overwrite=overwrite) as writer:
            writer.write_json("rig.json", rig_to_dict(rig))
            for frame in tqdm(range(frames), desc=scenario.name, unit="frame", disable=not progress):
                stop_if_interrupted()
                state, projection, visibility = world.frame(frame, times)
                refuse_crashes(scenario, seed, state)
                events.extend({"frame": state.frame, "event": name} for name in state.events)
                _write_frame(frame, state, projection, visibility, world, sensor, plans, writer, times,
                             images=images, driver=driver)
            with times.stage("writing"):
                manifest = writer.commit(_manifest_record(scenario, seed, frames, events, removed, driver))
    finally:
        world.close()
    times.total = time.perf_counter() - started
    return GenerateResult(path=out, manifest=manifest, times=times)


def _check_request(scenario: Scenario, seed: int, frames, images: bool, world_from: Dataset | None,
                   driver: Driver | None) -> None:
    """Refuse, before any work, a frame count that is no positive integer, a detection latency beyond the
    scenario's length, and a reused world that cannot be (with images, in a drive, or not the same world)."""
    if not isinstance(frames, int) or frames < 1:
        raise ValueError(f"frames: must be a positive integer, got {frames!r}")
    too_late = latency_beyond(scenario, frames)  # checked for the scenario's own length; --frames may be shorter
    if too_late:
        raise ScenarioError(too_late)
    if world_from is not None and driver is not None:
        raise ValueError("driver: a closed-loop drive simulates its own world; it cannot reuse one (world_from)")
    if world_from is not None:
        if images:
            raise ValueError("images: cannot be written when the world is reused (world_from); generate in full")
        if world_from.manifest.get("world_key") != world_key(scenario, seed, frames):
            raise DatasetError(f"{world_from.path}: not the same world as {scenario.name!r} seed {seed}, "
                               f"{frames} frames (traffic, rig, rendering or world perturbations differ)")


def _write_frame(frame: int, state, projection, visibility, world, sensor: SensorModel, plans, writer: DatasetWriter,
                 times: StageTimes, *, images: bool, driver: Driver | None) -> None:
    """One frame of the world (its state, projection and visibility) through the sensor, its images when asked
    for, its rows with the ground-truth plan written, and a drive's perception handed back to the ego."""
    rig = sensor.rig
    if frame == 0 and world.markings is not None:
        writer.write_json("road.json", world.markings.to_dict())
    with times.stage("sensor"):
        output = sensor.observe(state, projection, visibility)
    if images:
        with times.stage("images"):
            scene = world.scene
            scene.set_frame(state.ego, state.classes, state.boxes)
            for camera in rig.cameras:
                writer.write_image(f"{IMAGES_FOLDER}/{camera.name}/{frame:06d}.png",
                                   scene.colour(camera, rig, state.ego))
    with times.stage("writing"):
        columns = frame_columns(state, visibility, output, rig.camera_names)
    with times.stage("planning"):
        columns["truth_plans"] = plans.row(state)
    with times.stage("writing"):
        writer.write_frame(columns)
    if driver is not None:
        with times.stage("driving"):
            world.traffic.perceive(*driver.decide(state, columns))


def _manifest_record(scenario: Scenario, seed: int, frames: int, events: list[dict], removed, driver) -> dict:
    """What the manifest says of a generation besides its files: the resolved scenario, seed, frames, versions, the
    simulator's events, the world's key (a drive's: with who perceived), and the causes removed."""
    return {
        "scenario": scenario.model_dump(mode="json"),
        "seed": seed,
        "frames": frames,
        "frame_rate_hz": scenario.frame_rate_hz,
        "visibility": "rendered" if scenario.render.visibility else "not measured",
        "versions": package_versions(),
        "events": events,
        "world_key": (world_key(scenario, seed, frames) if driver is None
                      else drive_key(scenario, seed, frames, driver.record)),
        **({"removed_causes": sorted(removed)} if removed else {}),
        **({"drive": driver.record} if driver is not None else {}),
    }


def refuse_crashes(scenario: Scenario, seed: int, state: GroundTruthFrame) -> None:
    """A :class:`~simrig.errors.TrafficCrashError` when ``scenario`` refuses crashes (``traffic.crashes``) and two
    road users other than the ego collided during the step to ``state``."""
    if scenario.traffic.crashes != "refused":
        return
    crashes = [c for c in state.collisions if c.geometry and EGO_ID not in (c.first, c.second)]
    if crashes:
        first = crashes[0]
        pair = (f"vehicle {first.second} and a fixed obstacle" if first.first == OBSTACLE_ID  # ids sorted: −2 first
                else f"vehicles {first.first} and {first.second}")
        raise TrafficCrashError(f"{scenario.name}: seed {seed}: {pair} collide at frame {state.frame}, and the "
                                "scenario refuses crashes (traffic.crashes = \"refused\"): choose another seed, or "
                                "allow them")


class _TruthPlans:
    """The ``truth_plans`` rows of a generation (:mod:`simrig.scoring.truth_plans`): asked of the ego's planner, or,
    when the world is reused from a dataset that recorded them, its rows (the same ground truth, the same plans)."""

    def __init__(self, scenario: Scenario, seed: int, world_from: Dataset | None):
        self._recorded = (world_from.table("truth_plans")
                          if world_from is not None and world_from.has_table("truth_plans") else None)
        if self._recorded is None:
            self._planner = TruthPlanner(PlanningRoad(scenario.traffic, scenario.frame_rate_hz, seed))

    def row(self, state: GroundTruthFrame) -> dict:
        """The row of ``state``'s frame, as column chunks."""
        if self._recorded is not None:
            return {name: self._recorded.column(name).slice(state.frame, 1).combine_chunks()
                    for name in self._recorded.column_names}
        return self._planner.row(state.frame, state.ego, state.actor_ids, state.classes, state.boxes)


class _SimulatedWorld:
    """The world of a full generation: highway-env traffic, analytic projection, rendered visibility."""

    def __init__(self, scenario: Scenario, rig, streams: RandomStreams, images: bool, ego_on_perception: bool = False):
        self.scenario, self.rig, self.images = scenario, rig, images
        self.traffic = TrafficWorld(
            scenario.traffic,
            scenario.frame_rate_hz,
            env_seed=streams.integer_seed("traffic"),
            rng=streams.generator("population"),
            scripted=tuple((i, p) for i, p in enumerate(scenario.perturbations) if p.kind in WORLD_KINDS),
            ego_on_perception=ego_on_perception,
        )
        self.markings = self.scene = self.meter = None

    def frame(self, frame: int, times: StageTimes) -> tuple[GroundTruthFrame, Projection, Visibility]:
        with times.stage("traffic"):
            state = self.traffic.reset() if frame == 0 else self.traffic.step()
            if frame == 0:
                self.markings = self.traffic.road_markings()
                if self.scenario.render.visibility or self.images:
                    from simrig.render.meter import VisibilityMeter
                    from simrig.render.scene import RigScene

                    self.scene = RigScene(self.markings)
                    self.meter = VisibilityMeter(self.rig, self.scenario.render.visibility_scale, self.scene)

        with times.stage("projection"):
            projection = project_boxes(state.boxes, self.rig, state.ego)

        with times.stage("visibility"):
            if self.scenario.render.visibility:
                visibility = self.meter.measure(state, projection)
            else:
                visibility = Visibility.unmeasured(projection)
        return state, projection, visibility

    def close(self) -> None:
        self.traffic.close()
