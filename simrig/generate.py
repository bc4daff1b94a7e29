"""``simrig generate``: run a scenario's traffic, project it through the rig, write the dataset."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

from tqdm import tqdm

from scenarios import Scenario

from .dataset import DatasetWriter, check_output_folder
from .dataset.manifest import package_versions
from .dataset.tables import frame_columns
from .geometry import project_boxes
from .rig import build_rig, rig_to_dict
from .seeding import RandomStreams
from .world import TrafficWorld


@dataclass
class StageTimes:
    """Wall-clock seconds spent per stage of a generation run."""

    traffic: float = 0.0
    projection: float = 0.0
    writing: float = 0.0
    total: float = 0.0


@dataclass
class GenerateResult:
    """What a generation produced: the dataset folder, its manifest, and where the time went."""

    path: Path
    manifest: dict
    times: StageTimes = field(default_factory=StageTimes)


def generate(
    scenario: Scenario,
    *,
    seed: int,
    out: Path | str,
    frames: int | None = None,
    overwrite: bool = False,
    progress: bool = False,
) -> GenerateResult:
    """Generate the dataset of ``scenario`` with ``seed`` into ``out``; ``frames`` defaults to the scenario's.

    Same scenario, seed and frame count give byte-identical tables. Raises
    :class:`~simrig.errors.DatasetExistsError` if ``out`` holds a complete dataset and ``overwrite`` is false
    (checked before any simulation work).
    """
    frames = scenario.frames if frames is None else frames
    if not isinstance(frames, int) or frames < 1:
        raise ValueError(f"frames: must be a positive integer, got {frames!r}")
    out = Path(out)
    check_output_folder(out, overwrite=overwrite)
    streams = RandomStreams(seed)
    rig = build_rig(scenario.rig)
    times = StageTimes()
    started = time.perf_counter()
    world = TrafficWorld(
        scenario.traffic,
        scenario.frame_rate_hz,
        env_seed=streams.integer_seed("traffic"),
        rng=streams.generator("population"),
    )
    events: list[dict] = []
    try:
        with DatasetWriter(out, overwrite=overwrite) as writer:
            writer.write_json("rig.json", rig_to_dict(rig))
            for frame in tqdm(range(frames), desc=scenario.name, unit="frame", disable=not progress):
                tick = time.perf_counter()
                state = world.reset() if frame == 0 else world.step()
                events.extend({"frame": state.frame, "event": name} for name in state.events)
                tock = time.perf_counter()
                projection = project_boxes(state.boxes, rig, state.ego)
                tuck = time.perf_counter()
                writer.write_frame(frame_columns(state, projection, rig.camera_names))
                times.traffic += tock - tick
                times.projection += tuck - tock
                times.writing += time.perf_counter() - tuck
            tick = time.perf_counter()
            manifest = writer.commit(
                {
                    "scenario": scenario.model_dump(mode="json"),
                    "seed": seed,
                    "frames": frames,
                    "frame_rate_hz": scenario.frame_rate_hz,
                    "versions": package_versions(),
                    "events": events,
                }
            )
            times.writing += time.perf_counter() - tick
    finally:
        world.close()
    times.total = time.perf_counter() - started
    return GenerateResult(path=out, manifest=manifest, times=times)
