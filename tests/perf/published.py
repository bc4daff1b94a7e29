"""Helpers of the explicit benchmarks and reports: cached datasets and publishing a Markdown table."""

from __future__ import annotations

import platform
import shlex
import shutil
import sys
import tempfile
from pathlib import Path

import tomli_w
from simrig.scenarios import load_scenario

from simrig.dataset import Dataset
from simrig.errors import DatasetError
from simrig.pipeline.generate import generate


def cached_dataset(scenario: str, seed: int, frames: int, data: Path, *, preset: str | None = None) -> Dataset:
    """The dataset of (``scenario``, ``seed``, ``frames``) under ``data``, generated only if absent or made from
    another scenario (a catalog or preset change since); ``preset``: the catalog scenario with that detector preset
    (``[sensor] preset``) instead of its own detector. A dataset of the same world made with another detector is
    reused for its traffic and visibility (only the detector reruns)."""
    from simrig.pipeline.content_keys import world_key

    out = data / f"{scenario}{'' if preset is None else '-' + preset}-seed{seed}-{frames}f"
    with tempfile.TemporaryDirectory() as tmp:
        source = scenario
        if preset is not None:  # as a user's file would say it, so the preset lies under the scenario's keys
            source = Path(tmp) / f"{scenario}-{preset}.toml"
            source.write_text(tomli_w.dumps({"extends": scenario, "sensor": {"preset": preset}}))
        wanted = load_scenario(source)
    try:
        existing = Dataset.open(out)
    except DatasetError:
        existing = None
    if existing is not None and existing.frame_count == frames:
        if existing.scenario == wanted.model_dump(mode="json"):
            return existing
        made_from = load_scenario_dump(existing.scenario)
        if made_from is not None and world_key(made_from, seed, frames) == world_key(wanted, seed, frames):
            with tempfile.TemporaryDirectory(dir=data) as tmp:
                staged = generate(wanted, seed=seed, out=Path(tmp) / "new", frames=frames, world_from=existing).path
                shutil.rmtree(out)
                staged.rename(out)
            return Dataset.open(out)
    generate(wanted, seed=seed, out=out, frames=frames, overwrite=True)
    return Dataset.open(out)


def load_scenario_dump(dump: dict):
    """The scenario a dataset's manifest recorded, or None when today's schema no longer reads it."""
    from simrig.scenarios.schema import scenario_from_record

    try:
        return scenario_from_record(dump)
    except ValueError:
        return None


def command_line() -> str:
    """The command that is running, as a user would type it from the repository root."""
    return shlex.join(["python", str(Path(sys.argv[0]).as_posix()), *sys.argv[1:]])


def machine() -> str:
    """The processor (or machine type) and Python version a report was produced on: ``x86_64, Python 3.11.7``."""
    return f"{platform.processor() or platform.machine()}, Python {platform.python_version()}"


def publish(lines: list[str], out: Path) -> None:
    """Write ``lines`` to ``out`` and print them."""
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(lines))
    print("\n".join(lines))
    print(f"wrote {out}")


def alternating(sides: dict[str, list[str]], repeats: int, measure) -> tuple[dict[str, list[float]], dict[str, str]]:
    """Run every side's command ``repeats`` times, the sides alternating (so that a busy moment of the machine hits
    every side alike); ``measure(command)`` gives (a cost, the command's stdout). Returns each side's costs and its
    last stdout."""
    costs: dict[str, list[float]] = {name: [] for name in sides}
    outputs: dict[str, str] = {}
    for _ in range(repeats):
        for name, command in sides.items():
            cost, outputs[name] = measure(command)
            costs[name].append(cost)
    return costs, outputs


def seed_range(text: str) -> list[int]:
    """The seeds of a ``--seeds`` option: ``100-109`` (inclusive) or one seed.

    >>> seed_range("100-102"), seed_range("7")
    ([100, 101, 102], [7])
    """
    low, _, high = text.partition("-")
    return list(range(int(low), int(high or low) + 1))
