"""The installed layout: import names are ``simrig`` and ``simrig.*`` only, and every package folder ships."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SOURCES = {"simrig": "simrig", "simrig.trackers": "tracker", "simrig.scenarios": "scenarios"}


def _config() -> dict:
    with (ROOT / "pyproject.toml").open("rb") as handle:
        return tomllib.load(handle)["tool"]["setuptools"]


def test_package_dirs_map_the_repository_folders_into_the_simrig_namespace() -> None:
    assert _config()["package-dir"] == SOURCES


def _folder(package: str) -> Path:
    """The repository folder of an installed package name, through pyproject's ``package-dir``."""
    for name, folder in sorted(SOURCES.items(), key=lambda item: -len(item[0])):
        if package == name or package.startswith(name + "."):
            return ROOT / folder / Path(*package[len(name):].lstrip(".").split(".") if package != name else ())
    raise AssertionError(f"{package} is under no package-dir entry")


def test_every_package_folder_is_listed_and_nothing_installs_outside_simrig() -> None:
    on_disk = set()
    for name, folder in SOURCES.items():
        for init in (ROOT / folder).rglob("__init__.py"):
            relative = init.parent.relative_to(ROOT / folder).parts
            on_disk.add(".".join((name, *relative)))
    data_only = {name for name in _config()["package-data"] if not any(True for _ in _folder(name).glob("*.py"))}
    listed = set(_config()["packages"])
    assert listed - data_only == on_disk  # a catalog folder of TOML files is listed so that setuptools ships it
    assert all(_folder(name).is_dir() for name in data_only)
    assert all(name == "simrig" or name.startswith("simrig.") for name in listed)


def test_version_names_the_distribution_to_install(capsys) -> None:
    import pytest

    from simrig.cli import main
    from simrig.version import DISTRIBUTION, __version__

    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out == f"simrig {__version__} (pip: {DISTRIBUTION})\n"
    with (ROOT / "pyproject.toml").open("rb") as handle:
        assert tomllib.load(handle)["project"]["name"] == DISTRIBUTION == "simrig-mot"


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_the_wheel_and_sdist_pass_twine_check_under_the_distribution_name(release_build) -> None:
    """Built as a release would be (``python -m build``), both pass ``twine check``; the wheel's metadata names
    the distribution ``simrig-mot`` with the ``testing`` extra, and installs the ``simrig`` command."""
    import subprocess
    import sys
    import zipfile

    import pytest

    pytest.importorskip("twine")
    wheel, sdist = release_build
    checked = subprocess.run([sys.executable, "-m", "twine", "check", "--strict", str(wheel), str(sdist)],
                             capture_output=True, text=True, timeout=300)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    with zipfile.ZipFile(wheel) as archive:
        metadata = archive.read(next(n for n in archive.namelist() if n.endswith(".dist-info/METADATA"))).decode()
        entry_points = archive.read(next(n for n in archive.namelist() if n.endswith("entry_points.txt"))).decode()
    assert "\nName: simrig-mot\n" in metadata and "Provides-Extra: testing" in metadata
    assert "simrig = simrig.cli:console" in entry_points


def test_the_tested_versions_are_recorded_and_the_readme_and_ci_install_them():
    """constraints.txt pins what the documented numbers were made with; the README's two commands and CI install
    with it, and it pins every package whose release can move those numbers."""
    from conftest import PINNED, constraint_versions

    root = Path(__file__).resolve().parents[1]
    pins = constraint_versions(root / "constraints.txt")
    assert set(PINNED) <= set(pins), sorted(set(PINNED) - set(pins))
    readme = (root / "README.md").read_text(encoding="utf-8")
    assert "pip install -e . -c constraints.txt && simrig run" in readme
    assert "pip install -e '.[dev]' -c constraints.txt && pytest" in readme
    assert "-e '.[dev]' -c constraints.txt" in (root / ".ci" / "run").read_text(encoding="utf-8")
