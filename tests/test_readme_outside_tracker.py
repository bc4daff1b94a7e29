"""The README's "Wrapping an outside 2D tracker" example runs as written in an empty folder, and its wrapper is
at most 40 lines."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def example() -> str:
    section = README.read_text(encoding="utf-8").split("### Wrapping an outside 2D tracker", 1)[1].split("\n#", 1)[0]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_the_outside_tracker_example_runs_and_scores(tmp_path: Path) -> None:
    code = example()
    wrapper = code[code.index("class Wrapped"):]
    assert len(wrapper.splitlines()) <= 40
    code += ("\nassert len(run.tracks.tracks2d) > 0 and run.tracks.tracks3d is None\n"
             "assert set(run.tracks.tracks2d.camera) <= set(dataset.rig.camera_names)\n")
    result = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    hota, switches = map(float, re.fullmatch(r"HOTA (\S+)  IDSW (\S+)\n", result.stdout).groups())
    assert 0.0 < hota <= 1.0 and switches >= 0
