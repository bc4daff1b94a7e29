"""Helpers of the explicit benchmarks and reports: cached datasets and publishing a Markdown table."""

from __future__ import annotations

import platform
import shlex
import sys
from pathlib import Path

from simrig.scenarios import load_scenario

from simrig.dataset import Dataset
from simrig.errors import DatasetError
from simrig.pipeline.generate import generate


def cached_dataset(scenario: str, seed: int, frames: int, data: Path) -> Dataset:
    """The dataset of (``scenario``, ``seed``, ``frames``) under ``data``, generated only if absent."""
    out = data / f"{scenario}-seed{seed}-{frames}f"
    try:
        existing = Dataset.open(out)
        if existing.manifest["frames"] == frames:
            return existing
    except DatasetError:
        pass
    generate(load_scenario(scenario), seed=seed, out=out, frames=frames, overwrite=True)
    return Dataset.open(out)


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
