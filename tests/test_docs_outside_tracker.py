"""The "Wrapping an outside 2D tracker" example of docs/test-your-tracker.md runs as written in an empty folder,
prints what the page shows, and its wrapper is at most 40 lines."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

PAGE = Path(__file__).resolve().parents[1] / "docs" / "test-your-tracker.md"


def example() -> tuple[str, str]:
    """The section's python block and the text block that shows what it prints."""
    section = PAGE.read_text(encoding="utf-8").split("## A 2D tracker, one camera at a time", 1)[1].split("\n## ", 1)[0]
    code, printed = re.search(r"```python\n(.*?)```\s*```text\n(.*?)```", section, re.S).groups()
    return code, printed


def test_the_outside_tracker_example_runs_and_scores(tmp_path: Path) -> None:
    code, printed = example()
    wrapper = code[code.index("class Wrapped"):]
    assert len(wrapper.splitlines()) <= 40
    code += ("\nassert len(run.tracks.tracks2d) > 0 and run.tracks.tracks3d is None\n"
             "assert set(run.tracks.tracks2d.camera) <= set(dataset.rig.camera_names)\n")
    result = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    hota, switches = map(float, re.fullmatch(r"HOTA (\S+)  IDSW (\S+)\n", result.stdout).groups())
    assert 0.0 < hota <= 1.0 and switches >= 0
    assert result.stdout == printed  # the page shows what it prints (deterministic per seed)
