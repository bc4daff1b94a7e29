"""The README's "Python API" example runs as written, in a fresh interpreter in an empty folder, and prints what
the README shows; docs/test-your-tracker.md shows the same example and output."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
PAGE = ROOT / "docs" / "test-your-tracker.md"


def example(text: str, heading: str) -> tuple[str, str]:
    """The python block under ``heading`` and the text block after it (what it prints)."""
    section = text.split(heading, 1)[1].split("\n## ", 1)[0]
    code, printed = re.search(r"```python\n(.*?)```\s*```text\n(.*?)```", section, re.S).groups()
    return code, printed


def api_example() -> str:
    return example(README.read_text(encoding="utf-8"), "## Python API")[0]


def test_the_python_api_example_runs_and_prints_scores(tmp_path: Path) -> None:
    code = api_example() + (
        "\nassert len(run.tracks.tracks3d) > 0  # the user's tracker did report tracks\n"
        "again = simrig.score(simrig.open_dataset('runs/api-demo'), run.tracks)\n"
        "assert again.metrics3d['overall']['AMOTA'] == report.metrics3d['overall']['AMOTA']\n"
    )
    result = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    hota, amota = map(float, re.fullmatch(r"HOTA (\S+)  AMOTA (\S+)\n", result.stdout).groups())
    assert 0.0 < hota <= 1.0 and 0.0 < amota <= 1.0
    assert (tmp_path / "runs" / "api-demo" / "manifest.json").is_file()
    assert result.stdout == example(README.read_text(encoding="utf-8"), "## Python API")[1]  # deterministic per seed


def test_the_docs_show_the_readme_s_example_and_output() -> None:
    """docs/test-your-tracker.md's block is marked as run here: it must be this very example."""
    assert example(PAGE.read_text(encoding="utf-8"), "## Your tracker, from Python") == \
        example(README.read_text(encoding="utf-8"), "## Python API")


def test_import_simrig_loads_nothing_heavy_and_exports_what_all_says() -> None:
    code = (
        "import sys, simrig\n"
        "heavy = {'numpy', 'pyarrow', 'pydantic', 'highway_env', 'pyrender', 'scipy'} & set(sys.modules)\n"
        "print(sorted(heavy))\n"
        "missing = [name for name in simrig.__all__ if not hasattr(simrig, name)]\n"
        "missing += sorted(set(simrig._EXPORTS) - set(simrig.__all__))\n"
        "print(missing)\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.splitlines() == ["[]", "[]"]


def test_python_m_simrig_is_the_simrig_command_and_dir_shows_the_public_names() -> None:
    done = subprocess.run([sys.executable, "-m", "simrig", "--version"], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and done.stdout.startswith(f"simrig {simrig_version()} "), done.stderr[-2000:]
    code = ("import simrig\nprint(sorted(n for n in dir(simrig) if not n.startswith('__'))"
            " == sorted(set(simrig.__all__) - {'__version__'}))")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout.strip() == "True"


def simrig_version() -> str:
    from simrig.version import __version__

    return __version__
